"""The sweep folder: its definition, and every finished point appended durably.

``DIR/sweep.toml`` and ``DIR/scene.toml``
    the sweep's definition, written before the first point (``--resume DIR`` reads them).
``DIR/points.jsonl``
    one JSON line per finished point, in the order points finish; each line is written
    whole and flushed to disk (``fsync``) before the next point is taken, so a Ctrl-C or
    a kill keeps every finished point. A kill in the middle of a write leaves at most an
    unterminated last line, which is cut off on resume.
``DIR/sweep.log``
    timings and progress (the only file with wall-clock times).

Only one process may write a sweep folder at a time (an ``flock`` on points.jsonl).
"""

from __future__ import annotations

import fcntl
import json
import math
import os
import time
from pathlib import Path
from typing import Any

__all__ = ["LOG_NAME", "POINTS_NAME", "SCENE_NAME", "SWEEP_NAME", "PointStore", "read_points"]

SWEEP_NAME = "sweep.toml"
SCENE_NAME = "scene.toml"
POINTS_NAME = "points.jsonl"
LOG_NAME = "sweep.log"


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


def read_points(path: Path) -> tuple[list[dict[str, Any]], int]:
    """The records of a points file and the byte length of its whole lines (a partial
    last line from a kill is not a record)."""
    if not path.exists():
        return [], 0
    data = path.read_bytes()
    end = data.rfind(b"\n") + 1
    records = []
    for number, line in enumerate(data[:end].splitlines(), start=1):
        if not line.strip():
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            raise StoreError(f"{path}: line {number} is not a JSON record") from None
    return records, end


class PointStore:
    """Appends finished points to ``DIR/points.jsonl`` (durably) and lines to the log."""

    def __init__(self, directory: Path):
        self.directory = directory
        self.path = directory / POINTS_NAME
        directory.mkdir(parents=True, exist_ok=True)
        records, end = read_points(self.path)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(self.fd)
            raise StoreError(f"another sweep is writing {directory}") from None
        if os.fstat(self.fd).st_size != end:  # cut off a partial last line
            os.ftruncate(self.fd, end)
            os.fsync(self.fd)
        os.lseek(self.fd, 0, os.SEEK_END)
        self.records = {int(r["index"]): r for r in records}
        self.log_file = open(directory / LOG_NAME, "a", encoding="utf-8")  # noqa: SIM115

    def append(self, record: dict[str, Any]) -> None:
        line = encode(record)
        written = 0
        while written < len(line):
            written += os.write(self.fd, line[written:])
        os.fsync(self.fd)
        self.records[int(record["index"])] = json.loads(line)

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
