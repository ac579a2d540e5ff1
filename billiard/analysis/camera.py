"""Imitating the experiment's camera: which impacts a finite frame rate could see.

The experiment (Feldt and Olafsen, filmed at a finite frame rate) did not see impacts in
rapid succession, while the model counts every one of them. :func:`camera_filter` keeps
the impacts that a camera with a given frame interval could have told apart. It only
filters: a run's file is read by :func:`billiard.runfile.tables.read_collisions`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from fractions import Fraction

import numpy as np

from billiard.runfile.record import RunDataError

__all__ = ["camera_filter", "parse_frame_interval"]


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


def parse_frame_interval(text: str) -> float:
    """A camera frame interval in seconds from text: a number (``0.0333``) or a fraction
    (``1/30``), > 0. The one parser of ``--frame-interval`` (``billiard run`` and
    ``billiard plot``).

    Raises:
        RunDataError: not a number, or not a positive finite one.
    """
    try:
        value = float(Fraction(text.strip())) if "/" in text else float(text)
    except (ValueError, ZeroDivisionError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise RunDataError(
            f"frame interval {text!r} must be a positive number of seconds (e.g. 0.0333 or 1/30)"
        )
    return value
