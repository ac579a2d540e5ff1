"""A full disk loses nothing written: the CSV file keeps its whole rows, ``--resume``
keeps every one of them (rows after the last checkpoint are recomputed and checked, not
dropped and rewritten) and the finished file equals an uninterrupted run byte for byte.

The full disk is simulated: ``os.write`` on the run's CSV file raises
``OSError(ENOSPC)`` once a byte budget is spent (after a short write, as a real file
system does), or the checkpoint write raises it.
"""

from __future__ import annotations

import errno
import importlib
import os
import types
from pathlib import Path

import pytest

from billiard.cli import main
from billiard.run.simulate import CHECKPOINT_NAME, CSV_NAME, resume, simulate
from billiard.runfile.checkpoint import read_checkpoint
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene

engine = importlib.import_module("billiard.engine.simulation")
driver = importlib.import_module("billiard.engine.driver")
persist = importlib.import_module("billiard.run.persist")
stream = importlib.import_module("billiard.runfile.stream")

IMPACTS = 300


class Disk:
    """``os.write`` with room for ``budget`` more bytes in files named collisions.csv."""

    def __init__(self, budget: float):
        self.budget = budget
        self.written = 0
        self.whole = 0  # writes to collisions.csv that wrote all they were given
        self._write = os.write

    def __call__(self, fd: int, data) -> int:
        if not os.readlink(f"/proc/self/fd/{fd}").endswith(CSV_NAME):
            return self._write(fd, data)
        if self.budget <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        done = self._write(fd, bytes(data[: int(min(len(data), self.budget))]))
        self.budget -= done
        self.written += done
        self.whole += done == len(data)
        return done


@pytest.fixture
def frequent_checkpoints(monkeypatch):
    """A wall clock that advances 0.25 s per reading: a flush and checkpoint every few
    impacts, the same ones in every run."""
    ticks = iter(range(10**9))
    monkeypatch.setattr(driver, "time", types.SimpleNamespace(monotonic=lambda: next(ticks) / 4))


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> bytes:
    out = tmp_path_factory.mktemp("reference")
    simulate(load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out)
    return (out / CSV_NAME).read_bytes()


def full_disk_run(out: Path, disk: Disk, monkeypatch):
    monkeypatch.setattr(os, "write", disk)
    with pytest.raises(persist.RunWriteError) as caught:
        simulate(load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out)
    monkeypatch.setattr(os, "write", disk._write)
    return caught.value


def test_a_write_cut_short_keeps_the_whole_rows_and_resume_keeps_them(
    tmp_path, reference, frequent_checkpoints, monkeypatch
):
    cut_short_then_resumed(tmp_path, reference, monkeypatch)


def test_a_spill_cut_short_keeps_the_whole_rows_and_resume_keeps_them(
    tmp_path, reference, monkeypatch
):
    """The same with rows written between checkpoints because enough are pending
    (``SPILL_BYTES``): the write that fails is a spill, the checkpoint the first one."""
    monkeypatch.setattr(stream, "SPILL_BYTES", 3000)
    monkeypatch.setattr(engine, "CHECKPOINT_INTERVAL", 3600.0)
    # the engine hands out rows in chunks of 64 or more: room for a few of them
    disk = cut_short_then_resumed(tmp_path, reference, monkeypatch, budget=60_000 + 17)
    assert disk.whole >= 2  # the header, and rows written before the run's end


def cut_short_then_resumed(
    tmp_path: Path, reference: bytes, monkeypatch, budget: int = 20_000 + 17
) -> Disk:
    """Run until the disk is full, resume on a full disk, resume with space: returns
    the disk of the first run."""
    # budget: runs out in the middle of a row, in the middle of a flush
    out = tmp_path / "run"
    first = Disk(budget)
    error = full_disk_run(out, first, monkeypatch)
    whole = reference.rfind(b"\n", 0, budget) + 1
    kept = reference[:whole].count(b"\n") - 1
    assert error.errno == errno.ENOSPC and error.rows == kept
    assert f"the disk is full (No space left on device): {kept} impacts kept in" in str(error)
    assert (out / CSV_NAME).read_bytes() == reference[:whole]  # the partial row was cut
    checkpoint_rows = read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"]
    assert checkpoint_rows == error.checkpoint_rows < kept

    # resuming while the disk is still full needs no space for the rows it has
    still_full = Disk(0)
    notes: list[str] = []
    monkeypatch.setattr(os, "write", still_full)
    with pytest.raises(persist.RunWriteError) as again:
        resume(out, notify=notes.append)
    monkeypatch.setattr(os, "write", still_full._write)
    assert again.value.rows == kept and (out / CSV_NAME).read_bytes() == reference[:whole]
    assert notes == [
        f"resuming {out} after impact {checkpoint_rows} of {IMPACTS}; "
        f"{kept - checkpoint_rows} row(s) written after the checkpoint are kept "
        f"(each checked against the recomputed impact)"
    ]

    # with space again, the run finishes as an uninterrupted one
    disk = Disk(float("inf"))
    monkeypatch.setattr(os, "write", disk)
    resume(out)
    assert (out / CSV_NAME).read_bytes() == reference
    assert disk.written == len(reference) - whole  # the kept rows were not rewritten
    return first


def test_a_failed_checkpoint_write_loses_no_row(
    tmp_path, reference, frequent_checkpoints, monkeypatch
):
    """The reported case: the rows reached the disk but the checkpoint could not follow,
    so it stayed at impact 0 and resume dropped every row."""
    write_checkpoint = persist.write_checkpoint
    calls = []

    def failing(path, body):
        calls.append(body["csv"]["rows"])
        if len(calls) > 1:  # the first (at impact 0) goes through, then the disk is full
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        write_checkpoint(path, body)

    monkeypatch.setattr(persist, "write_checkpoint", failing)
    out = tmp_path / "run"
    with pytest.raises(persist.RunWriteError) as caught:
        simulate(load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out)
    monkeypatch.setattr(persist, "write_checkpoint", write_checkpoint)
    kept = calls[1]
    assert caught.value.rows == kept > 0 and caught.value.checkpoint_rows == 0
    assert read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"] == 0
    assert len(read_collisions(out / CSV_NAME)["n"]) == kept
    notes: list[str] = []
    on_disk = (out / CSV_NAME).stat().st_size
    disk = Disk(float("inf"))
    monkeypatch.setattr(os, "write", disk)
    resume(out, notify=notes.append)
    assert "dropped" not in notes[0] and f"{kept} row(s) written after the checkpoint" in notes[0]
    assert (out / CSV_NAME).read_bytes() == reference
    assert disk.written == len(reference) - on_disk  # the kept rows were not rewritten


def test_the_command_line_says_the_disk_is_full_in_one_line(
    tmp_path, reference, frequent_checkpoints, monkeypatch, capsys
):
    out = tmp_path / "run"
    monkeypatch.setattr(os, "write", Disk(30_000))
    status = main(
        ["run", "wedge-6.6hz", "--collisions", str(IMPACTS), "--out", str(out), "--no-plot"]
    )
    monkeypatch.undo()
    err = capsys.readouterr().err
    kept = reference[: reference.rfind(b"\n", 0, 30_000) + 1].count(b"\n") - 1
    assert status == 2 and err.count("\n") == 1, err
    assert err == (
        f"billiard: error: cannot write the run: the disk is full (No space left on device): "
        f"{kept} impacts kept in {out / CSV_NAME}; free some space, then continue with "
        f"`billiard run --resume {out}`\n"
    )
    assert main(["run", "--resume", str(out), "--no-plot"]) == 0
    assert (out / CSV_NAME).read_bytes() == reference


def test_an_edited_row_after_the_checkpoint_is_refused_and_nothing_changes(
    tmp_path, reference, frequent_checkpoints, monkeypatch, capsys
):
    out = tmp_path / "run"
    error = full_disk_run(out, Disk(20_000), monkeypatch)
    assert error.checkpoint_rows < error.rows
    data = (out / CSV_NAME).read_bytes()
    edited = data[:-3] + (b"7" if data[-3:-2] != b"7" else b"8") + data[-2:]
    (out / CSV_NAME).write_bytes(edited)
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["run", "--resume", str(out), "--no-plot"]) == 2
    # the note on where it resumes from, then the one-line error
    note, err = capsys.readouterr().err.splitlines()
    assert note.startswith(f"billiard: resuming {out} after impact {error.checkpoint_rows} ")
    assert err.startswith(f"billiard: error: cannot resume {out}: ")
    assert f"impact {error.rows} on disk differs" in err, err
    assert f"`billiard run {out / 'scene.toml'} --out {out} --overwrite`" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == files
