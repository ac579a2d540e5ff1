"""The boundary's prescribed motion over the state vector: a sinusoidal translation
D = A sin(theta) along n1 (``HORIZ`` = 1.0, the paper's experiments) or n2 (0.0, the
bouncing ball), theta = omega t + phase the drive angle (rad), from the drive block
(``AMP`` m, ``OMEGA`` rad/s, ``HORIZ``, ``DRIVE_ACCEL`` = A w^2 m/s^2).

The one place the drive's kinematics is written: every kernel reads the drive through
these functions, and :class:`billiard.geometry.drive.Drive` is these, run interpreted
over a drive block of its own (which it also writes into the engine's ``ctx``). Each
function is inlined into its compiled callers (:func:`~.decorators.inline`): the
operations of the formulas the kernels wrote before, in the same order.

``-A w^2 sin(theta)`` is ``-DRIVE_ACCEL * sin(theta)``: negation is exact and rounding
to nearest is symmetric in sign, so it has the bits of ``(-A) * w * w * sin(theta)``.
"""

from __future__ import annotations

import math

from .decorators import inline
from .layout import AMP, DRIVE_ACCEL, HORIZ, OMEGA


@inline
def static(ctx):
    """Is the boundary at rest (no amplitude or no frequency)?"""
    return ctx[AMP] == 0.0 or ctx[OMEGA] == 0.0


@inline
def displacement(ctx, theta):
    """The boundary's displacement D (m) along the drive's axis at drive angle theta."""
    return ctx[AMP] * math.sin(theta)


@inline
def velocity(ctx, theta):
    """dD/dt (m/s) along the drive's axis."""
    return ctx[AMP] * ctx[OMEGA] * math.cos(theta)


@inline
def acceleration(ctx, theta):
    """d2D/dt2 (m/s^2) along the drive's axis."""
    return -ctx[DRIVE_ACCEL] * math.sin(theta)


@inline
def boundary_velocity(ctx, theta):
    """(vb1, vb2): the boundary's velocity (m/s) in the lab frame."""
    v = velocity(ctx, theta)
    if ctx[HORIZ] != 0.0:
        return v, 0.0
    return 0.0, v


@inline
def boundary_motion(ctx, theta):
    """(vb1, vb2, ab1, ab2): the boundary's velocity (m/s) and acceleration (m/s^2) in
    the lab frame."""
    v = velocity(ctx, theta)
    a = acceleration(ctx, theta)
    if ctx[HORIZ] != 0.0:
        return v, 0.0, a, 0.0
    return 0.0, v, 0.0, a


@inline
def to_boundary_frame(ctx, theta, q1, q2, u1, u2):
    """(px, py, vx, vy): a lab-frame position (m) and velocity (m/s) relative to the
    boundary."""
    d = displacement(ctx, theta)
    v = velocity(ctx, theta)
    if ctx[HORIZ] != 0.0:
        return q1 - d, q2, u1 - v, u2
    return q1, q2 - d, u1, u2 - v


@inline
def to_lab_frame(ctx, theta, px, py):
    """(q1, q2): a position (m) in the boundary's frame, in the lab frame."""
    d = displacement(ctx, theta)
    if ctx[HORIZ] != 0.0:
        return px + d, py
    return px, py + d


@inline
def accel_to_boundary_frame(ctx, theta, a1, a2):
    """(ax, ay): a lab-frame acceleration (a1, a2) (m/s^2) relative to the boundary."""
    ab = acceleration(ctx, theta)
    if ctx[HORIZ] != 0.0:
        return a1 - ab, a2
    return a1, a2 - ab
