"""The boundary's prescribed motion: a sinusoidal translation D = A sin(w t + phase) along
n1 (horizontal, the paper's experiments) or n2 (vertical, the bouncing-ball case).

The drive's parameters, which :meth:`Drive.write` puts into a state vector's drive block;
its kinematics is :mod:`billiard.kernels.drive`, the one place it is written, which the
kernels inline and :class:`Drive` runs interpreted over a drive block of its own.
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from billiard.kernels.interpreted import drive as _drive
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.names import write

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

    @cached_property
    def ctx(self) -> list[float]:
        """The drive block (the first slots of a state vector), which the kernels'
        drive functions read."""
        ctx = [0.0] * _L.DR_END
        self.write(ctx)
        return ctx

    def write(self, ctx: MutableSequence[float]) -> None:
        """Write the drive block of a state vector: amplitude (m), omega (rad/s), the
        axis and the peak acceleration A w^2 (m/s^2)."""
        write(ctx, "drive.amplitude", float(self.amplitude))
        write(ctx, "drive.omega", float(self.omega))
        write(ctx, "drive.horizontal", 1.0 if self.horizontal else 0.0)
        write(ctx, "drive.peak_acceleration", self.peak_acceleration)

    @property
    def static(self) -> bool:
        """Is the boundary at rest (no amplitude or no frequency)?"""
        return _drive.static(self.ctx)

    @property
    def period(self) -> float:
        """Drive period (s); infinite for a boundary at rest."""
        if self.static:
            return math.inf
        return 2.0 * math.pi / self.omega

    @property
    def peak_acceleration(self) -> float:
        """A w^2 (m/s^2)."""
        return float(self.amplitude) * float(self.omega) * float(self.omega)

    def displacement(self, theta: float) -> float:
        """D (m) along the drive's axis at drive angle theta (rad)."""
        return _drive.displacement(self.ctx, theta)

    def velocity(self, theta: float) -> float:
        """dD/dt (m/s) along the drive's axis."""
        return _drive.velocity(self.ctx, theta)

    def acceleration(self, theta: float) -> float:
        """d2D/dt2 (m/s^2) along the drive's axis."""
        return _drive.acceleration(self.ctx, theta)

    def boundary_velocity(self, theta: float) -> tuple[float, float]:
        """Lab-frame velocity (vb1, vb2) of the boundary (m/s)."""
        return _drive.boundary_velocity(self.ctx, theta)

    def to_boundary_frame(
        self, theta: float, q1: float, q2: float, u1: float, u2: float
    ) -> tuple[float, float, float, float]:
        """Ball centre position and velocity relative to the boundary: (px, py, vx, vy)."""
        return _drive.to_boundary_frame(self.ctx, theta, q1, q2, u1, u2)

    def to_lab_frame(self, theta: float, px: float, py: float) -> tuple[float, float]:
        """A position (m) in the boundary's frame, in the lab frame."""
        return _drive.to_lab_frame(self.ctx, theta, px, py)
