"""Kane and Levinson's impact law with the low-velocity rule
(:class:`billiard.impact.KaneLevinsonImpact`, :class:`billiard.impact.LowVelocityRule`)
on the generated maps; same operations in the same order."""

from __future__ import annotations

import math

from billiard.impact import REGIME_RTOL
from billiard.kernels.ball import contact_velocity, impact_slip, impact_stick
from billiard.kernels.borrow import inline
from billiard.kernels.layout import (
    ELASTIC,
    IM_E,
    IM_EB,
    IM_K,
    IM_M,
    IM_MUK,
    IM_MUS,
    IM_R,
    SLIP,
    STICK,
)


@inline
def kane_levinson(ctx, u1, u2, u3, z, vb1, vb2, pressing):
    """Post-impact (u1, u2, u3, Rt, Rn, regime code, resting) for a ball with speeds
    (u1, u2, u3) hitting a boundary with tangent angle z moving at (vb1, vb2);
    ``pressing``: its relative acceleration pushes it into the surface."""
    m = ctx[IM_M]
    r = ctx[IM_R]
    k = ctx[IM_K]
    threshold = ctx[IM_EB]
    wt, wn = contact_velocity(u1, u2, u3, z, vb1, vb2, r)
    e = ctx[IM_E]
    low = abs(wn) < threshold
    resting = False
    v1, v2 = u1, u2
    if low:
        e = 1.0
        if pressing and wn > -threshold:
            # a lying ball: shift its normal velocity to an approach at the threshold
            shift = -threshold - wn
            v1 -= math.sin(z) * shift
            v2 += math.cos(z) * shift
            resting = True
    if wn >= 0.0 and not resting:
        # the contact point is already separating: no impulse
        return u1, u2, u3, 0.0, 0.0, ELASTIC if low else SLIP, False
    n1, n2, n3, rt, rn = impact_stick(v1, v2, u3, z, vb1, vb2, m, r, k, e)
    regime = STICK
    rounding = REGIME_RTOL * m * (abs(v1) + abs(v2) + r * abs(u3) + abs(vb1) + abs(vb2))
    applied = 1.0
    if resting and rn > 0.0:
        c, s = math.cos(z), math.sin(z)
        applied = m * (c * (n2 - u2) - s * (n1 - u1)) / rn
    if abs(rt) > ctx[IM_MUS] * applied * rn + rounding:
        sgn = math.copysign(1.0, wt)
        n1, n2, n3, rt, rn = impact_slip(
            v1, v2, u3, z, vb1, vb2, m, r, k, e, ctx[IM_MUK] * applied, sgn
        )
        regime = SLIP
    if low:
        regime = ELASTIC
    if resting:
        # the impulse actually applied to the ball's true pre-impact velocity
        c, s = math.cos(z), math.sin(z)
        du1, du2 = n1 - u1, n2 - u2
        rt = m * (c * du1 + s * du2)
        rn = m * (c * du2 - s * du1)
    return n1, n2, n3, rt, rn, regime, resting
