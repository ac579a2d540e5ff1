"""Impact records: one row per impact, kept in memory or streamed to a CSV file; and the
checkpoint file that lets a streamed run continue after an interruption.

Columns (the first thirteen, in this order, are a contract for plots and analyses):

=========  ===============================================================================
n          impact index, 1-based
t          impact time (s)
q1, q2     centre position in the lab frame at the impact (m)
v1, v2     centre velocity just after the impact (m/s)
omega      spin just after the impact (rad/s, counter-clockwise positive)
u4, un     centre velocity just after the impact along c1 (the paper's u4) and c2 (m/s)
tof        time since the previous impact (s); for n = 1 the time since the start
regime     ``stick``, ``slip`` or ``elastic`` (the low-velocity rule)
z          tangent angle of the boundary at the contact (rad; pi for the lid)
energy     mechanical energy just after the impact (J), potential zero at q2 = 0
wall       index of the wall hit (``0``, ``1``, ...) or ``lid``
Rt, Rn     impulse on the ball along c1 and c2 (N s)
s          abscissa of the contact point in the boundary frame (m)
q3         rotation angle of the ball (rad), the integral of the spin
=========  ===============================================================================

Floats are written with :func:`repr`, so a CSV file reads back bit for bit.

A streamed file only ever grows by whole rows: rows are collected in memory and written
with one system call per flush (at least once a second), then synced to disk. A process
killed in the middle of that call can leave an unterminated last line; readers here skip
it, and resuming the run (:func:`billiard.simulate.resume`) cuts the file back to the
checkpoint's row.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import os
import shutil
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

try:  # advisory file locks (POSIX); elsewhere two processes are not kept apart
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "COLUMNS",
    "CheckpointError",
    "CsvMark",
    "CsvRecorder",
    "MemoryRecorder",
    "RunBusyError",
    "read_checkpoint",
    "read_collisions",
    "write_checkpoint",
    "write_text_atomic",
]

COLUMNS: tuple[str, ...] = (
    "n",
    "t",
    "q1",
    "q2",
    "v1",
    "v2",
    "omega",
    "u4",
    "un",
    "tof",
    "regime",
    "z",
    "energy",
    "wall",
    "Rt",
    "Rn",
    "s",
    "q3",
)
_TEXT = frozenset({"regime", "wall"})
_INTEGER = frozenset({"n"})
FLUSH_INTERVAL = 1.0  # s of wall-clock time between flushes of a streamed file

#: ``format`` and ``version`` fields of a checkpoint file.
CHECKPOINT_FORMAT = "billiard-checkpoint"
CHECKPOINT_VERSION = 1


class CheckpointError(ValueError):
    """A run directory cannot be resumed: the checkpoint is missing, corrupt or does not
    match the CSV file or the scene. The message is one line."""


def _as_arrays(columns: dict[str, list[Any]]) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, values in columns.items():
        if name in _TEXT:
            out[name] = np.array(values, dtype=str)
        elif name in _INTEGER:
            out[name] = np.array(values, dtype=np.int64)
        else:
            out[name] = np.array(values, dtype=np.float64)
    return out


def _format(value: Any) -> str:
    return repr(value) if isinstance(value, float) else str(value)


class MemoryRecorder:
    """Rows kept in memory, column by column."""

    def __init__(self, columns: Sequence[str] = COLUMNS):
        self.names = tuple(columns)
        self._data: list[list[Any]] = [[] for _ in self.names]

    def append(self, row: Sequence[Any]) -> None:
        for column, value in zip(self._data, row, strict=True):
            column.append(value)

    def __len__(self) -> int:
        return len(self._data[0])

    def close(self) -> None:
        pass

    def columns(self) -> dict[str, np.ndarray]:
        return _as_arrays(dict(zip(self.names, self._data, strict=True)))

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        with open(path, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(self.names)
            for row in zip(*self._data, strict=True):
                writer.writerow([_format(v) for v in row])


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
    """What reopening a CSV file at a mark cut off: complete rows written after the
    mark, and the bytes of an unterminated last line (0 when the file ended cleanly)."""

    rows: int
    partial_bytes: int


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        written = os.write(fd, view)
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


class CsvRecorder:
    """Rows streamed to a CSV file as they are produced; nothing but the rows since the
    last flush is kept in memory, so long runs stay flat. Read back with :meth:`columns`.

    Args:
        path: the file; emptied (or created) and given its header at once.
        columns: column names.
        autoflush: flush on its own at least once a second. A run that checkpoints
            turns this off and calls :meth:`flush` itself, so that what is on disk is
            always exactly what a checkpoint describes.
        durable: sync each flush to the storage device (``os.fsync``), so that rows
            said to be kept survive a crash of the machine too, not only of the process.

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
        _open: tuple[int, CsvMark] | None = None,
    ):
        self.path = Path(path)
        self.names = tuple(columns)
        self.autoflush = autoflush
        self.durable = durable
        self._pending = io.StringIO()
        self._writer = csv.writer(self._pending)
        self._pending_rows = 0
        self._last_flush = time.monotonic()
        if _open is None:
            self._fd: int | None = _open_locked(self.path)
            os.ftruncate(self._fd, 0)
            header = _header_line(self.names)
            data = header.encode("utf-8")
            _write_all(self._fd, data)
            if durable:
                os.fsync(self._fd)
            self._mark = CsvMark(0, len(data), header)
        else:
            self._fd, self._mark = _open

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
        and, at the mark, the expected last line; cut off everything after the mark (rows
        written after the checkpoint and any unterminated last line); append from there.

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
        header = _header_line(columns).encode()
        line = mark.last_line.encode()
        fd = _open_locked(path)
        try:
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
            tail = _read_at(fd, size - mark.size, mark.size)
            if tail:
                os.ftruncate(fd, mark.size)
                os.fsync(fd)
            os.lseek(fd, mark.size, os.SEEK_SET)
        except BaseException:
            os.close(fd)
            raise
        cut = Truncation(tail.count(b"\n"), len(tail) - (tail.rfind(b"\n") + 1))
        recorder = cls(path, columns, autoflush=autoflush, durable=durable, _open=(fd, mark))
        return recorder, cut

    def append(self, row: Sequence[Any]) -> None:
        self._writer.writerow([_format(v) for v in row])
        self._pending_rows += 1
        if self.autoflush:
            # wall-clock time decides only when bytes reach the disk, never what they are
            now = time.monotonic()
            if now - self._last_flush >= FLUSH_INTERVAL:
                self.flush()

    def flush(self) -> CsvMark:
        """Write the rows collected since the last flush in one system call, sync them
        (when durable), and return the new end of the file."""
        self._last_flush = time.monotonic()
        text = self._pending.getvalue()
        if not text:
            return self._mark
        if self._fd is None:
            raise ValueError(f"{self.path} is closed")
        data = text.encode("utf-8")
        _write_all(self._fd, data)
        if self.durable:
            os.fsync(self._fd)
        # the last line of what was just written (every row ends with "\r\n")
        start = text.rfind("\n", 0, len(text) - 1) + 1
        self._mark = CsvMark(
            self._mark.rows + self._pending_rows, self._mark.size + len(data), text[start:]
        )
        self._pending.seek(0)
        self._pending.truncate()
        self._pending_rows = 0
        return self._mark

    @property
    def mark(self) -> CsvMark:
        """The end of what has been flushed to the file."""
        return self._mark

    def __len__(self) -> int:
        return self._mark.rows + self._pending_rows

    @property
    def closed(self) -> bool:
        return self._fd is None

    def close(self) -> None:
        """Flush the remaining rows and close the file (idempotent)."""
        if self._fd is None:
            return
        try:
            self.flush()
        finally:
            os.close(self._fd)
            self._fd = None

    def columns(self) -> dict[str, np.ndarray]:
        if self._fd is not None:
            self.flush()
        return read_collisions(self.path)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if self._fd is not None:
            self.flush()
        if Path(path).resolve() != self.path.resolve():
            shutil.copyfile(self.path, path)


def _header_line(columns: Sequence[str]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer).writerow(columns)
    return buffer.getvalue()


def _complete_lines(lines: Iterable[str]) -> Iterator[str]:
    """The lines that end with a line terminator: an unterminated last line is the
    remains of an interrupted write, not a row."""
    for line in lines:
        if line.endswith("\n"):
            yield line


def read_collisions(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a collisions CSV written by a run into numpy arrays, one per column. An
    unterminated last line (a write cut short by a kill) is skipped."""
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.reader(_complete_lines(handle))
        names = next(reader)
        data: list[list[Any]] = [[] for _ in names]
        convert = [str if name in _TEXT else int if name in _INTEGER else float for name in names]
        for row in reader:
            for column, conv, value in zip(data, convert, row, strict=True):
                column.append(conv(value))
    return _as_arrays(dict(zip(names, data, strict=True)))


# ----------------------------------------------------------------------------------
# atomic files and checkpoints


def _fsync_directory(directory: Path) -> None:
    """Make a rename in ``directory`` durable (best effort: not every platform or file
    system lets a directory be opened)."""
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Replace ``path`` by ``text`` atomically: a reader (or a crash) sees the old file
    or the new one, never a mixture (temporary file in the same directory, synced, then
    ``os.replace``)."""
    path = Path(path)
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(temp, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temp.unlink()
        raise
    _fsync_directory(path.parent)


def _checksum(body: Mapping[str, Any]) -> str:
    canonical = json.dumps(body, sort_keys=True, allow_nan=False, separators=(",", ":"))
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def write_checkpoint(path: str | os.PathLike[str], body: Mapping[str, Any]) -> None:
    """Write a checkpoint atomically: ``body`` plus format, version and a checksum.

    Floats are written by :mod:`json` with :func:`repr`, which reads back to the same
    double, so an engine state survives the round trip bit for bit. Non-finite floats
    are refused (``ValueError``): they have no JSON spelling.
    """
    data = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, **body}
    data["sha256"] = _checksum(data)
    text = json.dumps(data, indent=1, allow_nan=False) + "\n"
    write_text_atomic(path, text)


def read_checkpoint(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and verify a checkpoint written by :func:`write_checkpoint`.

    Raises:
        CheckpointError: the file is missing, unreadable, not JSON, of another format
            or version, or fails its checksum.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CheckpointError(f"{path} is missing") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CheckpointError(f"{path} cannot be read: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CheckpointError(f"{path} is corrupt (not valid JSON: {exc})") from None
    if not isinstance(data, dict) or data.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not a billiard checkpoint")
    if data.get("version") != CHECKPOINT_VERSION:
        raise CheckpointError(
            f"{path} has checkpoint version {data.get('version')!r}; this version of "
            f"billiard reads version {CHECKPOINT_VERSION}"
        )
    stored = data.pop("sha256", None)
    try:
        expected = _checksum(data)
    except ValueError:
        expected = None
    if stored != expected:
        raise CheckpointError(f"{path} is corrupt (its checksum does not match its content)")
    return data
