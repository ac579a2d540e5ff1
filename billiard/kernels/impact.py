"""The impact laws, chosen by their kind (``ctx[IM_KIND]``) in :func:`impact_law`, which
every kernel calls: Kane and Levinson's law with the low-velocity rule on the generated
maps (:class:`billiard.models.impact.KaneLevinsonImpact` is this, run interpreted;
:class:`billiard.models.impact.LowVelocityRule` describes the rule), the other laws of
the ladder (docs/impact-laws.md) on the same maps; and the chatter series an impact
starts."""

from __future__ import annotations

import math

from .ball import contact_velocity, impact_slip, impact_stick, impact_walton
from .decorators import inline
from .layout import (
    ANGLE_DEPENDENT,
    E_KIND,
    ELASTIC,
    EN_ERR_VALUE,
    EN_STOP,
    ENERGY_DEPENDENT,
    IM_ASLOPE,
    IM_BETA0,
    IM_E,
    IM_EB,
    IM_EREF,
    IM_ESCALE,
    IM_EXP,
    IM_K,
    IM_KIND,
    IM_M,
    IM_MUK,
    IM_MUS,
    IM_R,
    IM_VISC,
    IM_VREF,
    KANE_LEVINSON,
    POINT_PARTICLE,
    POWER_LAW,
    SLIP,
    STICK,
    VISCOELASTIC,
    WALTON,
    KernelError,
)

#: Relative tolerance of the friction-cone test |Rt| <= mu_s Rn, in units of the
#: momenta that enter the impulses: 16 ulps. The no-slip impulse Rt is a sum of a few
#: products of the ball's and the boundary's velocity components with the mass, so it
#: carries a rounding error of a few ulps of m (|u1| + |u2| + r |u3| + |vb1| + |vb2|).
#: A purely normal impact (no tangential relative velocity, no spin) has Rt = 0 exactly
#: but computes |Rt| ~ 1e-17 m |u|, which with mu_s = 0 used to exceed mu_s Rn = 0 and
#: label the impact ``slip``. The cone is widened by this much so that rounding alone
#: never decides the regime; an impulse genuinely outside the cone (by more than 1e-14 of
#: the momenta) still slips.
REGIME_RTOL = 16 * 2.0**-52

#: The viscoelastic restitution's series in x = A alpha^(2/5) v^(1/5) (v the normal
#: impact speed, m/s): e = 1 - C1 x + C2 x^2 (J. Ramirez, T. Poeschel, N. V. Brilliantov
#: and T. Schwager, Phys. Rev. E 60, 4465, 1999; the first order is N. V. Brilliantov,
#: F. Spahn, J.-M. Hertzsch and T. Poeschel, Phys. Rev. E 53, 5382, 1996).
VISCO_C1 = 1.15344
VISCO_C2 = 0.79826
#: Beyond x = C1 / (2 C2) the truncated series would rise again: it is held at its
#: minimum there, 1 - C1^2 / (4 C2) = 0.5834, so that e never grows with the speed.
VISCO_XMAX = VISCO_C1 / (2.0 * VISCO_C2)
VISCO_EMIN = 1.0 - VISCO_C1 * VISCO_C1 / (4.0 * VISCO_C2)


@inline
def viscoelastic_restitution(b, v):
    """The viscoelastic restitution at the normal impact speed ``v`` (m/s) of a contact
    with dissipation ``b`` = A alpha^(2/5) ((s/m)^(1/5)): the series VISCO_C1, VISCO_C2."""
    x = b * v**0.2
    if x >= VISCO_XMAX:
        return VISCO_EMIN
    return 1.0 - VISCO_C1 * x + VISCO_C2 * x * x


@inline
def restitution(ctx, kind, wt, wn):
    """Newton's e of an impact of kind ``kind`` whose contact point approaches with the
    relative velocity (wt, wn) (m/s): contact.restitution for Kane and Levinson's,
    Walton's and the point particle's constant e, else the law's e(v) (docs/impact-laws.md)."""
    v = abs(wn)
    if kind == POWER_LAW:
        # e_ref (v / v_ref)^-p, at most 1; p = 0 is e_ref exactly; 1 at v = 0 (p > 0)
        p = ctx[IM_EXP]
        if not v > 0.0:
            return 1.0 if p > 0.0 else ctx[IM_EREF]
        e = ctx[IM_EREF] * (v / ctx[IM_VREF]) ** (-p)
        return e if e < 1.0 else 1.0
    if kind == VISCOELASTIC:
        return viscoelastic_restitution(ctx[IM_VISC], v)
    if kind == ENERGY_DEPENDENT or kind == POINT_PARTICLE:
        scale = ctx[IM_ESCALE]
        if scale > 0.0:
            # from 1 for a slow impact to contact.restitution for an energetic one
            inf = ctx[IM_E]
            return inf + (1.0 - inf) * math.exp(-0.5 * ctx[IM_M] * wn * wn / scale)
    if kind == ANGLE_DEPENDENT:
        slope = ctx[IM_ASLOPE]
        if slope != 0.0 and v > 0.0:
            # e rises with the tangent of the angle of incidence |wt| / |wn|, at most 1
            e = ctx[IM_E] + slope * (abs(wt) / v)
            return e if e < 1.0 else 1.0
    return ctx[IM_E]


@inline
def impact_law(ctx, u1, u2, u3, z, vb1, vb2, pressing):
    """The impact law of kind ``ctx[IM_KIND]``: post-impact (u1, u2, u3, Rt, Rn, regime
    code, resting, wt, wn), as :func:`kane_levinson` documents them. Another law is a
    branch here and in :func:`restitution` (docs/design.md, "How to add a model"); a
    kind the kernels do not have stops with E_KIND."""
    kind = ctx[IM_KIND]
    if kind == KANE_LEVINSON:
        return kane_levinson(ctx, u1, u2, u3, z, vb1, vb2, pressing)
    if kind >= WALTON and kind <= POINT_PARTICLE and kind == math.floor(kind):
        return ladder(ctx, kind, u1, u2, u3, z, vb1, vb2, pressing)
    ctx[EN_ERR_VALUE] = kind
    ctx[EN_STOP] = E_KIND
    raise KernelError(E_KIND)


@inline
def kane_levinson(ctx, u1, u2, u3, z, vb1, vb2, pressing):
    """Post-impact (u1, u2, u3, Rt, Rn, regime code, resting, wt, wn) for a ball with
    speeds (u1, u2, u3) hitting a boundary with tangent angle z moving at (vb1, vb2);
    ``pressing``: its relative acceleration pushes it into the surface. (wt, wn): the
    contact point's velocity relative to the boundary before the impact (m/s), which
    the law starts from (the landing test and the record read it too). The impulse-
    momentum equations are T. R. Kane and D. A. Levinson, *Dynamics: Theory and
    Applications* (McGraw-Hill, 1985), derived in ``derivation/ball.py``."""
    return ladder(ctx, KANE_LEVINSON, u1, u2, u3, z, vb1, vb2, pressing)


@inline
def ladder(ctx, kind, u1, u2, u3, z, vb1, vb2, pressing):
    """:func:`kane_levinson` for the impact law ``kind``: Newton's e from
    :func:`restitution`; the sticking impact Kane and Levinson's no-slip one, or
    Walton's tangential restitution wt+ = -beta0 wt- (WALTON, its cone mu =
    contact.mu_kinetic), or none for the frictionless POINT_PARTICLE, which keeps the
    tangential velocity and the spin (regime slip); the low-velocity rule for all."""
    m = ctx[IM_M]
    r = ctx[IM_R]
    k = ctx[IM_K]
    threshold = ctx[IM_EB]
    wt, wn = contact_velocity(u1, u2, u3, z, vb1, vb2, r)
    e = restitution(ctx, kind, wt, wn)
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
        return u1, u2, u3, 0.0, 0.0, ELASTIC if low else SLIP, False, wt, wn
    frictionless = kind == POINT_PARTICLE
    if frictionless:
        n1, n2, n3, rt, rn = impact_slip(v1, v2, u3, z, vb1, vb2, m, r, k, e, 0.0, 1.0)
        n3 = u3
        regime = SLIP
        cone = math.inf
    elif kind == WALTON:
        n1, n2, n3, rt, rn = impact_walton(v1, v2, u3, z, vb1, vb2, m, r, k, e, ctx[IM_BETA0])
        regime = STICK
        cone = ctx[IM_MUK]
    else:
        n1, n2, n3, rt, rn = impact_stick(v1, v2, u3, z, vb1, vb2, m, r, k, e)
        regime = STICK
        cone = ctx[IM_MUS]
    rounding = REGIME_RTOL * m * (abs(v1) + abs(v2) + r * abs(u3) + abs(vb1) + abs(vb2))
    applied = 1.0
    if resting and rn > 0.0:
        c, s = math.cos(z), math.sin(z)
        applied = m * (c * (n2 - u2) - s * (n1 - u1)) / rn
    if not frictionless and abs(rt) > cone * applied * rn + rounding:
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
    return n1, n2, n3, rt, rn, regime, resting, wt, wn


@inline
def rebound_settles(e, below, wn, elastic):
    """Does the chattering an impact starts settle: an inelastic contact (e < 1) whose
    rebound speed e |wn| (m/s) is at most the landing speed ``below``
    (``contact.elastic_below``), or the low-velocity rule applied (``elastic``)? The one
    criterion for landing on a wall and for being held by two."""
    if e >= 1.0:
        return False
    return e * abs(wn) <= below or elastic


#: The chatter's tail is summed (:func:`chatter_tail`) once the time it has left is at
#: most this fraction of the drive period: the series is followed impact by impact down to
#: there. Far below any time resolved (1e-6 of a period), far above the time the impacts
#: pile up in (``rules.COLLAPSE_SPAN`` holds only a few of its impacts for e < 0.9).
CHATTER_TAIL = 1e-6


@inline
def chatter_period(omega):
    """The time scale (s) of the chatter's tail: the drive period 2 pi / omega, or 1 s on a
    boundary with no drive frequency (omega = 0, rad/s)."""
    if omega > 0.0:
        return 2.0 * math.pi / omega
    return 1.0


@inline
def chatter_tail(e, wn, accel, omega):
    """May the chattering an impact starts be summed: an inelastic contact (e < 1) whose
    rebound speed v = e |wn| (m/s) the wall, pressing the ball with acceleration ``accel``
    (m/s^2, > 0), brings to rest within CHATTER_TAIL of the drive period (omega, rad/s):
    2 v / (accel (1 - e)), the sum of the remaining flights at a constant ``accel``? The
    engine then decides on the exact bound (:mod:`billiard.models.chatter`)."""
    if e >= 1.0 or not accel > 0.0:
        return False
    return 2.0 * e * abs(wn) <= CHATTER_TAIL * chatter_period(omega) * accel * (1.0 - e)


#: The largest error of a summed chatter series' end accepted, as a fraction of the
#: drive period (1 s without a drive frequency): 1e-8 of 0.05 s is 5e-10 s.
CHATTER_TOL = 1e-8
#: :func:`chatter_time`'s answer when the series may not be summed
NOT_SUMMED = -1.0


@inline
def chatter_bracket(v, e, a0, jerk, window):
    """The times (s) within which a chatter series ends (see
    :mod:`billiard.models.chatter`): rebound speed ``v`` (m/s), restitution ``e`` < 1,
    acceleration into the wall ``a0`` (m/s^2) at its start, changing at most ``jerk``
    (m/s^3) over ``window`` seconds. (0, inf) when the bound does not hold: the
    acceleration may vanish in the window, the series may not converge, or it may
    outlast the window."""
    if v == 0.0:
        return 0.0, 0.0
    spread = jerk * window
    a_lo, a_hi = a0 - spread, a0 + spread
    if not a_lo > 0.0:
        return 0.0, math.inf
    rho = math.sqrt(a_hi / a_lo)
    if not e * rho < 1.0:
        return 0.0, math.inf
    lo = 2.0 * v / (a_hi * (1.0 - e / rho))
    hi = 2.0 * v / (a_lo * (1.0 - e * rho))
    if hi > window:
        return 0.0, math.inf
    return lo, hi


@inline
def chatter_time(v, e, a0, period):
    """T0 = 2 v / (a0 (1 - e)), the time a chatter series with rebound speed ``v`` takes
    at the constant acceleration ``a0`` into the wall, when it is positive and at most
    CHATTER_TAIL of ``period`` (0.0 for v = 0); NOT_SUMMED otherwise. The series is
    summed when also :func:`chatter_bounded` holds."""
    if not a0 > 0.0:
        return NOT_SUMMED
    t0 = 2.0 * v / (a0 * (1.0 - e))
    if t0 == 0.0:
        return 0.0
    if not t0 <= CHATTER_TAIL * period:
        return NOT_SUMMED  # followed impact by impact until its tail is this short
    return t0


@inline
def chatter_bounded(v, e, a0, a1, a2, t0, period):
    """Is the error of T0 = ``t0`` at most CHATTER_TOL of ``period``, the acceleration
    into the wall being a0, a1, a2 at 0, t0 and 2 t0 after the impact (its rate
    bounded by twice the larger difference quotient over the window 2 t0)?"""
    window = 2.0 * t0
    jerk = 2.0 * pmax(abs(a1 - a0), abs(a2 - a1)) / t0
    lo, hi = chatter_bracket(v, e, a0, jerk, window)
    return not hi - lo > CHATTER_TOL * period


@inline
def pmax(a, b):
    """Python's ``max(a, b)``: b only when it is greater."""
    return b if b > a else a
