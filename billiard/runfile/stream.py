"""A run file streamed to disk as it grows: rows appended in whole lines, flushed and synced
at least once a second, with the marks a checkpoint stores to find its place again.

A streamed file only ever grows by whole rows: rows are collected in memory and written
with one system call per flush, then synced to disk. A process killed in the middle of
that call can leave an unterminated last line; readers skip it, and resuming the run
(:func:`billiard.run.persist.resume`) cuts the file back to the checkpoint's row or checks
the rows after it against a recomputation.

Rows handed over as arrays (:meth:`CsvRecorder.append_rows`, a compiled run's chunks)
are formatted and spilled on a thread of the recorder's own
(:class:`billiard.runfile.handoff.Handoff`) while the engine computes the next chunk; every call
that flushes, closes or reads the recorder waits for it first, and an error of that
thread is raised by the next call on the recorder. The bytes are the same.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import os
import shutil
import time
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from billiard.runfile.checkpoint import CheckpointError
from billiard.runfile.csvfile import (
    CsvMark,
    RowMismatchError,
    RunBusyError,
    Truncation,
    _open_locked,
    _read_at,
    _scan_rows,
    _ShortWrite,
    _write_all,
    prefix_crc32,
)
from billiard.runfile.handoff import Handoff
from billiard.runfile.record import (
    _LINE_ENDS,
    COLUMNS,
    LINE_END,
    format_field,
    header_line,
    read_collisions_csv,
    record_of,
)
from billiard.runfile.rows import format_rows_bytes

__all__ = [
    "CsvMark",
    "CsvRecorder",
    "RowMismatchError",
    "RunBusyError",
    "Truncation",
    "check_mark",
]

#: Wall-clock seconds between flushes of a streamed file.
FLUSH_INTERVAL = 1.0
#: Bytes of rows collected before they are written to the file, synced or not,
#: whatever the time since the last flush: a compiled run makes hundreds of thousands
#: of rows a second, which would otherwise all wait in memory for the next flush.
SPILL_BYTES = 1 << 22
#: Format and write the blocks of :meth:`CsvRecorder.append_rows` on a thread of their
#: own, while the engine computes the next rows (False: in the caller's thread).
BACKGROUND = True
#: Blocks handed to that thread and not yet taken up, at most: beyond them
#: ``append_rows`` waits, so that memory stays bounded when writing falls behind.
QUEUE_BLOCKS = 4


class CsvRecorder:
    """Rows streamed to a CSV file as they are produced; nothing but the rows since the
    last flush is kept in memory, so long runs stay flat. Read back with :meth:`columns`.

    A failed write (a full disk) leaves the file ending with the whole rows that reached
    it: a row cut short is removed again, :attr:`mark` counts the whole rows, and the
    recorder writes nothing more (:meth:`close` only closes the file).

    Args:
        path: the file; emptied (or created) and given its header at once.
        columns: column names.
        autoflush: flush on its own at least once a second. A run that checkpoints
            turns this off and calls :meth:`flush` itself, so that what is on disk is
            always exactly what a checkpoint describes.
        durable: sync each flush to the storage device (``os.fsync``), so that rows
            said to be kept survive a crash of the machine too, not only of the process.
        line_end: the rows' line terminator (:data:`LINE_END`; ``"\\r\\n"`` only to
            continue a file written so).

    Raises:
        RunBusyError: another process holds the file (a run still going on).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        columns: Sequence[str] = COLUMNS,
        *,
        autoflush: bool = True,
        durable: bool = True,
        line_end: str = LINE_END,
        _open: tuple[int, CsvMark] | None = None,
    ):
        if line_end not in _LINE_ENDS:
            raise ValueError(f"line_end must be one of {_LINE_ENDS!r}, got {line_end!r}")
        self.path = Path(path)
        self.names = tuple(columns)
        self.autoflush = autoflush
        self.durable = durable
        self.line_end = line_end
        # the rows' bytes, as they go to the file (a row appended as a record is
        # formatted by the csv module in _row_text first)
        self._pending = bytearray()
        self._row_text = io.StringIO()
        self._writer = csv.writer(self._row_text, lineterminator=line_end)
        self._pending_rows = 0
        self._unsynced = False  # rows written without a sync since the last one
        self._last_flush = time.monotonic()
        #: the write error that ended writing (None while writes succeed)
        self.failed: OSError | CheckpointError | None = None
        # rows already on disk after the mark, checked against the appended ones
        self._check: BinaryIO | None = None
        self._check_end = 0
        self._check_rows = 0
        # the writer thread of append_rows
        self._writer_thread = Handoff(self, "_take", QUEUE_BLOCKS, f"writer {self.path.name}")
        if _open is None:
            self._fd: int | None = _open_locked(self.path)
            os.ftruncate(self._fd, 0)
            header = header_line(self.names, line_end)
            data = header.encode("utf-8")
            try:
                _write_all(self._fd, data)
            except _ShortWrite as short:
                os.close(self._fd)
                raise short.error from None
            if durable:
                os.fsync(self._fd)
            self._mark = CsvMark(0, len(data), header, zlib.crc32(data))
        else:
            self._fd, self._mark = _open

    @staticmethod
    def header_mark(path: str | os.PathLike[str], columns: Sequence[str] = COLUMNS) -> CsvMark:
        """The mark of a run file's header (no rows), in the file's line ending.

        Raises:
            CheckpointError: the file is missing or does not start with the header.
        """
        path = Path(path)
        try:
            with open(path, "rb") as handle:
                # no further than the longest header: the file may be anything
                start = handle.readline(len(header_line(columns, "\r\n")))
        except FileNotFoundError:
            raise CheckpointError(f"{path} is missing") from None
        except OSError as exc:
            raise CheckpointError(f"{path} cannot be read: {exc.strerror or exc}") from None
        for line_end in _LINE_ENDS:
            header = header_line(columns, line_end)
            if start == header.encode():
                return CsvMark(0, len(start), header, zlib.crc32(start))
        raise CheckpointError(f"{path} does not start with the header of a run file")

    @classmethod
    def reopen(
        cls,
        path: str | os.PathLike[str],
        mark: CsvMark,
        columns: Sequence[str] = COLUMNS,
        *,
        autoflush: bool = True,
        durable: bool = True,
    ) -> tuple[CsvRecorder, Truncation]:
        """Continue a streamed file at ``mark``: check that the file holds the header
        and, at the mark, the expected last line, and append from there, with the line
        terminator the file was written with (its header's).

        Whole rows already in the file after the mark (written after the checkpoint
        that gave the mark) are not rewritten: each row appended is compared with the
        next of them (:class:`RowMismatchError` if it differs, before anything is
        written), and only rows beyond them are written. Until then the file is left
        as it is; at the first row written (or :meth:`end_check`), an unterminated last
        line is cut off.

        Raises:
            CheckpointError: the file is missing, shorter than the mark, or differs
                from what the mark describes (the file is then left as it was).
            RunBusyError: another process is still writing it.
        """
        path = Path(path)
        if not path.is_file():
            raise CheckpointError(
                f"{path} is missing" if not path.exists() else f"{path} is not a file"
            )
        line_end = "\r\n" if mark.last_line.endswith("\r\n") else "\n"
        fd = _open_locked(path)
        check: BinaryIO | None = None
        try:
            mark = check_mark(fd, path, mark, columns)
            size = os.fstat(fd).st_size
            rows, whole = _scan_rows(fd, mark.size, size)
            if rows:
                check = open(path, "rb")  # noqa: SIM115 - closed by the recorder
                check.seek(mark.size)
            elif size > mark.size:
                os.ftruncate(fd, mark.size)
                os.fsync(fd)
            os.lseek(fd, mark.size, os.SEEK_SET)
        except BaseException:
            os.close(fd)
            raise
        recorder = cls(
            path, columns, autoflush=autoflush, durable=durable, line_end=line_end, _open=(fd, mark)
        )
        recorder._check, recorder._check_end, recorder._check_rows = check, whole, rows
        return recorder, Truncation(rows, size - whole)

    @property
    def checking(self) -> bool:
        """Are appended rows still being compared with rows already in the file?"""
        return self._check is not None

    @property
    def rows_on_disk(self) -> int:
        """Whole rows in the file: the flushed (or checked) ones, plus rows still to be
        checked."""
        self._drain()
        return self._mark.rows + self._check_rows

    def append(self, row: Sequence[Any]) -> None:
        self._settle()
        self._writer.writerow([format_field(v) for v in row])
        self._pending += self._row_text.getvalue().encode("utf-8")
        self._row_text.seek(0)
        self._row_text.truncate()
        self._pending_rows += 1
        if self._check is not None:
            self._check_row()
            if self._check is not None:
                return
        if self.autoflush:
            # wall-clock time decides only when bytes reach the disk, never what they are
            now = time.monotonic()
            if now - self._last_flush >= FLUSH_INTERVAL:
                self.flush()

    def append_rows(self, block: np.ndarray) -> None:
        """Append impact rows (``(rows, NCOL)`` float64, :mod:`billiard.runfile.rows`), the
        same bytes as appending their records one by one."""
        if self._check is not None:
            # rows already on disk are compared one by one
            for row in block.tolist():
                self.append(record_of(row))
            return
        self._writer_thread.raise_error()
        if BACKGROUND and self.failed is None:
            self._hand_over(block)
            if self.autoflush and time.monotonic() - self._last_flush >= FLUSH_INTERVAL:
                self.flush()
            return
        self._drain()
        self._pending += format_rows_bytes(block, self.line_end)
        self._pending_rows += len(block)
        if self.autoflush and time.monotonic() - self._last_flush >= FLUSH_INTERVAL:
            self.flush()
        elif len(self._pending) >= SPILL_BYTES:
            # written, not synced: the next flush syncs them with the rest; a checkpoint
            # comes only after a flush, and rows on disk past it are checked on resume
            self._write(sync=False)

    def _hand_over(self, block: np.ndarray) -> None:
        """Give a block to the writer thread or, while :data:`QUEUE_BLOCKS` blocks are
        waiting, its bytes formatted here (the thread writes them in turn)."""
        if self._writer_thread.full():
            item: Any = format_rows_bytes(block, self.line_end), len(block)
        else:
            item = np.array(block, dtype=np.float64)  # a copy: the caller reuses its array
        self._writer_thread.put(item)

    def _take(self, block: np.ndarray | tuple[bytes, int]) -> None:
        """(writer thread) Format ``block`` into the pending rows and spill them when
        :data:`SPILL_BYTES` are pending, as ``append_rows`` does in the caller's thread."""
        if self.failed is not None:
            return
        if isinstance(block, tuple):
            data, rows = block
        else:
            data, rows = format_rows_bytes(block, self.line_end), len(block)
        self._pending += data
        self._pending_rows += rows
        if len(self._pending) >= SPILL_BYTES:
            self._write(sync=False)  # written, not synced, as in append_rows

    def _drain(self) -> None:
        self._writer_thread.drain()

    def _settle(self) -> None:
        """Wait for the writer thread, then raise its error if it had one."""
        self._writer_thread.drain()
        self._writer_thread.raise_error()

    def _check_row(self) -> None:
        """Compare the one pending row with the next row in the file."""
        assert self._check is not None and self._pending_rows == 1
        if self._mark.size >= self._check_end:
            self.end_check()
            return
        line = bytes(self._pending)
        if self._check.readline() != line:
            self._discard_pending()
            self._close_check()
            self.failed = RowMismatchError(self.path, self._mark.rows + 1)
            raise self.failed
        self._mark = self._mark.then(line, 1, line.decode())
        self._check_rows -= 1
        self._discard_pending()

    def end_check(self) -> None:
        """Stop checking: cut the file after the rows checked so far (dropping rows not
        reached and an unterminated last line), and write from there."""
        if self._check is None:
            return
        self._close_check()
        self._check_rows = 0
        if self._fd is not None and os.fstat(self._fd).st_size > self._mark.size:
            os.ftruncate(self._fd, self._mark.size)
            if self.durable:
                os.fsync(self._fd)
        if self._fd is not None:
            os.lseek(self._fd, self._mark.size, os.SEEK_SET)

    def _close_check(self) -> None:
        if self._check is not None:
            self._check.close()
            self._check = None

    def _discard_pending(self) -> None:
        # a new buffer: the written one may be megabytes
        self._pending = bytearray()
        self._pending_rows = 0

    def flush(self) -> CsvMark:
        """Write the rows collected since the last flush in one system call, sync them
        (when durable), and return the new end of the file.

        Raises:
            OSError: the write or the sync failed (e.g. the disk is full); the file then
                ends with the whole rows that reached it (:attr:`mark`), and nothing
                more is written.
        """
        self._settle()
        self._last_flush = time.monotonic()
        return self._write(sync=self.durable)

    def _write(self, sync: bool) -> CsvMark:
        """Write the pending rows in one system call (then sync them if ``sync``)."""
        if self.failed is not None:
            raise self.failed
        data = self._pending
        if not data:
            if sync and self._unsynced and self._fd is not None:
                # rows written unsynced since the last sync (spilled)
                try:
                    os.fsync(self._fd)
                except OSError as exc:
                    self.failed = exc
                    raise
                self._unsynced = False
            return self._mark
        if self._fd is None:
            raise ValueError(f"{self.path} is closed")
        try:
            _write_all(self._fd, data)
            if sync:
                os.fsync(self._fd)
        except _ShortWrite as short:
            self._fail(data, short.written, short.error)
        except OSError as exc:  # the sync failed: the bytes are in the file
            self._fail(data, len(data), exc)
        self._unsynced = not sync
        self._advance(data, len(data), self._pending_rows)
        self._discard_pending()
        return self._mark

    def _advance(self, data: bytes | bytearray, size: int, rows: int) -> None:
        # the last line of what was written (every row ends with the line terminator)
        start = data.rfind(b"\n", 0, size - 1) + 1
        last = bytes(data[start:size]).decode("utf-8")
        with memoryview(data) as view:  # released at once: the buffer may grow later
            self._mark = self._mark.then(view[:size], rows, last)

    def _fail(self, data: bytes | bytearray, written: int, error: OSError) -> None:
        """A flush failed after ``written`` bytes of ``data``: keep the whole rows among
        them, cut a row cut short (which frees space rather than needing it), write
        nothing more, and raise ``error``."""
        whole = data.rfind(b"\n", 0, written) + 1
        if whole:
            self._advance(data, whole, data.count(b"\n", 0, whole))
        if whole < written:
            with contextlib.suppress(OSError):
                os.ftruncate(self._fd, self._mark.size)  # type: ignore[arg-type]
        self._discard_pending()
        self.failed = error
        raise error

    @property
    def mark(self) -> CsvMark:
        """The end of what has been flushed to the file."""
        self._drain()
        return self._mark

    def __len__(self) -> int:
        self._drain()
        return self._mark.rows + self._pending_rows

    @property
    def closed(self) -> bool:
        return self._fd is None

    def close(self) -> None:
        """Flush the remaining rows and close the file (idempotent). After a failed
        write, or while rows are still being checked, it only closes the file.

        Raises:
            the writer thread's error if no call has raised it yet (after flushing the
            rows before it, when it was not a failed write).
        """
        if self._fd is None:
            return
        error: BaseException | None = None
        try:
            self._drain()
            error = self._writer_thread.take_error()
            if self.failed is None and self._check is None:
                self.flush()
        finally:
            self._writer_thread.stop()
            self._close_check()
            os.close(self._fd)
            self._fd = None
        if error is not None:
            raise error

    def columns(self) -> dict[str, np.ndarray]:
        self._settle()
        if self._fd is not None and self.failed is None:
            self.flush()
        return read_collisions_csv(self.path)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        self._settle()
        if self._fd is not None and self.failed is None:
            self.flush()
        if Path(path).resolve() != self.path.resolve():
            shutil.copyfile(self.path, path)


def check_mark(
    fd: int, path: Path, mark: CsvMark, columns: Sequence[str] = COLUMNS, *, whole: bool = False
) -> CsvMark:
    """Check that the CSV run file open as ``fd`` holds what ``mark`` describes: at least
    its bytes, the header, the mark's last line where the mark says, its rows before it,
    and their CRC-32 (when the mark has one); with ``whole`` (the last checkpoint of a
    run that ended), also nothing after them. Nothing is changed.

    Returns:
        ``mark`` with the CRC-32 of the bytes before it (also where it had none).

    Raises:
        CheckpointError: the file differs from what the mark describes (one line naming
            ``path`` and what differs).
    """
    line = mark.last_line.encode()
    line_end = "\r\n" if mark.last_line.endswith("\r\n") else "\n"
    header = header_line(columns, line_end).encode()
    size = os.fstat(fd).st_size
    if size < mark.size:
        raise CheckpointError(
            f"{path} holds {size} bytes, fewer than the {mark.size} bytes of the "
            f"{mark.rows} impacts the checkpoint describes (was it replaced?)"
        )
    start = _read_at(fd, len(header), 0)
    at_mark = b""
    if mark.size >= max(len(line), len(header)):
        at_mark = _read_at(fd, len(line), mark.size - len(line))
    if start != header or at_mark != line:
        raise CheckpointError(
            f"{path} does not match the checkpoint (impact {mark.rows} is not "
            f"where the checkpoint says; was the file edited or replaced?)"
        )
    # everything before the mark, byte for byte: its checksum (one byte edited in the
    # middle leaves the mark's line in place) and its rows
    crc, lines = prefix_crc32(fd, mark.size)
    if mark.crc32 is not None and crc != mark.crc32:
        raise CheckpointError(
            f"{path} does not match the checkpoint (its first {mark.rows} impacts "
            f"were changed since: their CRC-32 differs; was the file edited?)"
        )
    if lines != mark.rows + 1:
        raise CheckpointError(
            f"{path} does not match the checkpoint ({lines - 1} rows before the "
            f"checkpoint's place, which follows impact {mark.rows}; was the file edited?)"
        )
    if whole and size > mark.size:
        raise CheckpointError(
            f"{path} holds {size - mark.size} bytes after the {mark.rows} impacts of the "
            f"finished run its checkpoint describes (was the file edited?)"
        )
    return dataclasses.replace(mark, crc32=crc)
