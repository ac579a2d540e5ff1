"""Runs with contact phases (``contact.model = "phases"``): the files, the API, and the
byte-for-byte resume contract with contact phases and sampling."""

from __future__ import annotations

import json

import numpy as np
import pytest

from billiard.cli import main
from billiard.engine.interrupt import signal_after
from billiard.engine.state import EngineState
from billiard.run.simulate import RunInterrupted, Simulation, resume, simulate
from billiard.runfile.record import CONTACT_COLUMNS, TRAJECTORY_COLUMNS
from billiard.scene.scene import SceneError, load_scene, with_values

FILES = ("collisions.csv", "contacts.csv", "trajectory.csv", "scene.toml")


def wedge_phases():
    return with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"})


def test_the_paper_scenes_use_the_impact_model():
    for name in ("wedge-6.6hz", "parabola-5.4hz", "hyperbola-4.5hz", "hyperbola-5.8hz"):
        assert load_scene(name).contact.model == "impacts"


def test_an_unknown_contact_model_is_a_one_line_error():
    with pytest.raises(SceneError, match="contact.model") as caught:
        with_values(load_scene("wedge-6.6hz"), {"contact.model": "rolling"})
    assert "\n" not in str(caught.value)


def test_samples_and_phases_in_the_result():
    result = simulate(wedge_phases(), collisions=100_000, duration=3.0, sample=0.01)
    traj = result.trajectory
    assert list(traj) == list(TRAJECTORY_COLUMNS)
    assert len(traj["t"]) == 301
    assert np.array_equal(traj["t"], 0.01 * np.arange(301))
    assert set(traj["mode"]) <= {"flight", "roll", "slide"}
    contacts = result.contacts
    assert list(contacts) == list(CONTACT_COLUMNS)
    assert len(contacts["t_start"]) > 0
    assert np.all(contacts["t_end"] >= contacts["t_start"])
    times = result.mode_times
    total = sum(times.values()) / 3.0 - 1
    print(f"[validation] phases: the modes' times sum to 3 s {total:+.1e} rel.")
    assert abs(total) <= 1e-14  # measured 0: the phases tile the 3 s to the bit
    assert times["roll"] > 0.0 and times["slide"] > 0.0
    # the samples inside a finished phase say its mode
    i = int(np.argmax(contacts["t_end"] - contacts["t_start"]))
    inside = (traj["t"] > contacts["t_start"][i]) & (traj["t"] < contacts["t_end"][i])
    assert inside.any() and set(traj["mode"][inside]) == {contacts["mode"][i]}
    assert "s rolling" in result.summary() and "s sliding" in result.summary()


def test_sampled_flight_is_the_exact_parabola():
    # no air: the samples of the first flight lie on the parabola from the start state
    scene = with_values(wedge_phases(), {"air.drag": "none", "initial.q2": 0.05})
    result = simulate(scene, collisions=1, sample=0.001)
    traj = result.trajectory
    first = result.columns["t"][0]
    t = traj["t"][traj["t"] < first]
    q2 = 0.05 - 0.5 * 9.81 * t**2
    off = float(np.max(np.abs(traj["q2"][: len(t)] - q2)))
    print(f"[validation] phases: sampled flight {off:.1e} m from the parabola")
    assert off <= 1e-16  # measured 0 m: the exact flight, 14 ulp of 0.05 m


def test_engine_state_round_trips_in_contact():
    sim = Simulation(wedge_phases())
    while sim.mode == "flight":
        sim.step()
    state = sim.state
    assert state.mode in ("roll", "slide") and len(state.contact) == 6
    back = EngineState.from_dict(json.loads(json.dumps(state.to_dict())), 201)
    assert back == state


@pytest.mark.parametrize("k", [1, 180, 399])
def test_interrupt_and_resume_with_phases_is_byte_identical(k, tmp_path):
    scene = wedge_phases()
    ref = tmp_path / "ref"
    simulate(scene, collisions=400, out_dir=ref, sample=0.01)
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=400, out_dir=out, sample=0.01, on_record=signal_after(k))
    resume(out)
    for name in FILES:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name


def test_cli_sample(tmp_path, capsys):
    out = tmp_path / "w"
    code = main(
        ["run", "wedge-6.6hz", "--set", "contact.model=phases", "--duration", "2",
         "--sample", "0.01", "--out", str(out), "--no-plot"]
    )  # fmt: skip
    assert code == 0
    text = capsys.readouterr().out
    assert "s flying" in text and "s rolling" in text and "s sliding" in text
    for name in FILES:
        assert (out / name).is_file()
    assert (out / "trajectory.csv").read_text().count("\n") == 202


def test_cli_bad_sample_is_one_line(tmp_path, capsys):
    assert main(["run", "wedge-6.6hz", "--sample", "-1", "--out", str(tmp_path / "x")]) != 0
    err = capsys.readouterr().err.strip()
    assert "--sample" in err and "\n" not in err


def test_a_contact_with_no_impulse_is_neither_recorded_nor_counted(monkeypatch):
    # a still frictionless wedge, the ball sliding out of the vertex up the left wall; it
    # meets the right wall on its way back. An impact law that gives no impulse there
    # (as for a ball leaving that wall): the step ends with the phase, no impact. The
    # law is replaced in the engine's interpreted twin, whose source is the compiled one
    import math

    from billiard.kernels.interpreted import engine_modules

    b = 1.85
    beta, r, v = math.atan(b), 1.55e-3, 1e-4
    sc = with_values(
        wedge_phases(),
        {
            "boundary.parameters.b": b, "boundary.parameters.c": 0.0,
            "drive.amplitude": 0.0, "drive.frequency": 0.0, "air.drag": "none",
            "contact.mu_static": 0.0, "contact.mu_kinetic": 0.0,
            "initial.q1": 0.0, "initial.q2": r / math.cos(beta),
            "initial.v1": -v * math.cos(beta), "initial.v2": v * math.sin(beta),
        },
    )  # fmt: skip
    sim = Simulation(sc)
    sim.driver.interpreted = True
    machine = engine_modules()[0]
    law = machine.impact_law
    applied = []

    def no_impulse(ctx, u1, u2, u3, z, vb1, vb2, press):
        res = law(ctx, u1, u2, u3, z, vb1, vb2, press)
        applied.append(res)
        return (u1, u2, u3, 0.0, 0.0, *res[5:])

    monkeypatch.setattr(machine, "impact_law", no_impulse)
    before = sim.ball
    record = sim.step()
    assert len(applied) == 1 and applied[0][4] > 0.0  # the real law gives an impulse
    assert record.mode == "slide" and record.end == "impact"  # the phase, no impact
    assert sim.state.impacts == 0 and sum(sim.counts.values()) == 0
    assert (sim.ball.u1, sim.ball.u2) != (before.u1, before.u2)  # it slid back
    assert sim.ball.t == record.t_end
