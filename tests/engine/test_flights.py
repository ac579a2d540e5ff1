"""Contact phases with the flights between them on the kernels
(:meth:`billiard.engine.simulation.Simulation._fly`): the same records, phases, times
and engine state as the one-event step on the classes, and interrupted runs that resume
to the same bytes."""

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
    assert sim._flights is not None
    if not kernels:
        sim._flights = None  # the one-event step on the classes throughout
    contacts = []
    sim.on_contact = contacts.append
    records: list = []
    sim.run(impacts, records, checkpoint=None if checkpoints is None else checkpoints.append)
    rows = [repr(tuple(record)) for record in records]
    return rows, [repr(tuple(c)) for c in contacts], sim.mode_times(), sim.state, sim.status


@pytest.mark.parametrize(
    ("name", "drag"),
    [
        ("wedge-6.6hz", "fowles"),
        ("wedge-6.6hz", "none"),
        ("hyperbola-5.8hz", "fowles"),
        ("parabola-5.4hz", "none"),
    ],
)
def test_flights_on_the_kernels_are_the_one_event_step(name, drag):
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
