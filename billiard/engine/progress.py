"""The progress protocol of a run: ``progress(done, total)``, called every few impacts
with the impacts done and asked for; a progress object that also has an ``at_time(t)``
method is told the simulated time reached (s), which advances while the ball rolls,
slides or is held and the impact count stands still."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

__all__ = ["Progress", "report_time"]

Progress = Callable[[int, int], None]


def report_time(progress: Any, t: float) -> None:
    """Tell a progress object that has an ``at_time`` method the simulated time (s)."""
    at_time = getattr(progress, "at_time", None)
    if at_time is not None and math.isfinite(t):
        at_time(t)
