"""The boundary's prescribed motion: a sinusoidal translation D = A sin(w t + phase) along
n1 (horizontal, the paper's experiments) or n2 (vertical, the bouncing-ball case).

This is the one place the drive kinematics is written; the locators inline the same
formulas in their hot loops and say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["Drive"]


@dataclass(frozen=True)
class Drive:
    """Sinusoidal translation of the boundary, D = amplitude * sin(theta) along one axis.

    The drive angle theta = omega t + phase is carried by the engine as a state variable
    (reduced modulo 2 pi) so that it stays accurate at large t.
    """

    amplitude: float
    omega: float
    phase: float
    horizontal: bool

    @classmethod
    def from_scene(cls, drive: Any) -> Drive:
        return cls(
            amplitude=float(drive.amplitude),
            omega=float(drive.omega),
            phase=float(drive.phase),
            horizontal=drive.direction == "horizontal",
        )

    def angle(self, t: float) -> float:
        """Drive angle omega t + phase, reduced to [0, 2 pi)."""
        return (self.omega * t + self.phase) % (2.0 * math.pi)

    @property
    def period(self) -> float:
        """Drive period (s); infinite for a boundary at rest."""
        if self.amplitude == 0.0 or self.omega == 0.0:
            return math.inf
        return 2.0 * math.pi / self.omega

    @property
    def peak_acceleration(self) -> float:
        return self.amplitude * self.omega * self.omega

    def displacement(self, theta: float) -> float:
        return self.amplitude * math.sin(theta)

    def velocity(self, theta: float) -> float:
        return self.amplitude * self.omega * math.cos(theta)

    def acceleration(self, theta: float) -> float:
        return -self.amplitude * self.omega * self.omega * math.sin(theta)

    def boundary_velocity(self, theta: float) -> tuple[float, float]:
        """Lab-frame velocity (vb1, vb2) of the boundary."""
        v = self.velocity(theta)
        return (v, 0.0) if self.horizontal else (0.0, v)

    def to_boundary_frame(
        self, theta: float, q1: float, q2: float, u1: float, u2: float
    ) -> tuple[float, float, float, float]:
        """Ball centre position and velocity relative to the boundary: (px, py, vx, vy)."""
        d = self.amplitude * math.sin(theta)
        v = self.amplitude * self.omega * math.cos(theta)
        if self.horizontal:
            return q1 - d, q2, u1 - v, u2
        return q1, q2 - d, u1, u2 - v

    def to_lab_frame(self, theta: float, px: float, py: float) -> tuple[float, float]:
        d = self.amplitude * math.sin(theta)
        return (px + d, py) if self.horizontal else (px, py + d)
