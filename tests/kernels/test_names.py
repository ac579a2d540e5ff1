"""The state vector by name (``billiard/kernels/names.py``): each accessor reads and
writes the slots ``billiard/kernels/layout.py`` declares for the name, and nothing else."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.kernels import layout as L
from billiard.kernels import names as N


def _numbered(*shape: int) -> np.ndarray:
    """Distinct values, one per slot of each row."""
    return np.arange(math.prod(shape), dtype=np.float64).reshape(shape) + 0.5


def test_quantities_are_read_and_written_at_their_slots():
    ctx = _numbered(L.SIZE)
    assert N.read(ctx, "engine.q1") == ctx[L.EN_Q1]
    assert N.read(ctx, "engine.counts") == tuple(ctx[L.COUNTS : L.COUNTS + 4])
    before = ctx.copy()
    N.write(ctx, "engine.target", -7.0)
    assert ctx[L.EN_TARGET] == -7.0
    changed = np.nonzero(ctx != before)[0]
    assert changed.tolist() == [L.EN_TARGET]


def test_columns_of_an_ensemble_are_the_named_slots():
    ctxs = _numbered(3, L.SIZE)
    names = ("engine.theta", "engine.t", "flight.step")
    assert np.array_equal(N.columns(ctxs, names), ctxs[:, [L.EN_THETA, L.EN_T, L.FL_H]])
    assert np.array_equal(N.column(ctxs, "engine.u3"), ctxs[:, L.EN_U3])
    before = ctxs.copy()
    N.set_columns(ctxs, ("engine.q3", "engine.clock"), [[1.0, 2.0]] * 3)
    N.set_columns(ctxs, ("engine.until",), math.inf)
    assert (ctxs[:, L.EN_Q3] == 1.0).all() and (ctxs[:, L.EN_CLOCK] == 2.0).all()
    assert np.isinf(ctxs[:, L.EN_UNTIL]).all()
    assert sorted(set(np.nonzero(ctxs != before)[1])) == [L.EN_Q3, L.EN_CLOCK, L.EN_UNTIL]


def test_a_wrong_name_is_refused():
    ctx = _numbered(L.SIZE)
    with pytest.raises(ValueError, match="engine.counts has 4 slots, not one"):
        N.write(ctx, "engine.counts", 0.0)
    with pytest.raises(KeyError, match="no quantity 'engine.nothing'"):
        N.column(ctx[None], "engine.nothing")
    with pytest.raises(KeyError, match="no quantity 'nothing' in a surface's block"):
        N.write_surface(ctx, 0, nothing=1.0)
    with pytest.raises(KeyError, match="'warm_s' is no constant"):
        N.surface_constants(ctx, 0, warm_s=1.0)


def test_a_surfaces_block_is_read_and_written_at_its_slots():
    j = 3
    base = L.SURF + j * L.SURF_STRIDE
    ctx = list(_numbered(L.SIZE))
    assert len(N.surface_ctx(4)) == L.SURF + 4 * L.SURF_STRIDE
    assert not any(N.surface_ctx(1))
    assert N.read_surface(ctx, j, "b") == ctx[base + L.S_B]
    assert N.warm_start(ctx, j) == (ctx[base + L.S_WS], ctx[base + L.S_WSLOPE])
    block = N.surface_block(ctx, j)
    assert block == ctx[base : base + L.SURF_STRIDE]
    before = list(ctx)
    N.write_surface(ctx, j, kind=L.LINE, d=0.25)
    N.put_warm_s(ctx, j, -1.5)
    changed = {i: ctx[i] for i in range(len(ctx)) if ctx[i] != before[i]}
    assert changed == {base + L.S_KIND: L.LINE, base + L.S_D: 0.25, base + L.S_WS: -1.5}
    constants = N.surface_constants(ctx, j, slope_at=math.nan)
    assert len(constants) == L.S_WS
    assert math.isnan(constants[L.S_SLOPE_AT])
    assert constants[: L.S_SLOPE_AT] == ctx[base : base + L.S_SLOPE_AT]
    N.put_surface_block(ctx, 0, block)
    assert ctx[L.SURF : L.SURF + L.SURF_STRIDE] == block


def _changed(before, after) -> dict[int, float]:
    return {i: after[i] for i in range(len(after)) if after[i] != before[i]}


def test_a_blocks_quantities_are_written_at_their_slots():
    ctx = list(_numbered(L.SIZE))
    before = list(ctx)
    N.write_block(ctx, "phase", mass=-1.0, rtol=-2.0)
    N.write_slots(ctx, "phase.y", (-3.0, -4.0, -5.0))
    N.write_slots(ctx, "rk4.lo", [-6.0, -7.0])  # the first slots of a longer quantity
    N.write_slots(ctx, "rk4.answer", (-8.0, -9.0), at=4)
    assert _changed(before, ctx) == {
        L.PH_M: -1.0, L.PH_RTOL: -2.0, L.PH_Y: -3.0, L.PH_Y + 1: -4.0, L.PH_Y + 2: -5.0,
        L.RK_LO: -6.0, L.RK_LO + 1: -7.0, L.RK_ANSWER + 4: -8.0, L.RK_ANSWER + 5: -9.0,
    }  # fmt: skip
    assert len(ctx) == L.SIZE
    assert N.read_slots(ctx, "phase.y") == (-3.0, -4.0, -5.0)
    assert N.read_slots(ctx, "rk4.lo", 2) == (-6.0, -7.0)
    assert N.read_slots(np.array(ctx), "phase.y", 2) == (-3.0, -4.0)


def test_slots_beyond_a_quantity_are_refused():
    ctx = list(_numbered(L.SIZE))
    with pytest.raises(ValueError, match="phase.y has 3 slots: 4 from slot 0 do not fit"):
        N.write_slots(ctx, "phase.y", (1.0, 2.0, 3.0, 4.0))
    with pytest.raises(ValueError, match="phase.y has 3 slots: 2 from slot 2 do not fit"):
        N.write_slots(ctx, "phase.y", (1.0, 2.0), at=2)
    with pytest.raises(ValueError, match="phase.y has 3 slots, not 4"):
        N.read_slots(ctx, "phase.y", 4)
    with pytest.raises(KeyError, match="no quantity 'phase.nothing'"):
        N.write_block(ctx, "phase", nothing=1.0)
    with pytest.raises(ValueError, match="phase.y has 3 slots, not one"):
        N.write_block(ctx, "phase", y=1.0)
    assert ctx == list(_numbered(L.SIZE))


def test_copy_takes_a_block_or_the_slots_from_one_name_through_another():
    source = _numbered(L.SIZE)
    to = N.new_ctx()
    assert to == [0.0] * L.SIZE
    N.copy(to, source, "impact")
    N.copy(to, source, "drive", "locator.longest_bracket")
    N.copy(to, source, "flight.kind", "flight.step")
    copied = [*range(L.IM, L.IM_END), *range(L.DR, L.H_BRACKET + 1), *range(L.FL_KIND, L.FL_U3)]
    assert sorted(_changed(N.new_ctx(), to)) == sorted(copied)
    assert all(to[i] == source[i] for i in copied)
    # a model's own vector that ends with its block
    short = N.new_ctx("impact")
    assert len(short) == L.IM_END
    N.copy(short, source, "impact")
    assert short[L.IM :] == list(source[L.IM : L.IM_END])
    with pytest.raises(ValueError, match="flight.kind comes before flight.step"):
        N.copy(to, source, "flight.step", "flight.kind")
