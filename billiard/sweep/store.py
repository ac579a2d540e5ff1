"""The sweep folder: its definition, and every finished point appended durably.

``DIR/sweep.toml`` and ``DIR/scene.toml``
    the sweep's definition, written before the first point (``--resume DIR`` reads them).
``DIR/sweep.sha256``
    the SHA-256 of both, in ``sha256sum`` format, written with them: a resume refuses a
    definition edited since the sweep started (its points would mix two sweeps).
``DIR/points.jsonl``
    one JSON line per finished point, in the order points finish; each line is written
    whole and flushed to disk (``fsync``) before the next point is taken, so a Ctrl-C or
    a kill keeps every finished point. A kill in the middle of a write leaves at most an
    unterminated last line, which is cut off on resume.
``DIR/sweep.log``
    timings and progress (the only file with wall-clock times).

Only one process may write a sweep folder at a time (an ``flock`` on points.jsonl).
Finished points are not kept in memory: the store holds one byte per point of the grid
(finished or not), and the result is built by reading points.jsonl back line by line.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import math
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

__all__ = [
    "DIGEST_NAME",
    "LOG_NAME",
    "POINTS_NAME",
    "SCENE_NAME",
    "SWEEP_NAME",
    "PointStore",
    "iter_points",
    "read_points",
]

SWEEP_NAME = "sweep.toml"
SCENE_NAME = "scene.toml"
POINTS_NAME = "points.jsonl"
LOG_NAME = "sweep.log"
DIGEST_NAME = "sweep.sha256"

#: Longest line of points.jsonl read (bytes): a record with keep = 100 is about 5 kB; a
#: longer line is a damaged file, not a record to load into memory.
MAX_LINE = 64 * 2**20


class StoreError(Exception):
    """A sweep folder that cannot be used; one-line message."""


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def encode(record: dict[str, Any]) -> bytes:
    """One record as one JSON line (floats written exactly, keys sorted)."""
    return (json.dumps(_plain(record), sort_keys=True, allow_nan=False) + "\n").encode()


def iter_points(path: Path) -> Iterator[tuple[dict[str, Any], int]]:
    """Each record of a points file, one at a time, with the byte offset just after its
    line; a partial last line (from a kill) is not a record and ends the iteration."""
    if not path.exists():
        return
    offset = 0
    with open(path, "rb") as f:
        number = 0
        while True:
            line = f.readline(MAX_LINE + 1)
            if not line.endswith(b"\n"):
                if len(line) > MAX_LINE:
                    raise StoreError(f"{path}: line {number + 1} is longer than any record")
                return  # end of file, or a partial last line
            number += 1
            offset += len(line)
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except (json.JSONDecodeError, UnicodeDecodeError):
                raise StoreError(f"{path}: line {number} is not a JSON record") from None
            index = record.get("index") if isinstance(record, dict) else None
            if isinstance(index, bool) or not isinstance(index, int):
                raise StoreError(f"{path}: line {number} is not a point record (no index)")
            yield record, offset


def read_points(path: Path) -> tuple[list[dict[str, Any]], int]:
    """The records of a points file and the byte length of its whole lines (a partial
    last line from a kill is not a record). Holds every record: for small sweeps and
    tests; the sweep itself reads with :func:`iter_points`."""
    records, end = [], 0
    for record, offset in iter_points(path):
        records.append(record)
        end = offset
    return records, end


def digest_lines(contents: dict[str, bytes]) -> str:
    """``sha256sum`` lines (``HEX  NAME``) of file contents, by name."""
    return "".join(
        f"{hashlib.sha256(data).hexdigest()}  {name}\n" for name, data in contents.items()
    )


def definition_digest(directory: Path) -> str:
    """``sha256sum`` lines of the folder's sweep.toml and scene.toml, as they are now."""
    names = (SWEEP_NAME, SCENE_NAME)
    return digest_lines({name: (directory / name).read_bytes() for name in names})


class PointStore:
    """Appends finished points to ``DIR/points.jsonl`` (durably) and lines to the log.

    Args:
        directory: the sweep folder.
        size: points in the sweep.
        check: called with each stored record when the folder is opened (it raises
            StoreError for a record that is not one of this sweep's points).

    Attributes:
        done: one byte per point of the sweep, 1 once the point is stored.
        count: points stored.
    """

    def __init__(
        self,
        directory: Path,
        size: int,
        check: Callable[[dict[str, Any]], None] | None = None,
    ):
        self.directory = directory
        self.path = directory / POINTS_NAME
        directory.mkdir(parents=True, exist_ok=True)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(self.fd)
            raise StoreError(f"another sweep is writing {directory}") from None
        self.done = bytearray(size)
        self.count = 0
        end = 0
        try:
            for record, offset in iter_points(self.path):
                end = offset
                index = record["index"]
                if not 0 <= index < size:
                    raise StoreError(
                        f"{self.path}: point {index} is not in the sweep (0 to {size - 1})"
                    )
                if check is not None:
                    check(record)
                self._mark(index)
        except BaseException:
            os.close(self.fd)
            raise
        if os.fstat(self.fd).st_size != end:  # cut off a partial last line
            os.ftruncate(self.fd, end)
            os.fsync(self.fd)
        os.lseek(self.fd, 0, os.SEEK_END)
        self.log_file = open(directory / LOG_NAME, "a", encoding="utf-8")  # noqa: SIM115

    def _mark(self, index: int) -> None:
        if not self.done[index]:
            self.done[index] = 1
            self.count += 1

    def __contains__(self, index: int) -> bool:
        return bool(self.done[index])

    def append(self, record: dict[str, Any]) -> None:
        line = encode(record)
        written = 0
        while written < len(line):
            written += os.write(self.fd, line[written:])
        os.fsync(self.fd)
        self._mark(int(record["index"]))

    def records(self) -> Iterator[dict[str, Any]]:
        """The stored records, read back from the file one at a time."""
        for record, _ in iter_points(self.path):
            yield record

    def log(self, message: str) -> None:
        self.log_file.write(f"{time.strftime('%Y-%m-%d %H:%M:%S')} {message}\n")
        self.log_file.flush()

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1
        self.log_file.close()

    def __enter__(self) -> PointStore:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
