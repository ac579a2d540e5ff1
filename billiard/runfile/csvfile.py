"""A streamed run file on disk: the marks of its row boundaries (:class:`CsvMark`), what
reopening it at a mark found (:class:`Truncation`), its exclusive lock, and the whole
writes, reads and line scans :class:`billiard.runfile.stream.CsvRecorder` makes of it.
"""

from __future__ import annotations

import os
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from billiard.runfile.checkpoint import CheckpointError

try:  # advisory file locks (POSIX); elsewhere two processes are not kept apart
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]


__all__ = ["CsvMark", "RowMismatchError", "RunBusyError", "Truncation", "crc32_range"]


@dataclass(frozen=True)
class CsvMark:
    """A row boundary of a streamed CSV file: ``rows`` data rows occupy the first
    ``size`` bytes, the last of which form ``last_line`` (the header when rows = 0,
    line terminator included), and ``crc32`` is the CRC-32 of those bytes (None when
    unknown: a checkpoint of an earlier version). A checkpoint stores one to find its
    place in the file and to tell that nothing before it was changed."""

    rows: int
    size: int
    last_line: str
    crc32: int | None = None

    def as_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = {"rows": self.rows, "bytes": self.size, "last_line": self.last_line}
        if self.crc32 is not None:
            data["crc32"] = self.crc32
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> CsvMark:
        rows, size, line = data.get("rows"), data.get("bytes"), data.get("last_line")
        crc = data.get("crc32")
        if not (
            _is_count(rows) and _is_count(size) and isinstance(line, str) and line.endswith("\n")
        ) or not (crc is None or is_crc32(crc)):
            raise CheckpointError("its 'csv' entry is malformed")
        return cls(rows, size, line, crc)

    def then(self, data: bytes | bytearray | memoryview, rows: int, last_line: str) -> CsvMark:
        """The mark after ``rows`` more rows, the bytes ``data``."""
        crc = None if self.crc32 is None else zlib.crc32(data, self.crc32)
        return CsvMark(self.rows + rows, self.size + len(data), last_line, crc)


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def is_crc32(value: Any) -> bool:
    """A CRC-32 as a checkpoint stores it: an int in [0, 2^32)."""
    return _is_count(value) and value < 1 << 32


def prefix_crc32(fd: int, size: int) -> tuple[int, int]:
    """(CRC-32, number of line ends) of the first ``size`` bytes of the open file ``fd``
    (fewer when the file is shorter), read in chunks: a checkpoint's check of what a
    file holds before it."""
    lines = 0

    def count(chunk: bytes) -> None:
        nonlocal lines
        lines += chunk.count(b"\n")

    crc = crc32_range(fd, 0, size, each=count)
    return crc, lines


def crc32_range(
    fd: int, start: int, stop: int, crc: int = 0, each: Callable[[bytes], object] | None = None
) -> int:
    """The CRC-32 ``crc`` continued over the bytes ``start .. stop`` of the open file
    ``fd`` (fewer when the file is shorter), read in chunks of 1 MiB (``each`` is given
    every chunk too). A running CRC-32 continues from its value, so a checkpoint's
    checksum of a file that grows by appending is extended without reading it again."""
    offset = start
    while offset < stop:
        chunk = _read_at(fd, min(_SCAN_CHUNK, stop - offset), offset)
        if not chunk:
            break
        crc = zlib.crc32(chunk, crc)
        if each is not None:
            each(chunk)
        offset += len(chunk)
    return crc


def check_recorded(
    path: Path, fd: int, crc: int, crc32: int | None, size: int, end: tuple[int, int] | None
) -> None:
    """Compare the open file ``fd`` (``path``) with what a checkpoint recorded of it:
    ``crc``, the CRC-32 of its bytes before the checkpoint's place ``size``, against the
    recorded ``crc32`` (None: not recorded, by an earlier version); with ``end`` (the
    last checkpoint of a run that ended: its whole length and CRC-32), the bytes from
    ``size`` to there too.

    Raises:
        CheckpointError: the file is shorter than recorded, or bytes were changed.
    """
    if crc32 is not None and crc != crc32:
        raise CheckpointError(
            f"{path} does not match the checkpoint (its rows before it were changed "
            f"since: their CRC-32 differs; was the file edited?)"
        )
    if end is not None:
        stop, final = end
        if stop < size or os.fstat(fd).st_size < stop:
            raise CheckpointError(f"{path} is shorter than its checkpoint says")
        if crc32_range(fd, size, stop, crc) != final:
            raise CheckpointError(
                f"{path} does not match the checkpoint (its last rows were changed "
                f"since: their CRC-32 differs; was the file edited?)"
            )


def rows_past_flush(flushed: int, appended: int, rows: int | None) -> int | None:
    """For a side file's mark after the first ``rows`` rows appended since it was opened
    (``SideCsv.mark``, ``SideNpy.mark``): how many rows after those of the last flush
    (``flushed`` of ``appended`` rows) it lies, or None at the end of the file.

    Raises:
        ValueError: ``rows`` is before the last flush or after the last row.
    """
    if rows is None or rows == appended:
        return None
    if not flushed <= rows < appended:
        raise ValueError(f"no mark after {rows} rows: {flushed} to {appended} can be marked")
    return rows - flushed


@dataclass(frozen=True)
class Truncation:
    """What reopening a CSV file at a mark found after it: complete rows written after
    the mark (a kill or a failed write between a flush and its checkpoint leaves them;
    they are checked against the recomputed rows and kept), and the bytes of an
    unterminated last line, which are dropped (0 when the file ended cleanly)."""

    rows: int
    partial_bytes: int


class _ShortWrite(Exception):
    """A write that failed after ``written`` bytes reached the file."""

    def __init__(self, written: int, error: OSError):
        super().__init__(written, error)
        self.written = written
        self.error = error


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    done = 0
    while view:
        try:
            written = os.write(fd, view)
        except OSError as exc:
            raise _ShortWrite(done, exc) from exc
        done += written
        view = view[written:]


def _read_at(fd: int, size: int, offset: int) -> bytes:
    chunks = []
    while size > 0:
        chunk = os.pread(fd, size, offset)
        if not chunk:
            break
        chunks.append(chunk)
        size -= len(chunk)
        offset += len(chunk)
    return b"".join(chunks)


class RunBusyError(CheckpointError):
    """Another process is writing the same run file."""


class RowMismatchError(CheckpointError):
    """A row already in a run file differs from the same impact recomputed on resume:
    the file is not (a prefix of) this run. Nothing was written to the file."""

    def __init__(self, path: Path, impact: int):
        super().__init__(
            f"{path}: impact {impact} on disk differs from the same impact recomputed "
            f"(was the file edited or replaced?)"
        )
        self.path = path
        self.impact = impact


_SCAN_CHUNK = 1 << 20


def _scan_rows(fd: int, start: int, end: int) -> tuple[int, int]:
    """(number of whole lines, end of the last whole line) of the bytes [start, end)."""
    rows, whole, offset = 0, start, start
    while offset < end:
        chunk = _read_at(fd, min(_SCAN_CHUNK, end - offset), offset)
        if not chunk:
            break
        rows += chunk.count(b"\n")
        last = chunk.rfind(b"\n")
        if last >= 0:
            whole = offset + last + 1
        offset += len(chunk)
    return rows, whole


def _open_locked(path: Path) -> int:
    """Open ``path`` for writing (created if missing, not truncated) and take an exclusive
    advisory lock on it, so that two processes never write one run; the lock goes with
    the descriptor, also when the process is killed."""
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise RunBusyError(f"{path} is being written by another process") from None
    return fd
