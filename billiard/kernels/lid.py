"""The ball pressed against the lid: a contact phase in closed form.

The lid is flat and horizontal in the boundary's frame, the centre on its offset line
(py = the lid's level). While the lid presses the ball the centre moves with the lid
vertically, so the normal force is N = m (A w^2 sin(theta) - g) under the vertical drive
D = A sin(theta): positive while the lid accelerates downward faster than g. Horizontally
the lid exerts only friction: sliding, -mu_k N sgn on the contact point (the top of the
ball, slip vx - r u3); rolling, none (flat, no drag: static friction needs no force). So
with I(tau) and J(tau) = N / m integrated once and twice from the phase's start,

    vx = vx0 - mu_k sgn I,  u3 = u3_0 + mu_k sgn I / (k r),  px = px0 + vx0 tau - mu_k sgn J,

the slip vx - r u3 falls by mu_k (1 + 1/k) I, the phase releases the ball where
sin(theta) = g / (A w^2) on the way down (N = 0), and a wall is reached where px leaves
the interval of x the lid's offset line has inside the walls. Under a horizontal drive
N = -m g: the lid holds no ball (:func:`lid_holds`).

Drag is left out of the phase (an approximation, said in docs/design.md): a phase lasts
less than a drive period P, over which Fowles drag changes the ball's velocity by at most
(c_lin + c_quad |v|) |v| P / m, against mu_k N P / m of friction and the lid's own motion;
in the vertex family of tests/validation/test_vertex.py at most 1.5e-4 of the lid's speed
amplitude A w.
"""

from __future__ import annotations

import math

from .contact import pmin
from .decorators import inline, jit
from .layout import (
    CURVED,
    DRIVE_ACCEL,
    HORIZ,
    IM_K,
    IM_MUK,
    IM_R,
    LINE,
    NSURF,
    OMEGA,
    S_A,
    S_KIND,
    S_WS,
    S_WSLOPE,
    SURF,
    SURF_STRIDE,
    G,
)
from .surfaces import gap_rate

#: bisection steps of an event time: the bracket halves each, to rounding well before
BISECTIONS = 200


@inline
def lid_holds(ctx):
    """Can the lid hold a ball in this scene at all: a vertical drive stronger than g?"""
    if ctx[HORIZ] != 0.0:
        return False
    return ctx[DRIVE_ACCEL] > ctx[G] and ctx[OMEGA] > 0.0


@inline
def lid_press(ctx, theta):
    """N / m (m/s^2) of the lid on a ball moving with it at drive angle theta (vertical
    drive): the lid's downward acceleration A w^2 sin(theta) beyond g."""
    return ctx[DRIVE_ACCEL] * math.sin(theta) - ctx[G]


@inline
def lid_release(ctx, theta0):
    """tau (s) from drive angle theta0, where the lid presses, to the first instant it no
    longer does: sin(theta) = g / (A w^2) with theta in [pi/2, pi] (mod 2 pi)."""
    phi = theta0 % (2.0 * math.pi)
    leave = math.pi - math.asin(ctx[G] / ctx[DRIVE_ACCEL])
    return max(0.0, (leave - phi) / ctx[OMEGA])


@inline
def lid_integrals(ctx, theta0, tau):
    """(I, J): N / m integrated once (m/s) and twice (m) over tau seconds from drive
    angle theta0 (differences of cosines and sines as products: no cancellation)."""
    ga, g, w = ctx[DRIVE_ACCEL], ctx[G], ctx[OMEGA]
    half = math.sin(0.5 * w * tau)
    mid = theta0 + 0.5 * w * tau
    i = 2.0 * ga / w * math.sin(mid) * half - g * tau
    j = ga / w * tau * math.cos(theta0) - 2.0 * ga / (w * w) * math.cos(mid) * half
    return i, j - 0.5 * g * tau * tau


@inline
def lid_motion(ctx, theta0, px0, vx0, w0, sgn, tau):
    """(px, vx, u3, angle turned) of the ball tau seconds into a phase on the lid that
    started at (px0, vx0, w0): sliding with slip sign sgn, or rolling (sgn = 0)."""
    if sgn == 0.0:
        return px0 + vx0 * tau, vx0, w0, w0 * tau
    i, j = lid_integrals(ctx, theta0, tau)
    f = ctx[IM_MUK] * sgn
    spin = f / (ctx[IM_K] * ctx[IM_R])
    return px0 + vx0 * tau - f * j, vx0 - f * i, w0 + spin * i, w0 * tau + spin * j


@inline
def integral_reaches(ctx, theta0, target, hi):
    """The tau in [0, hi] at which I(tau) (increasing while the lid presses) reaches
    target (m/s), or inf where it does not."""
    if target <= 0.0:
        return 0.0
    if lid_integrals(ctx, theta0, hi)[0] < target:
        return math.inf
    lo = 0.0
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        if lid_integrals(ctx, theta0, mid)[0] < target:
            lo = mid
        else:
            hi = mid
    return hi


@inline
def lid_slip_end(ctx, theta0, slip0, hi):
    """tau (s) at which the slip slip0 (m/s) of a ball sliding on the lid vanishes
    (mu_k (1 + 1/k) I = |slip0|), or inf after hi."""
    k = ctx[IM_K]
    return integral_reaches(ctx, theta0, abs(slip0) / (ctx[IM_MUK] * (1.0 + 1.0 / k)), hi)


@jit
def wall_gap(ctx, p, walls, px, py):
    """(gap, j): the least gap (m) of the walls for a centre at (px, py) in the
    boundary's frame and its wall's surface, their warm starts left as they were."""
    least, at = math.inf, -1
    for j in range(int(ctx[NSURF])):
        base = SURF + j * SURF_STRIDE
        kind = ctx[base + S_KIND]
        if kind != CURVED and kind != LINE:
            continue
        ws, slope = ctx[base + S_WS], ctx[base + S_WSLOPE]
        gap = gap_rate(ctx, p, walls, j, px, py, 0.0, 0.0)[0]
        ctx[base + S_WS] = ws
        ctx[base + S_WSLOPE] = slope
        if gap < least:
            least, at = gap, j
    return least, at


@inline
def first_crossing(ctx, p, walls, lid, theta0, px0, vx0, w0, sgn, a, b):
    """The tau in [a, b], over which px moves one way, at which the centre on the lid
    reaches a wall (the least gap falls to zero), or inf."""
    py = ctx[SURF + lid * SURF_STRIDE + S_A]
    pa = lid_motion(ctx, theta0, px0, vx0, w0, sgn, a)[0]
    pb = lid_motion(ctx, theta0, px0, vx0, w0, sgn, b)[0]
    if not (wall_gap(ctx, p, walls, pa, py)[0] > 0.0 and wall_gap(ctx, p, walls, pb, py)[0] <= 0.0):
        return math.inf
    for _ in range(BISECTIONS):
        mid = 0.5 * (a + b)
        if not a < mid < b:
            break
        pm = lid_motion(ctx, theta0, px0, vx0, w0, sgn, mid)[0]
        if wall_gap(ctx, p, walls, pm, py)[0] > 0.0:
            a = mid
        else:
            b = mid
    return b


@jit
def lid_wall_reach(ctx, p, walls, lid, theta0, px0, vx0, w0, sgn, hi):
    """tau (s) in [0, hi] at which the ball on the lid reaches a wall, or inf: px is
    monotone on each side of the one instant vx may vanish (sliding, vx changes at the
    rate -mu_k sgn N / m of one sign)."""
    turn = hi
    if sgn != 0.0 and vx0 * sgn > 0.0:
        turn = pmin(integral_reaches(ctx, theta0, vx0 / (ctx[IM_MUK] * sgn), hi), hi)
    tau = first_crossing(ctx, p, walls, lid, theta0, px0, vx0, w0, sgn, 0.0, turn)
    if tau == math.inf and turn < hi:
        tau = first_crossing(ctx, p, walls, lid, theta0, px0, vx0, w0, sgn, turn, hi)
    return tau
