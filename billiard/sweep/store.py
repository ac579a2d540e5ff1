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
``DIR/checksums.json``
    the commit of each chunk, written atomically after its rows and their count: how
    many rows of points.npy and bytes of reasons.jsonl are stored, and the CRC-32 of
    each (continued chunk by chunk from the stored value: nothing is read again). Opening
    the folder again (a resume) reads both files once and refuses one that differs
    (:class:`StoreError` naming the file); what follows the committed bytes (a chunk
    whose commit a kill prevented) is cut off. A folder of a sweep started before the
    checksums has none: it is resumed unverified, said once (:attr:`ChunkStore.unverified`),
    and the checksums are written from then on.
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
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from billiard.errors import UnverifiedDataWarning
from billiard.runfile.checkpoint import write_text_atomic
from billiard.runfile.csvfile import crc32_range, is_crc32
from billiard.runfile.npyfile import Table, header_bytes, header_size, open_rows, read_header
from billiard.runfile.record import RunDataError
from billiard.sweep.columns import ChunkResult, disk_dtype

__all__ = [
    "CHECKSUMS_NAME",
    "DIGEST_NAME",
    "LEGACY_POINTS_NAME",
    "LOG_NAME",
    "POINTS_NAME",
    "REASONS_NAME",
    "SCENE_NAME",
    "SWEEP_NAME",
    "ChunkStore",
    "StoreError",
    "UnverifiedSweepWarning",
    "points_table",
    "iter_rows",
    "read_reasons",
    "stored_points",
]

SWEEP_NAME = "sweep.toml"
SCENE_NAME = "scene.toml"
POINTS_NAME = "points.npy"
REASONS_NAME = "reasons.jsonl"
LOG_NAME = "sweep.log"
DIGEST_NAME = "sweep.sha256"
CHECKSUMS_NAME = "checksums.json"
#: ``format`` and ``version`` of checksums.json.
CHECKSUMS_FORMAT = "billiard-sweep-checksums"
CHECKSUMS_VERSION = 1
#: Largest checksums.json read (bytes): it holds four numbers.
MAX_CHECKSUMS_BYTES = 1 << 12
#: The points file of sweeps made before points.npy (one JSON line per point).
LEGACY_POINTS_NAME = "points.jsonl"

#: Longest line of reasons.jsonl read (bytes): a longer line is a damaged file.
MAX_LINE = 1 << 20


class StoreError(Exception):
    """A sweep folder that cannot be used; one-line message."""


class UnverifiedSweepWarning(UnverifiedDataWarning):
    """A sweep folder resumed without its stored points checked: it was written before
    its checksums.json."""


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


@dataclass(frozen=True)
class Committed:
    """What checksums.json commits: the rows of points.npy and their CRC-32, the bytes
    of reasons.jsonl and theirs."""

    rows: int
    crc32: int
    reasons_bytes: int
    reasons_crc32: int

    def as_text(self) -> str:
        return (
            json.dumps(
                {
                    "format": CHECKSUMS_FORMAT,
                    "version": CHECKSUMS_VERSION,
                    "points": {"rows": self.rows, "crc32": self.crc32},
                    "reasons": {"bytes": self.reasons_bytes, "crc32": self.reasons_crc32},
                },
                indent=1,
            )
            + "\n"
        )


def read_committed(directory: Path) -> Committed | None:
    """The folder's checksums.json; None when it has none (a sweep started before it).

    Raises:
        StoreError: the file cannot be read or is not a sweep's checksums.
    """
    path = directory / CHECKSUMS_NAME
    try:
        with open(path, "rb") as handle:
            data = json.loads(handle.read(MAX_CHECKSUMS_BYTES + 1).decode("utf-8"))
        if data["format"] != CHECKSUMS_FORMAT or data["version"] != CHECKSUMS_VERSION:
            raise ValueError
        done = Committed(
            data["points"]["rows"],
            data["points"]["crc32"],
            data["reasons"]["bytes"],
            data["reasons"]["crc32"],
        )
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise StoreError(f"{path} cannot be read: {exc.strerror or exc}") from None
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        raise StoreError(f"{path} is damaged (not a sweep's checksums)") from None
    counts = (done.rows, done.reasons_bytes)
    if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in counts) or not (
        is_crc32(done.crc32) and is_crc32(done.reasons_crc32)
    ):
        raise StoreError(f"{path} is damaged (not a sweep's checksums)")
    return done


def _points(
    fd: int, path: Path, dtype: np.dtype, size: int, committed: Committed | None
) -> tuple[int, int, bytearray]:
    """(rows, CRC-32, one byte per point of the sweep, 1 where stored) of the points
    file open as ``fd``: the rows ``committed`` counts, checked against its CRC-32, or
    without it (an older sweep) those the header counts. Reads the file once, a block at
    a time; changes nothing.

    Raises:
        StoreError: the file is not this sweep's points file, is shorter than what is
            committed, differs from its checksum, or holds a point outside the sweep.
    """
    head = header_size(dtype)
    try:
        found, counted, offset = read_header(os.pread(fd, head, 0))
    except ValueError as exc:
        raise StoreError(f"{path} is not a sweep's points file ({exc})") from None
    if found != dtype or offset != head:
        raise StoreError(f"{path} holds rows of another kind than this sweep's (another --keep?)")
    on_disk = (os.fstat(fd).st_size - head) // dtype.itemsize
    if committed is None:
        rows = counted
        if on_disk < rows:
            raise StoreError(f"{path} holds fewer rows than its header counts (cut?)")
    else:
        rows = committed.rows
        if on_disk < rows or counted < rows:
            raise StoreError(
                f"{path} holds {min(on_disk, counted)} whole rows, fewer than the {rows} "
                f"points {CHECKSUMS_NAME} stores (cut short?)"
            )
    done = bytearray(size)
    flags = np.frombuffer(done, dtype=np.uint8)
    crc = 0
    for block in iter_rows(fd, dtype, rows):
        crc = zlib.crc32(block, crc)
        index = np.asarray(block["index"], dtype=np.int64)
        if index.size and (index.min() < 0 or index.max() >= size):
            bad = int(index[(index < 0) | (index >= size)][0])
            raise StoreError(f"{path}: point {bad} is not in the sweep (0 to {size - 1})")
        flags[index] = 1
    if committed is not None and crc != committed.crc32:
        raise StoreError(
            f"{path} differs from what {CHECKSUMS_NAME} stores: the CRC-32 of its {rows} "
            f"points does not match (was the file edited?)"
        )
    return rows, crc, done


def stored_points(directory: Path, size: int, keep: int) -> bytearray:
    """One byte per point of a sweep of ``size`` points keeping ``keep`` impacts, 1 for
    a point stored in ``directory`` (read-only, no lock: what a resume has left to do),
    the points file checked against checksums.json as :class:`ChunkStore` checks it.

    Raises:
        StoreError: as :class:`ChunkStore`.
    """
    path = directory / POINTS_NAME
    if not path.exists():
        return bytearray(size)
    fd = os.open(path, os.O_RDONLY)
    try:
        return _points(fd, path, points_table(keep).dtype, size, read_committed(directory))[2]
    finally:
        os.close(fd)


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
        unverified: None, or a one-line notice that the stored points were written
            before checksums.json and are not verified.

    Raises:
        StoreError: another process writes the folder, or its points file is not this
            sweep's (another row type, a point outside the sweep), or points.npy or
            reasons.jsonl differ from what checksums.json stores.
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
        self.unverified: str | None = None
        try:
            committed = read_committed(directory)
            self.done = bytearray(size)
            self.count = 0
            self.rows = self._open_rows(size, committed)
            self._open_reasons(committed)
            if committed is None:
                if self.rows or self.reasons_size:
                    self.unverified = (
                        f"{directory} was written before {CHECKSUMS_NAME}: its {self.rows} "
                        f"stored points are not verified (they are from now on)"
                    )
                self._commit()
        except BaseException:
            self.close()
            raise
        self.log_file = open(directory / LOG_NAME, "a", encoding="utf-8")  # noqa: SIM115

    def _open_rows(self, size: int, committed: Committed | None) -> int:
        """Check the file's header and its committed rows' checksum, cut rows after
        them (a chunk being written when the sweep was killed) and mark the stored
        points; returns the rows."""
        length = os.fstat(self.fd).st_size
        if length == 0 and committed is None:  # a new file
            self._write(header_bytes(self.dtype, 0))
            os.fsync(self.fd)
            self.crc32 = 0
            return 0
        rows, self.crc32, done = _points(self.fd, self.path, self.dtype, size, committed)
        end = self.head + rows * self.dtype.itemsize
        if length > end:  # a chunk's rows written, not yet committed: cut off
            os.ftruncate(self.fd, end)
            os.pwrite(self.fd, header_bytes(self.dtype, rows), 0)
            os.fsync(self.fd)
        self.done = done
        self.count = int(np.count_nonzero(np.frombuffer(done, dtype=np.uint8)))
        os.lseek(self.fd, end, os.SEEK_SET)
        return rows

    def _open_reasons(self, committed: Committed | None) -> None:
        path = self.directory / REASONS_NAME
        end = 0
        if committed is None:
            for _, offset in _lines(path):
                end = offset
        else:
            end = committed.reasons_bytes
        self.reasons_fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        length = os.fstat(self.reasons_fd).st_size
        if length < end:
            raise StoreError(
                f"{path} holds {length} bytes, fewer than the {end} bytes {CHECKSUMS_NAME} "
                f"stores (cut short?)"
            )
        self.reasons_crc32 = crc32_range(self.reasons_fd, 0, end)
        if committed is not None and self.reasons_crc32 != committed.reasons_crc32:
            raise StoreError(
                f"{path} differs from what {CHECKSUMS_NAME} stores: the CRC-32 of its "
                f"{end} bytes does not match (was the file edited?)"
            )
        if length != end:  # cut off a partial last line, or a chunk's not committed
            os.ftruncate(self.reasons_fd, end)
            os.fsync(self.reasons_fd)
        self.reasons_size = end
        os.lseek(self.reasons_fd, end, os.SEEK_SET)

    def _commit(self) -> None:
        """Write checksums.json for what the files hold now (atomically: the old one or
        the new one, never a mixture)."""
        committed = Committed(self.rows, self.crc32, self.reasons_size, self.reasons_crc32)
        write_text_atomic(self.directory / CHECKSUMS_NAME, committed.as_text())

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
        """Store a chunk: its reasons (synced), its rows (synced), the row count, then
        the commit (checksums.json, the CRC-32s continued over the new bytes)."""
        if not len(chunk):
            return
        if chunk.reasons:
            text = "".join(
                json.dumps({"index": int(i), "reason": r}) + "\n"
                for i, r in sorted(chunk.reasons.items())
            )
            data = text.encode("utf-8")
            self._write_fd(self.reasons_fd, data)
            os.fsync(self.reasons_fd)
            self.reasons_size += len(data)
            self.reasons_crc32 = zlib.crc32(data, self.reasons_crc32)
        rows = chunk.rows(self.dtype["last_height"].shape[0])
        data = rows.tobytes()
        self._write(memoryview(data))
        os.fsync(self.fd)
        self.rows += len(rows)
        self.crc32 = zlib.crc32(data, self.crc32)
        # after the rows are on disk: the header never counts a row that is not
        os.pwrite(self.fd, header_bytes(self.dtype, self.rows), 0)
        os.fsync(self.fd)
        self._commit()
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
