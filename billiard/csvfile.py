"""A streamed run file on disk: the marks of its row boundaries (:class:`CsvMark`), what
reopening it at a mark found (:class:`Truncation`), its exclusive lock, and the whole
writes, reads and line scans :class:`billiard.stream.CsvRecorder` makes of it.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from billiard.checkpoint import CheckpointError

try:  # advisory file locks (POSIX); elsewhere two processes are not kept apart
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]


__all__ = ["CsvMark", "RowMismatchError", "RunBusyError", "Truncation"]


@dataclass(frozen=True)
class CsvMark:
    """A row boundary of a streamed CSV file: ``rows`` data rows occupy the first
    ``size`` bytes, the last of which form ``last_line`` (the header when rows = 0,
    line terminator included). A checkpoint stores one to find its place in the file."""

    rows: int
    size: int
    last_line: str

    def as_dict(self) -> dict[str, Any]:
        return {"rows": self.rows, "bytes": self.size, "last_line": self.last_line}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> CsvMark:
        rows, size, line = data.get("rows"), data.get("bytes"), data.get("last_line")
        if not (
            _is_count(rows) and _is_count(size) and isinstance(line, str) and line.endswith("\n")
        ):
            raise CheckpointError("its 'csv' entry is malformed")
        return cls(rows, size, line)


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


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
