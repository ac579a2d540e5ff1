"""Reading a run's ``collisions.csv`` and imitating the experiment's camera.

A run writes one row per impact to ``collisions.csv``. :func:`read_collisions` reads it
into a dict of numpy arrays (one per column). :func:`camera_filter` keeps only the
impacts that a camera with a given frame interval could have told apart: the experiment
(Feldt and Olafsen, filmed at a finite frame rate) did not see impacts in rapid
succession, while the model counts every one of them.

Units follow the CSV: times in s, positions in m, velocities in m/s, spin in rad/s,
energy in J.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

__all__ = [
    "REQUIRED_COLUMNS",
    "STRING_COLUMNS",
    "RunDataError",
    "camera_filter",
    "read_collisions",
    "write_collisions",
]

#: Columns every ``collisions.csv`` has, in this order; more may follow.
REQUIRED_COLUMNS: tuple[str, ...] = (
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
)
#: Columns read as strings; every other column is read as float.
STRING_COLUMNS: frozenset[str] = frozenset({"regime"})


class RunDataError(ValueError):
    """A run's files cannot be read or plotted; the message is one line naming the file."""


def _fail(path: str | os.PathLike[str], problem: str) -> RunDataError:
    return RunDataError(f"{path}: {' '.join(problem.split())}")


def read_collisions(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a run's ``collisions.csv``.

    The first non-blank line that does not start with ``#`` is the header; blank lines
    and ``#`` comment lines are skipped, and so is an unterminated last row (a write cut
    short when the run was killed). Every column in :data:`REQUIRED_COLUMNS` must
    be present; extra columns (e.g. ``wall``, ``Rt``, ``Rn``) are kept.

    Args:
        path: the CSV file.

    Returns:
        A dict column name -> 1-D array with one entry per impact, in file order:
        ``regime`` (and any other column whose values are not all numbers, such as a
        wall label) as a string array, every other column as a float64 array in the
        CSV's units (s, m, m/s, rad/s, J). A file with a header and no rows gives
        arrays of length 0.

    Raises:
        RunDataError: the file is missing or unreadable, has no header, lacks a
            required column, has a row with the wrong number of fields, or a required
            numeric column holds something that is not a number. The message is one
            line starting with the path.
    """
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            lines = [
                (number, line)
                for number, line in enumerate(handle, start=1)
                if line.strip() and not line.lstrip().startswith("#")
            ]
    except FileNotFoundError:
        raise _fail(path, "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise _fail(path, f"cannot read: {exc}") from None
    if not lines:
        raise _fail(path, "empty file (no header line)")
    if len(lines) > 1 and not lines[-1][1].endswith("\n"):
        # an unterminated last row is a write cut short by a kill: every complete row
        # before it is kept (the run can be resumed and completes that row)
        lines.pop()
    rows = csv.reader(line for _, line in lines)
    try:
        header = [name.strip() for name in next(rows)]
        body = list(rows)
    except csv.Error as exc:
        raise _fail(path, f"not valid CSV: {exc}") from None
    missing = [name for name in REQUIRED_COLUMNS if name not in header]
    if missing:
        raise _fail(
            path, f"missing column(s) {', '.join(missing)} (header: {','.join(header)[:120]})"
        )
    duplicated = sorted({name for name in header if header.count(name) > 1})
    if duplicated:
        raise _fail(path, f"duplicated column(s) {', '.join(duplicated)}")
    width = len(header)
    if len(body) != len(lines) - 1:
        raise _fail(path, "not valid CSV: a quoted field spans lines")
    for (number, _), row in zip(lines[1:], body, strict=True):
        if len(row) != width:
            raise _fail(path, f"line {number}: expected {width} fields, got {len(row)}")
    table = list(zip(*body, strict=True)) if body else [()] * width
    columns: dict[str, np.ndarray] = {}
    for index, name in enumerate(header):
        cells = [cell.strip() for cell in table[index]]
        if name in STRING_COLUMNS:
            columns[name] = np.array(cells, dtype=str)
            continue
        try:
            columns[name] = np.array([float(cell) for cell in cells], dtype=float)
        except ValueError:
            if name in REQUIRED_COLUMNS:
                for (number, _), cell in zip(lines[1:], cells, strict=True):
                    try:
                        float(cell)
                    except ValueError:
                        raise _fail(
                            path, f"line {number}: column {name}: {cell[:40]!r} is not a number"
                        ) from None
            columns[name] = np.array(cells, dtype=str)
    if body and columns["t"].size > 1 and np.any(np.diff(columns["t"]) < 0):
        first = int(np.argmax(np.diff(columns["t"]) < 0)) + 1
        raise _fail(
            path,
            f"line {lines[first + 1][0]}: impact times decrease (column t must be non-decreasing)",
        )
    return columns


def camera_filter(
    columns: Mapping[str, np.ndarray], frame_interval: float
) -> dict[str, np.ndarray]:
    """The impacts a camera with the given frame interval would have recorded.

    The camera cannot tell apart impacts that follow one another within one frame
    interval. Going through the impacts in time order, the first impact is always
    kept (nothing was recorded before it), and an impact at time t is kept when
    ``t - t_kept > frame_interval`` (strictly), where ``t_kept`` is the time of the
    last *kept* impact; the others are dropped. So a burst of impacts in rapid
    succession is seen as its first impact, and a long burst as one impact per frame
    interval or so.

    Example: impact times [0, 0.001, 0.1, 0.1005, 0.3] s with ``frame_interval`` =
    1/30 s keep the impacts at [0, 0.1, 0.3] s.

    Args:
        columns: the run's columns (see :func:`read_collisions`); only ``t`` (s) is
            needed, sorted in non-decreasing order; every column has one entry per
            impact.
        frame_interval: the camera's time between frames (s), > 0 (1/30 s for a
            30 frames-per-second camera).

    Returns:
        A new dict with the same keys holding the kept rows, in order. If the input has
        a ``tof`` column, the kept rows' ``tof`` is recomputed as the time (s) since
        the previous kept impact; the first kept row (the first impact) keeps its
        ``tof``, the time since the start of the run or the previous impact before it.
        The other columns, including ``n`` (the impact's index in the full run), are
        unchanged.

    Raises:
        ValueError: ``frame_interval`` is not a positive finite number, ``t`` is
            missing or not sorted, or the columns have different lengths.
    """
    interval = float(frame_interval)
    if not (math.isfinite(interval) and interval > 0):
        raise ValueError(
            f"camera frame interval must be a positive number of seconds, got {frame_interval!r}"
        )
    if "t" not in columns:
        raise ValueError("camera_filter: the columns have no impact time 't'")
    t = np.asarray(columns["t"], dtype=float)
    lengths = {name: len(values) for name, values in columns.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"camera_filter: columns have different lengths: {lengths}")
    if t.size > 1 and np.any(np.diff(t) < 0):
        raise ValueError("camera_filter: impact times t must be non-decreasing")

    kept: list[int] = []
    i = 0
    while i < t.size:
        kept.append(i)
        # First index j with t[j] - t[i] > interval, found by bisection then made exact
        # (t[i] + interval may round differently from the difference).
        j = int(np.searchsorted(t, t[i] + interval, side="right"))
        while j < t.size and not (t[j] - t[i] > interval):
            j += 1
        while j - 1 > i and t[j - 1] - t[i] > interval:
            j -= 1
        i = max(j, i + 1)
    index = np.asarray(kept, dtype=np.intp)

    out = {name: np.asarray(values)[index] for name, values in columns.items()}
    if "tof" in out and index.size:
        tof = np.asarray(out["tof"], dtype=float).copy()
        tof[1:] = np.diff(t[index])
        out["tof"] = tof
    return out


def write_collisions(path: str | os.PathLike[str], columns: Mapping[str, np.ndarray]) -> Path:
    """Write columns back to a CSV in the ``collisions.csv`` format (header line, one row
    per impact, floats in full precision). Used to save camera-filtered data.

    Returns:
        The path written.
    """
    names = list(columns)
    arrays = [np.asarray(columns[name]) for name in names]
    path = Path(path)
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(names)
        for row in zip(*arrays, strict=True):
            writer.writerow([_cell(v) for v in row])
    return path


def _cell(value: object) -> str:
    if isinstance(value, (float, np.floating)):
        text = repr(float(value))
        return text[:-2] if text.endswith(".0") else text
    return str(value)
