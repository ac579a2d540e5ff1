"""Flight between impacts over the state vector: the exact parabola without air forces,
Dormand-Prince 5(4) with them. :class:`billiard.models.flight.ExactFlight` and
:class:`billiard.models.flight.AdaptiveFlight` are these functions, run interpreted."""

from __future__ import annotations

import math

from .ball import flight_exact, flight_rhs_drag, flight_rhs_magnus
from .decorators import inline
from .layout import (
    E_STEP_CONTROL,
    EN_ERR_VALUE,
    EN_STOP,
    FL_CLIN,
    FL_CMAG,
    FL_CQUAD,
    FL_H,
    FL_KA,
    FL_KB,
    FL_KIND,
    FL_M,
    FL_RTOL,
    FL_TA,
    FL_TB,
    FL_U3,
    FL_YA,
    FL_YB,
    FLIGHT_EXACT,
    G,
    KernelError,
)

# Dormand-Prince 5(4) tableau (Dormand & Prince 1980; as in Hairer, Norsett & Wanner).
_A21 = 1 / 5
_A31, _A32 = 3 / 40, 9 / 40
_A41, _A42, _A43 = 44 / 45, -56 / 15, 32 / 9
_A51, _A52, _A53, _A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
_A61, _A62, _A63, _A64, _A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
_B1, _B3, _B4, _B5, _B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
# error weights: 5th-order minus embedded 4th-order weights (the 7th stage is FSAL)
_E1, _E3, _E4, _E5, _E6, _E7 = (
    71 / 57600,
    -71 / 16695,
    71 / 1920,
    -17253 / 339200,
    22 / 525,
    -1 / 40,
)


@inline
def rhs(ctx, u1, u2):
    """Acceleration (du1/dt, du2/dt) in flight with air forces (generated)."""
    if ctx[FL_CMAG] != 0.0:
        return flight_rhs_magnus(
            u1, u2, ctx[FL_U3], ctx[FL_M], ctx[G], ctx[FL_CLIN], ctx[FL_CQUAD], ctx[FL_CMAG]
        )
    return flight_rhs_drag(u1, u2, ctx[FL_M], ctx[G], ctx[FL_CLIN], ctx[FL_CQUAD])


@inline
def acceleration(ctx, u1, u2):
    """The ball's acceleration (m/s^2) at velocity (u1, u2)."""
    if ctx[FL_KIND] == FLIGHT_EXACT:
        return 0.0, -ctx[G]
    return rhs(ctx, u1, u2)


@inline
def aero_bound(ctx, speed):
    """Bound on the non-gravitational acceleration at a speed (m/s^2)."""
    if ctx[FL_KIND] == FLIGHT_EXACT:
        return 0.0
    return (
        (ctx[FL_CLIN] + ctx[FL_CQUAD] * speed) * speed + abs(ctx[FL_CMAG] * ctx[FL_U3]) * speed
    ) / ctx[FL_M]


@inline
def begin(ctx, q1, q2, u1, u2, u3):
    """Start a flight at tau = 0."""
    ctx[FL_YA] = q1
    ctx[FL_YA + 1] = q2
    ctx[FL_YA + 2] = u1
    ctx[FL_YA + 3] = u2
    if ctx[FL_KIND] == FLIGHT_EXACT:
        return
    ctx[FL_U3] = u3
    ctx[FL_TA] = 0.0
    ctx[FL_TB] = 0.0
    ctx[FL_YB] = q1
    ctx[FL_YB + 1] = q2
    ctx[FL_YB + 2] = u1
    ctx[FL_YB + 3] = u2
    kx, ky = rhs(ctx, u1, u2)
    ctx[FL_KA] = kx
    ctx[FL_KA + 1] = ky
    ctx[FL_KB] = kx
    ctx[FL_KB + 1] = ky


@inline
def stages(ctx, q1, q2, u1, u2, k1x, k1y, h, with_error):
    """One Dormand-Prince step of length h from (q1, q2, u1, u2) whose acceleration is
    (k1x, k1y): (n1, n2, w1, w2, k7x, k7y, scaled error norm)."""
    v2x, v2y = u1 + h * _A21 * k1x, u2 + h * _A21 * k1y
    k2x, k2y = rhs(ctx, v2x, v2y)
    v3x = u1 + h * (_A31 * k1x + _A32 * k2x)
    v3y = u2 + h * (_A31 * k1y + _A32 * k2y)
    k3x, k3y = rhs(ctx, v3x, v3y)
    v4x = u1 + h * (_A41 * k1x + _A42 * k2x + _A43 * k3x)
    v4y = u2 + h * (_A41 * k1y + _A42 * k2y + _A43 * k3y)
    k4x, k4y = rhs(ctx, v4x, v4y)
    v5x = u1 + h * (_A51 * k1x + _A52 * k2x + _A53 * k3x + _A54 * k4x)
    v5y = u2 + h * (_A51 * k1y + _A52 * k2y + _A53 * k3y + _A54 * k4y)
    k5x, k5y = rhs(ctx, v5x, v5y)
    v6x = u1 + h * (_A61 * k1x + _A62 * k2x + _A63 * k3x + _A64 * k4x + _A65 * k5x)
    v6y = u2 + h * (_A61 * k1y + _A62 * k2y + _A63 * k3y + _A64 * k4y + _A65 * k5y)
    k6x, k6y = rhs(ctx, v6x, v6y)
    n1 = q1 + h * (_B1 * u1 + _B3 * v3x + _B4 * v4x + _B5 * v5x + _B6 * v6x)
    n2 = q2 + h * (_B1 * u2 + _B3 * v3y + _B4 * v4y + _B5 * v5y + _B6 * v6y)
    w1 = u1 + h * (_B1 * k1x + _B3 * k3x + _B4 * k4x + _B5 * k5x + _B6 * k6x)
    w2 = u2 + h * (_B1 * k1y + _B3 * k3y + _B4 * k4y + _B5 * k5y + _B6 * k6y)
    if not with_error:
        return n1, n2, w1, w2, math.nan, math.nan, 0.0
    k7x, k7y = rhs(ctx, w1, w2)
    e1 = h * (_E1 * u1 + _E3 * v3x + _E4 * v4x + _E5 * v5x + _E6 * v6x + _E7 * w1)
    e2 = h * (_E1 * u2 + _E3 * v3y + _E4 * v4y + _E5 * v5y + _E6 * v6y + _E7 * w2)
    e3 = h * (_E1 * k1x + _E3 * k3x + _E4 * k4x + _E5 * k5x + _E6 * k6x + _E7 * k7x)
    e4 = h * (_E1 * k1y + _E3 * k3y + _E4 * k4y + _E5 * k5y + _E6 * k6y + _E7 * k7y)
    rtol = ctx[FL_RTOL]
    s1 = rtol * (1.0 + max(abs(q1), abs(n1)))
    s2 = rtol * (1.0 + max(abs(q2), abs(n2)))
    s3 = rtol * (1.0 + max(abs(u1), abs(w1)))
    s4 = rtol * (1.0 + max(abs(u2), abs(w2)))
    r1, r2, r3, r4 = e1 / s1, e2 / s2, e3 / s3, e4 / s4
    err = math.sqrt((r1 * r1 + r2 * r2 + r3 * r3 + r4 * r4) / 4)
    return n1, n2, w1, w2, k7x, k7y, err


@inline
def advance(ctx, tau_a, tau_target):
    """One step from tau_a towards tau_target; returns where it ended."""
    if ctx[FL_KIND] == FLIGHT_EXACT:
        return tau_target
    q1, q2, u1, u2 = ctx[FL_YB], ctx[FL_YB + 1], ctx[FL_YB + 2], ctx[FL_YB + 3]
    kx, ky = ctx[FL_KB], ctx[FL_KB + 1]
    span = tau_target - tau_a
    h = min(ctx[FL_H], span)
    for _ in range(200):
        n1, n2, w1, w2, k7x, k7y, err = stages(ctx, q1, q2, u1, u2, kx, ky, h, True)
        if err <= 1.0:
            factor = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err**-0.2))
            # a step cut short by the target says nothing about the next step size
            ctx[FL_H] = max(ctx[FL_H], h * factor) if h == span else h * factor
            ctx[FL_TA] = tau_a
            ctx[FL_YA] = q1
            ctx[FL_YA + 1] = q2
            ctx[FL_YA + 2] = u1
            ctx[FL_YA + 3] = u2
            ctx[FL_KA] = kx
            ctx[FL_KA + 1] = ky
            ctx[FL_TB] = tau_target if h == span else tau_a + h
            ctx[FL_YB] = n1
            ctx[FL_YB + 1] = n2
            ctx[FL_YB + 2] = w1
            ctx[FL_YB + 3] = w2
            ctx[FL_KB] = k7x
            ctx[FL_KB + 1] = k7y
            return ctx[FL_TB]
        h *= max(0.2, 0.9 * err**-0.2)
        ctx[FL_H] = h
    ctx[EN_ERR_VALUE] = tau_a
    ctx[EN_STOP] = E_STEP_CONTROL
    raise KernelError(E_STEP_CONTROL)


@inline
def state(ctx, tau):
    """(q1, q2, u1, u2) at flight time tau (in the current step for Dormand-Prince)."""
    if ctx[FL_KIND] == FLIGHT_EXACT:
        return flight_exact(tau, ctx[FL_YA], ctx[FL_YA + 1], ctx[FL_YA + 2], ctx[FL_YA + 3], ctx[G])
    if tau == ctx[FL_TB]:
        return ctx[FL_YB], ctx[FL_YB + 1], ctx[FL_YB + 2], ctx[FL_YB + 3]
    if tau == ctx[FL_TA]:
        return ctx[FL_YA], ctx[FL_YA + 1], ctx[FL_YA + 2], ctx[FL_YA + 3]
    n1, n2, w1, w2, _, _, _ = stages(
        ctx,
        ctx[FL_YA],
        ctx[FL_YA + 1],
        ctx[FL_YA + 2],
        ctx[FL_YA + 3],
        ctx[FL_KA],
        ctx[FL_KA + 1],
        tau - ctx[FL_TA],
        False,
    )
    return n1, n2, w1, w2
