"""Telling attractors apart across a sweep, for basin maps.

Points of the same class are the same attractor, except periodic ones: those are told
apart by their period and their mean impact height, two periodic points with the same
period and mean heights within ``height_tolerance`` (default 1 mm, chained) being the
same orbit. Labels are numbered in a fixed order (class, then period, then height), so
they depend only on the records.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from billiard.sweep.attractor import CLASSES

__all__ = ["attractor_labels"]


def attractor_labels(
    records: Sequence[dict[str, Any]], height_tolerance: float = 1e-3
) -> tuple[list[int], list[str]]:
    """Per record the number of its attractor, and the attractors' labels."""
    keys: list[tuple[Any, ...]] = []
    for r in records:
        if r["attractor"] == "periodic":
            keys.append((CLASSES.index("periodic"), int(r["period"]), float(r["height_mean"])))
        else:
            keys.append((CLASSES.index(r["attractor"]), 0, 0.0))
    order = sorted(range(len(records)), key=lambda i: keys[i])
    group_of: dict[int, int] = {}
    labels: list[str] = []
    previous: tuple[Any, ...] | None = None
    for i in order:
        cls, period, height = keys[i]
        same = (
            previous is not None
            and previous[0] == cls
            and previous[1] == period
            and (CLASSES[cls] != "periodic" or height - previous[2] <= height_tolerance)
        )
        if not same:
            name = CLASSES[cls]
            if name == "periodic":
                name = f"period {period}, mean q2 {height:.4f} m"
            labels.append(name)
        group_of[i] = len(labels) - 1
        previous = keys[i]
    return [group_of[i] for i in range(len(records))], labels
