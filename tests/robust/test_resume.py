"""Long runs survive interruptions: Ctrl-C, SIGTERM and SIGKILL leave a valid CSV and a
checkpoint, and ``billiard run --resume DIR`` finishes the run byte for byte as an
uninterrupted run would have."""

from __future__ import annotations

import importlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from billiard import jit
from billiard.cli import main
from billiard.engine.interrupt import signal_after
from billiard.run.simulate import (
    CHECKPOINT_NAME,
    CSV_NAME,
    SCENE_NAME,
    EngineState,
    RunInterrupted,
    resume,
    simulate,
)
from billiard.runfile.checkpoint import CheckpointError, read_checkpoint
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene, replace, with_values
from billiard.scene.spec import InitialSpec

# billiard.run.simulate the module (the package exports a function of the same name)
engine = importlib.import_module("billiard.engine.simulation")
persist = importlib.import_module("billiard.run.persist")
record = importlib.import_module("billiard.runfile.record")
stream = importlib.import_module("billiard.runfile.stream")

REPO = Path(__file__).resolve().parents[2]

# (scene, changes, method, impacts, where to interrupt)
CASES = {
    "event-drag": ("hyperbola-5.8hz", {"air.drag": "fowles"}, "event", 2500, (1, 900, 2499)),
    "event-no-drag": ("wedge-6.6hz", {"air.drag": "none"}, "event", 2500, (1, 1234, 2499)),
    "rk4": ("wedge-6.6hz", {"air.drag": "fowles"}, "rk4", 250, (1, 120)),
}


def case_scene(name: str, changes: dict):
    scene = load_scene(name)
    return with_values(scene, changes) if changes else scene


def reference(tmp_path: Path, scene, method: str, impacts: int) -> Path:
    """An uninterrupted streamed run; returns its directory."""
    out = tmp_path / "reference"
    result = simulate(scene, collisions=impacts, method=method, out_dir=out)
    assert result.stop_reason is None and len(result) == impacts
    return out


def stop_after(at: str):
    """The ``on_record`` hook for "K" (SIGINT after impact K), "K:TERM" or "K:KILL"."""
    count, _, name = at.partition(":")
    return signal_after(int(count), getattr(signal, f"SIG{name or 'INT'}"))


def interrupted(
    scene, method: str, impacts: int, out: Path, at: str, monkeypatch
) -> RunInterrupted:
    with pytest.raises(RunInterrupted) as caught:
        simulate(scene, collisions=impacts, method=method, out_dir=out, on_record=stop_after(at))
    return caught.value


def same_run(a: Path, b: Path) -> bool:
    return (a / CSV_NAME).read_bytes() == (b / CSV_NAME).read_bytes() and (
        a / SCENE_NAME
    ).read_bytes() == (b / SCENE_NAME).read_bytes()


def cli(*args: str, cwd: Path, env: dict | None = None, timeout: float = 120.0):
    """``billiard ARGS`` in a fresh interpreter."""
    return subprocess.run(
        [sys.executable, "-m", "billiard.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
    )


_STOPPING_CLI = """
import importlib, sys
from billiard import cli
from billiard.engine.interrupt import signal_after
import signal
api = importlib.import_module("billiard.run.simulate")
run = api.simulate
count, _, name = sys.argv[1].partition(":")
hook = signal_after(int(count), getattr(signal, "SIG" + (name or "INT")))
api.simulate = lambda *a, **k: run(*a, on_record=hook, **k)
sys.exit(cli.main(sys.argv[2:]))
"""


def cli_stopping(at: str, *args: str, cwd: Path, timeout: float = 120.0):
    """``billiard ARGS`` in a fresh interpreter whose run signals itself after impact K
    (``at`` = "K", "K:TERM" or "K:KILL")."""
    return subprocess.run(
        [sys.executable, "-c", _STOPPING_CLI, at, *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def start_cli(*args: str, cwd: Path, env: dict | None = None) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "billiard.cli", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
    )


def wait_for_rows(out: Path, proc: subprocess.Popen, timeout: float = 60.0) -> int:
    """Wait until a checkpoint with rows on disk exists (or the process ended)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            rows = read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"]
        except (CheckpointError, KeyError):
            rows = 0
        if rows > 0:
            return rows
        time.sleep(0.01)
    return 0


# ---------------------------------------------------------------------------------
# interrupt and resume, deterministic (the run signals itself after impact K)


@pytest.mark.parametrize("case", list(CASES))
def test_interrupt_and_resume_is_byte_identical(case, tmp_path, monkeypatch):
    name, changes, method, impacts, stops = CASES[case]
    scene = case_scene(name, changes)
    ref = reference(tmp_path, scene, method, impacts)
    expected = simulate(scene, collisions=impacts, method=method).counts
    for k in stops:
        out = tmp_path / f"stopped-{k}"
        stop = interrupted(scene, method, impacts, out, str(k), monkeypatch)
        assert (stop.signum, stop.rows, stop.checkpoint_rows, stop.out_dir) == (
            signal.SIGINT,
            k,
            k,
            out,
        )
        # what an interruption leaves: every completed impact, whole lines, a checkpoint
        text = (out / CSV_NAME).read_bytes()
        assert text.endswith(b"\n") and b"\r" not in text
        assert read_collisions(out / CSV_NAME)["n"].tolist() == list(range(1, k + 1))
        assert text == (ref / CSV_NAME).read_bytes()[: len(text)]
        checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
        assert checkpoint["status"] == "interrupted"
        assert checkpoint["csv"]["rows"] == k and checkpoint["csv"]["bytes"] == len(text)
        assert (out / SCENE_NAME).read_bytes() == (ref / SCENE_NAME).read_bytes()
        notes: list[str] = []
        result = resume(out, notify=notes.append)
        assert notes == [f"resuming {out} after impact {k} of {impacts}"]
        assert same_run(ref, out), f"{case}: resumed after impact {k} differs"
        assert result.counts == expected
        assert result.resumed_from == k and len(result) == impacts
        assert f"resumed after impact {k}" in result.summary()
        assert read_checkpoint(out / CHECKPOINT_NAME)["status"] == "complete"


def test_repeated_interruptions(tmp_path, monkeypatch):
    name, changes, method, impacts, _ = CASES["event-drag"]
    scene = case_scene(name, changes)
    ref = reference(tmp_path, scene, method, impacts)
    out = tmp_path / "run"
    interrupted(scene, method, impacts, out, "300", monkeypatch)
    for k in (301, 1000, 1001, 2000):  # a TERM, then INTs, each inside the resumed run
        with pytest.raises(RunInterrupted) as caught:
            resume(out, on_record=stop_after(f"{k}:TERM" if k == 301 else str(k)))
        assert caught.value.rows == k
        assert caught.value.signum == (signal.SIGTERM if k == 301 else signal.SIGINT)
    resume(out)
    assert same_run(ref, out)


@pytest.mark.slow  # long runs; SIGINT and resume also in tests/engine
def test_resume_from_every_kind_of_checkpoint(tmp_path, monkeypatch):
    """Checkpoint after every impact, and resume from copies of the run directory taken
    at many of them: mid-run states with drag (step-size memory), rk4 (warm starts) and
    the ball's first impacts all continue exactly."""
    monkeypatch.setattr(engine, "CHECKPOINT_INTERVAL", 0.0)
    monkeypatch.setattr(record.os, "fsync", lambda fd: None)  # thousands of checkpoints
    for case, impacts, every in (("event-drag", 700, 97), ("rk4", 120, 17)):
        name, changes, method, _, _ = CASES[case]
        scene = case_scene(name, changes)
        work = tmp_path / case
        ref = reference(work, scene, method, impacts)
        out = work / "live"
        snapshots: list[Path] = []
        original = persist.write_checkpoint

        def snapshot(path, body, out=out, snapshots=snapshots, every=every, original=original):
            original(path, body)
            rows = body["csv"]["rows"]
            if body["status"] == "running" and rows % every in (0, 1):
                copy = out.parent / f"at-{rows}"
                shutil.copytree(out, copy, dirs_exist_ok=True)
                snapshots.append(copy)

        monkeypatch.setattr(persist, "write_checkpoint", snapshot)
        simulate(scene, collisions=impacts, method=method, out_dir=out)
        monkeypatch.setattr(persist, "write_checkpoint", original)
        assert len(snapshots) >= 8
        for copy in snapshots:
            resume(copy)
            assert same_run(ref, copy), f"{case}: resume from {copy.name} differs"


def test_engine_state_round_trips_exactly():
    sim = engine.Simulation(load_scene("hyperbola-5.8hz", overrides=["air.drag=fowles"]))
    sim.run(30, record.MemoryRecorder())
    captured = sim.state
    assert captured is not None and captured.impacts == 30 and captured.flight
    captured.ball.q3 = -0.0
    captured.recent = (5e-324, 0.1 + 0.2, 1e308)
    text = json.dumps(captured.to_dict(), allow_nan=False)
    back = EngineState.from_dict(json.loads(text), engine.COLLAPSE_COUNT + 1)
    assert back == captured
    assert repr(back.ball.q3) == "-0.0" and back.recent[0] == 5e-324


# ---------------------------------------------------------------------------------
# real signals, through the command line

# impacts of the parabola scene: a few seconds of running, compiled (where writing the
# rows costs most of the time) or interpreted
# long enough that a signal sent once the first periodic checkpoint is on disk (after
# about a second) finds the run still going
LONG = 600_000 if jit.ENABLED else 25_000


@pytest.fixture(scope="module")
def long_reference(tmp_path_factory) -> Path:
    return reference(tmp_path_factory.mktemp("long"), load_scene("parabola-5.4hz"), "event", LONG)


@pytest.mark.slow  # long runs; SIGINT and resume also in tests/engine
def test_sigint_mid_run_keeps_rows_and_says_how_to_resume(tmp_path, long_reference):
    out = tmp_path / "run"
    proc = start_cli(
        "run",
        "parabola-5.4hz",
        "--collisions",
        str(LONG),
        "--store",
        "csv",  # a run this long would be stored as binary rows by default
        "--out",
        str(out),
        "--no-plot",
        cwd=tmp_path,
    )
    wait_for_rows(out, proc)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    ref = long_reference
    if proc.returncode == 0:  # pragma: no cover - a machine fast enough to finish first
        assert same_run(ref, out)
        return
    assert proc.returncode == 130, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr
    match = re.fullmatch(
        r"billiard: interrupted \(SIGINT\): (\d+) impacts kept in (.+); continue with "
        r"`billiard run --resume (.+)`",
        lines[0],
    )
    assert match, lines[0]
    kept = int(match.group(1))
    assert match.group(2) == str(out / CSV_NAME) and match.group(3) == str(out)
    assert 0 < kept < LONG
    assert len(read_collisions(out / CSV_NAME)["n"]) == kept
    assert read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"] == kept
    done = cli("run", "--resume", str(out), "--no-plot", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert f"resuming {out} after impact {kept} of {LONG}" in done.stderr
    assert same_run(ref, out)


@pytest.mark.slow  # 8 s; SIGINT and SIGTERM mid-run stay in the default suite
def test_sigkill_mid_run_then_resume(tmp_path, long_reference):
    """A kill leaves the last checkpoint and whatever rows reached the disk; a half
    written last line is dropped on resume; the result equals an uninterrupted run."""
    out = tmp_path / "run"
    proc = start_cli(
        "run",
        "parabola-5.4hz",
        "--collisions",
        str(LONG),
        "--store",
        "csv",  # a run this long would be stored as binary rows by default
        "--out",
        str(out),
        "--no-plot",
        cwd=tmp_path,
    )
    wait_for_rows(out, proc)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode in (-signal.SIGKILL, 0)
    kept = read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"]
    rows = read_collisions(out / CSV_NAME)["n"]
    assert len(rows) >= kept and rows.tolist() == list(range(1, len(rows) + 1))
    # else the run was finished first (the kill may still land before the exit)
    killed = read_checkpoint(out / CHECKPOINT_NAME)["status"] != "complete"
    if killed:
        with open(out / CSV_NAME, "ab") as handle:  # the remains of a write cut short
            handle.write(b"99999,12.5,0.0012")
    done = cli("run", "--resume", str(out), "--no-plot", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "an unterminated last line (17 bytes)" in done.stderr or not killed
    assert same_run(long_reference, out)


def test_kill_before_the_first_flush_keeps_the_scene_and_a_checkpoint(tmp_path):
    """The run kills itself after impact 5, long before the first flush: scene.toml and a
    checkpoint at impact 0 were written at the start, so the run can be resumed."""
    out = tmp_path / "run"
    proc = cli_stopping(
        "5:KILL",
        "run",
        "wedge-6.6hz",
        "--collisions",
        "600",
        "--out",
        str(out),
        "--no-plot",
        cwd=tmp_path,
    )
    assert proc.returncode == -signal.SIGKILL
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    assert checkpoint["status"] == "running" and checkpoint["csv"]["rows"] == 0
    assert read_collisions(out / CSV_NAME)["n"].size == 0
    ref = reference(tmp_path, load_scene("wedge-6.6hz"), "event", 600)
    assert (out / SCENE_NAME).read_bytes() == (ref / SCENE_NAME).read_bytes()
    resume(out)
    assert same_run(ref, out)


def test_sigterm_stops_cleanly(tmp_path):
    out = tmp_path / "run"
    proc = cli_stopping(
        "250:TERM",
        "run",
        "wedge-6.6hz",
        "--collisions",
        "600",
        "--out",
        str(out),
        "--no-plot",
        cwd=tmp_path,
    )
    assert proc.returncode == 128 + signal.SIGTERM
    assert proc.stderr.startswith("billiard: interrupted (SIGTERM): 250 impacts kept in ")
    assert len(proc.stderr.strip().splitlines()) == 1
    assert read_checkpoint(out / CHECKPOINT_NAME)["status"] == "interrupted"


# ---------------------------------------------------------------------------------
# the end of the file


def test_truncated_last_line_is_dropped_and_rows_after_the_checkpoint_kept(tmp_path, monkeypatch):
    name, changes, method, impacts, _ = CASES["event-no-drag"]
    scene = case_scene(name, changes)
    ref = reference(tmp_path, scene, method, impacts)
    out = tmp_path / "run"
    interrupted(scene, method, impacts, out, "700", monkeypatch)
    # rows written after the checkpoint (as a kill between flush and checkpoint leaves
    # them) and the first bytes of one more
    lines = (ref / CSV_NAME).read_bytes().splitlines(keepends=True)
    with open(out / CSV_NAME, "ab") as handle:
        handle.write(b"".join(lines[701:704]) + lines[704][:40])
    assert len(read_collisions(out / CSV_NAME)["n"]) == 703  # the partial line is skipped
    notes: list[str] = []
    resume(out, notify=notes.append)
    assert notes == [
        f"resuming {out} after impact 700 of {impacts}; 3 row(s) written after the "
        "checkpoint are kept (each checked against the recomputed impact); dropped an "
        "unterminated last line (40 bytes)"
    ]
    assert same_run(ref, out)


# ---------------------------------------------------------------------------------
# finished runs, extensions


def test_resume_of_a_finished_run_says_so(tmp_path, capsys):
    out = tmp_path / "run"
    simulate(load_scene("wedge-6.6hz"), collisions=200, out_dir=out)
    before = (out / CSV_NAME).read_bytes()
    assert main(["run", "--resume", str(out), "--no-plot"]) == 0
    captured = capsys.readouterr()
    assert captured.out == (
        f"billiard: {out}: the run is already complete (200 impacts); nothing to resume "
        "(--collisions N extends it)\n"
    )
    assert (out / CSV_NAME).read_bytes() == before
    result = resume(out)
    assert result.already_finished and len(result) == 200 and result.stop_reason is None


def test_resume_of_a_stopped_run_says_so(tmp_path, capsys):
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {"boundary.ceiling": None, "boundary.escape_height": 0.2, "air.drag": "none"},
    )
    scene = replace(scene, initial=InitialSpec(q1=0.0, q2=0.05, v2=2.5))
    out = tmp_path / "run"
    first = simulate(scene, collisions=50, out_dir=out)
    assert first.stop_reason.startswith("ball escaped")
    assert read_checkpoint(out / CHECKPOINT_NAME)["status"] == "stopped"
    assert main(["run", "--resume", str(out), "--no-plot"]) == 3
    err = capsys.readouterr().err
    assert err == f"billiard: {out}: the run already stopped after impact 0: {first.stop_reason}\n"


def test_a_finished_run_can_be_extended(tmp_path):
    scene = load_scene("hyperbola-5.8hz")
    ref = reference(tmp_path, scene, "event", 1500)
    out = tmp_path / "run"
    simulate(scene, collisions=600, out_dir=out)
    result = resume(out, collisions=1500)
    assert not result.already_finished and len(result) == 1500
    assert same_run(ref, out)
    with pytest.raises(CheckpointError, match="already has 1500 impacts"):
        resume(out, collisions=1000)


# ---------------------------------------------------------------------------------
# resume errors: one line, exit 2, nothing touched


def finished_run(tmp_path: Path, monkeypatch, impacts: int = 400, at: int = 150) -> Path:
    out = tmp_path / "run"
    interrupted(load_scene("wedge-6.6hz"), "event", impacts, out, str(at), monkeypatch)
    return out


def _edit_checkpoint_number(path: Path) -> None:
    data = json.loads(path.read_text())
    data["engine"]["ball"]["u1"] += 1e-9  # a different state, the old checksum
    path.write_text(json.dumps(data))


def _edit_scene(path: Path) -> None:
    path.write_text(path.read_text().replace("restitution = 0.393", "restitution = 0.4"))


def _replace_csv(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[-10] = ord("7") if data[-10] != ord("7") else ord("8")
    path.write_bytes(bytes(data))


BREAKAGES = {
    "missing checkpoint": (lambda d: (d / CHECKPOINT_NAME).unlink(), "checkpoint.json is missing"),
    "truncated checkpoint": (
        lambda d: (d / CHECKPOINT_NAME).write_text((d / CHECKPOINT_NAME).read_text()[:200]),
        "is corrupt (not valid JSON",
    ),
    "empty checkpoint": (
        lambda d: (d / CHECKPOINT_NAME).write_text(""),
        "is corrupt (not valid JSON",
    ),
    "edited checkpoint": (
        lambda d: _edit_checkpoint_number(d / CHECKPOINT_NAME),
        "is corrupt (its checksum does not match its content)",
    ),
    "not a checkpoint": (
        lambda d: (d / CHECKPOINT_NAME).write_text("[1, 2]"),
        "is not a billiard checkpoint",
    ),
    "edited scene": (
        lambda d: _edit_scene(d / SCENE_NAME),
        "is not the scene the checkpoint was written for",
    ),
    "missing scene": (lambda d: (d / SCENE_NAME).unlink(), "scene.toml is missing"),
    "replaced csv": (lambda d: _replace_csv(d / CSV_NAME), "does not match the checkpoint"),
    "missing csv": (lambda d: (d / CSV_NAME).unlink(), "collisions.csv is missing"),
}


@pytest.mark.parametrize("breakage", list(BREAKAGES))
def test_resume_errors_are_one_line(breakage, tmp_path, monkeypatch, capsys):
    out = finished_run(tmp_path, monkeypatch)
    breaker, fragment = BREAKAGES[breakage]
    breaker(out)
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["run", "--resume", str(out), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"billiard: error: cannot resume {out}: ") and err.count("\n") == 1
    assert fragment in err, err
    # a failed resume changes nothing
    assert {p.name: p.read_bytes() for p in out.iterdir()} == files


def test_resume_errors_through_the_command_line(tmp_path, monkeypatch):
    """No traceback, one line, exit status 2 (a fresh interpreter, as a user runs it)."""
    out = finished_run(tmp_path, monkeypatch)
    (out / CHECKPOINT_NAME).write_text("{ not json")
    for args, fragment in (
        (["run", "--resume", str(out)], "is corrupt (not valid JSON"),
        (["run", "--resume", str(tmp_path / "nowhere")], "is not a run directory"),
        (["run", "--resume", str(out), "--set", "drive.phase=1"], "give no SCENE"),
        (["run"], "give a SCENE"),
    ):
        proc = cli(*args, cwd=tmp_path)
        assert proc.returncode == 2, (args, proc.stderr)
        assert proc.stderr.startswith("billiard: error: ") and proc.stderr.count("\n") == 1
        assert fragment in proc.stderr and "Traceback" not in proc.stderr


def test_a_new_run_replaces_an_old_checkpoint(tmp_path, monkeypatch):
    out = finished_run(tmp_path, monkeypatch)
    simulate(load_scene("wedge-6.6hz"), collisions=100, out_dir=out)
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    assert checkpoint["status"] == "complete" and checkpoint["csv"]["rows"] == 100


def test_one_run_directory_one_writer(tmp_path, monkeypatch):
    """While a run writes DIR (its CSV file is locked), neither a new run nor a resume
    touches it."""
    out = finished_run(tmp_path, monkeypatch)
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    holder = stream.CsvRecorder.reopen(
        out / CSV_NAME, stream.CsvMark.from_dict(read_checkpoint(out / CHECKPOINT_NAME)["csv"])
    )[0]
    try:
        with pytest.raises(stream.RunBusyError, match="being written by another process"):
            simulate(load_scene("wedge-6.6hz"), collisions=10, out_dir=out)
        with pytest.raises(CheckpointError, match="being written by another process"):
            resume(out)
        assert {p.name: p.read_bytes() for p in out.iterdir()} == files
    finally:
        holder.close()
    resume(out)
    assert len(read_collisions(out / CSV_NAME)["n"]) == 400


def test_recorder_writes_whole_rows_at_least_once_a_second(tmp_path, monkeypatch):
    path = tmp_path / "rows.csv"
    recorder = stream.CsvRecorder(path)  # the header is on disk at once
    header = path.read_bytes()
    assert header == b",".join(name.encode() for name in record.COLUMNS) + b"\n"
    row = (
        1,
        0.5,
        0.0,
        0.1,
        1.0,
        -1.0,
        3.0,
        0.2,
        0.3,
        0.5,
        "stick",
        0.1,
        1e-3,
        "0",
        1e-6,
        2e-6,
        0.01,
        1.5,
    )
    monkeypatch.setattr(stream, "FLUSH_INTERVAL", 3600.0)
    recorder.append(row)
    assert path.read_bytes() == header  # collected, not yet due
    monkeypatch.setattr(stream, "FLUSH_INTERVAL", 0.0)
    recorder.append(row)  # due: both rows go out in one write
    data = path.read_bytes()
    assert data.count(b"\n") == 3 and data.endswith(b"\n") and b"\r" not in data
    mark = recorder.flush()
    assert (mark.rows, mark.size) == (2, len(data)) and data.endswith(mark.last_line.encode())
    recorder.close()
    assert read_collisions(path)["t"].tolist() == [0.5, 0.5]


def test_rows_beyond_the_spill_size_are_written_unsynced_before_a_flush(tmp_path, monkeypatch):
    """A block of rows longer than SPILL_BYTES goes to the file at once, without a sync;
    the next flush syncs it; the file's bytes are those of the same rows written in
    memory (MemoryRecorder.write_csv)."""
    sim = engine.Simulation(load_scene("wedge-6.6hz"))
    kept = record.MemoryRecorder()
    sim.run(300, kept)
    reference_csv = tmp_path / "memory.csv"
    kept.write_csv(reference_csv)
    block = np.concatenate(kept._blocks)
    syncs: list[int] = []
    monkeypatch.setattr(stream.os, "fsync", lambda fd: syncs.append(fd))
    path = tmp_path / "rows.csv"
    recorder = stream.CsvRecorder(path, autoflush=False)
    header = path.read_bytes()
    monkeypatch.setattr(stream, "SPILL_BYTES", 20 * 300)  # about 20 rows
    recorder.append_rows(block[:10])
    assert path.read_bytes() == header  # short of the spill size: still pending
    syncs.clear()
    recorder.append_rows(block[10:])
    assert syncs == [] and recorder.mark.rows == 300  # written, not synced
    assert path.read_bytes() == reference_csv.read_bytes()
    mark = recorder.flush()
    assert len(syncs) == 1 and mark.rows == 300  # nothing pending; the spilled rows synced
    recorder.flush()
    assert len(syncs) == 1  # nothing left to sync
    recorder.close()
    assert path.read_bytes() == reference_csv.read_bytes()


def test_interrupt_and_resume_with_rows_spilled_between_checkpoints(tmp_path, monkeypatch):
    """Rows written between two checkpoints (spilled) leave an interrupted run and its
    resumption as without them: byte-identical to an uninterrupted run."""
    name, changes, method, impacts, _ = CASES["event-no-drag"]
    scene = case_scene(name, changes)
    ref = reference(tmp_path, scene, method, impacts)
    monkeypatch.setattr(stream, "SPILL_BYTES", 3000)
    monkeypatch.setattr(engine, "CHECKPOINT_INTERVAL", 3600.0)  # only the first and last
    out = tmp_path / "run"
    stop = interrupted(scene, method, impacts, out, "1500", monkeypatch)
    assert (stop.rows, stop.checkpoint_rows) == (1500, 1500)
    text = (out / CSV_NAME).read_bytes()
    assert text == (ref / CSV_NAME).read_bytes()[: len(text)]
    resume(out)
    assert same_run(ref, out)
