"""The container as a basin map over starting positions shows it: the wall y = f(x) and
the lid, in the lab frame at the start time, where the ball's centre (initial.q1,
initial.q2) is placed.

The boundary is displaced by the drive, D(t) = A sin(omega t + phase) along n1 (or n2
for a vertical drive); at the start time ``initial.t`` the wall is ``f`` shifted by
D(initial.t), as the engine places it when it checks the starting position. Only the
geometry wing is used (the plot wing is a sibling of this one, not below it).
"""

from __future__ import annotations

import math

import numpy as np

from billiard.geometry.curves import load_curve
from billiard.scene.scene import Scene

__all__ = ["POSITION_KEYS", "lid_height", "start_offset", "wall_outline"]

#: The swept keys of a map over starting positions (the ball's centre, m).
POSITION_KEYS = ("initial.q1", "initial.q2")


def start_offset(scene: Scene) -> tuple[float, float]:
    """The boundary's displacement (m) at the start time, along n1 and n2."""
    drive = scene.drive
    d = drive.amplitude * math.sin(drive.omega * scene.initial.t + drive.phase)
    return (d, 0.0) if drive.direction == "horizontal" else (0.0, d)


def wall_outline(scene: Scene, lo: float, hi: float, count: int = 801) -> tuple[np.ndarray, ...]:
    """The wall in the lab frame at the start time: ``(x, y)`` (m) on ``count`` points of
    lab x from ``lo`` to ``hi`` (m), plus the curve's kinks (a wedge's vertex drawn
    sharp); y is NaN where the curve is undefined.

    Raises:
        ValueError: the scene's curve cannot be loaded.
    """
    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    dx, dy = start_offset(scene)
    grid, height = curve.samples(lo - dx, hi - dx, count)  # in the boundary's own x
    return grid + dx, height + dy


def lid_height(scene: Scene) -> float | None:
    """The lid's height (m) in the lab frame at the start time, or None without a lid."""
    ceiling = scene.boundary.ceiling
    return None if ceiling is None else float(ceiling) + start_offset(scene)[1]
