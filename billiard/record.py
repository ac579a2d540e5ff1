"""Impact records: one row per impact, kept in memory or streamed to a CSV file.

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
"""

from __future__ import annotations

import csv
import os
import shutil
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["COLUMNS", "CsvRecorder", "MemoryRecorder", "read_collisions"]

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
_FLUSH_INTERVAL = 1.0  # s of wall-clock time between flushes of a streamed file


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


class CsvRecorder:
    """Rows streamed to a CSV file as they are produced (flushed at least once a second);
    nothing is kept in memory, so long runs stay flat. Read back with :meth:`columns`."""

    def __init__(self, path: str | os.PathLike[str], columns: Sequence[str] = COLUMNS):
        self.path = Path(path)
        self.names = tuple(columns)
        self._handle = open(self.path, "w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._handle)
        self._writer.writerow(self.names)
        self._rows = 0
        self._last_flush = time.monotonic()

    def append(self, row: Sequence[Any]) -> None:
        self._writer.writerow([_format(v) for v in row])
        self._rows += 1
        # wall-clock time decides only when bytes reach the disk, never what they are
        now = time.monotonic()
        if now - self._last_flush >= _FLUSH_INTERVAL:
            self._handle.flush()
            self._last_flush = now

    def __len__(self) -> int:
        return self._rows

    def close(self) -> None:
        if not self._handle.closed:
            self._handle.close()

    def columns(self) -> dict[str, np.ndarray]:
        if not self._handle.closed:
            self._handle.flush()
        return read_collisions(self.path)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if not self._handle.closed:
            self._handle.flush()
        if Path(path).resolve() != self.path.resolve():
            shutil.copyfile(self.path, path)


def read_collisions(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a collisions CSV written by a run into numpy arrays, one per column."""
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        names = next(reader)
        data: list[list[Any]] = [[] for _ in names]
        convert = [str if name in _TEXT else int if name in _INTEGER else float for name in names]
        for row in reader:
            for column, conv, value in zip(data, convert, row, strict=True):
                column.append(conv(value))
    return _as_arrays(dict(zip(names, data, strict=True)))
