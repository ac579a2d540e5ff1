"""Every run ends, says why, and stops on request in every motion state.

Under ``contact.model = "phases"`` a ball that settles into rolling has no impact any
more: a run that asked for impacts ends (status ``IN_CONTACT``) once none came for
``run.contact_span`` seconds of simulated time; the phase in progress is written to
contacts.csv as ``cut``; SIGTERM stops a run in the middle of a long phase within a
second and the resumed run's files equal an uninterrupted one's; the progress report
advances in simulated time while the impact count stands still; a ball that rolls off
the container's range ends the run; an impact with e = 0 lands instead of repeating at
one instant.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from billiard import load_scene, simulate, with_values
from billiard.engine.interrupt import RunInterrupted
from billiard.engine.simulation import Simulation
from billiard.errors import SimulationError
from billiard.run.persist import CHECKPOINT_NAME, resume
from billiard.runfile.record import LID_WALL
from billiard.runfile.sidecsv import CONTACTS_NAME, read_side_csv
from billiard.scene.scene import scene_from_toml
from billiard.status import Status

ROOT = Path(__file__).resolve().parents[2]


def _gentle(**changes):
    """The paper's parabola, shaken gently, under contact phases: the ball rolls in the
    bottom from the start and never flies."""
    values = {"contact.model": "phases", "drive.amplitude": 0.005, **changes}
    return with_values(load_scene("parabola-5.4hz"), values)


def test_a_rolling_ball_ends_the_run_after_the_contact_span():
    result = simulate(_gentle(**{"run.contact_span": 2.0}), collisions=300)
    assert result.status is Status.IN_CONTACT and result.status.finished
    assert result.stop_reason is None and len(result) == 0
    # the first step boundary at or after the span: steps are at most 1/20 drive period
    assert 2.0 <= result.final_time < 2.0 + 0.05 / 5.4
    assert result.final_mode == "roll"
    assert "run.contact_span = 2 s" in result.summary() and "--duration" in result.summary()
    contacts = result.contacts
    assert contacts["end"][-1] == "cut" and contacts["t_end"][-1] == result.final_time
    assert sum(result.mode_times.values()) == pytest.approx(result.final_time, rel=1e-12)


def test_the_span_counts_from_the_last_impact():
    """A ball dropped into the gently shaken bowl bounces, lands, rolls: the run ends
    contact_span after its last impact, with those impacts kept."""
    scene = _gentle(**{"run.contact_span": 1.0, "initial.q1": 0.0, "initial.q2": 0.03})
    result = simulate(scene, collisions=10_000)
    assert result.status is Status.IN_CONTACT and len(result) >= 3
    last = float(result.columns["t"][-1])
    assert last + 1.0 <= result.final_time < last + 1.0 + 0.05 / 5.4


def test_a_duration_follows_the_rolling_ball_and_writes_the_cut_phase(tmp_path):
    result = simulate(_gentle(**{"run.duration": 30.0}), collisions=300, out_dir=tmp_path)
    assert result.status is Status.TIME_LIMIT and result.final_time == 30.0
    contacts = read_side_csv(tmp_path / CONTACTS_NAME)
    assert list(contacts["end"][-1:]) == ["cut"] and contacts["t_end"][-1] == 30.0
    assert contacts["mode"][-1] == "roll"


def test_a_static_ball_at_rest_still_ends_at_rest():
    """The contact span does not hide the at-rest rule: a ball at rest on a still
    boundary ends AT_REST from its start, whatever the span."""
    scene = _gentle(**{"drive.amplitude": 0.0, "run.contact_span": 1.0})
    result = simulate(scene, collisions=300)
    assert result.status is Status.AT_REST and result.final_time == 0.0


def test_simulation_step_ends_in_contact_instead_of_running_for_ever():
    sim = Simulation(_gentle(**{"run.contact_span": 0.5}))
    with pytest.raises(SimulationError) as caught:
        while True:
            sim.step()
    assert caught.value.status is Status.IN_CONTACT
    assert 0.5 <= sim.final_time < 0.6


class _Progress:
    """A progress report that records the simulated times it is told, and sends the
    process SIGTERM at the first one (in the middle of the rolling phase)."""

    def __init__(self, interrupt: bool = False):
        self.times: list[float] = []
        self.done: list[int] = []
        self.interrupt = interrupt
        self.sent: float | None = None

    def __call__(self, done: int, total: int) -> None:
        self.done.append(done)

    def at_time(self, t: float) -> None:
        self.times.append(t)
        if self.interrupt and self.sent is None and t > 0.0:
            self.sent = time.monotonic()
            os.kill(os.getpid(), signal.SIGTERM)


def test_sigterm_stops_a_long_rolling_phase_and_resume_is_exact(tmp_path):
    """SIGTERM in the middle of 4,000 s of rolling (one phase, half a second of
    computing): the run stops within a second, the phase so far is in contacts.csv as
    cut (after the checkpoint, which leaves it out), and the resumed run's files equal
    an uninterrupted run's byte for byte. The progress report, told the simulated time
    while no impact comes, sends the signal."""
    scene = _gentle(**{"run.duration": 4_000.0})
    progress = _Progress(interrupt=True)
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=300, out_dir=tmp_path / "cut", progress=progress)
    assert progress.sent is not None, "no progress report while the ball rolled"
    assert time.monotonic() - progress.sent < 1.0
    contacts = read_side_csv(tmp_path / "cut" / CONTACTS_NAME)
    assert contacts["end"][-1] == "cut" and 0.0 < contacts["t_end"][-1] < 4_000.0
    assert progress.times[0] > 0.0 and set(progress.done) <= {0}
    resumed = resume(tmp_path / "cut")
    assert resumed.status is Status.TIME_LIMIT
    simulate(scene, collisions=300, out_dir=tmp_path / "whole")
    for name in ("collisions.csv", CONTACTS_NAME):
        assert (tmp_path / "cut" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()
    assert read_side_csv(tmp_path / "whole" / CONTACTS_NAME)["t_end"][-1] == 4_000.0


def test_a_checkpoint_without_the_last_impact_time_still_resumes(tmp_path):
    """Checkpoints written before the last impact's time was kept count the span from
    the state's time."""
    from billiard.runfile.checkpoint import read_checkpoint, write_checkpoint

    scene = _gentle(**{"run.contact_span": 1.0})
    simulate(scene, collisions=300, out_dir=tmp_path)
    path = tmp_path / CHECKPOINT_NAME
    data = {k: v for k, v in read_checkpoint(path).items() if k not in ("sha256", "format")}
    del data["engine"]["last_impact"]
    data["status"] = "interrupted"
    write_checkpoint(path, data)
    result = resume(tmp_path)
    assert result.status is Status.IN_CONTACT


def test_a_ball_rolling_off_the_containers_range_ends_the_run(tmp_path, monkeypatch):
    """A plane rising to the right only: the ball rolls down to the left for ever; at
    the container's end of x (-1000 m, where a curve that never reaches the top is cut)
    the run ends, never rolling on outside it."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    scene = scene_from_toml(
        '[boundary]\ncurve = "0.1*x"\n[initial]\nq1 = 0.0\nq2 = 0.01\n'
        "[run]\ncollisions = 300\nduration = 300.0\n"
    )
    result = simulate(scene)
    assert result.status is Status.ESCAPED
    assert "left the container's range" in result.stop_reason
    contacts = result.contacts
    assert contacts["end"][-1] == "wall-end"
    assert contacts["q1_end"][-1] == pytest.approx(-1000.0, abs=0.01)
    assert result.final_time < 300.0


README_SCENE = """
[boundary]
curve = "3e4*x**4 + 0.0063"
ceiling = 0.15
[drive]
amplitude = 0.02
frequency = 5.4
[contact]
restitution = 0.393
[run]
collisions = 300
"""


def test_an_impact_with_zero_restitution_lands_instead_of_repeating_at_one_instant(
    tmp_path, monkeypatch
):
    """e = 0 in the README's bowl: a settling impact where the wall does not press the
    ball (it flies on) left it touching the wall with zero normal speed, and rounding
    made the next flight hit the wall at once: 200 impacts at one instant, labelled
    elastic, until the collapse detector stopped the run."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    scene = with_values(scene_from_toml(README_SCENE), {"contact.restitution": 0.0})
    result = simulate(scene, collisions=300)
    assert result.status is Status.COMPLETE, result.stop_reason
    cols = result.columns
    assert len(cols["t"]) == len(set(cols["t"].tolist()))  # no two impacts at one instant
    assert cols["tof"][1:].min() > 1e-6
    assert "elastic" not in set(cols["regime"].tolist())


def test_the_cli_ends_a_gently_shaken_run_and_says_why(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", "parabola-5.4hz", "--set",
         "contact.model=phases", "--set", "drive.amplitude=0.005", "--set",
         "run.contact_span=1.0", "--collisions", "300", "--no-plot", "--out",
         str(tmp_path / "run")],
        capture_output=True, text=True, timeout=300, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "no impact for run.contact_span = 1 s" in proc.stdout
    assert "--duration" in proc.stdout
    assert math.isfinite(float(proc.stdout.split("up to t = ")[1].split(" s")[0]))


def test_the_lyapunov_exponent_of_a_rolling_ball_is_undefined():
    """It ran for ever; then it printed +nan over 0 impacts with exit status 0."""
    from billiard.analysis.lyapunov import lyapunov_exponent

    result = lyapunov_exponent(_gentle(**{"run.contact_span": 1.0}), impacts=50)
    assert result.undefined is not None and "without impacts" in result.undefined
    assert math.isnan(result.per_impact)


#: A hyperbola shaken vertically at Gamma 12 with a lid, no landing speed: the ball
#: chatters against the lid alone at t = 1.4 s. Before the lid could hold a ball this
#: stopped the run (85 impacts, t = 1.40 s: "no progress in simulated time: the ball is
#: pressed against the lid"), and before that stop it met the lid without impulse at
#: times that no longer advanced the clock (flights of 2e-18 s), inside the compiled
#: loop, which never came back to Python: the run ignored SIGTERM.
PRESSED_ON_THE_LID = [
    "boundary.ceiling=0.2108",
    "drive.amplitude=0.025695",
    "drive.frequency=10.968",
    "drive.direction=vertical",
    "contact.restitution=0.55",
    "contact.mu_static=0.816",
    "contact.model=phases",
    "contact.elastic_below=0",
]


def lid_release_time(scene, t_start: float) -> float:
    """The first instant after t_start (s) at which the lid of a vertically shaken
    scene, D = A sin(w t + phase), stops pressing a ball that moves with it:
    N = m (A w^2 sin(theta) - g) falls to zero, sin(theta) = g / (A w^2), theta in
    [pi/2, pi] mod 2 pi."""
    amplitude, w = scene.drive.amplitude, 2.0 * math.pi * scene.drive.frequency
    theta = w * t_start + scene.drive.phase
    leave = math.pi - math.asin(scene.run.gravity / (amplitude * w * w))
    return t_start + ((leave - theta) % (2.0 * math.pi)) / w


@pytest.mark.parametrize("sample", [None, 0.05])
def test_the_lid_holds_a_ball_pressed_against_it_until_it_lets_go(sample):
    # the state machine (no samples) and the engine's classes (samples) alike
    scene = with_values(load_scene("hyperbola-5.8hz", PRESSED_ON_THE_LID), {"run.duration": 2.0})
    result = simulate(scene, collisions=100_000, sample=sample)
    assert result.status is Status.TIME_LIMIT and result.final_time == 2.0, result.message
    assert len(result) > 85
    contacts = result.contacts
    on_lid = np.flatnonzero(contacts.wall == LID_WALL)
    assert on_lid.size >= 1
    i = on_lid[0]
    t_start, t_end = float(contacts.t_start[i]), float(contacts.t_end[i])
    assert 1.40 < t_start < 1.41 and contacts.end[i] == "lift-off"
    amplitude, w = scene.drive.amplitude, 2.0 * math.pi * scene.drive.frequency
    theta = w * t_start + scene.drive.phase
    # the lid pressed the ball where it landed, and let it go where N = 0, to 1e-9 s
    assert amplitude * w * w * math.sin(theta) > scene.run.gravity
    assert abs(t_end - lid_release_time(scene, t_start)) < 1e-9
    # all the while it moved with the lid: its height changed by the lid's displacement
    lift = amplitude * (math.sin(w * t_end + scene.drive.phase) - math.sin(theta))
    assert abs(contacts.q2_end[i] - contacts.q2_start[i] - lift) < 1e-12
    assert abs(contacts.v2_end[i] - amplitude * w * math.cos(w * t_end + scene.drive.phase)) < 1e-9


def test_the_cli_run_pressed_against_the_lid_ends(tmp_path):
    """The command that ran for ever, then stopped at the lid, runs to its duration."""
    args = [a for key in [*PRESSED_ON_THE_LID, "run.duration=2"] for a in ("--set", key)]
    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", "hyperbola-5.8hz", *args,
         "--no-plot", "--out", str(tmp_path / "run")],
        capture_output=True, text=True, timeout=240, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "no progress in simulated time" not in proc.stderr + proc.stdout
    contacts = read_side_csv(tmp_path / "run" / CONTACTS_NAME)
    assert "lift-off" in contacts["end"][contacts["wall"] == LID_WALL]
