"""The sweep folder: its definition, and every finished chunk of points appended durably.

``DIR/sweep.toml`` and ``DIR/scene.toml``
    the sweep's definition, written before the first point (``--resume DIR`` reads them).
``DIR/sweep.sha256``
    the SHA-256 of both, in ``sha256sum`` format, written with them: a resume refuses a
    definition edited since the sweep started (its points would mix two sweeps).
``DIR/points.npy``
    one row per finished point (the packed row of
    :func:`billiard.sweep.columns.disk_dtype`: 96 bytes plus 16 bytes per kept impact),
    in the order chunks finish; NumPy's ``.npy`` format with a fixed-size header, read by
    ``numpy.load(path, mmap_mode="r")``. A chunk's rows are written whole and synced
    (``fsync``), and only then is the row count in the header rewritten in place (and
    synced): one sync per chunk, never per point. A kill during a write leaves rows past
    the header's count, which are cut off on resume: at most the chunk being written is
    lost. (The header and row format are those of the run files,
    :mod:`billiard.runfile.npyfile`.)
``DIR/reasons.jsonl``
    one JSON line ``{"index": I, "reason": "..."}`` per point that failed or was invalid
    (written and synced before its chunk's rows; a line whose point is not counted in
    points.npy is ignored, a partial last line cut off).
``DIR/sweep.log``
    timings and progress (the only file with wall-clock times).

Only one process may write a sweep folder at a time (an ``flock`` on points.npy).
Finished points are not kept in memory: the store holds one byte per point of the grid
(finished or not), and the result is built from points.npy, mapped.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from billiard.runfile.npyfile import Table, header_bytes, header_size, open_rows, read_header
from billiard.runfile.record import RunDataError
from billiard.sweep.columns import ChunkResult, disk_dtype

__all__ = [
    "DIGEST_NAME",
    "LEGACY_POINTS_NAME",
    "LOG_NAME",
    "POINTS_NAME",
    "REASONS_NAME",
    "SCENE_NAME",
    "SWEEP_NAME",
    "ChunkStore",
    "StoreError",
    "points_table",
    "iter_rows",
    "read_reasons",
]

SWEEP_NAME = "sweep.toml"
SCENE_NAME = "scene.toml"
POINTS_NAME = "points.npy"
REASONS_NAME = "reasons.jsonl"
LOG_NAME = "sweep.log"
DIGEST_NAME = "sweep.sha256"
#: The points file of sweeps made before points.npy (one JSON line per point).
LEGACY_POINTS_NAME = "points.jsonl"

#: Longest line of reasons.jsonl read (bytes): a longer line is a damaged file.
MAX_LINE = 1 << 20


class StoreError(Exception):
    """A sweep folder that cannot be used; one-line message."""


def points_table(keep: int) -> Table:
    """The table of ``points.npy`` for a sweep keeping ``keep`` impacts."""
    dtype = disk_dtype(keep)
    return Table("points", "", POINTS_NAME, tuple(dtype.names or ()), dtype)


#: Rows read at a time by :func:`iter_rows`.
BLOCK_ROWS = 1 << 15


def iter_rows(fd: int, dtype: np.dtype, rows: int, block: int = BLOCK_ROWS) -> Iterator[np.ndarray]:
    """The first ``rows`` rows of the points file open as ``fd``, ``block`` rows at a
    time (read, not mapped)."""
    head = header_size(dtype)
    for start in range(0, rows, block):
        count = min(block, rows - start)
        data = os.pread(fd, count * dtype.itemsize, head + start * dtype.itemsize)
        if len(data) != count * dtype.itemsize:
            raise StoreError(f"points file: {rows} rows counted, fewer on disk (cut short?)")
        yield np.frombuffer(data, dtype=dtype)


def _lines(path: Path) -> Iterator[tuple[bytes, int]]:
    """Each whole line of a text file with the byte offset just after it; a partial last
    line (from a kill) ends the iteration."""
    if not path.exists():
        return
    offset = 0
    with open(path, "rb") as f:
        number = 0
        while True:
            line = f.readline(MAX_LINE + 1)
            if not line.endswith(b"\n"):
                if len(line) > MAX_LINE:
                    raise StoreError(f"{path}: line {number + 1} is longer than any reason")
                return
            number += 1
            offset += len(line)
            yield line, offset


def read_reasons(path: Path, done: bytearray | None = None) -> Iterator[tuple[int, str]]:
    """(index, reason) of each line of a reasons file, in file order (a later line of the
    same point repeats the earlier one); with ``done``, only the points marked there."""
    for number, (line, _) in enumerate(_lines(path), start=1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
            index, reason = int(entry["index"]), str(entry["reason"])
        except (ValueError, KeyError, TypeError):
            raise StoreError(f"{path}: line {number} is not a point's reason") from None
        if done is None or (0 <= index < len(done) and done[index]):
            yield index, reason


def digest_lines(contents: dict[str, bytes]) -> str:
    """``sha256sum`` lines (``HEX  NAME``) of file contents, by name."""
    return "".join(
        f"{hashlib.sha256(data).hexdigest()}  {name}\n" for name, data in contents.items()
    )


def definition_digest(directory: Path) -> str:
    """``sha256sum`` lines of the folder's sweep.toml and scene.toml, as they are now."""
    names = (SWEEP_NAME, SCENE_NAME)
    return digest_lines({name: (directory / name).read_bytes() for name in names})


class ChunkStore:
    """Appends finished chunks to ``DIR/points.npy`` (durably), their reasons to
    ``DIR/reasons.jsonl``, and lines to the log.

    Args:
        directory: the sweep folder.
        size: points in the sweep.
        keep: impacts kept per point (the rows' tails).

    Attributes:
        done: one byte per point of the sweep, 1 once the point is stored.
        count: points stored.

    Raises:
        StoreError: another process writes the folder, or its points file is not this
            sweep's (another row type, a point outside the sweep).
    """

    def __init__(self, directory: Path, size: int, keep: int):
        self.directory = directory
        self.path = directory / POINTS_NAME
        self.table = points_table(keep)
        self.dtype = self.table.dtype
        self.head = header_size(self.dtype)
        directory.mkdir(parents=True, exist_ok=True)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        self.reasons_fd = -1
        self.log_file: Any = None
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(self.fd)
            raise StoreError(f"another sweep is writing {directory}") from None
        try:
            self.done = bytearray(size)
            self.count = 0
            self.rows = self._open_rows(size)
            self._open_reasons()
        except BaseException:
            self.close()
            raise
        self.log_file = open(directory / LOG_NAME, "a", encoding="utf-8")  # noqa: SIM115

    def _open_rows(self, size: int) -> int:
        """Check the file's header, cut rows past its count (a chunk being written when
        the sweep was killed) and mark the stored points; returns the rows."""
        length = os.fstat(self.fd).st_size
        if length == 0:  # a new file
            self._write(header_bytes(self.dtype, 0))
            os.fsync(self.fd)
            return 0
        try:
            dtype, rows, offset = read_header(os.pread(self.fd, self.head, 0))
        except ValueError as exc:
            raise StoreError(f"{self.path} is not a sweep's points file ({exc})") from None
        if dtype != self.dtype or offset != self.head:
            raise StoreError(
                f"{self.path} holds rows of another kind than this sweep's (another --keep?)"
            )
        end = self.head + rows * self.dtype.itemsize
        if length < end:
            raise StoreError(f"{self.path} holds fewer rows than its header counts (cut?)")
        if length > end:  # a chunk's rows written, not yet counted: cut off
            os.ftruncate(self.fd, end)
            os.fsync(self.fd)
        for block in iter_rows(self.fd, self.dtype, rows):
            index = np.asarray(block["index"], dtype=np.int64)
            if index.size and (index.min() < 0 or index.max() >= size):
                bad = int(index[(index < 0) | (index >= size)][0])
                raise StoreError(f"{self.path}: point {bad} is not in the sweep (0 to {size - 1})")
            self._mark(index)
        os.lseek(self.fd, end, os.SEEK_SET)
        return rows

    def _open_reasons(self) -> None:
        path = self.directory / REASONS_NAME
        end = 0
        for _, offset in _lines(path):
            end = offset
        self.reasons_fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        if os.fstat(self.reasons_fd).st_size != end:  # cut off a partial last line
            os.ftruncate(self.reasons_fd, end)
            os.fsync(self.reasons_fd)
        os.lseek(self.reasons_fd, end, os.SEEK_SET)

    def _mark(self, indices: np.ndarray) -> None:
        done = np.frombuffer(self.done, dtype=np.uint8)
        indices = np.asarray(indices, dtype=np.int64)
        self.count += int(np.count_nonzero(done[indices] == 0))
        done[indices] = 1

    def __contains__(self, index: int) -> bool:
        return bool(self.done[index])

    @staticmethod
    def _write_fd(fd: int, data: bytes | memoryview) -> None:
        view = memoryview(data).cast("B")
        while len(view):
            view = view[os.write(fd, view) :]

    def _write(self, data: bytes | memoryview) -> None:
        self._write_fd(self.fd, data)

    def append(self, chunk: ChunkResult) -> None:
        """Store a chunk: its reasons (synced), its rows (synced), then the row count."""
        if not len(chunk):
            return
        if chunk.reasons:
            text = "".join(
                json.dumps({"index": int(i), "reason": r}) + "\n"
                for i, r in sorted(chunk.reasons.items())
            )
            self._write_fd(self.reasons_fd, text.encode("utf-8"))
            os.fsync(self.reasons_fd)
        rows = chunk.rows(self.dtype["last_height"].shape[0])
        self._write(memoryview(rows.tobytes()))
        os.fsync(self.fd)
        self.rows += len(rows)
        # after the rows are on disk: the header never counts a row that is not
        os.pwrite(self.fd, header_bytes(self.dtype, self.rows), 0)
        os.fsync(self.fd)
        self._mark(rows["index"])

    def stored(self) -> np.ndarray:
        """The stored rows, mapped read-only (in the order they were stored)."""
        try:
            return open_rows(self.path, self.table)
        except RunDataError as exc:
            raise StoreError(str(exc)) from None

    def blocks(self) -> Iterator[np.ndarray]:
        """The stored rows, read a block at a time (in the order they were stored; no
        mapping left behind: memory is one block)."""
        return iter_rows(self.fd, self.dtype, self.rows)

    def reasons(self) -> Iterator[tuple[int, str]]:
        """(index, reason) of the stored points not ``ok`` (read from the file)."""
        return read_reasons(self.directory / REASONS_NAME, self.done)

    def log(self, message: str) -> None:
        self.log_file.write(f"{time.strftime('%Y-%m-%d %H:%M:%S')} {message}\n")
        self.log_file.flush()

    def close(self) -> None:
        for name in ("fd", "reasons_fd"):
            fd = getattr(self, name)
            if fd >= 0:
                os.close(fd)
                setattr(self, name, -1)
        if self.log_file is not None:
            self.log_file.close()

    def __enter__(self) -> ChunkStore:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
