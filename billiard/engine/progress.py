"""The progress protocol of a run: ``progress(done, total)``, called every few impacts
with the impacts done and asked for; a progress object that also has an ``at_time(t)``
method is told the simulated time reached (s), which advances while the ball rolls,
slides or is held and the impact count stands still."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

__all__ = ["Progress", "duration_text", "report_time"]

Progress = Callable[[int, int], None]


def report_time(progress: Any, t: float) -> None:
    """Tell a progress object that has an ``at_time`` method the simulated time (s)."""
    at_time = getattr(progress, "at_time", None)
    if at_time is not None and math.isfinite(t):
        at_time(t)


def duration_text(seconds: float) -> str:
    """A wall-clock duration for humans (an estimated time left, a time elapsed): ``42 s``,
    ``3 min 5 s``, ``2 h 10 min``; ``?`` when it is not finite.

    The duration is rounded to whole seconds before it is split, so that 59.6 s reads
    ``1 min 0 s`` and never ``60 s`` next to ``1 min 0 s``, nor ``1 min 60 s``.
    """
    if not math.isfinite(seconds):
        return "?"
    whole = max(0, round(seconds))
    if whole < 60:
        return f"{whole} s"
    if whole < 3600:
        return f"{whole // 60} min {whole % 60} s"
    return f"{whole // 3600} h {whole % 3600 // 60} min"
