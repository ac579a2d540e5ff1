"""Contact phases on the one engine, the state machine (:mod:`billiard.kernels.machine`):
compiled, the same records, phases, cut phases, times, final time and engine state as
the same source interpreted (``sim.driver.interpreted``), and interrupted runs that
resume to the same bytes."""

from __future__ import annotations

import pytest

from billiard.engine import simulation as engine
from billiard.engine.interrupt import signal_after
from billiard.run.simulate import RunInterrupted, Simulation, resume, simulate
from billiard.scene.scene import load_scene, with_values

FILES = ("collisions.csv", "contacts.csv", "scene.toml")


def phases(name: str, drag: str = "fowles"):
    return with_values(load_scene(name), {"contact.model": "phases", "air.drag": drag})


def run(scene, impacts: int, *, kernels: bool, checkpoints: list | None = None):
    """(impact rows, contact records, mode times, final state, status) of a run."""
    sim = Simulation(scene)
    if not kernels:
        sim.driver.interpreted = True  # the same source as plain Python
    contacts = []
    sim.on_contact = contacts.append
    records: list = []
    sim.run(impacts, records, checkpoint=None if checkpoints is None else checkpoints.append)
    rows = [repr(tuple(record)) for record in records]
    return rows, [repr(tuple(c)) for c in contacts], sim.mode_times(), sim.state, sim.status


def run_ends(scene, impacts: int, *, kernels: bool) -> dict:
    """Everything a run reports, its cut phases and how it ended included."""
    sim = Simulation(scene)
    if not kernels:
        sim.driver.interpreted = True
    contacts: list = []
    cuts: list = []
    sim.on_contact = contacts.append
    sim.on_contact_cut = cuts.append
    records: list = []
    reason = sim.run(impacts, records)
    return {
        "rows": [repr(tuple(record)) for record in records],
        "contacts": [repr(tuple(c)) for c in contacts],
        "cuts": [repr(tuple(c)) for c in cuts],
        "times": sim.mode_times(),
        "state": sim.state,
        "status": sim.status,
        "reason": reason,
        "final_time": repr(sim.final_time),
        "mode": sim.mode,
    }


def _bench_cases() -> dict:
    from bench.contact import cases

    return {case.name: case for case in cases()}


def _vertical_wedge(elastic_below: float | None = None):
    changes = {"drive.direction": "vertical", "drive.frequency": 9.25, "run.duration": 2.0}
    if elastic_below is not None:
        changes["contact.elastic_below"] = elastic_below
    return with_values(phases("wedge-6.6hz"), changes)


@pytest.mark.parametrize(
    "case",
    ["bowl at rest", "vertex at rest", "bowl rolling", "floor drop", "steep wall slide",
     "shaken table"],
)  # fmt: skip
def test_the_state_machine_is_the_engine_on_the_closed_form_cases(case):
    # rest, chatter, long rolling phases cut by the run's end, a hold in the vertex
    scene = with_values(_bench_cases()[case].build("phases"), {"run.duration": 0.6})
    machine = run_ends(scene, 2000, kernels=True)
    classes = run_ends(scene, 2000, kernels=False)
    assert machine == classes


@pytest.mark.parametrize(
    "scene",
    [
        pytest.param(_vertical_wedge(), id="vertical-wedge"),
        pytest.param(_vertical_wedge(0.0), id="vertical-wedge-eb0"),
        pytest.param(
            with_values(phases("wedge-6.6hz"), {"contact.elastic_below": 0.0, "run.duration": 1.5}),
            id="wedge-eb0",
        ),  # fmt: skip
        pytest.param(
            with_values(phases("parabola-5.4hz"), {"drive.amplitude": 0.005}), id="in-contact"
        ),
        pytest.param("shaken-vertex-eb0", id="shaken-vertex-eb0"),
        pytest.param("escape-in-flight", id="escape-in-flight"),
        pytest.param("no-impulse-rk4", id="no-impulse-rk4"),
    ],
)
def test_the_state_machine_is_the_engine_at_corners_and_ends(scene):
    # holds and releases in the vertex, summed chatter series, the contact span's end
    if scene == "shaken-vertex-eb0":
        # held after meeting both walls at one instant (no landing speed)
        from tests.validation.test_vertex import SHAKEN_VERTEX

        changes = {**SHAKEN_VERTEX, "contact.elastic_below": 0.0, "run.duration": 3.0}
        scene = with_values(load_scene("wedge-6.6hz"), changes)
    elif scene == "escape-in-flight":
        # thrown out of an open wedge after 17 impacts, the last flights in one call:
        # the run's end and last impact are the last impact's
        from bench.soak import scene_from_draw
        from tests.validation.test_vertex import shaken_wedge_draw

        draw = {**shaken_wedge_draw(1), "lid": False, "amplitude": 0.02}
        draw["direction"] = "horizontal"
        scene = with_values(scene_from_draw(draw), {"run.duration": 4.0})
    elif scene == "no-impulse-rk4":
        scene = NO_IMPULSE_SCENE()
    machine = run_ends(scene, 3000, kernels=True)
    classes = run_ends(scene, 3000, kernels=False)
    assert (machine["contacts"] or machine["rows"]) and machine == classes


#: a soak draw (rk4, elastic_below = 0) whose flights met the wall at contacts without
#: impulse, four rows of collisions.csv with Rn = Rt = 0 before these were no impacts
NO_IMPULSE_DRAW = {
    "curve": "sqrt(0.0001 + 2*x**2) + 0.005", "lid": True, "top": 0.20839944028502777,
    "amplitude": 0.01686359089452354, "frequency": 10.271816606746174,
    "direction": "vertical", "phase": 0.17898080738076383,
    "restitution": 0.3366277744944862, "mu_static": 0.3157302140007536,
    "mu_kinetic_fraction": 0.15106581863291246, "elastic_below": 0.0,
    "radius_fraction": 0.6491456029567633, "log_mass": -3.1415996728332525,
    "inertia_factor": 0.4023221243171379, "drag": "fowles", "magnus": 3.3793995395315235e-09,
    "start": "inside", "x_fraction": 0.2852880225422403, "y_fraction": 0.22894593725059206,
    "v1": 0.9651679322295577, "v2": 1.0596079653419408, "omega": -109.83684024852582,
    "t0": 2.284395411357998, "model": "phases",
}  # fmt: skip


def NO_IMPULSE_SCENE():  # noqa: N802  (a constant's name: the scene is built on use)
    from bench.soak import scene_from_draw

    return with_values(scene_from_draw(NO_IMPULSE_DRAW), {"run.method": "rk4"})


def test_a_flights_contact_without_impulse_is_no_row():
    result = simulate(NO_IMPULSE_SCENE(), collisions=2000)
    # a documented stop (the fixed step is too coarse here), before it only impacts
    assert result.status.name == "SOLVER_FAILED", result.message
    columns = result.columns
    assert len(result) >= 20
    assert not ((columns["Rn"] == 0.0) & (columns["Rt"] == 0.0)).any()


_INTERPRETED_MACHINE = """
import sys
from billiard import jit
from billiard.scene.scene import load_scene, with_values
from billiard.run.simulate import simulate
assert not jit.ENABLED
scene = with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"})
simulate(scene, collisions=300, out_dir=sys.argv[1])
"""


def test_the_interpreted_state_machine_writes_the_compiled_bytes(tmp_path):
    import os
    import subprocess
    import sys

    from billiard import jit

    if not jit.ENABLED:
        pytest.skip("numba unavailable: both runs would be interpreted")
    # the paper's wedge: rolling, sliding, lift-offs and impacts from contact
    scene = with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"})
    simulate(scene, collisions=300, out_dir=tmp_path / "compiled")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run(
        [sys.executable, "-c", _INTERPRETED_MACHINE, str(tmp_path / "interpreted")],
        env=env,
        check=True,
    )
    for name in FILES:
        a = (tmp_path / "interpreted" / name).read_bytes()
        b = (tmp_path / "compiled" / name).read_bytes()
        assert a == b, name
    assert (tmp_path / "compiled" / "contacts.csv").read_text().count("\n") > 20


@pytest.mark.parametrize(
    ("name", "drag"),
    [
        ("wedge-6.6hz", "fowles"),
        ("wedge-6.6hz", "none"),
        ("hyperbola-5.8hz", "fowles"),
        ("parabola-5.4hz", "none"),
    ],
)
def test_flights_compiled_are_the_interpreted_engine(name, drag):
    scene = phases(name, drag)
    on_kernels = run(scene, 2500, kernels=True)
    on_classes = run(scene, 2500, kernels=False)
    rows, contacts = on_kernels[0], on_kernels[1]
    assert len(rows) == 2500
    if name != "parabola-5.4hz":
        assert len(contacts) > 20  # the ball lands many times: many hand-overs
    names = ("rows", "contacts", "times", "state", "status")
    for a, b, what in zip(on_kernels, on_classes, names, strict=True):
        assert a == b, what


def test_checkpoints_between_flights_resume_bit_for_bit(monkeypatch):
    # a checkpoint after every chunk of flights: each one continues to the same records
    monkeypatch.setattr(engine, "CHECKPOINT_INTERVAL", 0.0)
    scene = phases("wedge-6.6hz")
    states: list = []
    rows, contacts, *_ = run(scene, 600, kernels=True, checkpoints=states)
    assert len(states) > 100 and len(contacts) > 20
    for state in states[::10]:
        sim = Simulation(scene)
        records: list = []
        sim.run(600, records, start=state)
        tail = [repr(tuple(record)) for record in records]
        assert tail == rows[state.impacts :], state.impacts


@pytest.mark.parametrize("k", [1, 150, 399])
def test_interrupt_and_resume_with_flights_on_the_kernels_is_byte_identical(k, tmp_path):
    scene = phases("wedge-6.6hz")
    ref = tmp_path / "ref"
    simulate(scene, collisions=400, out_dir=ref)
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=400, out_dir=out, on_record=signal_after(k))
    resume(out)
    for name in FILES:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name


def _unsampled_hold_cases() -> list:
    from tests.kernels.test_contact import _hold_cases

    return [case for case in _hold_cases() if case[4] is None]


@pytest.mark.parametrize("index", range(len(_unsampled_hold_cases())))
def test_the_state_machine_is_the_engine_in_the_vertex(index):
    # the hold cases of the kernels' tests: at rest, spinning, released, held again
    scene, until, impacts, *_ = _unsampled_hold_cases()[index]
    if until != float("inf"):
        scene = with_values(scene, {"run.duration": until})
    machine = run_ends(scene, impacts, kernels=True)
    classes = run_ends(scene, impacts, kernels=False)
    assert machine == classes
