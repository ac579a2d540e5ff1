"""One impact of the impact-only engine (``contact.model = "impacts"``, method
``event``) and ``run_chunk``, a loop over it that writes one row per impact into a
preallocated array: :meth:`billiard.engine.simulation.Simulation.step` and the body of
:meth:`billiard.engine.simulation.Simulation.run`, with the same operations in the same order.
"""

from __future__ import annotations

import math

from . import fixed_step, flight
from .ball import energy, frame_velocity
from .decorators import borrow, inline, jit
from .drive import accel_to_boundary_frame, boundary_velocity, to_boundary_frame
from .impact import chatter_tail, impact_law, rebound_settles
from .layout import (
    COLLAPSE,
    COUNTS,
    DONE,
    E_COLLAPSE,
    E_ESCAPED,
    E_NON_FINITE,
    ELASTIC,
    EN_CLOCK,
    EN_CLOCK_ERR,
    EN_ERR_VALUE,
    EN_EVENT_T,
    EN_FAULT,
    EN_IMPACTS,
    EN_LAND_ON,
    EN_LAST_J,
    EN_LAST_REGIME,
    EN_LAST_S,
    EN_LAST_WN,
    EN_NO_ROW,
    EN_ONE,
    EN_Q1,
    EN_Q2,
    EN_Q3,
    EN_RCOUNT,
    EN_RHEAD,
    EN_SETTLES,
    EN_STOP,
    EN_T,
    EN_TARGET,
    EN_THETA,
    EN_U1,
    EN_U2,
    EN_U3,
    EN_UNTIL,
    EN_ZERO,
    ESCAPE,
    FLOWN,
    FULL,
    IM_E,
    IM_EB,
    IM_K,
    IM_M,
    IM_R,
    LAND,
    LID,
    LID_LABEL,
    LOC_KIND,
    LOC_RK4,
    MC_LAST_IMPACT,
    NCOL,
    OMEGA,
    RECENT,
    S_KIND,
    S_WALL,
    SURF,
    SURF_STRIDE,
    TIME_LIMIT,
    G,
    KernelError,
)
from .lid import lid_holds
from .locate import locate
from .rules import COLLAPSE_COUNT, COLLAPSE_SPAN, ZERO_FLIGHT_LIMIT
from .rules import compensated_add as _compensated_add
from .surfaces import gap_accel

compensated_add = inline(_compensated_add)

#: slots of the collapse window's ring
RING = COLLAPSE_COUNT + 1
#: EN_SETTLES after an impact, the sum of the landing criteria it meets: the rebound is
#: below the landing speed (or the low-velocity rule applied) ...
SETTLES_SLOW = 1.0
#: ... and the chatter's tail may be summed (``impact.chatter_tail``); plus SETTLES_CORNER
#: times (i + 1) when the impact came at the instant of one with another surface i, the
#: ball touching both (a corner: the machine resolves the series of impacts there)
SETTLES_TAIL = 2.0
SETTLES_CORNER = 4.0
#: EN_FAULT of a ball that meets a surface without impulse again and again at one time
#: (:func:`no_impulse`); 1.0 is an inelastic collapse, 2.0 phases of zero duration
FAULT_PRESSED = 3.0
#: contacts without impulse in a row after which a chunk returns to Python (FULL, with
#: the rows it has), so that a stop request is seen within milliseconds whatever the
#: ball does
QUIET_STEPS = 4096


@inline
def pressing(ctx, p, walls, j, theta, q1, q2, u1, u2):
    """Does the ball's acceleration relative to the boundary push it into surface j?"""
    return gap_acceleration(ctx, p, walls, j, theta, q1, q2, u1, u2) < 0.0


@inline
def gap_acceleration(ctx, p, walls, j, theta, q1, q2, u1, u2):
    """d2G/dt2 (m/s^2) of surface j for the ball in free flight: negative when its
    acceleration relative to the boundary pushes it into the surface."""
    px, py, vx, vy = to_boundary_frame(ctx, theta, q1, q2, u1, u2)
    a1, a2 = flight.acceleration(ctx, u1, u2)
    ax, ay = accel_to_boundary_frame(ctx, theta, a1, a2)
    return gap_accel(ctx, p, walls, j, px, py, vx, vy, ax, ay)


@inline
def step(ctx, p, walls, out, row):
    """Advance to the next impact and write its row ``out[row]``; returns False (and
    changes nothing) when the impact comes after ``ctx[EN_UNTIL]``."""
    if ctx[EN_FAULT] != 0.0:
        ctx[EN_STOP] = E_COLLAPSE
        raise KernelError(E_COLLAPSE)
    ctx[EN_EVENT_T] = math.nan  # searching: a stop here is "after" the last impact
    tau, j, q1, q2, u1, u2, theta, s, z = locate(
        ctx, p, walls, ctx[EN_THETA], ctx[EN_Q1], ctx[EN_Q2], ctx[EN_U1], ctx[EN_U2], ctx[EN_U3]
    )
    return impact(ctx, p, walls, out, row, tau, j, q1, q2, u1, u2, theta, s, z)


@inline
def step_fixed(ctx, p, walls, nears, out, row):
    """:func:`step` with the paper's fixed-step detection (method ``rk4``,
    :func:`billiard.kernels.fixed_step.locate`; ``nears``: the nearest-point functions)."""
    if ctx[EN_FAULT] != 0.0:
        ctx[EN_STOP] = E_COLLAPSE
        raise KernelError(E_COLLAPSE)
    ctx[EN_EVENT_T] = math.nan  # searching: a stop here is "after" the last impact
    tau, j, q1, q2, u1, u2, theta, s, z = fixed_step.locate(
        ctx, p, walls, nears, ctx[EN_THETA], ctx[EN_Q1], ctx[EN_Q2], ctx[EN_U1], ctx[EN_U2],
        ctx[EN_U3],
    )  # fmt: skip
    return impact(ctx, p, walls, out, row, tau, j, q1, q2, u1, u2, theta, s, z)


@inline
def impact(ctx, p, walls, out, row, tau, j, q1, q2, u1, u2, theta, s, z):
    """The impact a search found, tau after the last (on surface j at s, angle z, the
    ball at (q1, q2, u1, u2), drive angle theta): the impact law, its row ``out[row]``
    and the engine state after it; False (nothing changed) when it comes after
    ``ctx[EN_UNTIL]``."""
    u3 = ctx[EN_U3]
    total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], tau)
    t = total + error
    ctx[EN_EVENT_T] = t
    if t > ctx[EN_UNTIL]:
        return False
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == ESCAPE:
        ctx[EN_STOP] = E_ESCAPED
        raise KernelError(E_ESCAPED)
    q3 = ctx[EN_Q3] + u3 * tau
    vb1, vb2 = boundary_velocity(ctx, theta)
    accel = -gap_acceleration(ctx, p, walls, j, theta, q1, q2, u1, u2)
    # under contact phases a lying ball lands or reflects: the low-velocity rule's
    # relaunch (which adds energy) is the impacts model's alone
    press = accel > 0.0 and ctx[EN_LAND_ON] == 0.0
    n1, n2, n3, rt, rn, regime, resting, _, wn = impact_law(ctx, u1, u2, u3, z, vb1, vb2, press)
    u4, un = frame_velocity(n1, n2, z)
    m, r, k = ctx[IM_M], ctx[IM_R], ctx[IM_K]
    e = energy(q2, n1, n2, n3, m, r, k, ctx[G])
    n = ctx[EN_IMPACTS] + 1.0
    wall = LID_LABEL if kind == LID else ctx[base + S_WALL]
    write_row(out, row * NCOL, n, t, q1, q2, n1, n2, n3, u4, un, tau, regime, z, e, wall, rt, rn,
              s, q3)  # fmt: skip
    # the row is written before the check, so that the caller can name the culprit
    if not math.isfinite(
        t + q1 + q2 + n1 + n2 + n3 + u4 + un + tau + z + e + rt + rn + s + q3
    ):  # fmt: skip
        ctx[EN_STOP] = E_NON_FINITE
        raise KernelError(E_NON_FINITE)
    # the previous impact was at this instant (a flight of zero or no resolved time) on
    # another surface: the ball may touch both (machine.corner looks)
    corner = ctx[MC_LAST_IMPACT] == t and ctx[EN_LAST_J] != j
    if ctx[EN_LAND_ON] != 0.0 and rn == 0.0 and rt == 0.0:
        # under contact phases a contact without impulse is no impact: no row, nothing
        # counted; the ball goes on from it, or lands
        no_impulse(ctx, t, theta, q1, q2, n1, n2, n3, q3, total, error, tau, j)
        settles(ctx, j, kind, s, wn, regime, accel)
        return True
    # commit
    ctx[EN_NO_ROW] = 0.0
    ctx[MC_LAST_IMPACT] = t
    ctx[EN_IMPACTS] = n
    set_ball(ctx, t, theta, q1, q2, n1, n2, n3, q3)
    ctx[EN_CLOCK] = total
    ctx[EN_CLOCK_ERR] = error
    ctx[COUNTS + int(regime)] += 1.0
    if resting:
        ctx[COUNTS + 3] += 1.0
    ctx[EN_ZERO] = ctx[EN_ZERO] + 1.0 if tau == 0.0 else 0.0
    remember_impact(ctx, t)
    if int(ctx[EN_RCOUNT]) > COLLAPSE_COUNT or ctx[EN_ZERO] >= ZERO_FLIGHT_LIMIT:
        ctx[EN_FAULT] = 1.0
    if ctx[EN_LAND_ON] != 0.0:
        i = ctx[EN_LAST_J]
        settles(ctx, j, kind, s, wn, regime, accel)
        if corner:
            ctx[EN_SETTLES] += SETTLES_CORNER * (i + 1.0)
    return True


@inline
def remember_impact(ctx, t):
    """The collapse window after an impact at t: the impact times within COLLAPSE_SPAN
    of it, a ring of RING slots at RECENT (EN_RHEAD the oldest, EN_RCOUNT of them)."""
    count = int(ctx[EN_RCOUNT])
    head = int(ctx[EN_RHEAD])
    if count == RING:
        head = (head + 1) % RING
        count -= 1
    ctx[RECENT + (head + count) % RING] = t
    count += 1
    while t - ctx[RECENT + head] >= COLLAPSE_SPAN:
        head = (head + 1) % RING
        count -= 1
    ctx[EN_RCOUNT] = count
    ctx[EN_RHEAD] = head


@inline
def write_row(out, o, n, t, q1, q2, u1, u2, u3, u4, un, tau, regime, z, e, wall, rt, rn, s, q3):
    """One row of collisions.csv (NCOL floats, regime and wall as codes) at out[o:]."""
    out[o] = n
    out[o + 1] = t
    out[o + 2] = q1
    out[o + 3] = q2
    out[o + 4] = u1
    out[o + 5] = u2
    out[o + 6] = u3
    out[o + 7] = u4
    out[o + 8] = un
    out[o + 9] = tau
    out[o + 10] = regime
    out[o + 11] = z
    out[o + 12] = e
    out[o + 13] = wall
    out[o + 14] = rt
    out[o + 15] = rn
    out[o + 16] = s
    out[o + 17] = q3


@inline
def set_ball(ctx, t, theta, q1, q2, u1, u2, u3, q3):
    """The engine's ball (EN_T .. EN_Q3)."""
    ctx[EN_T] = t
    ctx[EN_THETA] = theta
    ctx[EN_Q1] = q1
    ctx[EN_Q2] = q2
    ctx[EN_U1] = u1
    ctx[EN_U2] = u2
    ctx[EN_U3] = u3
    ctx[EN_Q3] = q3


@inline
def no_impulse(ctx, t, theta, q1, q2, u1, u2, u3, q3, total, error, tau, j):
    """The state at a flight's contact without impulse (contact phases) with surface j:
    the ball there, no impact counted, EN_NO_ROW set. Such contacts enter the collapse
    window as impacts do, and those at one instant count as zero flights: a ball
    pressed against a surface that does not hold it meets it again and again
    at times that no longer advance the clock (flights of 1e-18 s at t ~ 1 s), which
    stops the run (EN_FAULT = FAULT_PRESSED, the surface in EN_ERR_VALUE) instead of
    turning for ever."""
    ctx[EN_NO_ROW] = 1.0
    set_ball(ctx, t, theta, q1, q2, u1, u2, u3, q3)
    ctx[EN_CLOCK] = total
    ctx[EN_CLOCK_ERR] = error
    ctx[EN_ZERO] = ctx[EN_ZERO] + 1.0 if tau == 0.0 else 0.0
    remember_impact(ctx, t)
    if ctx[EN_ZERO] >= ZERO_FLIGHT_LIMIT or int(ctx[EN_RCOUNT]) > COLLAPSE_COUNT:
        ctx[EN_FAULT] = FAULT_PRESSED
        ctx[EN_ERR_VALUE] = float(j)


@inline
def settles(ctx, j, kind, s, wn, regime, accel):
    """After an impact on surface j at s with the normal velocity wn (m/s) of the
    contact point relative to the boundary before it: does the
    chattering it starts settle (an inelastic contact with a
    wall or the lid whose rebound speed e |wn| is at most the landing speed, or the low-velocity
    rule applied; e and the landing speed are the impact law's IM_E and IM_EB), or may
    its tail be summed (``chatter_tail``, ``accel`` the free flight's acceleration into
    the wall, m/s^2)? Sets EN_SETTLES (SETTLES_SLOW plus SETTLES_TAIL, the criteria met)
    and the impact's EN_LAST_J, EN_LAST_S, EN_LAST_WN, EN_LAST_REGIME."""
    e = ctx[IM_E]
    ctx[EN_LAST_J] = j
    ctx[EN_LAST_S] = s
    ctx[EN_LAST_WN] = wn
    ctx[EN_LAST_REGIME] = regime
    ctx[EN_SETTLES] = 0.0
    if kind == LID and not lid_holds(ctx):
        # the lid holds no ball in this scene (machine.land_lid): the flight goes on
        return
    flags = 0.0
    if rebound_settles(e, ctx[IM_EB], wn, regime == ELASTIC):
        flags += SETTLES_SLOW
    if chatter_tail(e, wn, accel, ctx[OMEGA]):
        flags += SETTLES_TAIL
    ctx[EN_SETTLES] = flags


@jit
def run_chunk(ctx, p, walls, out, rows):
    """Up to ``rows`` impacts, one row each in ``out`` (``rows * NCOL`` floats), until
    impact number ``ctx[EN_TARGET]``. Returns (status, rows written): DONE, FULL,
    TIME_LIMIT, COLLAPSE (after the row that detected it) or LAND (after the row of an
    impact that settles, when ``ctx[EN_LAND_ON]``); a documented stop inside
    raises KernelError, with ``ctx`` as after the last row written."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx, p, out = borrow(ctx), borrow(p), borrow(out)
    row = 0
    quiet = 0
    while ctx[EN_IMPACTS] < ctx[EN_TARGET]:
        if row == rows or quiet == QUIET_STEPS:
            return FULL, row
        if not step(ctx, p, walls, out, row):
            return TIME_LIMIT, row
        if ctx[EN_NO_ROW] == 0.0:
            row += 1
            quiet = 0
        else:
            quiet += 1
        code = chunk_ends(ctx)
        if code >= 0:
            return code, row
    return DONE, row


@jit
def run_chunk_fixed(ctx, p, walls, nears, out, rows):
    """:func:`run_chunk` with the paper's fixed-step detection (method ``rk4``):
    ``nears`` are the walls' nearest-point functions (:mod:`billiard.kernels.fixed_step`).
    A search that needs the curve's global nearest point raises KernelError(E_FOOT),
    ``ctx`` as after the last row written: answered, the next call goes on."""
    ctx, p, out = borrow(ctx), borrow(p), borrow(out)
    row = 0
    quiet = 0
    while ctx[EN_IMPACTS] < ctx[EN_TARGET]:
        if row == rows or quiet == QUIET_STEPS:
            return FULL, row
        if not step_fixed(ctx, p, walls, nears, out, row):
            return TIME_LIMIT, row
        if ctx[EN_NO_ROW] == 0.0:
            row += 1
            quiet = 0
        else:
            quiet += 1
        code = chunk_ends(ctx)
        if code >= 0:
            return code, row
    return DONE, row


@inline
def chunk_ends(ctx):
    """The status that ends a chunk after the row just written, or -1 to go on."""
    if ctx[EN_FAULT] != 0.0:
        return COLLAPSE
    if ctx[EN_SETTLES] != 0.0:
        return LAND
    if ctx[EN_ONE] != 0.0:
        # the state machine samples each flight when it ends (machine.run_machine)
        return FLOWN
    return -1


@jit
def run_flights(ctx, p, walls, nears, out, rows):
    """The state machine's flights: :func:`run_chunk_fixed` for the paper's fixed-step
    detection (``ctx[LOC_KIND]`` = LOC_RK4; ``nears``: the walls' nearest-point
    functions), else :func:`run_chunk` (the locator chosen by its kind, as the flight
    model is by FL_KIND)."""
    if ctx[LOC_KIND] == LOC_RK4:
        return run_chunk_fixed(ctx, p, walls, nears, out, rows)
    return run_chunk(ctx, p, walls, out, rows)
