"""Numerical faults stop a run with a one-line reason that names the impact and the time,
and every row before the fault is kept (in memory and in the streamed CSV)."""

from __future__ import annotations

import importlib
import math
import re
import types

import pytest
from billiard.generated import ball as generated_ball

from billiard.checkpoint import read_checkpoint
from billiard.checks import LIMITS, Limit
from billiard.cli import main
from billiard.errors import SimulationError
from billiard.events import Event, EventLocator
from billiard.interrupt import signal_after
from billiard.record import MemoryRecorder, read_collisions
from billiard.scene import load_scene, with_values
from billiard.simulate import (
    CHECKPOINT_NAME,
    COLLAPSE_COUNT,
    CSV_NAME,
    RunInterrupted,
    Simulation,
    resume,
    simulate,
)
from billiard.status import Status

impact_module = importlib.import_module("billiard.impact")
flight_module = importlib.import_module("billiard.flight")

K = 37  # the impact at which a fault is injected


def nan_after(function, calls: int):
    """``function`` that returns NaNs from its ``calls``-th call on."""
    count = [0]

    def wrapped(*args):
        count[0] += 1
        out = function(*args)
        if count[0] < calls:
            return out
        return tuple(math.nan for _ in out) if isinstance(out, tuple) else math.nan

    return wrapped


def patched_ball(monkeypatch, module, name: str, calls: int) -> None:
    """Replace one generated function, as seen from ``module``, by ``nan_after``."""
    fake = types.SimpleNamespace(
        **{
            key: getattr(generated_ball, key)
            for key in dir(generated_ball)
            if not key.startswith("__")
        }
    )
    setattr(fake, name, nan_after(getattr(generated_ball, name), calls))
    monkeypatch.setattr(module, "_ball", fake)


def time_of_impact(scene, k: int) -> str:
    """The time of impact k of an undisturbed run, as the messages print it."""
    return f"{simulate(scene, collisions=k).columns['t'][k - 1]:.9g}"


def assert_kept(result, out, rows: int) -> None:
    assert len(result) == rows
    assert read_collisions(out / CSV_NAME)["n"].tolist() == list(range(1, rows + 1))
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    assert checkpoint["status"] == "stopped" and checkpoint["csv"]["rows"] == rows
    assert checkpoint["stop_reason"] == result.stop_reason


def test_non_finite_impact_result(tmp_path, monkeypatch):
    """The impact map returns NaN at impact K: the run stops there, K - 1 rows kept."""
    scene = load_scene("hyperbola-5.8hz")
    when = time_of_impact(scene, K)
    patched_ball(monkeypatch, impact_module, "impact_stick", K)
    result = simulate(scene, collisions=200, out_dir=tmp_path)
    assert result.stop_reason == f"non-finite state at impact {K} (t = {when} s): v1 = nan"
    assert_kept(result, tmp_path, K - 1)
    # and resuming it says so rather than running into the fault again
    assert resume(tmp_path).already_finished


def test_non_finite_energy_is_named(monkeypatch):
    scene = load_scene("wedge-6.6hz")
    when = time_of_impact(scene, K)
    patched_ball(monkeypatch, importlib.import_module("billiard.engine"), "energy", K)
    result = simulate(scene, collisions=100)
    assert result.stop_reason == f"non-finite state at impact {K} (t = {when} s): energy = nan"
    assert len(result) == K - 1


def test_root_solver_failure_in_the_offset_inversion(tmp_path):
    """The curve's slope turns NaN after impact 100 (a generated function gone bad):
    Newton on the offset curve cannot converge, the run stops after impact 100."""
    scene = load_scene("parabola-5.4hz")
    when = time_of_impact(scene, 100)
    sim = Simulation(scene)
    broken = [False]
    for wall in sim.boundary.offsets:
        good = wall.df
        wall.df = lambda s, p, good=good: math.nan if broken[0] else good(s, p)

    def progress(done: int, total: int) -> None:
        broken[0] = broken[0] or done >= 100

    recorder = MemoryRecorder()
    reason = sim.run(300, recorder, progress)
    assert re.fullmatch(
        rf"offset-curve inversion did not converge at x = \S+ m after impact 100 "
        rf"\(t = {re.escape(when)} s\)",
        reason,
    ), reason
    assert len(recorder) == 100


def test_root_solver_failure_in_the_impact_time(monkeypatch):
    """The impact-time root solve gives up (as after 200 iterations without converging)."""
    scene = load_scene("wedge-6.6hz")
    times = simulate(scene, collisions=100).columns["t"]
    calls = [0]
    original = EventLocator._root

    def failing(self, *args):
        calls[0] += 1
        if calls[0] >= K:
            raise SimulationError("the impact time did not converge")
        return original(self, *args)

    monkeypatch.setattr(EventLocator, "_root", failing)
    result = simulate(scene, collisions=100)
    done = len(result)
    assert done >= 1
    assert result.stop_reason == (
        f"the impact time did not converge after impact {done} (t = {times[done - 1]:.9g} s)"
    )


def test_flight_integrator_failure(tmp_path, monkeypatch):
    """The drag right-hand side turns NaN in the flight after impact K - 1: the step-size
    control rejects every step; the run stops with a message, no traceback."""
    scene = load_scene("hyperbola-5.8hz", overrides=["air.drag=fowles"])  # adaptive flight
    when = time_of_impact(scene, K - 1)
    sim = Simulation(scene)
    broken = [False]
    good = sim.flight._rhs
    sim.flight._rhs = lambda *a: (math.nan, math.nan) if broken[0] else good(*a)

    class Rows(MemoryRecorder):
        def append(self, row):
            super().append(row)
            broken[0] = len(self) >= K - 1

    rows = Rows()
    reason = sim.run(200, rows)
    assert reason.startswith(
        "the flight's step-size control failed (Dormand-Prince, 200 rejected steps from tau = "
    )
    assert reason.endswith(f"after impact {K - 1} (t = {when} s)")
    assert len(rows) == K - 1


def test_overflow_is_a_numerical_failure(monkeypatch):
    # a scene refuses such a start (initial.v1 is at most 100 m/s); lift the scene's
    # limit to test the engine's own guard
    monkeypatch.setitem(LIMITS, "initial.v1", Limit(-math.inf, math.inf, "m/s"))
    scene = with_values(load_scene("parabola-5.4hz"), {"initial.v1": 1e200})
    result = simulate(scene, collisions=10)
    # the generated code squares by multiplying, which overflows to inf (pow raised
    # OverflowError): the guard on every record's values stops the run there
    assert result.status is Status.NON_FINITE and len(result) == 0
    assert result.stop_reason == "non-finite state at impact 1 (t = 0 s): energy = inf"


def test_unresolvable_collapse_keeps_rows_on_disk(tmp_path):
    """Without the low-velocity rule a ball lying on the shaken bottom cannot be lifted:
    zero-time flights pile up and the run stops, every row kept (the 200 impacts within
    1e-6 s come before the 1,000 consecutive zero flights)."""
    scene = load_scene("parabola-5.4hz", overrides=["contact.elastic_below=0"])
    result = simulate(scene, collisions=5000, out_dir=tmp_path)
    assert result.stop_reason == (
        "inelastic collapse: 200 impacts within 1e-06 s of simulated time, at impact 201 (t = 0 s)"
    )
    assert_kept(result, tmp_path, 201)


def hopping_in_place(monkeypatch) -> None:
    """Every flight lasts 1e-12 s and ends where it began: impacts pile up in time."""

    def locate(self, theta0, q1, q2, u1, u2, u3):
        self.theta0 = theta0
        self.flight.begin(q1, q2, u1, u2, u3)
        surface = self.surfaces[0]
        px = self._relative(0.0, (q1, q2, u1, u2))[0]
        s, z, _ = surface.contact(px, self.warm[0])
        return Event(1e-12, surface, q1, q2, u1, u2, theta0, s, z, 0)

    monkeypatch.setattr(EventLocator, "locate", locate)


def test_collapse_in_time_is_detected_and_survives_a_checkpoint(tmp_path, monkeypatch):
    """200 impacts within 1e-6 s stop the run; the detector's window is part of the
    engine state, so a run interrupted in the middle of the pile-up stops at the same
    impact after resuming."""
    hopping_in_place(monkeypatch)
    scene = load_scene("parabola-5.4hz")
    whole = simulate(scene, collisions=20000, out_dir=tmp_path / "whole")
    assert whole.stop_reason.startswith(
        f"inelastic collapse: {COLLAPSE_COUNT} impacts within 1e-06 s of simulated time, "
        f"at impact {COLLAPSE_COUNT + 1} (t = "
    )
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=20000, out_dir=tmp_path / "parts", on_record=signal_after(120))
    checkpoint = read_checkpoint(tmp_path / "parts" / CHECKPOINT_NAME)
    assert len(checkpoint["engine"]["recent"]) == 120
    parts = resume(tmp_path / "parts")
    assert parts.stop_reason == whole.stop_reason
    assert (tmp_path / "parts" / CSV_NAME).read_bytes() == (
        tmp_path / "whole" / CSV_NAME
    ).read_bytes()


def test_command_line_reports_a_fault_in_one_line(tmp_path, monkeypatch, capsys):
    when = time_of_impact(load_scene("wedge-6.6hz"), K)
    patched_ball(monkeypatch, impact_module, "impact_stick", K)
    out = tmp_path / "run"
    code = main(["run", "wedge-6.6hz", "--collisions", "100", "--out", str(out), "--no-plot"])
    captured = capsys.readouterr()
    assert code == 3
    assert captured.err == (
        f"billiard: stopped: non-finite state at impact {K} (t = {when} s): v1 = nan\n"
    )
    assert f"{K - 1} impacts" in captured.out
    assert len(read_collisions(out / CSV_NAME)["n"]) == K - 1
