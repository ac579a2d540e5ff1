"""The measured columns of a sweep: one numpy array per quantity, one entry per point.

A chunk of points measured in a worker comes back as a :class:`ChunkResult` of these
columns (plus the text reasons of the points that are not ``ok``), is appended to the
sweep folder's ``points.npy`` as rows of :func:`disk_dtype`, and ``sweep.nc`` is built
from those rows. The names are those of the ``sweep.nc`` variables, so a compiled
ensemble can fill a chunk's arrays directly.

Codes (int8) stand for the text a point's record holds:

* ``status``: :data:`STATUSES` (``ok``, ``failed``, ``invalid``);
* ``attractor``: :data:`billiard.sweep.attractor.CLASSES`;
* ``run_status``: :data:`RUN_STATUSES` (``""``: no run, then the lower-case names of
  :class:`billiard.status.Status` in value order);
* ``final_mode``: :data:`MODES` (``""``: no run).

``period`` and ``drive_periods`` hold 0 where there is none; the float columns NaN where
nothing was measured. ``elastic_impacts`` and ``lid_impacts`` are counts: the shares of
``sweep.nc`` are count / ``impacts``, computed when the result is written.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from billiard.status import Status
from billiard.sweep.attractor import CLASSES

__all__ = [
    "FLOATS",
    "INTS",
    "MODES",
    "RUN_STATUSES",
    "STATUSES",
    "TAILS",
    "ChunkResult",
    "disk_dtype",
    "empty_columns",
    "record_of_row",
    "set_row",
]

STATUSES = ("ok", "failed", "invalid")
RUN_STATUSES = ("", *(s.name.lower() for s in sorted(Status, key=int)))
MODES = ("", "flight", "roll", "slide", "held")
#: The coded text columns and their names.
CODES: dict[str, tuple[str, ...]] = {
    "status": STATUSES,
    "attractor": CLASSES,
    "run_status": RUN_STATUSES,
    "final_mode": MODES,
}

#: Integer columns: name -> (dtype in a chunk, dtype on disk). Counts of impacts fit an
#: int32 on disk: a point runs at most impacts + transient <= 10^9 impacts.
INTS: dict[str, tuple[str, str]] = {
    "index": ("<i8", "<i4"),  # a sweep has at most 10^9 points
    "status": ("i1", "i1"),
    "attractor": ("i1", "i1"),
    "run_status": ("i1", "i1"),
    "final_mode": ("i1", "i1"),
    "period": ("<i4", "<i4"),
    "drive_periods": ("<i4", "<i4"),
    "impacts": ("<i8", "<i4"),
    "total_impacts": ("<i8", "<i4"),
    "elastic_impacts": ("<i8", "<i4"),
    "lid_impacts": ("<i8", "<i4"),
}
FLOATS = (
    "rest_height",
    "height_mean",
    "height_std",
    "height_max",
    "tof_mean",
    "tof_std",
    "lyapunov",
    "lyapunov_per_second",
)
#: The last K impact heights and times of flight, (points, K), NaN-padded at the front.
TAILS = ("last_height", "last_tof")


def disk_dtype(keep: int) -> np.dtype:
    """The packed little-endian row of ``points.npy`` for a sweep keeping ``keep``
    impacts: 96 bytes plus 16 bytes per kept impact."""
    fields: list[tuple[Any, ...]] = [(name, disk) for name, (_, disk) in INTS.items()]
    fields += [(name, "<f8") for name in FLOATS]
    fields += [(name, "<f8", (keep,)) for name in TAILS]
    return np.dtype(fields)


@dataclass
class ChunkResult:
    """The measurements of the points of one chunk.

    Attributes:
        columns: name -> array, one entry per point (in the order of ``columns["index"]``;
            the tails ``(points, K)``).
        reasons: one-line reasons of the points not ``ok``, by point index.
    """

    columns: dict[str, np.ndarray]
    reasons: dict[int, str] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.columns["index"])

    def rows(self, keep: int) -> np.ndarray:
        """The chunk as ``points.npy`` rows."""
        out = np.empty(len(self), dtype=disk_dtype(keep))
        for name in out.dtype.names or ():
            out[name] = self.columns[name]
        return out


def empty_columns(points: int, keep: int) -> dict[str, np.ndarray]:
    """Columns of ``points`` points with nothing measured: codes and counts 0, floats
    NaN."""
    columns = {name: np.zeros(points, dtype=dtype) for name, (dtype, _) in INTS.items()}
    columns |= {name: np.full(points, np.nan) for name in FLOATS}
    columns |= {name: np.full((points, keep), np.nan) for name in TAILS}
    return columns


def _float(value: Any) -> float:
    return math.nan if value is None else float(value)


def _count(record: Mapping[str, Any], name: str, share: str) -> int:
    """A count of impacts: the record's own, or its share times its impacts (exact: the
    share is count / impacts rounded once)."""
    if record.get(name) is not None:
        return int(record[name])
    value = record.get(share)
    return 0 if value is None else round(float(value) * int(record.get("impacts") or 0))


def set_row(columns: dict[str, np.ndarray], row: int, record: Mapping[str, Any]) -> None:
    """Write a point's record (the dict of :func:`billiard.sweep.measure.measure_point`)
    into entry ``row`` of ``columns``."""
    columns["index"][row] = int(record["index"])
    for name, codes in CODES.items():
        columns[name][row] = codes.index(str(record.get(name) or ""))
    for name in ("period", "drive_periods", "impacts", "total_impacts"):
        columns[name][row] = int(record.get(name) or 0)
    columns["elastic_impacts"][row] = _count(record, "elastic_impacts", "elastic_share")
    columns["lid_impacts"][row] = _count(record, "lid_impacts", "lid_share")
    for name in FLOATS:
        columns[name][row] = _float(record.get(name))
    for name in TAILS:
        keep = columns[name].shape[1]
        tail = list(record.get(name) or ())[-keep:]
        columns[name][row] = np.nan
        if tail:
            columns[name][row, keep - len(tail) :] = tail


def share(count: np.ndarray, impacts: np.ndarray) -> np.ndarray:
    """count / impacts as float64, NaN where no impact was measured (the value
    ``numpy.mean`` of a boolean column gives)."""
    count = np.asarray(count, dtype=np.float64)
    impacts = np.asarray(impacts, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(impacts > 0, count / np.where(impacts > 0, impacts, 1.0), np.nan)


def _plain(value: float) -> float | None:
    return value if math.isfinite(value) else None


def record_of_row(row: Any, values: dict[str, Any], reason: str = "") -> dict[str, Any]:
    """A point's record (the dict :func:`~billiard.sweep.measure.measure_point` gives)
    from one stored row (a ``points.npy`` row, or a mapping of scalars)."""
    keep = len(row["last_height"])
    impacts = int(row["impacts"])
    record: dict[str, Any] = {"index": int(row["index"]), "values": values}
    for name, codes in CODES.items():
        record[name] = codes[int(row[name])]
    record["reason"] = reason
    for name in ("period", "drive_periods", "impacts", "total_impacts"):
        record[name] = int(row[name])
    for name in FLOATS:
        record[name] = _plain(float(row[name]))
    for name, count in (("elastic_share", "elastic_impacts"), ("lid_share", "lid_impacts")):
        record[name] = float(row[count]) / impacts if impacts else None
    for name in TAILS:
        tail = np.asarray(row[name], dtype=float)[-keep:]
        record[name] = [float(x) for x in tail if math.isfinite(x)]
    return record
