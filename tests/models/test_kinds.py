"""Models as kinds inside the kernels (:mod:`billiard.models.kinds`): every registered
impact law, flight model and locator names the code its block of the state vector
starts with, the kernels branch on that code, and a run of each kind is the same,
bit for bit, compiled and interpreted (the twin, ``billiard.kernels_py``). A model
without a kernel kind is refused with one line, not run interpreted without a word."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from billiard import jit
from billiard.engine.ctx import state_vector
from billiard.engine.simulation import Simulation
from billiard.geometry.wall_functions import near_functions, plain_wall_functions, wall_functions
from billiard.kernels import interpreted as twin
from billiard.kernels import layout as L
from billiard.models.flight import FLIGHT_MODELS, ExactFlight
from billiard.models.impact import IMPACT_LAWS, KaneLevinsonImpact
from billiard.models.kinds import REGISTRIES, kernel_kind, require_kernel
from billiard.models.locators import LOCATORS
from billiard.models.rk4_locator import answer_foot
from billiard.scene.checks import SceneError
from billiard.scene.scene import load_scene, with_values

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

#: each kind's code, as the kernels' layout declares it
KINDS = {
    "impact law": {
        "kane-levinson": L.KANE_LEVINSON,
        "walton": L.WALTON,
        "power-law": L.POWER_LAW,
        "viscoelastic": L.VISCOELASTIC,
        "energy-dependent": L.ENERGY_DEPENDENT,
        "angle-dependent": L.ANGLE_DEPENDENT,
        "point-particle": L.POINT_PARTICLE,
    },
    "flight model": {
        "exact": L.FLIGHT_EXACT,
        "adaptive": L.FLIGHT_ADAPTIVE,
        "rk4": L.FLIGHT_RK4,
    },
    "locator": {"event": L.LOC_EVENT, "rk4": L.LOC_RK4},
}
#: the registered laws, as the refusal of a law without a kernel lists them
LAW_NAMES = ", ".join(KINDS["impact law"])
#: the slot each kind is written to
SLOTS = {"impact law": L.IM_KIND, "flight model": L.FL_KIND, "locator": L.LOC_KIND}

#: one short run per case, together every kind: (scene, overrides, rows, kinds by what)
CASES = {
    # the exact parabola and the event locator, the vertical drive's branch
    "exact-event": (
        "wedge-6.6hz",
        {"air.drag": "none", "drive.direction": "vertical"},
        300,
        {"impact law": "kane-levinson", "flight model": "exact", "locator": "event"},
    ),
    "adaptive-event": (
        "hyperbola-5.8hz",
        {"air.drag": "fowles"},
        300,
        {"impact law": "kane-levinson", "flight model": "adaptive", "locator": "event"},
    ),
    "rk4-rk4": (
        "parabola-5.4hz",
        {"air.drag": "fowles", "run.method": "rk4"},
        200,
        {"impact law": "kane-levinson", "flight model": "rk4", "locator": "rk4"},
    ),
    # the other impact laws, each with its parameters (docs/impact-laws.md)
    **{
        f"{law}-exact": (
            "wedge-6.6hz",
            {"air.drag": "none", "contact.law": law, **values},
            300,
            {"impact law": law, "flight model": "exact", "locator": "event"},
        )
        for law, values in {
            "walton": {"contact.beta0": 0.35},
            "power-law": {"contact.e_ref": 0.4, "contact.v_ref": 0.5, "contact.exponent": 0.2},
            "viscoelastic": {"contact.viscous": 0.5},
            "energy-dependent": {"contact.energy_scale": 2e-5},
            "angle-dependent": {"contact.angle_slope": 0.05},
            "point-particle": {"contact.energy_scale": 2e-5},
        }.items()
    },
}


def _sim(case: str) -> Simulation:
    name, values, _, _ = CASES[case]
    return Simulation(with_values(load_scene(name), values))


def _models(sim: Simulation) -> dict:
    return {"impact law": sim.impact, "flight model": sim.flight, "locator": sim.locator}


def test_every_registered_model_names_its_kind():
    assert set(REGISTRIES) == set(KINDS)
    assert REGISTRIES["impact law"] is IMPACT_LAWS
    assert REGISTRIES["flight model"] is FLIGHT_MODELS
    assert REGISTRIES["locator"] is LOCATORS
    for what, registry in REGISTRIES.items():
        assert {name: cls.kind for name, cls in registry.items()} == KINDS[what], what
    # the cases below cover every kind
    for what, kinds in KINDS.items():
        assert {case[3][what] for case in CASES.values()} == set(kinds), what


@pytest.mark.parametrize("case", CASES)
def test_each_model_writes_its_kind_into_the_state_vector(case):
    sim = _sim(case)
    ctx = state_vector(sim)
    for what, model in _models(sim).items():
        expected = KINDS[what][CASES[case][3][what]]
        assert type(model) is REGISTRIES[what][CASES[case][3][what]]
        assert kernel_kind(model) == require_kernel(model, what) == expected
        assert ctx[SLOTS[what]] == expected, what
        # the block it writes is its own ctx's
        block = [float("nan")] * L.SIZE
        model.write(block)
        written = [i for i, x in enumerate(block) if x == x]
        assert written and all(block[i] == model.ctx[i] == ctx[i] for i in written), what


def _run(module, ctx, params, walls, nears, out, rows, boundary, error):
    """Rows of ``module.run_chunk`` (``run_chunk_fixed`` with ``nears``) into ``out``,
    a search's question for the global nearest point answered as the engine does."""
    done = 0
    while True:
        view = out[done * L.NCOL :]
        try:
            if nears is None:
                return module.run_chunk(ctx, params, walls, view, rows - done)
            return module.run_chunk_fixed(ctx, params, walls, nears, view, rows - done)
        except error as exc:
            if exc.args[0] != L.E_FOOT:
                raise
            done = int(ctx[L.EN_IMPACTS])
            answer_foot(ctx, boundary)


@compiled
@pytest.mark.parametrize("case", CASES)
def test_each_kind_runs_the_same_compiled_and_interpreted(case):
    sim = _sim(case)
    rows = CASES[case][2]
    values = state_vector(sim)
    values[L.EN_TARGET] = float(rows)
    fixed = sim.method == "rk4"
    walls = sim.boundary.walls
    # interpreted: the twin's loop over a list, the generated functions themselves
    ctx = list(values)
    out = np.zeros(rows * L.NCOL)
    plain_nears = (tuple(w.near for w in walls), tuple(w.dnear for w in walls))
    done = _run(
        importlib.import_module(f"{twin.PACKAGE}.loop"),
        ctx,
        tuple(walls[0].p),
        plain_wall_functions(walls),
        plain_nears if fixed else None,
        out,
        rows,
        sim.boundary,
        twin.layout.KernelError,
    )
    # compiled
    from billiard.kernels import loop

    array = np.array(values, dtype=np.float64)
    buffer = np.zeros(rows * L.NCOL)
    again = _run(
        loop,
        array,
        np.array(walls[0].p, dtype=np.float64),
        wall_functions(sim),
        near_functions(sim) if fixed else None,
        buffer,
        rows,
        sim.boundary,
        L.KernelError,
    )
    assert int(ctx[L.EN_IMPACTS]) == int(array[L.EN_IMPACTS]) == rows
    assert done[0] == again[0] == L.DONE
    assert out.tobytes() == buffer.tobytes()
    assert np.array(ctx).tobytes() == array.tobytes()


@pytest.mark.parametrize("module", ["compiled", "twin"])
def test_an_impact_law_kind_the_kernels_do_not_have_stops_the_kernel(module):
    if module == "compiled" and not jit.ENABLED:
        pytest.skip(f"numba unavailable: {jit.numba_problem()}")
    impact = (
        importlib.import_module("billiard.kernels.impact") if module == "compiled" else twin.impact
    )
    law = KaneLevinsonImpact(0.01, 0.005, 0.4, 0.8, 0.3, 0.2, 0.0)
    values = [0.0] * L.SIZE
    law.write(values)
    ctx = np.array(values) if module == "compiled" else values
    args = (0.3, -1.0, 2.0, 0.1, 0.0, 0.2, False)
    # the law's own kind: Kane and Levinson's law itself
    assert impact.impact_law(ctx, *args) == twin.impact.kane_levinson(values, *args)
    ctx[L.IM_KIND] = 7.0
    errors = (L.KernelError, twin.layout.KernelError)
    with pytest.raises(errors) as caught:
        impact.impact_law(ctx, *args)
    assert caught.value.args[0] == L.E_KIND == ctx[L.EN_STOP]
    assert twin.stop_text(L.E_KIND, ctx[L.EN_ERR_VALUE]) == (
        "the kernels have no impact law of kind 7"
    )


class _Elastic:
    """An impact law with an ``apply`` method alone (perfectly elastic, frictionless)."""

    regimes = ("elastic",)

    @classmethod
    def from_scene(cls, scene: object) -> _Elastic:
        return cls()

    def apply(self, state, contact):  # pragma: no cover - never run here
        raise NotImplementedError


class _Audited(KaneLevinsonImpact):
    """Kane and Levinson's law with another ``apply``: not its parent's kernel."""


def test_a_law_without_a_kernel_kind_is_refused_in_one_line(monkeypatch):
    with pytest.raises(SceneError) as caught:
        require_kernel(_Elastic(), "impact law")
    assert str(caught.value) == (
        "impact law _Elastic has no compiled kernel: choose from " + LAW_NAMES
    )
    monkeypatch.setitem(IMPACT_LAWS, "elastic", _Elastic)
    with pytest.raises(SceneError, match="^impact law 'elastic' has no compiled kernel: "):
        require_kernel(_Elastic(), "impact law")
    audited = _Audited(0.01, 0.005, 0.4, 0.8, 0.3, 0.2, 0.0)
    assert kernel_kind(audited) is None
    with pytest.raises(SceneError, match="^impact law _Audited has no compiled kernel"):
        require_kernel(audited, "impact law")


def test_a_simulation_with_a_law_without_a_kernel_is_refused():
    # refused when it is built: there is no other engine to run it on
    scene = with_values(load_scene("wedge-6.6hz"), {"air.drag": "none"})
    with pytest.raises(SceneError) as caught:
        Simulation(scene, law=_Elastic())
    message = str(caught.value)
    assert message == "impact law _Elastic has no compiled kernel: choose from " + LAW_NAMES
    assert "\n" not in message


def test_a_flight_model_without_a_kernel_kind_is_refused():
    class Drifting(ExactFlight):
        """Another flight, which does not name a kernel."""

    with pytest.raises(SceneError, match="^flight model Drifting has no compiled kernel: "
                       "choose from exact, adaptive, rk4$"):  # fmt: skip
        require_kernel(Drifting(9.81), "flight model")
