"""Sampled runs are sized before they start: a trajectory that may exceed 1 GB (of
trajectory.csv, or of memory) is refused in one line naming the estimate unless the
caller confirms it (``billiard run --yes``, ``simulate(..., allow_large=True)``), and a run
never exceeds its estimate silently."""

from __future__ import annotations

import json
import math
import resource
import subprocess
import sys
from pathlib import Path

import pytest

import billiard.run.output_size as output_size
import billiard.runfile.sidecsv as sidecsv
from billiard.cli import main
from billiard.engine.interrupt import signal_after
from billiard.engine.simulation import Simulation
from billiard.geometry.boundary import Boundary
from billiard.geometry.curves import load_curve
from billiard.run.output_size import (
    MEMORY_ROW_BYTES,
    OutputSizeError,
    estimate_samples,
    longest_flight,
)
from billiard.run.persist import CHECKPOINT_NAME
from billiard.run.simulate import RunInterrupted, resume, simulate
from billiard.runfile.checkpoint import CheckpointError, read_checkpoint, write_checkpoint
from billiard.runfile.record import TRAJECTORY_COLUMNS
from billiard.runfile.sidecsv import SideCsv, read_side_csv
from billiard.scene.scene import load_scene, with_values

WEDGE = "wedge-6.6hz"


def boundary_of(scene) -> Boundary:
    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    return Boundary.from_scene(scene, curve.walls)


def _limit_resources() -> None:
    # a run that starts writing its 140 GB (or keeping its rows in memory) is stopped by
    # the kernel after 50 MB of file or 3 GB of address space
    resource.setrlimit(resource.RLIMIT_FSIZE, (50 << 20, 50 << 20))
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


def test_the_cli_refuses_a_huge_trajectory_before_writing(tmp_path):
    """The issue's case: --sample 1e-9 --duration 1 started writing ~130 GB."""
    out = tmp_path / "run"
    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", WEDGE, "--sample", "1e-9",
         "--duration", "1", "--out", str(out), "--no-plot"],
        capture_output=True, text=True, timeout=120, preexec_fn=_limit_resources,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("billiard: error: run: ")
    assert "sampling every 1e-09 s over at most 1 s of simulated time (run.duration)" in (
        proc.stderr
    )
    assert "1,000,000,000 rows (140 GB of trajectory.csv)" in proc.stderr
    assert "over the limit of 1 GB" in proc.stderr and "--yes" in proc.stderr
    assert not out.exists()  # nothing written, not even the folder


def test_without_a_duration_the_impacts_bound_the_time(capsys, tmp_path, monkeypatch):
    """The bound (every impact after the longest flight) is refused when it is over
    BOUND_FACTOR times the limit."""
    monkeypatch.setattr(output_size, "MAX_BYTES", 100_000)
    out = tmp_path / "run"
    args = ["run", WEDGE, "--collisions", "300", "--sample", "0.0001", "--no-plot"]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    scene = load_scene(WEDGE)
    rows = math.floor(300 * longest_flight(scene, boundary_of(scene)) / 0.0001) + 1
    assert rows * 140 > output_size.BOUND_FACTOR * 100_000
    assert "300 impacts of at most 0.399 s each (the longest flight" in err
    assert f"makes up to {rows:,} rows ({rows * 140 / 1e6:.3g} MB of trajectory.csv)" in err
    assert not out.exists()


def test_the_api_refuses_a_huge_trajectory_in_memory(monkeypatch):
    """The issue's other case: sample=1e-12 grew memory by 27 MB/s."""
    monkeypatch.setattr(output_size, "MAX_BYTES", 100_000)
    scene = load_scene(WEDGE)
    with pytest.raises(OutputSizeError) as caught:
        simulate(scene, collisions=300, sample=0.0001)
    message = str(caught.value)
    assert "in memory" in message and "allow_large=True" in message and "\n" not in message
    rows = math.floor(300 * longest_flight(scene, boundary_of(scene)) / 0.0001) + 1
    assert f"{rows:,} rows ({rows * MEMORY_ROW_BYTES / 1e6:.3g} MB in memory)" in message


def test_a_bound_under_the_factor_runs_and_stops_at_the_limit(tmp_path, monkeypatch):
    """A bound over the limit but under BOUND_FACTOR times it is no refusal (the bound is
    some 25 times what runs make): the run goes ahead, and stops when its trajectory
    reaches the limit, in one line naming the limit and --yes; the rows so far are kept
    and the run resumes."""
    monkeypatch.setattr(output_size, "MAX_BYTES", 100_000)
    scene = load_scene(WEDGE)
    bound = (math.floor(300 * longest_flight(scene, boundary_of(scene)) / 0.002) + 1) * 140
    assert 100_000 < bound <= output_size.BOUND_FACTOR * 100_000
    small = simulate(scene, collisions=30, sample=0.002)  # 30 impacts: under the limit
    assert small.status.finished and len(small.trajectory["t"]) * 140 < 100_000
    out = tmp_path / "run"
    with pytest.raises(OutputSizeError) as caught:
        simulate(scene, collisions=300, sample=0.002, out_dir=out)
    message = str(caught.value)
    assert message.startswith("the trajectory reached the limit of 100,000 bytes")
    assert "allow_large=True to go beyond the limit" in message and "\n" not in message
    rows = read_side_csv(out / "trajectory.csv")["t"]
    assert len(rows) * 140 <= 100_000 + 140 * 1000
    assert resume(out, allow_large=True).status.finished


def test_the_longest_flight_without_air():
    """The wedge (no drag, lid at 0.2 m): rising and falling through the whole height."""
    scene = load_scene(WEDGE)
    assert scene.air.drag == "none" and scene.drive.direction == "horizontal"
    bottom = dict(scene.boundary.parameters).get("c", 0.0063) - scene.ball.radius
    height = scene.boundary.ceiling - bottom
    expected = 2.0 * math.sqrt(2.0 * height / scene.run.gravity)
    assert longest_flight(scene, boundary_of(scene)) == pytest.approx(expected, rel=1e-3)


def test_the_fall_against_drag_is_bounded_by_the_linear_law():
    g, height = 9.81, 0.3
    for terminal in (0.05, 1.0, 24.7, 1e3):
        t = output_size._gravity_fall(height, g, terminal)
        tau = terminal / g
        fallen = terminal * t - terminal * tau * (1.0 - math.exp(-t / tau))
        assert fallen == pytest.approx(height, rel=1e-9)
        # quadratic drag of the same terminal speed falls faster (closed form)
        x = g * height / terminal**2  # acosh(exp(x)), without overflow for large x
        quadratic = tau * (x + math.log1p(math.sqrt(-math.expm1(-2 * x))))
        assert quadratic <= t and math.sqrt(2 * height / g) <= t
    assert output_size._gravity_fall(height, g, math.inf) == math.sqrt(2 * height / g)


def test_drag_lengthens_the_bound():
    scene = load_scene(WEDGE)
    dragged = with_values(scene, {"air.drag": "fowles", "air.c_quad": 0.5})
    assert longest_flight(dragged, boundary_of(dragged)) > 3 * longest_flight(
        scene, boundary_of(scene)
    )


def test_the_estimate_with_a_duration_is_exact(tmp_path):
    scene = load_scene(WEDGE)
    out = tmp_path / "run"
    result = simulate(scene, collisions=100_000, duration=0.5, sample=0.01, out_dir=out)
    sim = Simulation(with_values(scene, {"run.duration": 0.5}))
    sim.sample_dt = 0.01
    estimate = estimate_samples(sim, 100_000, start_time=0.0, start_impacts=0, in_memory=False)
    assert estimate.rows == len(read_side_csv(out / "trajectory.csv")["t"]) == 51
    assert len(result.trajectory["t"]) == 51


def test_the_estimate_without_a_duration_bounds_the_run():
    scene = load_scene(WEDGE)
    result = simulate(scene, collisions=1500, sample=0.01)
    sim = Simulation(scene)
    sim.sample_dt = 0.01
    estimate = estimate_samples(sim, 1500, start_time=0.0, start_impacts=0, in_memory=True)
    assert len(result.trajectory["t"]) <= estimate.rows
    assert estimate.rows * MEMORY_ROW_BYTES == estimate.bytes


def test_confirming_lets_a_large_run_go(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(output_size, "MAX_BYTES", 2_000)  # about 14 rows on disk
    out = tmp_path / "run"
    args = ["run", WEDGE, "--duration", "0.5", "--sample", "0.01", "--out", str(out), "--no-plot"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "51 rows (7,140 bytes of trajectory.csv), over the limit of 2,000 bytes" in err
    assert "or --yes to go ahead" in err and "allow_large" not in err
    assert main([*args, "--yes"]) == 0
    assert len(read_side_csv(out / "trajectory.csv")["t"]) == 51
    scene = load_scene(WEDGE)
    with pytest.raises(OutputSizeError):
        simulate(scene, duration=0.5, sample=0.01)
    assert len(simulate(scene, duration=0.5, sample=0.01, allow_large=True).trajectory["t"]) == 51


def test_a_resumed_large_run_needs_the_confirmation_again(tmp_path, monkeypatch):
    monkeypatch.setattr(output_size, "MAX_BYTES", 2_000)
    scene = load_scene(WEDGE)
    ref = tmp_path / "ref"
    simulate(scene, collisions=900, sample=0.01, out_dir=ref, allow_large=True)
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted):
        simulate(
            scene, collisions=900, sample=0.01, out_dir=out, allow_large=True,
            on_record=signal_after(700),
        )  # fmt: skip
    with pytest.raises(OutputSizeError, match="allow_large=True"):
        resume(out)
    resume(out, allow_large=True)
    for name in ("collisions.csv", "trajectory.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes()


def test_a_run_never_exceeds_its_estimate_silently(monkeypatch, tmp_path):
    """Were the bound too small (time in contact phases is not in it), the run stops
    with a one-line error when the samples pass it."""
    monkeypatch.setattr(output_size, "MAX_BYTES", 0)
    monkeypatch.setattr(output_size, "longest_flight", lambda scene, boundary: 1e-3)
    scene = load_scene(WEDGE)
    for out_dir in (None, tmp_path / "run"):
        with pytest.raises(OutputSizeError) as caught:
            simulate(scene, collisions=1000, sample=0.01, out_dir=out_dir, allow_large=True)
        message = str(caught.value)
        assert message.startswith("the trajectory reached 101 samples at t = 1.01 s")
        assert "give a duration (run.duration, s)" in message and "\n" not in message
    lines = (tmp_path / "run" / "trajectory.csv").read_text().splitlines()
    assert lines[0] == ",".join(TRAJECTORY_COLUMNS) and len(lines) == 1 + 101


def test_a_checkpoint_that_samples_no_time_is_refused(tmp_path):
    """A forged ``sample = 0`` made the resumed run sample one instant for ever."""
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted):
        simulate(load_scene(WEDGE), collisions=900, sample=0.01, out_dir=out,
                 on_record=signal_after(700))  # fmt: skip
    body = read_checkpoint(out / CHECKPOINT_NAME)
    for forged in (0, 0.0, -0.01, "0.01", True):
        body["sample"] = forged
        write_checkpoint(
            out / CHECKPOINT_NAME, {k: v for k, v in body.items() if k not in ("format", "version")}
        )
        with pytest.raises(CheckpointError, match="sampling interval") as caught:
            resume(out)
        assert "\n" not in str(caught.value)
    assert json.loads((out / CHECKPOINT_NAME).read_text())["sample"] is True


def test_side_files_spill_rows_between_flushes(tmp_path, monkeypatch):
    """A flight sampled finely makes many rows before the next flush: they go to the
    file, not to memory."""
    monkeypatch.setattr(sidecsv, "SPILL_CHARS", 100)
    path = tmp_path / "trajectory.csv"
    side = SideCsv(path, TRAJECTORY_COLUMNS)
    for k in range(50):
        side.append((k * 0.01, 0.0, 0.1, 0.0, 0.0, 0.0, 1e-5, "flight"))
        assert len(side._pending) < 10
    assert side._file.tell() > 50 * 20  # written to the file object, not kept
    size = side.flush()
    side.close()
    assert size == path.stat().st_size and len(read_side_csv(path)["t"]) == 50


def test_help_names_the_confirmation(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--yes" in text and "1 GB" in text


def test_paths_are_not_touched_by_a_refusal(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    assert main(["run", WEDGE, "--collisions", "50", "--out", str(out), "--no-plot"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(output_size, "MAX_BYTES", 2_000)
    args = ["run", WEDGE, "--duration", "0.5", "--sample", "0.01", "--out", str(out)]
    assert main([*args, "--overwrite", "--no-plot"]) == 2
    assert {p.name: p.read_bytes() for p in Path(out).iterdir()} == before
