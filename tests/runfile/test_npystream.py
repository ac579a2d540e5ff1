"""A binary run file streamed to disk (billiard/runfile/npystream.py): a run interrupted,
killed between a flush and its checkpoint, cut short or left with a row cut in half
resumes to the bytes of an uninterrupted run; the header never counts a row that is not
on disk; a row on disk that is not the run's is refused before anything is written."""

from __future__ import annotations

import importlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from billiard.engine.interrupt import signal_after
from billiard.run.simulate import RunInterrupted, resume, simulate
from billiard.runfile import npyfile
from billiard.runfile.checkpoint import CheckpointError, read_checkpoint
from billiard.runfile.npyfile import COLLISIONS
from billiard.runfile.npystream import NpyMark, NpyRecorder
from billiard.runfile.record import MemoryRecorder
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene, with_values

engine = importlib.import_module("billiard.engine.simulation")
npystream = importlib.import_module("billiard.runfile.npystream")

ITEM = COLLISIONS.dtype.itemsize
HEAD = npyfile.header_size(COLLISIONS.dtype)
FILES = ("collisions.npy", "contacts.npy", "trajectory.npy", "scene.toml")


def phases_scene():
    return with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"})


# (scene, impacts, sampling interval s)
CASES = {
    "impacts": (lambda: load_scene("wedge-6.6hz"), 600, None),
    "phases-sampled": (phases_scene, 150, 0.01),
}


@pytest.fixture(scope="module")
def references(tmp_path_factory) -> dict[str, Path]:
    out = {}
    for key, (scene, impacts, sample) in CASES.items():
        folder = tmp_path_factory.mktemp(f"ref-{key}")
        simulate(scene(), collisions=impacts, out_dir=folder, sample=sample, store="npy")
        out[key] = folder
    return out


def same_files(a: Path, b: Path) -> None:
    for name in FILES:
        if (a / name).exists() or (b / name).exists():
            assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("stop", [1, 97])
def test_an_interrupted_binary_run_resumes_to_the_same_bytes(case, stop, references, tmp_path):
    scene, impacts, sample = CASES[case]
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted) as caught:
        simulate(
            scene(), collisions=impacts, out_dir=out, sample=sample, store="npy",
            on_record=signal_after(stop, signal.SIGINT),
        )  # fmt: skip
    assert caught.value.rows == stop
    checkpoint = read_checkpoint(out / "checkpoint.json")
    assert checkpoint["store"] == "npy" and "csv" not in checkpoint
    assert checkpoint["npy"]["rows"] == stop
    # what the interruption leaves: a file that counts its rows, a prefix of the run's
    rows = np.load(out / "collisions.npy")
    assert rows["n"].tolist() == list(range(1, stop + 1))
    data = (out / "collisions.npy").read_bytes()
    assert data[HEAD:] == (references[case] / "collisions.npy").read_bytes()[HEAD : len(data)]
    notes: list[str] = []
    result = resume(out, notify=notes.append)
    assert notes == [f"resuming {out} after impact {stop} of {impacts}"]
    assert result.resumed_from == stop and len(result) == impacts
    same_files(references[case], out)


def interrupted_at(tmp_path: Path, stop: int) -> Path:
    """A binary run of the "impacts" case stopped by SIGINT after impact ``stop``: its
    checkpoint describes ``stop`` rows."""
    scene, impacts, _ = CASES["impacts"]
    out = tmp_path / f"at-{stop}"
    with pytest.raises(RunInterrupted):
        simulate(
            scene(), collisions=impacts, out_dir=out, store="npy",
            on_record=signal_after(stop, signal.SIGINT),
        )  # fmt: skip
    assert read_checkpoint(out / "checkpoint.json")["npy"]["rows"] == stop
    return out


@pytest.mark.parametrize(
    ("stop", "extra", "counted", "partial"),
    [(1, 0, False, 50), (151, 40, False, 0), (301, 40, True, 77), (451, 3, True, 0)],
)
def test_a_kill_after_a_flush_and_a_row_cut_in_half_resume_to_the_same_bytes(
    references, tmp_path, stop, extra, counted, partial
):
    """What a SIGKILL can leave: rows flushed after the checkpoint (counted by the header
    or not yet), then part of a row. Resume keeps and checks the whole rows, drops the
    part, and finishes the run byte for byte."""
    reference = (references["impacts"] / "collisions.npy").read_bytes()
    copy = interrupted_at(tmp_path, stop)
    path = copy / "collisions.npy"
    end = HEAD + (stop + extra) * ITEM
    data = bytearray(reference[:end] + reference[end : end + partial])
    data[:HEAD] = npyfile.header_bytes(COLLISIONS.dtype, stop + extra if counted else stop)
    path.write_bytes(bytes(data))
    notes: list[str] = []
    result = resume(copy, notify=notes.append)
    kept = f"{extra} row(s) written after the checkpoint are kept" if extra else ""
    assert kept in notes[0]
    assert ("row cut short" in notes[0]) == bool(partial)
    assert result.truncation.rows == extra and result.truncation.partial_bytes == partial
    assert path.read_bytes() == reference


def test_a_file_cut_short_is_recomputed_and_checked(references, tmp_path):
    reference = references["impacts"]
    out = tmp_path / "run"
    shutil.copytree(reference, out)
    data = (out / "collisions.npy").read_bytes()
    (out / "collisions.npy").write_bytes(data[: HEAD + 250 * ITEM + 9])
    notes: list[str] = []
    resume(out, collisions=700, notify=notes.append)
    assert "holds 250 of the 600 impacts its checkpoint describes" in notes[0]
    assert "row cut short (9 bytes)" in notes[0]
    full = tmp_path / "full"
    simulate(CASES["impacts"][0](), collisions=700, out_dir=full, store="npy")
    same_files(full, out)


def test_a_row_on_disk_that_is_not_the_run_s_is_refused(references, tmp_path):
    copy = interrupted_at(tmp_path, 30)
    path = copy / "collisions.npy"
    reference = (references["impacts"] / "collisions.npy").read_bytes()
    data = bytearray(reference[: HEAD + 35 * ITEM])
    data[:HEAD] = npyfile.header_bytes(COLLISIONS.dtype, 30)
    data[HEAD + 32 * ITEM + 20] ^= 1  # a bit of impact 33
    path.write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match=r"impact 33 on disk differs") as caught:
        resume(copy)
    assert "billiard run" in str(caught.value) and "\n" not in str(caught.value)
    assert path.read_bytes() == bytes(data)


@pytest.mark.parametrize("edit", ["a row before the checkpoint", "the header's table"])
def test_a_file_edited_before_the_checkpoint_is_refused(references, tmp_path, edit):
    out = tmp_path / "run"
    shutil.copytree(references["impacts"], out)
    path = out / "collisions.npy"
    data = bytearray(path.read_bytes())
    if edit == "the header's table":
        data[:HEAD] = npyfile.header_bytes(npyfile.TRAJECTORY.dtype, 0).ljust(HEAD)[:HEAD]
    else:
        data[HEAD + 10 * ITEM + 3] ^= 1
    path.write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match="does not") as caught:
        resume(out, collisions=700)
    assert "\n" not in str(caught.value)
    assert path.read_bytes() == bytes(data)


def test_the_header_counts_flushed_rows_only(tmp_path, monkeypatch):
    """Spilled rows are written before they are counted: a reader sees the rows of the
    last flush, whole, whatever else is on disk."""
    kept = MemoryRecorder()
    engine.Simulation(load_scene("wedge-6.6hz")).run(300, kept)
    block = np.concatenate(kept._blocks)
    monkeypatch.setattr(npystream, "SPILL_BYTES", 50 * ITEM)
    path = tmp_path / "collisions.npy"
    recorder = NpyRecorder(path, autoflush=False, durable=False)
    recorder.append_rows(block[:100])
    first = recorder.flush()
    assert first == NpyMark(100, HEAD + 100 * ITEM, first.crc32)
    recorder.append_rows(block[100:170])  # spilled: on disk, not counted
    assert path.stat().st_size == HEAD + 170 * ITEM
    assert len(np.load(path)) == 100 and len(read_collisions(path)["n"]) == 100
    assert len(recorder) == 170 and recorder.mark.rows == 170
    recorder.append_rows(block[170:])
    recorder.close()
    columns = read_collisions(path)
    expected = MemoryRecorder()
    expected.append_rows(block)
    for name, values in expected.columns().items():
        assert np.array_equal(columns[name], values), name


def test_a_failed_write_keeps_the_whole_rows_and_counts_them(tmp_path, monkeypatch):
    kept = MemoryRecorder()
    engine.Simulation(load_scene("wedge-6.6hz")).run(50, kept)
    block = np.concatenate(kept._blocks)
    path = tmp_path / "collisions.npy"
    recorder = NpyRecorder(path, autoflush=False, durable=False)
    recorder.append_rows(block[:10])
    recorder.flush()
    csvfile = importlib.import_module("billiard.runfile.csvfile")

    def short_write(fd, data):  # 3.5 rows reach the disk, then the disk is full
        written = int(3.5 * ITEM)
        os.write(fd, bytes(data)[:written])
        raise csvfile._ShortWrite(written, OSError(28, "No space left on device"))

    monkeypatch.setattr(npystream, "_write_all", short_write)
    recorder.append_rows(block[10:30])
    with pytest.raises(OSError, match="No space"):
        recorder.flush()
    assert recorder.mark.rows == 13 and path.stat().st_size == HEAD + 13 * ITEM
    assert np.load(path)["n"].tolist() == list(range(1, 14))
    with pytest.raises(OSError, match="No space"):
        recorder.append_rows(block[30:])
    recorder.close()


@pytest.mark.slow
def test_sigkill_mid_run_then_resume(tmp_path):
    """A real SIGKILL of `billiard run --store npy` after its first checkpoint with rows,
    then --resume to 50,000 impacts past it: the bytes of an uninterrupted run of as
    many impacts."""
    out = tmp_path / "run"
    args = ["run", "wedge-6.6hz", "--collisions", "5000000", "--store", "npy", "--no-plot"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "billiard.cli", *args, "--out", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    rows = 0
    while time.monotonic() < deadline and proc.poll() is None and rows == 0:
        try:
            rows = read_checkpoint(out / "checkpoint.json")["npy"]["rows"]
        except (CheckpointError, KeyError):
            pass
        time.sleep(0.01)
    proc.kill()
    proc.wait()
    assert rows > 0
    total = rows + 50000
    done = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", "--resume", str(out), "--no-plot"]
        + ["--collisions", str(total)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    ref = tmp_path / "ref"
    simulate(load_scene("wedge-6.6hz"), collisions=total, out_dir=ref, store="npy")
    same_files(ref, out)
