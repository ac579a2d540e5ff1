"""The paper's impact detection (``method = "rk4"``, :mod:`billiard.models.rk4_locator`) as
kernels: fixed RK4 steps, after each the signed Euclidean distance to the curve from
Newton's method on each wall's nearest-point condition, and an impact located by
shrinking the step (Illinois while its start is clear, bisection otherwise) until the
gap is within 1e-12 m.

The nearest-point functions arrive as ``nears = (near, dnear)``, one first-class function
value per wall, ``g(s, px, py, p)``. When Newton fails from both starts the step needs
the curve's global nearest point, which takes polynomial roots (``numpy.roots``) in
Python: the search stops with ``E_FOOT`` and the question at ``RK_ASK``; the caller
answers it into ``RK_ANSWER`` and runs the search again from the flight's start, which
retraces the same steps (the Newton starts go back to ``RK_FEET0``) and takes the answer.
"""

from __future__ import annotations

import math

from . import flight
from .decorators import inline
from .layout import (
    E_DEPARTURES,
    E_FOOT,
    E_NO_IMPACT,
    EN_ERR_VALUE,
    FL_U3,
    OMEGA,
    RK_ANSWER,
    RK_ANSWERS,
    RK_ASK,
    RK_DEPARTURES,
    RK_ESCAPE,
    RK_FEET,
    RK_FEET0,
    RK_H,
    RK_HI,
    RK_LID,
    RK_LO,
    RK_NWALLS,
    RK_R,
    S_A,
    SURF,
    SURF_STRIDE,
    THETA0,
    KernelError,
)
from .locate import MAX_FLIGHT_TIME, relative

#: Consecutive impacts found at the previous impact's departure point that stop a run
DEPARTURE_LIMIT = 3
#: An impact found within this fraction of a step after the previous one is a departure
DEPARTURE_FRACTION = 1e-6
#: |gap| (m) at which the search accepts the impact time
GAP_TOLERANCE = 1e-12
#: shortest step interval (s) the search refines to
TIME_TOLERANCE = 1e-15
#: Newton iterations on the nearest-point condition from each start
NEWTON_ITERATIONS = 30


@inline
def rk4_step(ctx, q1, q2, u1, u2, h):
    """One classical RK4 step of length h from (q1, q2, u1, u2) (``RK4Flight.step``)."""
    k1x, k1y = flight.rhs(ctx, u1, u2)
    h2 = 0.5 * h
    v2x, v2y = u1 + h2 * k1x, u2 + h2 * k1y
    k2x, k2y = flight.rhs(ctx, v2x, v2y)
    v3x, v3y = u1 + h2 * k2x, u2 + h2 * k2y
    k3x, k3y = flight.rhs(ctx, v3x, v3y)
    v4x, v4y = u1 + h * k3x, u2 + h * k3y
    k4x, k4y = flight.rhs(ctx, v4x, v4y)
    h6 = h / 6.0
    return (
        q1 + h6 * (u1 + 2.0 * v2x + 2.0 * v3x + v4x),
        q2 + h6 * (u2 + 2.0 * v2y + 2.0 * v3y + v4y),
        u1 + h6 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        u2 + h6 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y),
    )


#: how :func:`nearest_newton` ended
NEWTON_FAILED = 0  # it met g'(s) <= 0 (a maximum of the distance nearby) or a non-finite s
NEWTON_CONVERGED = 1  # a step fell below 1e-15 relative
NEWTON_RAN_OUT = 2  # the iterations ran out first


@inline
def nearest_newton(near, dnear, p, s, px, py, iterations):
    """Newton's method on a wall's nearest-point condition
    g(s) = (s - px) + (f(s) - py) f'(s) = 0 from the start s (m), ``near`` and ``dnear``
    being g and dg/ds: (s, how it ended), the one place it is written
    (:func:`billiard.geometry.walls.nearest_newton` runs it interpreted)."""
    for _ in range(iterations):
        d = dnear(s, px, py, p)
        if not d > 0.0:
            return s, NEWTON_FAILED
        step = near(s, px, py, p) / d
        s -= step
        if not math.isfinite(s):
            return s, NEWTON_FAILED
        if abs(step) <= 1e-15 * (1.0 + abs(s)):
            return s, NEWTON_CONVERGED
    return s, NEWTON_RAN_OUT


@inline
def clamp(s, lo, hi):
    """min(max(s, lo), hi), as Python evaluates it."""
    if lo > s:
        s = lo
    if hi < s:
        s = hi
    return s


@inline
def global_foot(ctx, i, px, py):
    """The foot on wall i of the global nearest point of (px, py), as answered, else
    the question (``E_FOOT``)."""
    for k in range(int(ctx[RK_ANSWERS])):
        b = RK_ANSWER + 4 * k
        if ctx[b] == px and ctx[b + 1] == py and ctx[b + 2] == i:
            return ctx[b + 3]
    ctx[RK_ASK] = px
    ctx[RK_ASK + 1] = py
    ctx[RK_ASK + 2] = i
    raise KernelError(E_FOOT)


@inline
def wall_distance(ctx, p, walls, nears, i, px, py):
    """(s, distance (m)) of wall i's nearest point: Newton from the previous foot and
    from the vertical projection, the nearer wins (``FixedStepLocator._wall_distance``)."""
    f = walls[0][i]
    lo = ctx[RK_LO + i]
    hi = ctx[RK_HI + i]
    best_s = 0.0
    best_d = math.inf
    start = ctx[RK_FEET + i]
    for k in range(2):
        s, how = nearest_newton(
            nears[0][i], nears[1][i], p, start if k == 0 else px, px, py, NEWTON_ITERATIONS
        )
        if how != NEWTON_FAILED:
            s = clamp(s, lo, hi)
            dx, dy = px - s, py - f(s, p)
            dist = math.sqrt(dx * dx + dy * dy)
            if dist < best_d:
                best_s, best_d = s, dist
    if best_d == math.inf:
        best_s = global_foot(ctx, i, px, py)
        dx, dy = px - best_s, py - f(best_s, p)
        best_d = math.sqrt(dx * dx + dy * dy)
    ctx[RK_FEET + i] = best_s
    return best_s, best_d


@inline
def clearance(ctx, p, walls, nears, tau, q1, q2, u1, u2):
    """(distance to the boundary minus r (m), surface, s, z) at flight time tau: signed,
    negative for a centre below the curve (``FixedStepLocator._clearance``)."""
    px, py, _, _ = relative(ctx, tau, q1, q2, u1, u2)
    n = int(ctx[RK_NWALLS])
    d = math.inf
    i = 0
    s = 0.0
    for w in range(n):
        sw, dw = wall_distance(ctx, p, walls, nears, w, px, py)
        if dw < d:
            d, i, s = dw, w, sw
    top = walls[0][0](px, p)
    for w in range(1, n):
        fw = walls[0][w](px, p)
        if fw > top:
            top = fw
    if py < top:
        d = -d  # the centre is outside the container
    g, j, z = d - ctx[RK_R], i, math.atan(walls[1][i](s, p))
    lid = int(ctx[RK_LID])
    if lid >= 0:
        level = ctx[SURF + lid * SURF_STRIDE + S_A]
        if level - py < g:
            g, j, s, z = level - py, lid, px, math.pi
    escape = int(ctx[RK_ESCAPE])
    if escape >= 0 and py >= ctx[SURF + escape * SURF_STRIDE + S_A]:
        g, j, s, z = -math.inf, escape, px, math.pi
    return g, j, s, z


@inline
def locate_in_step(ctx, p, walls, nears, tau, q1, q2, u1, u2, gap_lo, h, g_hi, j, s, z):
    """Shrink the step from its start until |gap| <= GAP_TOLERANCE: the event tuple of
    :func:`locate` (``FixedStepLocator._locate_in_step``)."""
    lo, hi = 0.0, h
    g_lo = gap_lo
    best, bj, bs, bz = hi, j, s, z
    side = 0
    for _ in range(400):
        if g_lo > 0.0 and math.isfinite(g_hi):
            step = hi - g_hi * (hi - lo) / (g_hi - g_lo)
            if not lo < step < hi:
                step = 0.5 * (lo + hi)
        else:
            step = 0.5 * (lo + hi)
        y1, y2, y3, y4 = rk4_step(ctx, q1, q2, u1, u2, step)
        g, j, s, z = clearance(ctx, p, walls, nears, tau + step, y1, y2, y3, y4)
        if abs(g) <= GAP_TOLERANCE:
            best, bj, bs, bz = step, j, s, z
            break
        if g > 0.0:
            lo, g_lo = step, g
            if side == -1:
                g_hi *= 0.5
            side = -1
        else:
            hi, g_hi = step, g
            best, bj, bs, bz = hi, j, s, z
            if side == 1:
                g_lo *= 0.5
            side = 1
        if hi - lo < TIME_TOLERANCE:
            break
    e1, e2, e3, e4 = rk4_step(ctx, q1, q2, u1, u2, best)
    theta = (ctx[THETA0] + ctx[OMEGA] * (tau + best)) % (2.0 * math.pi)
    return tau + best, bj, e1, e2, e3, e4, theta, bs, bz


@inline
def count_departure(ctx, tau):
    """Count an impact found at the previous impact's departure point; stop at
    DEPARTURE_LIMIT of them in a row (``E_DEPARTURES``, the step in EN_ERR_VALUE)."""
    h = ctx[RK_H]
    if tau >= DEPARTURE_FRACTION * h:
        ctx[RK_DEPARTURES] = 0.0
        return
    ctx[RK_DEPARTURES] += 1.0
    if ctx[RK_DEPARTURES] >= DEPARTURE_LIMIT:
        ctx[RK_DEPARTURES] = 0.0
        ctx[EN_ERR_VALUE] = h
        raise KernelError(E_DEPARTURES)


@inline
def locate(ctx, p, walls, nears, theta0, q1, q2, u1, u2, u3):
    """Follow the flight from (q1, q2, u1, u2), drive angle theta0, spin u3, in fixed
    RK4 steps to the first contact: (tau, surface, q1, q2, u1, u2, theta, s, z), as
    :func:`billiard.kernels.locate.locate` returns it."""
    ctx[THETA0] = theta0
    ctx[FL_U3] = u3
    n = int(ctx[RK_NWALLS])
    # a search run again after an answer retraces the first one from the same feet
    if ctx[RK_ANSWERS] == 0.0:
        for i in range(n):
            ctx[RK_FEET0 + i] = ctx[RK_FEET + i]
    else:
        for i in range(n):
            ctx[RK_FEET + i] = ctx[RK_FEET0 + i]
    h = ctx[RK_H]
    gap0 = clearance(ctx, p, walls, nears, 0.0, q1, q2, u1, u2)[0]
    k = 0
    while k * h < MAX_FLIGHT_TIME:
        tau = k * h
        y1, y2, y3, y4 = rk4_step(ctx, q1, q2, u1, u2, h)
        g, j, s, z = clearance(ctx, p, walls, nears, tau + h, y1, y2, y3, y4)
        if g <= 0.0:
            event = locate_in_step(ctx, p, walls, nears, tau, q1, q2, u1, u2, gap0, h, g, j, s, z)
            ctx[RK_ANSWERS] = 0.0
            count_departure(ctx, event[0])
            return event
        q1, q2, u1, u2, gap0 = y1, y2, y3, y4, g
        k += 1
    ctx[RK_ANSWERS] = 0.0
    raise KernelError(E_NO_IMPACT)
