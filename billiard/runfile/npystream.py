"""A binary run file streamed to disk as it grows (``collisions.npy``, and the side
tables ``contacts.npy`` and ``trajectory.npy``): typed rows appended whole, the count in
the header rewritten after them, with the marks a checkpoint stores to find its place
again. The same guarantees as the CSV files of :mod:`billiard.runfile.stream`:

* rows are kept in memory (as the kernels' float64 blocks) until a flush, which writes
  them with one system call, syncs them, and only then rewrites the row count in the
  header (synced too): a reader, or a kill at any moment, finds a header that counts
  whole rows that are on disk;
* a spill (:data:`SPILL_BYTES` of rows waiting) writes rows without a sync and leaves the
  header as it was: rows past the header's count are not part of the file until a flush
  counts them;
* reopened at a checkpoint's mark (:meth:`NpyRecorder.reopen`), whole rows already on
  disk after the mark are compared with the recomputed ones instead of written again
  (:class:`~billiard.runfile.csvfile.RowMismatchError` if one differs, before anything is
  written), and a row cut short is dropped; a finished resumed file equals that of an
  uninterrupted run byte for byte.
"""

from __future__ import annotations

import contextlib
import os
import time
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from billiard.runfile.checkpoint import CheckpointError, open_checked
from billiard.runfile.csvfile import (
    RowMismatchError,
    Truncation,
    _open_locked,
    _read_at,
    _ShortWrite,
    _write_all,
    check_recorded,
    crc32_range,
    is_crc32,
    rows_past_flush,
)
from billiard.runfile.npyfile import (
    COLLISIONS,
    Table,
    export_csv,
    header_bytes,
    header_size,
    is_legacy_contacts,
    read_header,
    read_table,
    rows_of_block,
    rows_of_records,
)
from billiard.runfile.rows import NCOL, row_of

__all__ = ["NpyMark", "NpyRecorder", "SideNpy", "check_mark", "check_side_npy"]

#: Wall-clock seconds between flushes of a streamed file (when it flushes by itself).
FLUSH_INTERVAL = 1.0
#: Bytes of rows collected before they are written, synced or not, whatever the time
#: since the last flush (a compiled run makes hundreds of thousands of rows a second).
SPILL_BYTES = 1 << 22


@dataclass(frozen=True)
class NpyMark:
    """A row boundary of a streamed binary file: ``rows`` rows end at byte ``size``
    (header included), and ``crc32`` is the CRC-32 of the rows' bytes (the header, whose
    count changes, left out). A checkpoint stores one."""

    rows: int
    size: int
    crc32: int

    def as_dict(self) -> dict[str, Any]:
        return {"rows": self.rows, "bytes": self.size, "crc32": self.crc32}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> NpyMark:
        rows, size, crc = data.get("rows"), data.get("bytes"), data.get("crc32")
        if not (_is_count(rows) and _is_count(size) and is_crc32(crc)):
            raise CheckpointError("its 'npy' entry is malformed")
        return cls(rows, size, crc)

    def then(self, data: bytes | memoryview, rows: int) -> NpyMark:
        """The mark after ``rows`` more rows, the bytes ``data``."""
        return NpyMark(self.rows + rows, self.size + len(data), zlib.crc32(data, self.crc32))


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _check_header(path: Path, head: bytes, table: Table, expected: Any = None) -> None:
    """Refuse a file whose header is not that of ``table``'s binary file (rows of
    ``expected``, default the table's own dtype)."""
    expected = table.dtype if expected is None else expected
    try:
        dtype, _, offset = read_header(head)
    except ValueError:
        dtype, offset = None, -1
    if expected is table.dtype and dtype is not None and is_legacy_contacts(dtype, table):
        raise CheckpointError(
            f"{path} has other columns than this version writes (written by an earlier "
            f"version: wall as text, no wall_other): it cannot be continued; run the scene "
            f"again without --resume"
        )
    if dtype != expected or offset != header_size(expected):
        raise CheckpointError(
            f"{path} does not start with the header of a binary {table.name} file"
        )


def _check_place(path: Path, mark: NpyMark) -> None:
    """Refuse a mark that is not the end of a row of ``collisions.npy``."""
    if mark.size != header_size(COLLISIONS.dtype) + mark.rows * COLLISIONS.dtype.itemsize:
        raise CheckpointError(
            f"{path}: the checkpoint's place ({mark.size} bytes) is not the end of its "
            f"{mark.rows} impacts"
        )


def check_mark(fd: int, path: Path, mark: NpyMark, *, whole: bool = False) -> None:
    """Check that the binary impact file open as ``fd`` holds what ``mark`` describes:
    the header of ``collisions.npy``, at least the mark's bytes, and the CRC-32 of its
    rows before the mark; with ``whole`` (the last checkpoint of a run that ended), also
    nothing after them and a header that counts them. Nothing is changed.

    Raises:
        CheckpointError: the file differs from what the mark describes (one line naming
            ``path`` and what differs).
    """
    _check_place(path, mark)
    head_size = header_size(COLLISIONS.dtype)
    head = _read_at(fd, head_size, 0)
    _check_header(path, head, COLLISIONS)
    size = os.fstat(fd).st_size
    if size < mark.size:
        raise CheckpointError(
            f"{path} holds {size} bytes, fewer than the {mark.size} bytes of the "
            f"{mark.rows} impacts the checkpoint describes (was it replaced?)"
        )
    if crc32_range(fd, head_size, mark.size) != mark.crc32:
        raise CheckpointError(
            f"{path} does not match the checkpoint (its first {mark.rows} impacts "
            f"were changed since: their CRC-32 differs; was the file edited?)"
        )
    if whole:
        _check_end(path, head, size, mark.size, mark.rows, "impacts")


def _check_end(path: Path, head: bytes, size: int, end: int, rows: int, what: str) -> None:
    """Refuse a finished binary file that goes on after its last checkpointed byte
    ``end`` (of ``rows`` rows) or whose header counts other rows."""
    if size > end:
        raise CheckpointError(
            f"{path} holds {size - end} bytes after the {rows} {what} of the finished "
            f"run its checkpoint describes (was the file edited?)"
        )
    counted = read_header(head)[1]
    if counted != rows:
        raise CheckpointError(
            f"{path}: its header counts {counted} rows, its checkpoint {rows} {what} "
            f"(was the file edited?)"
        )


class NpyRecorder:
    """Impact rows streamed to ``collisions.npy`` as they are produced; nothing but the
    rows since the last flush is kept in memory. Read back with :meth:`columns`.

    The interface of :class:`billiard.runfile.stream.CsvRecorder` (what a streamed run
    and its resume use): a failed write leaves the file with the whole rows that
    reached it, counted in its header, and the recorder writes nothing more.

    Args:
        path: the file; emptied (or created) and given its header at once.
        autoflush: flush on its own at least once a second (a run that checkpoints
            turns this off and flushes before each checkpoint).
        durable: sync each flush to the storage device (``os.fsync``).

    Raises:
        RunBusyError: another process holds the file (a run still going on).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        autoflush: bool = True,
        durable: bool = True,
        _open: tuple[int, NpyMark] | None = None,
    ):
        self.path = Path(path)
        self.table = COLLISIONS
        self.names = COLLISIONS.columns
        self.autoflush = autoflush
        self.durable = durable
        self._itemsize = COLLISIONS.dtype.itemsize
        # the rows since the last write, as the kernels' float64 rows, and the same rows
        # as written: both kept from one write to the next (fresh memory costs a page
        # fault per 4 KiB on first touch, as much again as filling it)
        self._staged = np.empty((1024, NCOL), dtype=np.float64)
        self._pending_rows = 0
        self._buffer = np.empty((0, self._itemsize), dtype=np.uint8)
        self._last_flush = time.monotonic()
        #: the write error that ended writing (None while writes succeed)
        self.failed: OSError | CheckpointError | None = None
        # whole rows already on disk after the mark, compared with the appended ones
        self._check_rows = 0
        if _open is None:
            self._fd: int | None = _open_locked(self.path)
            os.ftruncate(self._fd, 0)
            header = header_bytes(COLLISIONS.dtype, 0)
            try:
                _write_all(self._fd, header)
            except _ShortWrite as short:
                os.close(self._fd)
                raise short.error from None
            if durable:
                os.fsync(self._fd)
            self._mark = NpyMark(0, len(header), 0)
        else:
            self._fd, self._mark = _open
        self._counted = self._mark.rows  # rows the header counts

    @staticmethod
    def header_mark(path: str | os.PathLike[str]) -> NpyMark:
        """The mark of a binary run file's header (no rows).

        Raises:
            CheckpointError: the file is missing or does not start with the header.
        """
        path = Path(path)
        size = header_size(COLLISIONS.dtype)
        try:
            with open(path, "rb") as handle:
                head = handle.read(size)
        except FileNotFoundError:
            raise CheckpointError(f"{path} is missing") from None
        except OSError as exc:
            raise CheckpointError(f"{path} cannot be read: {exc.strerror or exc}") from None
        _check_header(path, head, COLLISIONS)
        return NpyMark(0, size, 0)

    @classmethod
    def reopen(
        cls,
        path: str | os.PathLike[str],
        mark: NpyMark,
        *,
        autoflush: bool = True,
        durable: bool = True,
    ) -> tuple[NpyRecorder, Truncation]:
        """Continue a streamed binary file at ``mark``: check its header and the CRC-32
        of the rows before the mark, and append from there. Whole rows after the mark are
        compared with the appended ones (see the module's note); a row cut short is
        dropped.

        Raises:
            CheckpointError: the file is missing, shorter than the mark, or differs from
                what the mark describes (the file is then left as it was).
            RunBusyError: another process is still writing it.
        """
        path = Path(path)
        if not path.is_file():
            raise CheckpointError(
                f"{path} is missing" if not path.exists() else f"{path} is not a file"
            )
        itemsize = COLLISIONS.dtype.itemsize
        _check_place(path, mark)
        fd = _open_locked(path)
        try:
            check_mark(fd, path, mark)
            size = os.fstat(fd).st_size
            rows, partial = divmod(size - mark.size, itemsize)
            if not rows:
                _cut(fd, mark, durable)
            os.lseek(fd, mark.size, os.SEEK_SET)
        except BaseException:
            os.close(fd)
            raise
        recorder = cls(path, autoflush=autoflush, durable=durable, _open=(fd, mark))
        recorder._check_rows = rows
        # the header counts rows not yet checked, or none past the mark
        recorder._counted = -1 if rows else mark.rows
        return recorder, Truncation(rows, partial)

    @property
    def checking(self) -> bool:
        """Are appended rows still being compared with rows already in the file?"""
        return self._check_rows > 0

    @property
    def rows_on_disk(self) -> int:
        """Whole rows in the file: the flushed (or checked) ones, plus rows still to be
        checked."""
        return self._mark.rows + self._check_rows

    def append(self, row: Sequence[Any]) -> None:
        """Append one impact record (:class:`~billiard.runfile.record.ImpactRecord`)."""
        self.append_rows(np.array([row_of(row)], dtype=np.float64))

    def append_rows(self, block: np.ndarray) -> None:
        """Append impact rows (``(rows, NCOL)`` float64, :mod:`billiard.runfile.rows`)."""
        if self.failed is not None:
            raise self.failed
        block = np.asarray(block, dtype=np.float64).reshape(-1, NCOL)
        if self._check_rows:
            block = self._check_block(block)
            if not len(block):
                return
        start, stop = self._pending_rows, self._pending_rows + len(block)
        if stop > len(self._staged):
            grown = np.empty((max(stop, 2 * len(self._staged)), NCOL), dtype=np.float64)
            grown[:start] = self._staged[:start]
            self._staged = grown
        self._staged[start:stop] = block  # a copy: the caller reuses its array
        self._pending_rows = stop
        if self.autoflush and time.monotonic() - self._last_flush >= FLUSH_INTERVAL:
            self.flush()
        elif self._pending_rows * self._itemsize >= SPILL_BYTES:
            # written, not synced, not counted: the next flush syncs and counts them
            self._write(sync=False, count=False)

    def _check_block(self, block: np.ndarray) -> np.ndarray:
        """Compare the first rows of ``block`` with the rows on disk after the mark;
        returns the rows beyond them (the check then ends)."""
        assert self._fd is not None
        size = self._itemsize
        ahead = block[: self._check_rows]
        data = rows_of_block(ahead).tobytes()
        disk = _read_at(self._fd, len(data), self._mark.size)
        if disk != data:
            same = 0
            while data[same * size : (same + 1) * size] == disk[same * size : (same + 1) * size]:
                same += 1
            if same:
                self._mark = self._mark.then(data[: same * size], same)
            self._check_rows = 0
            self.failed = RowMismatchError(self.path, self._mark.rows + 1)
            raise self.failed
        self._mark = self._mark.then(data, len(ahead))
        self._check_rows -= len(ahead)
        if not self._check_rows:
            self.end_check()
        return block[len(ahead) :]

    def end_check(self) -> None:
        """Stop checking: cut the file after the rows checked so far (dropping rows not
        reached and a row cut short), count them in the header, and write from there."""
        if self._fd is None:
            return
        if self._check_rows or self._counted != self._mark.rows:
            self._check_rows = 0
            _cut(self._fd, self._mark, self.durable)
            self._counted = self._mark.rows
        os.lseek(self._fd, self._mark.size, os.SEEK_SET)

    def flush(self) -> NpyMark:
        """Write the rows collected since the last flush in one system call, sync them
        (when durable), count them in the header, and return the new end of the file.

        Raises:
            OSError: the write or the sync failed (e.g. the disk is full); the file then
                ends with the whole rows that reached it (:attr:`mark`), and nothing
                more is written.
        """
        self._last_flush = time.monotonic()
        return self._write(sync=self.durable, count=not self._check_rows)

    def _write(self, sync: bool, count: bool) -> NpyMark:
        if self.failed is not None:
            raise self.failed
        if self._fd is None:
            raise ValueError(f"{self.path} is closed")
        if self._pending_rows:
            rows = self._pending_rows
            if len(self._buffer) < rows:
                self._buffer = np.empty((len(self._staged), self._itemsize), dtype=np.uint8)
            data = self._buffer[:rows]
            rows_of_block(self._staged[:rows], data)
            data = data.reshape(-1)
            self._pending_rows = 0
            try:
                _write_all(self._fd, data)
            except _ShortWrite as short:
                self._fail(data, short.written, short.error)
            self._mark = self._mark.then(data, rows)
        try:
            if sync:
                os.fsync(self._fd)
            if count and self._counted != self._mark.rows:
                # after the rows are on disk: the header never counts a row that is not
                os.pwrite(self._fd, header_bytes(COLLISIONS.dtype, self._mark.rows), 0)
                if sync:
                    os.fsync(self._fd)
                self._counted = self._mark.rows
        except OSError as exc:
            self.failed = exc
            raise
        return self._mark

    def _fail(self, data: bytes, written: int, error: OSError) -> None:
        """A write failed after ``written`` bytes of ``data``: keep the whole rows among
        them, cut a row cut short, count the rows in the header (rewritten in place, it
        needs no space), write nothing more, and raise ``error``."""
        assert self._fd is not None
        whole = written // self._itemsize
        if whole:
            self._mark = self._mark.then(data[: whole * self._itemsize], whole)
        with contextlib.suppress(OSError):
            os.ftruncate(self._fd, self._mark.size)
            os.pwrite(self._fd, header_bytes(COLLISIONS.dtype, self._mark.rows), 0)
            self._counted = self._mark.rows
        self.failed = error
        raise error

    @property
    def mark(self) -> NpyMark:
        """The end of what has been flushed to the file."""
        return self._mark

    def __len__(self) -> int:
        return self._mark.rows + self._pending_rows

    @property
    def closed(self) -> bool:
        return self._fd is None

    def close(self) -> None:
        """Flush the remaining rows and close the file (idempotent). After a failed
        write, or while rows are still being checked, it only closes the file."""
        if self._fd is None:
            return
        try:
            if self.failed is None and not self._check_rows:
                self.flush()
        finally:
            os.close(self._fd)
            self._fd = None

    def columns(self) -> dict[str, np.ndarray]:
        if self._fd is not None and self.failed is None and not self._check_rows:
            self.flush()
        return read_table(self.path, COLLISIONS)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the impacts as ``collisions.csv`` (the bytes a CSV run writes)."""
        if self._fd is not None and self.failed is None and not self._check_rows:
            self.flush()
        export_csv(self.path, path, COLLISIONS)


def _cut(fd: int, mark: NpyMark, durable: bool) -> None:
    """End the file at ``mark`` and count its rows in the header."""
    os.ftruncate(fd, mark.size)
    os.pwrite(fd, header_bytes(COLLISIONS.dtype, mark.rows), 0)
    if durable:
        os.fsync(fd)


#: Rows of a side table collected before they are written (not synced) whatever the
#: time to the next flush: a long flight sampled finely makes millions of rows.
SIDE_SPILL_ROWS = 1 << 15


class SideNpy:
    """A side table (contacts, samples) streamed to its binary file, buffered until
    :meth:`flush`, with the CRC-32 of its rows (:attr:`crc32`, for a checkpoint): the
    interface of :class:`billiard.runfile.sidecsv.SideCsv`.

    Args:
        path: the file.
        table: :data:`~billiard.runfile.npyfile.CONTACTS` or ``TRAJECTORY``.
        size: None to start the file afresh; else the size (bytes) a checkpoint
            recorded, to which the file is cut back before writing on.
        crc32: with ``size``, the CRC-32 of the rows before it, already checked
            (:func:`check_side_npy`); None to compute it here.
    """

    def __init__(self, path: Path, table: Table, size: int | None = None, crc32: int | None = None):
        self.path = Path(path)
        self.table = table
        self._head = header_size(table.dtype)
        self._pending: list[Sequence[Any]] = []
        self.appended = 0
        if size is None:
            # read as well: a mark before the last rows reads them back (see mark)
            self._file = open(self.path, "w+b")  # noqa: SIM115 - closed by close()
            self._file.write(header_bytes(table.dtype, 0))
            self.crc32 = 0
            self.rows = 0
        else:
            try:
                self._file = open(self.path, "r+b")  # noqa: SIM115
            except FileNotFoundError:
                raise CheckpointError(f"{self.path} is missing") from None
            fd = self._file.fileno()
            if os.fstat(fd).st_size < size or (size - self._head) % table.dtype.itemsize:
                self._file.close()
                raise CheckpointError(f"{self.path} is shorter than its checkpoint says")
            self.crc32 = crc32_range(fd, self._head, size) if crc32 is None else crc32
            self.rows = (size - self._head) // table.dtype.itemsize
            self._file.truncate(size)
            os.pwrite(fd, header_bytes(table.dtype, self.rows), 0)
            self._file.seek(size)
        self._counted = self.rows
        #: (rows appended, size, CRC-32) at the last flush: where mark reads from
        self._flushed = (0, self._head + self.rows * table.dtype.itemsize, self.crc32)

    def append(self, row: Sequence[Any]) -> None:
        self._pending.append(row)
        self.appended += 1
        if len(self._pending) >= SIDE_SPILL_ROWS:
            # written, not synced: a resume cuts the file back to its checkpoint's size
            self._write()

    def _write(self) -> None:
        if self._pending:
            data = rows_of_records(self._pending, self.table).tobytes()
            self._file.write(data)
            self.crc32 = zlib.crc32(data, self.crc32)
            self.rows += len(self._pending)
            self._pending.clear()

    def flush(self) -> int:
        """Write the buffered rows, sync them, count them in the header; returns the
        file's size (bytes)."""
        self._write()
        self._file.flush()
        fd = self._file.fileno()
        os.fsync(fd)
        if self._counted != self.rows:
            os.pwrite(fd, header_bytes(self.table.dtype, self.rows), 0)
            os.fsync(fd)
            self._counted = self.rows
        size = self._file.tell()
        self._flushed = (self.appended, size, self.crc32)
        return size

    def mark(self, rows: int | None = None) -> tuple[int, int]:
        """:meth:`billiard.runfile.sidecsv.SideCsv.mark`: (size in bytes, CRC-32 of the
        rows) of the file up to the first ``rows`` rows appended since it was opened
        (default all), all rows written and synced. The header counts every row
        written; a resume cuts the file back to the size and counts again."""
        done, size, crc = self._flushed
        end = self.flush()
        past = rows_past_flush(done, self.appended, rows)
        if past is None:
            return end, self.crc32
        stop = size + past * self.table.dtype.itemsize
        return stop, crc32_range(self._file.fileno(), size, stop, crc)

    def close(self) -> None:
        if not self._file.closed:
            self.flush()
            self._file.close()


def check_side_npy(
    path: Path,
    table: Table,
    size: int,
    crc32: int | None,
    end: tuple[int, int] | None = None,
    *,
    current: bool = True,
) -> int:
    """Check that the binary side file ``path`` still holds the ``size`` bytes its
    checkpoint recorded, unchanged (the CRC-32 of its rows is ``crc32``), without
    changing it: before a run resumes, and when a run is opened. ``end`` (the last
    checkpoint of a run that ended): the file's whole length and the CRC-32 of all its
    rows, the phase its end cut included; the file must end there, its header counting
    them. ``current``: the rows must be this version's (a resume appends to them); else
    contacts written before ``wall`` was an integer are checked as they are (a reader
    converts them).

    Returns:
        The number of rows in the first ``size`` bytes.

    Raises:
        CheckpointError: the file is missing, not a regular file, not a binary file of
            ``table``, shorter than ``size``, or its rows before it were changed; with
            ``end``, it differs after ``size`` or goes on after ``end``.
    """
    fd = open_checked(path)
    dtype = table.dtype
    try:
        if not current:
            with contextlib.suppress(ValueError):
                found = read_header(_read_at(fd, 1 << 12, 0))[0]
                if is_legacy_contacts(found, table):
                    dtype = found
        head_size = header_size(dtype)
        head = _read_at(fd, head_size, 0)
        _check_header(path, head, table, dtype)
        length = os.fstat(fd).st_size
        if length < size or size < head_size:
            raise CheckpointError(f"{path} is shorter than its checkpoint says")
        rows, rest = divmod(size - head_size, dtype.itemsize)
        if rest:
            raise CheckpointError(f"{path}: the checkpoint's size is not the end of a row")
        crc = crc32_range(fd, head_size, size)
        check_recorded(path, fd, crc, crc32, size, None)
        if end is not None:
            total, rest = divmod(end[0] - head_size, dtype.itemsize)
            if rest:
                raise CheckpointError(f"{path} is shorter than its checkpoint says")
            check_recorded(path, fd, crc, None, size, end)
            _check_end(path, head, length, end[0], total, "rows")
    finally:
        os.close(fd)
    return rows
