"""The writer thread of a streamed run file (CsvRecorder.append_rows): the same bytes
as formatting and writing in the caller's thread, drained by flush and close, and its
errors raised at the next call on the recorder."""

from __future__ import annotations

import errno
import importlib
import os

import numpy as np
import pytest

from billiard.runfile import record
from billiard.runfile.record import record_of
from billiard.scene.scene import load_scene

engine = importlib.import_module("billiard.engine.simulation")
stream = importlib.import_module("billiard.runfile.stream")

IMPACTS = 300


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    kept = record.MemoryRecorder()
    engine.Simulation(load_scene("wedge-6.6hz")).run(IMPACTS, kept)
    return np.concatenate(kept._blocks)


def memory_bytes(tmp_path, rows: np.ndarray) -> bytes:
    """The file of ``rows`` as a run in memory writes it."""
    kept = record.MemoryRecorder()
    kept.append_rows(rows)
    kept.write_csv(tmp_path / "memory.csv")
    return (tmp_path / "memory.csv").read_bytes()


def blocks_of(rows: np.ndarray, size: int) -> list[np.ndarray]:
    return [rows[i : i + size] for i in range(0, len(rows), size)]


def written(path, rows: np.ndarray, size: int, monkeypatch, background: bool) -> tuple:
    """The file's bytes, the marks after each block's flush, and len() at the end."""
    monkeypatch.setattr(stream, "BACKGROUND", background)
    recorder = stream.CsvRecorder(path, autoflush=False, durable=False)
    marks = []
    buffer = np.empty((size, rows.shape[1]))
    for number, block in enumerate(blocks_of(rows, size)):
        # the caller's buffer is reused (and spoiled) after each block, as the engine's
        buffer[: len(block)] = block
        recorder.append_rows(buffer[: len(block)])
        buffer[:] = np.nan
        if number % 3 == 2:
            marks.append(recorder.flush())
    length = len(recorder)
    recorder.close()
    return path.read_bytes(), marks, length


@pytest.mark.parametrize("queue_blocks", [1, 4])
@pytest.mark.parametrize("spill", [300, 3000, 1 << 22])
def test_the_writer_thread_writes_the_bytes_of_the_callers_thread(
    tmp_path, rows, monkeypatch, spill, queue_blocks
):
    monkeypatch.setattr(stream, "SPILL_BYTES", spill)
    monkeypatch.setattr(stream, "QUEUE_BLOCKS", queue_blocks)
    here = written(tmp_path / "here.csv", rows, 7, monkeypatch, background=False)
    there = written(tmp_path / "there.csv", rows, 7, monkeypatch, background=True)
    assert there == here
    data, marks, length = there
    assert length == IMPACTS and data.count(b"\n") == IMPACTS + 1
    assert [mark.rows for mark in marks] == list(range(21, IMPACTS + 1, 21))
    assert data == memory_bytes(tmp_path, rows)


def test_mark_len_and_close_wait_for_the_writer_thread(tmp_path, rows, monkeypatch):
    monkeypatch.setattr(stream, "SPILL_BYTES", 20_000)  # about 60 rows
    path = tmp_path / "rows.csv"
    recorder = stream.CsvRecorder(path, autoflush=False)
    for block in blocks_of(rows, 40):
        recorder.append_rows(block)
    assert len(recorder) == IMPACTS
    mark = recorder.mark  # the spilled rows: all but the last few, still pending
    assert 0 < mark.rows < IMPACTS and path.read_bytes().count(b"\n") == mark.rows + 1
    recorder.close()
    assert path.read_bytes() == memory_bytes(tmp_path, rows)
    assert recorder.mark.rows == IMPACTS


class FullDisk:
    """``os.write`` that writes ``budget`` bytes to ``path`` and then fails."""

    def __init__(self, path, budget: int):
        self.path, self.budget, self._write = str(path), budget, os.write

    def __call__(self, fd: int, data) -> int:
        if os.readlink(f"/proc/self/fd/{fd}") != self.path:
            return self._write(fd, data)
        if self.budget <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        done = self._write(fd, bytes(data[: self.budget]))
        self.budget -= done
        return done


@pytest.mark.parametrize("next_call", ["append_rows", "append", "flush", "close"])
def test_a_failed_spill_is_raised_at_the_next_call(tmp_path, rows, monkeypatch, next_call):
    monkeypatch.setattr(stream, "SPILL_BYTES", 3000)
    path = tmp_path / "rows.csv"
    recorder = stream.CsvRecorder(path, autoflush=False)
    header = len(path.read_bytes())
    monkeypatch.setattr(os, "write", FullDisk(path.resolve(), 5000))
    recorder.append_rows(rows[:40])  # a spill of 40 rows, cut short after 5000 bytes
    assert recorder.mark.rows > 0  # waits for the thread: the whole rows are kept
    kept = recorder.mark
    with pytest.raises(OSError) as caught:
        if next_call == "append_rows":
            recorder.append_rows(rows[40:50])
        elif next_call == "append":
            recorder.append(record_of(rows[40].tolist()))
        else:
            getattr(recorder, next_call)()
    assert caught.value.errno == errno.ENOSPC and recorder.failed is caught.value
    data = path.read_bytes()
    assert len(data) == kept.size and data.count(b"\n") == kept.rows + 1
    assert kept.size < header + 5000 and data.endswith(kept.last_line.encode())
    assert data == memory_bytes(tmp_path, rows[: kept.rows])
    # raised once; afterwards the recorder behaves as after a failed write in its thread
    with pytest.raises(OSError) as again:
        recorder.flush()
    assert again.value is caught.value
    recorder.close()
    assert recorder.closed and path.read_bytes() == data


def test_an_error_formatting_a_block_is_raised_and_the_rows_before_it_kept(
    tmp_path, rows, monkeypatch
):
    """An error of the thread that is not a write's: raised at the next call, the blocks
    after it are dropped, and close writes the rows before it."""
    format_rows_bytes = stream.format_rows_bytes
    calls = []

    def failing(block, line_end):
        calls.append(len(block))
        if len(calls) == 3:
            raise ValueError("a row that cannot be written")
        return format_rows_bytes(block, line_end)

    monkeypatch.setattr(stream, "format_rows_bytes", failing)
    monkeypatch.setattr(stream, "QUEUE_BLOCKS", 8)
    path = tmp_path / "rows.csv"
    recorder = stream.CsvRecorder(path, autoflush=False)
    with pytest.raises(ValueError, match="cannot be written"):
        # raised by the first call after the thread met it: an append or close
        for block in blocks_of(rows[:50], 10):
            recorder.append_rows(block)
        recorder.close()
    recorder.close()
    assert recorder.closed and recorder.failed is None and calls[:3] == [10, 10, 10]
    assert path.read_bytes() == memory_bytes(tmp_path, rows[:20])
