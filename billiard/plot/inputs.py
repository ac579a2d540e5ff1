"""User input to the plots, checked: frame intervals and windows of impacts."""

from __future__ import annotations

import math

from billiard.analysis.camera import parse_frame_interval
from billiard.plot.common import RunDataError, Window

__all__ = ["checked_interval", "parse_frame_interval", "parse_window"]


def checked_interval(frame_interval: float | None) -> float | None:
    """A camera frame interval (s) as a positive finite float, or None.

    Raises:
        RunDataError: not a positive finite number.
    """
    if frame_interval is None:
        return None
    try:
        value = float(frame_interval)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise RunDataError(
            f"camera frame interval must be a positive number of seconds, got {frame_interval!r}"
        )
    return value


def parse_window(text: str) -> Window:
    """Parse ``"N0:N1"`` (either side may be empty) into a window of impact numbers.

    Raises:
        RunDataError: (a ValueError) not of that form, or not whole numbers.
    """
    start, sep, stop = text.partition(":")
    if not sep:
        raise RunDataError(
            f"window {text!r}: expected N0:N1 (impact numbers, N0 included, N1 excluded)"
        )
    try:
        n0 = int(start) if start.strip() else None
        n1 = int(stop) if stop.strip() else None
    except ValueError:
        raise RunDataError(f"window {text!r}: N0 and N1 must be whole impact numbers") from None
    return n0, n1
