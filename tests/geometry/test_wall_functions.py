"""A curve's wall functions as the compiled kernels take them
(``billiard/geometry/wall_functions.py``): a table of rows that numba types once and
unboxes as one pointer per row, whose ``row[w]`` calls the same compiled function as the
``cfunc`` itself."""

from __future__ import annotations

import cProfile
import pstats

import numpy as np
import pytest
from billiard.generated.curves import parabola, wedge

from billiard import jit
from billiard.geometry.wall_functions import WALL_SLOTS, WallFunction, WallTable

pytestmark = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

NAMES = ("f", "df", "d2f", "d3f")


def _table(module, walls: int) -> WallTable:
    """The rows f, f', f'', f''' of a generated curve's walls, compiled."""
    return WallTable(
        tuple(WallFunction(getattr(module, f"{n}_{i}")) for i in range(walls)) for n in NAMES
    )


def _read_all():
    import numba

    @numba.njit
    def read_all(walls, x, p, out):
        """Every function of every slot at x, row by row (a loop: w is not a constant)."""
        for w in range(2):
            out[0, w] = walls[0][w](x, p)
            out[1, w] = walls[1][w](x, p)
            out[2, w] = walls[2][w](x, p)
            out[3, w] = walls[3][w](x, p)
        return out

    return read_all


@pytest.mark.parametrize(("module", "walls"), [(wedge, 2), (parabola, 1)])
def test_a_kernel_calls_each_slot_s_own_function(module, walls):
    p = np.array(list(module.PARAMETERS.values()), dtype=np.float64)
    table = _table(module, walls)
    got = _read_all()(table, 0.0123, p, np.zeros((4, WALL_SLOTS)))
    for k, name in enumerate(NAMES):
        for w in range(WALL_SLOTS):
            # a curve of one wall repeats it in the second slot
            expected = getattr(module, f"{name}_{min(w, walls - 1)}")(0.0123, p)
            assert got[k, w] == expected, (name, w)


def test_a_kernel_call_unboxes_no_first_class_function():
    """numba unboxes a first-class function with Python calls (its
    ``_get_wrapper_address``, some 5 us each): a call of a kernel from Python that takes
    the table makes none of them, the rows reaching it as their addresses."""
    import numba

    @numba.njit
    def first(walls, p):
        return walls[0][0](0.0, p)

    table = _table(wedge, 2)
    p = np.array(list(wedge.PARAMETERS.values()), dtype=np.float64)
    first(table, p)  # compiled here, outside the profile
    profile = cProfile.Profile()
    profile.enable()
    value = first(table, p)
    profile.disable()
    calls = {
        name: count
        for (_, _, name), (count, *_rest) in pstats.Stats(profile).stats.items()
        if name in ("_get_wrapper_address", "_get_jit_address")
    }
    assert value == wedge.f_0(0.0, p)
    assert calls == {}, f"numba unboxed the wall functions one by one: {calls}"
