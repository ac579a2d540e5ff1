"""The event-driven impact locator over the state vector (the search
:mod:`billiard.models.event_locator` describes;
:class:`billiard.models.event_locator.EventLocator` is this, run interpreted): substeps
proven clear by the gap's deceleration bound, grazing candidates, halving, and the root
refinement. A substep split in two is one loop over a stack of substeps, not a
recursion. "No time" is :data:`NONE` (the times searched are >= 0)."""

from __future__ import annotations

import math

from . import flight
from .decorators import inline
from .decorators import ulp as _ulp
from .drive import accel_to_boundary_frame, to_boundary_frame
from .layout import (
    DRIVE_ACCEL,
    E_EXTREMUM,
    E_NO_IMPACT,
    E_ROOT,
    EN_STOP,
    H_BRACKET,
    H_FIRST,
    H_LONGEST,
    HORIZ,
    NSURF,
    OMEGA,
    S_DGA,
    S_DGB,
    S_GA,
    S_GB,
    S_LEAVING,
    SPLIT,
    STACK,
    STACK_DEPTH,
    STACK_ENTRY,
    SURF,
    SURF_STRIDE,
    THETA0,
    TURN,
    G,
    KernelError,
)
from .surfaces import contact, gap_accel, gap_accel_bound, gap_rate, max_gap_deceleration

# The longest flight the locators follow before giving up (s of simulated time).
MAX_FLIGHT_TIME = 1.0e3
# How many times a substep may be halved when the bound cannot prove it clear.
MAX_SPLITS = 8
# A gap this small (m) is contact to within rounding: G is a difference of heights of
# order 0.1 m, so its rounding error is ~1e-17 m; a surface that close at the start of a
# flight and moving away is being left, not approached.
CONTACT_TOLERANCE = 1e-13
# Rounding noise of a computed gap (m): below this a gap's sign carries no information.
GAP_NOISE = 1e-16
# Rounding noise of a gap's rate relative to the speeds it is a difference of (the
# ball's and the boundary's, m/s): each component of the relative velocity carries
# about 2.2e-16 of them, so a rate below this is zero to within rounding, and the
# gap's acceleration tells whether a surface in contact is being left or pressed. (A
# ball at rest in a shaken vertex, lifted off by the drive, approached a wall at 4e-20
# m/s beside speeds of 1.17 m/s: an impact at tau = 0 again and again; or, leaving at
# 3e-18 m/s, met it again 3e-20 s later, before the gap opened beyond rounding.) A
# separating rate, however small, of a ball pressed into the surface is left as it is:
# the end of a chatter series.
RATE_NOISE = 1e-15

assert MAX_SPLITS < STACK_DEPTH  # every split keeps at most one pending substep

#: "no impact in this substep"
NONE = -1.0


@inline
def provably_clear(ga, dga, gb, dgb, h, m):
    """True when G > 0 on the whole substep of length h, given G and dG/dtau at both ends
    (both G > 0) and m >= -d2G/dtau2 on it.

    From each end, G is above a parabola: L_a(t) = ga + dga t - m t^2 / 2 and
    L_b(t) = gb - dgb (h - t) - m (h - t)^2 / 2, so G >= max(L_a, L_b). Both are concave,
    so the minimum of their maximum is at an end (where it is ga or gb > 0) or where they
    cross; L_a - L_b is linear in t, so there is at most one crossing.
    """
    slope = dga - dgb - m * h
    if slope == 0.0:
        return True  # one parabola lies above the other throughout
    tc = (gb - ga - dgb * h - 0.5 * m * h * h) / slope
    if not 0.0 < tc < h:
        return True
    return ga + dga * tc - 0.5 * m * tc * tc > 0.0


@inline
def ulp(x):
    """math.ulp(x) for a finite x (numba has no math.ulp: compiled, exact arithmetic)."""
    return _ulp(x)


@inline
def relative(ctx, tau, q1, q2, u1, u2):
    """Centre position and velocity relative to the boundary at flight time tau."""
    return to_boundary_frame(ctx, ctx[THETA0] + ctx[OMEGA] * tau, q1, q2, u1, u2)


@inline
def relative_acceleration(ctx, tau, u1, u2):
    a1, a2 = flight.acceleration(ctx, u1, u2)
    return accel_to_boundary_frame(ctx, ctx[THETA0] + ctx[OMEGA] * tau, a1, a2)


@inline
def opening(ctx, p, walls, j, tau, u1, u2, px, py, vx, vy):
    """(d2G/dtau2, opens) of surface j at tau, the ball's velocity (u1, u2), the centre's
    position and velocity relative to the boundary (px, py, vx, vy): ``opens`` when the
    flight's acceleration does not press the ball into the surface beyond rounding (a
    lift-off, where the normal force has just reached zero; a release from a vertex; an
    impact with e = 0 where the wall does not press), nor beyond the air's forces, which
    a contact phase's equations hold only in part (no Magnus force: a spinning ball
    they let go of may be pressed back by it)."""
    ax, ay = relative_acceleration(ctx, tau, u1, u2)
    a = gap_accel(ctx, p, walls, j, px, py, vx, vy, ax, ay)
    noise = RATE_NOISE * (abs(ax) + abs(ay) + ctx[G] + ctx[DRIVE_ACCEL])
    air = flight.aero_bound(ctx, math.sqrt(u1 * u1 + u2 * u2))
    return a, a >= -gap_accel_bound(ctx, j, noise + air)


@inline
def gap(ctx, p, walls, j, tau):
    q1, q2, u1, u2 = flight.state(ctx, tau)
    px, py, vx, vy = relative(ctx, tau, q1, q2, u1, u2)
    return gap_rate(ctx, p, walls, j, px, py, vx, vy)


@inline
def event(ctx, p, walls, tau, j):
    """(tau, j, q1, q2, u1, u2, theta, s, z): the ball touches surface j at tau."""
    q1, q2, u1, u2 = flight.state(ctx, tau)
    px = relative(ctx, tau, q1, q2, u1, u2)[0]
    s, z = contact(ctx, p, walls, j, px)
    theta = (ctx[THETA0] + ctx[OMEGA] * tau) % (2.0 * math.pi)
    return tau, j, q1, q2, u1, u2, theta, s, z


@inline
def first_positive_root(c0, c1, c2):
    """Smallest positive root of c0 + c1 t + c2 t^2 (inf when there is none)."""
    if c2 == 0.0:
        return -c0 / c1 if c1 < 0.0 < c0 or c0 < 0.0 < c1 else math.inf
    disc = c1 * c1 - 4.0 * c2 * c0
    if disc < 0.0:
        return math.inf
    root = math.sqrt(disc)
    q = -0.5 * (c1 + math.copysign(root, c1))
    best = math.inf
    have = False
    x = q / c2
    if x > 0.0:
        best, have = x, True
    x = c0 / q if q != 0.0 else math.inf
    if x > 0.0 and (not have or x < best):
        best = x
    return best


@inline
def quadratic_start(lo, glo, dglo, hi, dghi):
    tc = first_positive_root(glo, dglo, 0.5 * (dghi - dglo) / (hi - lo))
    return lo + tc if tc < hi - lo else math.nan


@inline
def accel_bounds(ctx, u1, u2, window):
    """(sup |a_x|, sup -a_y, sup a_y) of the relative acceleration over a window."""
    g = ctx[G]
    speed = math.sqrt(u1 * u1 + u2 * u2) + 2.0 * g * window
    aero = flight.aero_bound(ctx, speed)
    if ctx[HORIZ] != 0.0:
        return ctx[DRIVE_ACCEL] + aero, g + aero, aero - g
    return aero, g + ctx[DRIVE_ACCEL] + aero, ctx[DRIVE_ACCEL] + aero - g


@inline
def root(ctx, p, walls, j, lo, glo, dglo, hi, ghi, dghi):
    """Earliest time with G <= 0 in a bracket with G(lo) > 0 >= G(hi), to rounding."""
    t = quadratic_start(lo, glo, dglo, hi, dghi)
    if not lo < t < hi:
        t = hi - ghi * (hi - lo) / (ghi - glo)  # regula falsi
        if not lo < t < hi:
            t = 0.5 * (lo + hi)
    dx = dx_old = hi - lo
    for _ in range(200):
        g, dg = gap(ctx, p, walls, j, t)
        if g > 0.0:
            lo = t
        else:
            hi = t
        width = hi - lo
        if width <= 4.0 * ulp(hi) or width * abs(dg) <= GAP_NOISE:
            return hi
        step = g / dg if dg != 0.0 else math.inf
        tiny = max(2.0 * ulp(t), 0.5 * GAP_NOISE / abs(dg)) if dg != 0.0 else 0.0
        if abs(step) < tiny:
            t = t + tiny if g > 0.0 else t - tiny
            if not lo < t < hi:
                t = lo + 0.5 * width
            continue
        newton = t - step
        if not lo < newton < hi or abs(2.0 * g) > abs(dx_old * dg):
            dx_old, dx = dx, 0.5 * width
            t = lo + dx
            continue
        dx_old, dx = dx, step
        t = newton
    ctx[EN_STOP] = E_ROOT
    raise KernelError(E_ROOT)


@inline
def rate_root(ctx, p, walls, j, a, da, b, db):
    """Root of dG/dtau in (a, b), where it changes sign (Illinois)."""
    side = 0
    for _ in range(200):
        t = b - db * (b - a) / (db - da)
        if not a < t < b:
            t = 0.5 * (a + b)
        _, d = gap(ctx, p, walls, j, t)
        if d == 0.0:
            return t
        if (d < 0.0) == (da < 0.0):
            a, da = t, d
            if side == -1:
                db *= 0.5
            side = -1
        else:
            b, db = t, d
            if side == 1:
                da *= 0.5
            side = 1
        if b - a <= 1e-13 + 4.0 * ulp(b):
            return 0.5 * (a + b)
    ctx[EN_STOP] = E_EXTREMUM
    raise KernelError(E_EXTREMUM)


@inline
def scan(ctx, p, walls, j, ta, ga, dga, tb, gb, dgb, m, splits, leaving):
    """First time in (ta, tb] at which the ball reaches surface j, or NONE. G and
    dG/dtau are known at both ends, m >= -d2G/dtau2 on the substep; ``leaving``: the
    ball is separating from j at ta (G ~ 0, dG/dtau >= 0), else it is clear of it.

    A substep split in two continues with its left half and keeps the right half on a
    stack, scanned when the left one holds no contact: the gaps are evaluated from left
    to right (the warm starts of the offset inversion depend on the order). A loop, not
    a recursion: numba cannot reload a cached recursive function.
    """
    top = 0
    while True:
        if leaving:
            span = tb - ta
            if not (gb > 0.0 and provably_clear(max(ga, 0.0), dga, gb, dgb, span, m)):
                # restart where the ball has certainly risen off the surface: after the
                # top of the bound's parabola dga t - m t^2 / 2, or, from a grazing
                # start (dga = 0: G opens with the acceleration, as t^2, or as t^3 at a
                # lift-off, where the normal force crosses zero), where G > 0 is
                # measured within half a bracket, which holds at most one crossing: G
                # leaves 0 at ta and is positive there, so it did not cross in between
                proven = m > 0.0 and dga > 0.0 and dga / m < span
                if proven:
                    tp = ta + dga / m
                else:
                    tp = ta + 0.5 * min(span, ctx[H_BRACKET])
                gp, dgp = gap(ctx, p, walls, j, tp)
                if gp > 0.0:
                    ta, ga, dga = tp, gp, dgp
                    leaving = False
                    continue
                if proven:
                    q1, q2, u1, u2 = flight.state(ctx, ta)
                    px, py, vx, vy = relative(ctx, ta, q1, q2, u1, u2)
                    if opening(ctx, p, walls, j, ta, u1, u2, px, py, vx, vy)[1]:
                        # a rate of rounding's size (a gap just below zero kept closed
                        # up to the top of its parabola) and an acceleration that
                        # opens it: a grazing start
                        dga = 0.0
                        continue
                if proven or splits == 0:
                    return tp  # the contact never opened beyond rounding
                ctx[SPLIT] = 1.0
                tb, gb, dgb = tp, gp, dgp
                splits -= 1
                continue
        elif gb <= 0.0 and (tb - ta <= ctx[H_BRACKET] or splits == 0):
            return root(ctx, p, walls, j, ta, ga, dga, tb, gb, dgb)
        elif gb > 0.0 and provably_clear(ga, dga, gb, dgb, tb - ta, m):
            pass
        elif gb > 0.0 and dga < 0.0 < dgb and splits > 0:
            # grazing candidate: a minimum of the gap inside the substep; the half after
            # it only matters when the gap is still positive there
            tm = rate_root(ctx, p, walls, j, ta, dga, tb, dgb)
            gm, dgm = gap(ctx, p, walls, j, tm)
            if gm > 0.0:
                top = push(ctx, top, tm, gm, dgm, tb, gb, dgb, splits - 1)
            tb, gb, dgb = tm, gm, dgm
            splits -= 1
            continue
        elif gb > 0.0 and splits == 0:
            pass
        else:
            # look closer: halve the substep, scan both halves in order
            ctx[SPLIT] = 1.0
            tm = 0.5 * (ta + tb)
            gm, dgm = gap(ctx, p, walls, j, tm)
            if gm > 0.0:
                top = push(ctx, top, tm, gm, dgm, tb, gb, dgb, splits - 1)
            tb, gb, dgb = tm, gm, dgm
            splits -= 1
            continue
        # no contact in this substep: the next pending one
        if top == 0:
            return NONE
        top -= 1
        o = STACK + top * STACK_ENTRY
        ta, ga, dga = ctx[o], ctx[o + 1], ctx[o + 2]
        tb, gb, dgb = ctx[o + 3], ctx[o + 4], ctx[o + 5]
        splits = int(ctx[o + 6])
        leaving = False


@inline
def push(ctx, top, ta, ga, dga, tb, gb, dgb, splits):
    """Keep a substep to scan later; returns the new stack size."""
    o = STACK + top * STACK_ENTRY
    ctx[o] = ta
    ctx[o + 1] = ga
    ctx[o + 2] = dga
    ctx[o + 3] = tb
    ctx[o + 4] = gb
    ctx[o + 5] = dgb
    ctx[o + 6] = float(splits)
    return top + 1


@inline
def locate(ctx, p, walls, theta0, q1, q2, u1, u2, u3):
    """Follow the flight from (q1, q2, u1, u2), drive angle theta0, to the first contact
    with a surface: the event tuple of :func:`event`."""
    ctx[THETA0] = theta0
    flight.begin(ctx, q1, q2, u1, u2, u3)
    n = int(ctx[NSURF])
    ta = 0.0
    ya3, ya4 = u1, u2
    pxa, pya, vxa, vya = relative(ctx, 0.0, q1, q2, u1, u2)
    for j in range(n):
        base = SURF + j * SURF_STRIDE
        g0, dg0 = gap_rate(ctx, p, walls, j, pxa, pya, vxa, vya)
        ctx[base + S_GA] = g0
        ctx[base + S_DGA] = dg0
        ctx[base + S_LEAVING] = 0.0
    # at tau = 0 a surface in contact is being left, or hit again at once
    immediate = -1
    immediate_rate = 0.0
    for j in range(n):
        base = SURF + j * SURF_STRIDE
        g0 = ctx[base + S_GA]
        dg0 = ctx[base + S_DGA]
        if g0 > CONTACT_TOLERANCE:
            continue
        # at rest relative to it to within rounding, and accelerating away (or not
        # pressed: ``opening``): a grazing start, G = dG/dtau = 0, whichever sign
        # rounding gave them, and the gap opened by the acceleration, which a rising
        # rate cannot prove (scan would wait dG/dtau / m for it, a time in which nothing
        # opens), nor a falling one deny (a search from G = 1e-18 m at -5e-17 m/s
        # meets it 2e-18 s on)
        still = abs(dg0) <= RATE_NOISE * (abs(u1) + abs(u2) + abs(u1 - vxa) + abs(u2 - vya))
        a0, opens = 0.0, False
        if still:
            a0, opens = opening(ctx, p, walls, j, 0.0, u1, u2, pxa, pya, vxa, vya)
        if opens:
            ctx[base + S_DGA] = 0.0
            dg0 = 0.0
        elif g0 > 0.0 and dg0 < 0.0:
            continue  # approached from outside: the search finds it
        elif still and dg0 <= 0.0:
            dg0 = a0
        if dg0 >= 0.0:
            ctx[base + S_LEAVING] = 1.0
        elif immediate < 0 or dg0 < immediate_rate:
            immediate = j
            immediate_rate = dg0
    if immediate >= 0:
        return event(ctx, p, walls, 0.0, immediate)

    h = ctx[H_FIRST]
    while ta < MAX_FLIGHT_TIME:
        tb = flight.advance(ctx, ta, ta + h)
        yb1, yb2, yb3, yb4 = flight.state(ctx, tb)
        pxb, pyb, vxb, vyb = relative(ctx, tb, yb1, yb2, yb3, yb4)
        for j in range(n):
            base = SURF + j * SURF_STRIDE
            g1, dg1 = gap_rate(ctx, p, walls, j, pxb, pyb, vxb, vyb)
            ctx[base + S_GB] = g1
            ctx[base + S_DGB] = dg1
        span = tb - ta
        speed = math.sqrt(vxa * vxa + vya * vya)
        ctx[H_BRACKET] = ctx[H_FIRST]
        if speed * ctx[H_BRACKET] > ctx[TURN]:
            ctx[H_BRACKET] = ctx[TURN] / speed
        bx, bdown, bup = accel_bounds(ctx, ya3, ya4, span)
        ctx[SPLIT] = 0.0
        first = NONE
        first_j = -1
        for j in range(n):
            base = SURF + j * SURF_STRIDE
            m = max_gap_deceleration(ctx, j, pxa, vxa, span, bx, bdown, bup)
            tau = scan(
                ctx,
                p,
                walls,
                j,
                ta,
                ctx[base + S_GA],
                ctx[base + S_DGA],
                tb,
                ctx[base + S_GB],
                ctx[base + S_DGB],
                m,
                MAX_SPLITS,
                ctx[base + S_LEAVING] != 0.0,
            )
            if tau != NONE and (first_j < 0 or tau < first):
                first = tau
                first_j = j
        if first_j >= 0:
            return event(ctx, p, walls, first, first_j)
        for j in range(n):
            base = SURF + j * SURF_STRIDE
            if ctx[base + S_LEAVING] != 0.0 and ctx[base + S_GB] > 0.0:
                ctx[base + S_LEAVING] = 0.0
        h = 0.5 * span if ctx[SPLIT] != 0.0 else min(2.0 * span, ctx[H_LONGEST])
        # aim the next substep at the predicted contact
        for j in range(n):
            base = SURF + j * SURF_STRIDE
            gb = ctx[base + S_GB]
            if ctx[base + S_LEAVING] != 0.0 and gb <= 0.0:
                continue
            dga = ctx[base + S_DGA]
            dgb = ctx[base + S_DGB]
            tc = first_positive_root(gb, dgb, 0.5 * (dgb - dga) / span)
            if tc < h:
                hb = ctx[H_BRACKET]
                h = max(tc - 0.5 * hb if tc > hb else tc + 0.5 * hb, 1e-3 * hb)
        ta = tb
        ya3, ya4 = yb3, yb4
        pxa, pya, vxa, vya = pxb, pyb, vxb, vyb
        for j in range(n):
            base = SURF + j * SURF_STRIDE
            ctx[base + S_GA] = ctx[base + S_GB]
            ctx[base + S_DGA] = ctx[base + S_DGB]
    ctx[EN_STOP] = E_NO_IMPACT
    raise KernelError(E_NO_IMPACT)
