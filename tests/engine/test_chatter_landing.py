"""Landing under contact phases (billiard/kernels/machine.py ``land``): a chatter
series is summed whatever ``contact.elastic_below`` is, the same on the kernels'
flights as on the one-event step, and a slow impact is never relaunched (the impacts
model's low-velocity rule adds energy; under phases the ball lands or reflects)."""

from __future__ import annotations

import math

import pytest

from billiard.engine.simulation import Simulation
from billiard.runfile.record import ImpactRecord
from billiard.scene.scene import scene_from_dict
from tests.engine.test_flights import run

G = 9.81
R = 1.55e-3


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def floor(contact: dict, initial: dict, drive: dict | None = None):
    return scene_from_dict(
        {
            "boundary": {"curve": "0.001", "escape_height": 10.0, "ceiling": 5.0},
            "drive": drive or {"amplitude": 0.0, "frequency": 1.0},
            "contact": {"model": "phases", "restitution": 0.5, **contact},
            "air": {"drag": "none"},
            "initial": initial,
        }
    )


def test_a_slow_impact_is_elastic_and_lands_without_a_relaunch():
    # 1e-3 m/s onto a still floor, below elastic_below = 0.01 m/s, gravity pressing: the
    # impacts model would relaunch the ball at 0.01 m/s (energy x 100); phases reflect
    # it elastically and land it
    sim = Simulation(floor({}, {"q1": 0.0, "q2": 0.001 + R + 1e-9, "v2": -1e-3}))
    record = sim.step()
    assert isinstance(record, ImpactRecord) and record.regime == "elastic"
    v_in = math.sqrt(1e-6 + 2 * G * 1e-9)
    assert record.v2 == pytest.approx(v_in, rel=1e-9)
    assert sim.counts.get("resting", 0) == 0
    assert sim.mode == "roll"


def test_with_elastic_below_zero_a_dropped_ball_lands_and_rests():
    # a still floor, the rule off: the series is summed once its tail is below 1e-6 s
    # (1e-6 of the 1 s period), then the ball rests; before, the run collapsed
    e, h = 0.5, 0.01
    sim = Simulation(floor({"elastic_below": 0.0}, {"q1": 0.0, "q2": 0.001 + R + h}))
    t0, v0 = math.sqrt(2 * h / G), math.sqrt(2 * G * h)
    impacts = []
    while sim.mode == "flight":
        impacts.append(sim.step())
    assert 15 < len(impacts) < 40
    # entered at the accumulation point t0 + 2 e v0 / (g (1 - e)), not at the impact
    settle = sim.state.contact[5]
    assert settle == sim.state.contact[4] > sim.state.ball.t == impacts[-1].t
    # (the impacts' times carry the locator's error of the tiny flights: 6e-12 s here)
    assert settle == pytest.approx(t0 + 2 * e * v0 / (G * (1 - e)), abs=1e-10)
    assert sim.step(until=10.0) is None and sim.state.impacts == len(impacts)
    assert sim.mode_times()["flight"] == pytest.approx(settle, abs=1e-15)


def test_a_run_that_ends_inside_the_summed_series_stays_at_the_impact():
    # the phase after a summed series starts at its end: a run ending before that keeps
    # the state at the impact (a resumed or extended run moves it on)
    sim = Simulation(floor({"elastic_below": 0.0}, {"q1": 0.0, "q2": 0.001 + R + 0.01}))
    while sim.mode == "flight":
        last = sim.step()
    settle = sim.state.contact[4]
    cut: list = []
    sim.on_contact_cut = cut.append
    assert sim.step(until=0.5 * (last.t + settle)) is None
    assert sim.state.ball.t == last.t and cut == []
    assert sim.mode_times()["roll"] == 0.0
    assert sim.step(until=1.0) is None
    assert cut[-1].t_start == settle and sim.state.ball.t == settle


def test_summed_landings_are_the_same_on_the_kernels_and_on_the_classes():
    gamma, f = 1.2, 20.0
    w = 2 * math.pi * f
    amplitude = gamma * G / w**2
    scene = floor(
        {"elastic_below": 0.0, "mu_static": 0.0, "mu_kinetic": 0.0},
        {"q1": 0.0, "q2": 0.001 + R + 0.01},
        {"amplitude": amplitude, "frequency": f, "direction": "vertical"},
    )
    on_kernels = run(scene, 300, kernels=True)
    on_classes = run(scene, 300, kernels=False)
    assert len(on_kernels[1]) > 5  # it lands, sticks and lifts off again and again
    for a, b, what in zip(on_kernels, on_classes, ("rows", "contacts", "times", "state",
                                                   "status"), strict=True):  # fmt: skip
        assert a == b, what


@pytest.mark.parametrize("at", [18, 19, 40])
def test_a_run_interrupted_at_a_summed_landing_resumes_to_the_same_bytes(tmp_path, at):
    # impact 18 is the last before the first summed landing: the checkpoint holds the
    # ball at that impact with its phase starting later, at the series' end
    import filecmp
    import signal

    from billiard.engine.interrupt import signal_after
    from billiard.run.simulate import RunInterrupted, resume, simulate
    from tests.validation.test_chatter import table_scene

    scene = table_scene()
    simulate(scene, collisions=60, out_dir=tmp_path / "a")
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=60, out_dir=tmp_path / "b",
                 on_record=signal_after(at, signal.SIGTERM))  # fmt: skip
    resume(tmp_path / "b")
    for name in ("collisions.csv", "contacts.csv"):
        assert filecmp.cmp(tmp_path / "a" / name, tmp_path / "b" / name, shallow=False)
