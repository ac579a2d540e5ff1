"""The engine: one compiled loop, the trajectory state machine, that advances every
scene. It takes a ball through flight, impact, landing (the chatter series summed),
rolling, sliding and being held by two walls, lift-off and back to flight, writing a
row per impact (``out``, the columns of collisions.csv), a row per finished or cut
contact phase (``cout``, :data:`~billiard.kernels.layout.CCOL` floats: contacts.csv)
and a row per trajectory sample (``sout``, :mod:`billiard.kernels.samples`), and
returning to Python only when a buffer is full, the run's impact count or time limit is
reached, a long phase pauses (every :data:`PAUSE_STEPS` steps, so that a stop request
is seen), a status ends the run, or a documented stop raises ``KernelError``. Under
``contact.model = "impacts"`` (no landing) it is a loop over the flights alone.

Python (:mod:`billiard.engine.driver`) configures it and calls it in chunks; the same
source runs interpreted under ``NUMBA_DISABLE_JIT=1`` or without numba, bit for bit.
The flights are :func:`billiard.kernels.loop.run_chunk` (or ``run_chunk_fixed``), a phase
:func:`billiard.kernels.contact.run_phase`, a hold :func:`billiard.kernels.vertex.run_hold`:
compiled functions of their own, which this loop calls (and numba compiles once).

The engine state lives in ``ctx``: the ball and clock (``EN_*``), the motion state and
its contact (``MC_MODE``, ``MC_CONTACT``), the time in finished phases, the last
impact's time, the run's end so far (``MC_*``), and a phase under way between two calls
(``MC_PHASE_ON``: its integration state in the ``PH_*`` slots). The ball's state is
that at the phase's start until the phase ends: a run stopped inside a phase redoes it.
"""

from __future__ import annotations

import math

from .ball import energy, frame_velocity
from .contact import pmax, pmin, run_phase
from .contact_equations import centre_state, roll_spin, s_dot_of_velocity, slip_velocity
from .contact_forces import forces
from .decorators import borrow, inline, jit
from .drive import boundary_motion as boundary
from .drive import displacement, to_lab_frame
from .drive import to_boundary_frame as boundary_frame
from .impact import (
    CHATTER_TAIL,
    NOT_SUMMED,
    chatter_bounded,
    chatter_period,
    chatter_time,
    impact_law,
    rebound_settles,
)
from .layout import (
    CCOL,
    COLLAPSE,
    CONTACTS_FULL,
    COUNTS,
    CURVED,
    DONE,
    E_ESCAPED,
    E_LEFT,
    E_PHASE_NON_FINITE,
    ELASTIC,
    EN_CLOCK,
    EN_CLOCK_ERR,
    EN_ERR_VALUE,
    EN_EVENT_T,
    EN_FAULT,
    EN_IMPACTS,
    EN_LAST_J,
    EN_LAST_REGIME,
    EN_LAST_S,
    EN_LAST_WN,
    EN_ONE,
    EN_Q1,
    EN_Q2,
    EN_Q3,
    EN_RCOUNT,
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
    END_CUT,
    END_IMPACT,
    END_JOIN,
    END_LIFT_OFF,
    END_RELEASE,
    END_ROLL,
    END_SLIP,
    END_WALL_END,
    ESCAPE,
    FLOWN,
    FULL,
    HORIZ,
    IM_E,
    IM_EB,
    IM_K,
    IM_M,
    IM_R,
    IN_CONTACT,
    LAND,
    LID,
    LID_LABEL,
    LINE,
    LOC_KIND,
    LOC_RK4,
    M_FLIGHT,
    M_HELD,
    M_ROLL,
    M_SLIDE,
    MC_CONTACT,
    MC_CROW,
    MC_FINAL,
    MC_FLIGHT_FROM,
    MC_FLYING,
    MC_HOLD_ON,
    MC_LAST_IMPACT,
    MC_MODE,
    MC_PHASE_ON,
    MC_PHASE_TIME,
    MC_ROW,
    MC_SPAN,
    MC_STOP_AT,
    MC_WALL_HI,
    MC_WALL_LO,
    MC_X_HI,
    MC_X_LO,
    NCOL,
    OMEGA,
    PAUSED,
    PH_END_I,
    PH_END_T,
    PH_END_Y,
    PH_HI,
    PH_LIMIT,
    PH_LO,
    PH_M,
    PH_MODE,
    PH_MUS,
    PH_NEXT,
    PH_PAUSE,
    PH_PAUSE_T,
    PH_R,
    PH_RSINCE,
    PH_SAMPLE_T,
    PH_SAMPLE_Y,
    PH_SGN,
    PH_STEPS,
    PH_SURF,
    PH_TAU,
    PH_THETA0,
    PH_WALL,
    PH_Y,
    PHASE_LIMIT,
    PHASE_PAUSE,
    PHASE_SAMPLE,
    ROLL,
    S_A,
    S_FIRST,
    S_KIND,
    S_LAST,
    S_SLOPE,
    S_SLOPE_AT,
    S_WALL,
    S_WS,
    S_WSLOPE,
    SAMPLES_FULL,
    SLIDE,
    SM_AFTER,
    SM_DONE,
    SM_DT,
    SM_FROM,
    SM_GEN,
    SM_K,
    SM_MARK,
    SM_PENDING,
    SM_ROW,
    SM_TO,
    SRC_CHATTER,
    SURF,
    SURF_STRIDE,
    TIME_LIMIT,
    VX_END_T,
    VX_KEEPS,
    VX_LIMIT,
    VX_NEXT,
    VX_SAMPLE_T,
    VX_SAMPLE_W,
    VX_THETA0,
    VX_W,
    VX_W_END,
    VX_ZA,
    VX_ZB,
    G,
    KernelError,
)
from .lid import (
    lid_holds,
    lid_motion,
    lid_press,
    lid_release,
    lid_slip_end,
    lid_wall_reach,
    wall_gap,
)
from .loop import (
    SETTLES_CORNER,
    compensated_add,
    remember_impact,
    run_flights,
    set_ball,
    write_row,
)
from .rules import COLLAPSE_COUNT, ZERO_FLIGHT_LIMIT
from .samples import (
    EMIT,
    EMITTED,
    flight_samples,
    next_emitted,
    sample_time,
    save_flight_start,
    start_flight_samples,
    write_sample,
)
from .surfaces import contact, gap_rate
from .vertex import forces as hold_forces
from .vertex import held_spin, run_hold, sign

#: Impacts of a series at one instant in a corner (:func:`corner`) followed at most: each
#: shrinks the speed relative to the boundary by a fixed factor (about 0.55 an impact in
#: the paper's wedge), so that the series reaches its limit within some 50.
CORNER_SERIES = 1000
#: The speed relative to the boundary, as a fraction of that at the series' start, at
#: which a series at one instant that has not ended is at its limit: rest relative to
#: the boundary (the two normals span the plane), where the rest is rounding.
CORNER_LIMIT = 1e-12
#: |distance| (m) between the centre and a wall's offset curve within which a ball
#: touches the wall at a corner
CORNER_GAP = 1e-9
#: :func:`corner`'s answers: no series (the ball leaves the first wall), a series that
#: ends (the ball leaves both walls), a series that does not end (at rest in the corner)
CORNER_NONE = -1
CORNER_ENDS = 1
CORNER_REST = 0
#: Normal speed (m/s) given to a ball leaving a surface under the paper's fixed-step
#: search alone (method "rk4", ``LOC_KIND`` = LOC_RK4). The event locator starts a flight
#: that grazes the surface it leaves (:func:`billiard.kernels.locate.locate`); the
#: fixed-step search has no such start: a ball leaving with no normal speed opens the gap
#: as tau^2 or tau^3, within rounding of the search's distances over a step, and it met
#: the surface again at once until the departures stop (the wedge under phases, rk4,
#: impact 378). 1e-6 m/s moves it 1e-10 m in a step of 1e-4 s.
RK4_DEPARTURE_SPEED = 1e-6
#: accepted steps of a phase between two returns to Python (a stop request is looked
#: at, progress reported): some milliseconds
PAUSE_STEPS = 1000.0
#: MC_PHASE_ON: no phase under way, one under way, one paused (its pause answered at
#: the next call), one to cut where it is (a stop request: the next call writes its
#: cut row and returns)
PHASE_OFF = 0.0
PHASE_ON = 1.0
PHASE_PAUSED = 2.0
PHASE_CUT = 3.0


# ---------------------------------------------------------------------- kinematics


@jit
def lab_state(ctx, p, walls, w, theta, s, sd, u3, roll):
    """(q1, q2, u1, u2, u3): the lab state of a ball on wall w at (s, s_dot) with spin
    u3 (the no-slip spin when ``roll``), drive angle theta
    (``ContactModel.lab_state``)."""
    f0 = walls[0][w](s, p)
    fp = walls[1][w](s, p)
    f2 = walls[2][w](s, p)
    d = displacement(ctx, theta)
    d1, d2 = (d, 0.0) if ctx[HORIZ] == 1.0 else (0.0, d)
    vb1, vb2, _, _ = boundary(ctx, theta)
    q1, q2, u1, u2 = centre_state(s, sd, f0, fp, f2, d1, d2, vb1, vb2, ctx[PH_R])
    spin = roll_spin(sd, fp, f2, ctx[PH_R]) if roll else u3
    return q1, q2, u1, u2, spin


@jit
def contact_lab(ctx, p, walls, j, theta, s, sd, u3, roll):
    """:func:`lab_state` of a ball in contact with surface j: a wall, or the lid (s the
    centre's x and sd its velocity relative to the boundary; the spin u3 as it is: a
    ball rolls on the flat lid with no force, its slip within rounding of zero)."""
    base = SURF + j * SURF_STRIDE
    if ctx[base + S_KIND] != LID:
        return lab_state(ctx, p, walls, wall_of(ctx, j), theta, s, sd, u3, roll)
    q1, q2 = to_lab_frame(ctx, theta, s, ctx[base + S_A])
    vb1, vb2, _, _ = boundary(ctx, theta)
    return q1, q2, sd + vb1, vb2, u3


@inline
def s_dot(ctx, p, walls, w, theta, s, u1, u2):
    """ds/dt (m/s) of a centre at s with the lab velocity (u1, u2)."""
    fp = walls[1][w](s, p)
    f2 = walls[2][w](s, p)
    vb1, vb2, _, _ = boundary(ctx, theta)
    return s_dot_of_velocity(u1, u2, fp, f2, vb1, vb2, ctx[PH_R])


@inline
def set_forces(ctx, w, mode, sgn):
    """The phase slots :func:`~billiard.kernels.contact_forces.forces` reads."""
    ctx[PH_WALL] = float(w)
    ctx[PH_MODE] = ROLL if mode == M_ROLL else SLIDE
    ctx[PH_SGN] = sgn


@jit
def forces_of(ctx, p, walls, w, mode, sgn, theta, s, sd):
    """(s_ddot, u3_dot, N, F) on wall w in contact mode ``mode`` with slip sign ``sgn``
    (:func:`~billiard.kernels.contact_forces.forces`; its slots set). One compiled
    function that every step of the machine calls: inlined, the generated equations
    would be compiled into each (numba compiles a kernel into every caller)."""
    set_forces(ctx, w, mode, sgn)
    return forces(ctx, p, walls, theta, s, sd)


@inline
def mode_for(ctx, p, walls, w, theta, s, sd, u3):
    """(mode, slip sign) of a ball at (s, s_dot, u3) on wall w: rolling when the slip
    vanishes (to rounding) and static friction can hold it, else sliding."""
    fp = walls[1][w](s, p)
    f2 = walls[2][w](s, p)
    r = ctx[PH_R]
    slip = slip_velocity(sd, u3, fp, f2, r)
    scale = abs(sd) * math.sqrt(1.0 + fp * fp) + r * abs(u3)
    if abs(slip) <= 1e-12 + 1e-9 * scale:
        _, _, n, f = forces_of(ctx, p, walls, w, M_ROLL, 0.0, theta, s, sd)
        if abs(f) <= ctx[PH_MUS] * n:
            return M_ROLL, 0.0
        return M_SLIDE, (-1.0 if f > 0.0 else 1.0)
    return M_SLIDE, (1.0 if slip > 0.0 else -1.0)


@inline
def normal_force(ctx, p, walls, w, mode, sgn, theta, s, sd):
    """N (N) of wall w on a ball in contact mode ``mode`` at (s, s_dot)."""
    return forces_of(ctx, p, walls, w, mode, sgn, theta, s, sd)[2]


@jit
def contact_kept(ctx, p, walls, j, px):
    """(s, z) of surface j's contact point for a centre at px, its warm start left as
    it was (the engine asks with a copy of it)."""
    base = SURF + j * SURF_STRIDE
    ws, at, slope = ctx[base + S_WS], ctx[base + S_SLOPE_AT], ctx[base + S_SLOPE]
    s, z = contact(ctx, p, walls, j, px)
    ctx[base + S_WS] = ws
    ctx[base + S_SLOPE_AT] = at
    ctx[base + S_SLOPE] = slope
    return s, z


@inline
def is_wall(ctx, j):
    kind = ctx[SURF + j * SURF_STRIDE + S_KIND]
    return kind == CURVED or kind == LINE


@inline
def wall_of(ctx, j):
    return int(ctx[SURF + j * SURF_STRIDE + S_WALL])


@inline
def set_contact(ctx, mode, c0, c1, c2, c3, c4, c5):
    ctx[MC_MODE] = mode
    ctx[MC_CONTACT] = c0
    ctx[MC_CONTACT + 1] = c1
    ctx[MC_CONTACT + 2] = c2
    ctx[MC_CONTACT + 3] = c3
    ctx[MC_CONTACT + 4] = c4
    ctx[MC_CONTACT + 5] = c5


@inline
def to_flight(ctx):
    ctx[MC_MODE] = M_FLIGHT
    for i in range(6):
        ctx[MC_CONTACT + i] = 0.0


# ---------------------------------------------------------------------- samples


@inline
def sampling(ctx):
    return ctx[SM_DT] > 0.0


@inline
def next_sample(ctx, t0, until):
    """The next sample time of a phase or hold that started at t0, as an offset from t0
    (s; inf: none up to ``until``), from sample SM_GEN on (samples before t0 skipped)."""
    if not sampling(ctx):
        return math.inf
    k = ctx[SM_GEN]
    while True:
        ts = sample_time(ctx, k)
        if ts > until:
            ctx[SM_GEN] = k
            return math.inf
        k += 1.0
        if ts >= t0:
            ctx[SM_GEN] = k
            return ts - t0


@inline
def first_sample(ctx, t0, until):
    """Where a phase or hold starting at t0 begins its samples: the count at its start
    (a cut goes back to it) and its first sample time (offset from t0)."""
    ctx[SM_MARK] = ctx[SM_K]
    ctx[SM_GEN] = ctx[SM_K]
    return next_sample(ctx, t0, until)


@jit
def chatter_samples(ctx, p, walls, sout, srows):
    """The pending samples in [SM_FROM, SM_TO] of a ball that landed at the end of a
    summed chatter series, before the phase starts: the state at the impact, carried by
    the boundary, its spin kept (mode flight). True when all are written."""
    j = int(ctx[MC_CONTACT])
    s, sd = ctx[MC_CONTACT + 1], ctx[MC_CONTACT + 2]
    roll = ctx[MC_MODE] == M_ROLL
    t, theta, u3 = ctx[EN_T], ctx[EN_THETA], ctx[EN_U3]
    while True:
        status, ts = next_emitted(ctx, srows)
        if status != EMIT:
            return status == EMITTED
        angle = theta + ctx[OMEGA] * (ts - t)
        q1, q2, u1, u2, _ = contact_lab(ctx, p, walls, j, angle, s, sd, u3, roll)
        write_sample(ctx, sout, ts, q1, q2, u1, u2, u3, M_FLIGHT)


@jit
def pending_samples(ctx, p, walls, sctx, sout, srows):
    """Go on with a pending emission: -1 when done and the run goes on, else the status
    to return (SAMPLES_FULL while the buffer is full, then the flight's own)."""
    if ctx[SM_PENDING] == SRC_CHATTER:
        if not chatter_samples(ctx, p, walls, sout, srows):
            return SAMPLES_FULL
        ctx[SM_DONE] = 1.0
        return -1
    if not flight_samples(ctx, sctx, sout, srows):
        return SAMPLES_FULL
    after = int(ctx[SM_AFTER])
    ctx[SM_AFTER] = -1.0
    return after


# ---------------------------------------------------------------------- landing


@inline
def chatter_accel(ctx, p, walls, w, mode, sgn, theta, s, sd, tau):
    """The acceleration (m/s^2) with which wall w presses the ball in contact mode
    ``mode`` tau seconds after the impact (w < 0: the lid)."""
    if w < 0:
        return lid_press(ctx, theta + ctx[OMEGA] * tau)
    y0 = s + sd * tau
    return forces_of(ctx, p, walls, w, mode, sgn, theta + ctx[OMEGA] * tau, y0, sd)[2] / ctx[PH_M]


@inline
def summed(ctx, p, walls, w, mode, sgn, theta, s, sd, v, e):
    """:func:`billiard.models.chatter.summed` (NOT_SUMMED for None)."""
    period = chatter_period(ctx[OMEGA])
    a0 = chatter_accel(ctx, p, walls, w, mode, sgn, theta, s, sd, 0.0)
    t0 = chatter_time(v, e, a0, period)
    if t0 == NOT_SUMMED or t0 == 0.0:
        return t0
    a1 = chatter_accel(ctx, p, walls, w, mode, sgn, theta, s, sd, t0)
    a2 = chatter_accel(ctx, p, walls, w, mode, sgn, theta, s, sd, 2.0 * t0)
    if not chatter_bounded(v, e, a0, a1, a2, t0, period):
        return NOT_SUMMED
    return t0


@inline
def departure_speed(ctx):
    """The normal speed (m/s) a ball leaving a surface is given: none, except under the
    fixed-step search (RK4_DEPARTURE_SPEED)."""
    return RK4_DEPARTURE_SPEED if ctx[LOC_KIND] == LOC_RK4 else 0.0


@inline
def push_off(ctx, nx, ny):
    """Under the fixed-step search, add :func:`departure_speed` along the unit vector
    (nx, ny) to the ball's velocity (a departure from a surface or two)."""
    kick = departure_speed(ctx)
    if kick > 0.0:
        norm = math.sqrt(nx * nx + ny * ny)
        ctx[EN_U1] = ctx[EN_U1] + kick * nx / norm
        ctx[EN_U2] = ctx[EN_U2] + kick * ny / norm


@inline
def leave_wall(ctx, p, walls, w, s, theta):
    """A settling impact where the wall does not press the ball (N <= 0): it flies on,
    with the relative normal speed the impact left, or none (after an impact with e = 0,
    or a grazing one): a normal speed towards the wall, rounding's, is taken away, so
    that the flight starts at most grazing it. Its acceleration away from the wall (N
    <= 0) opens the gap; the flight's locator takes it from there (a grazing start:
    :func:`billiard.kernels.locate.locate`). No speed is added: the ball leaves as the
    equations of motion say."""
    fp = walls[1][w](s, p)
    c = 1.0 / math.sqrt(1.0 + fp * fp)
    nx, ny = -fp * c, c
    vb1, vb2, _, _ = boundary(ctx, theta)
    vn = (ctx[EN_U1] - vb1) * nx + (ctx[EN_U2] - vb2) * ny
    leave = departure_speed(ctx)  # 0 but under the fixed-step search
    if vn >= leave:
        return
    ctx[EN_U1] = ctx[EN_U1] + (leave - vn) * nx
    ctx[EN_U2] = ctx[EN_U2] + (leave - vn) * ny


@jit
def land(ctx, p, walls, j, s, theta, u1, u2, u3, wn, elastic, tail, t):
    """After an impact at t on surface j at s (the speeds (u1, u2, u3) after it, the
    normal speed wn before it): enter contact while the wall presses the ball (the
    contact mode's N > 0) when either

    * the chatter series it starts may be summed (:func:`summed`: it ends within 1e-6
      of a drive period, and the bound on its end time is within ``CHATTER_TOL`` of a
      period): the ball enters contact at that time, t + 2 v / (a (1 - e)), v = e |wn|
      the rebound speed and a = N / m (the phase starts there: :func:`end_chatter`),
      whatever ``contact.elastic_below`` is;
    * or the rebound speed e |wn| is at most the landing speed
      (``contact.elastic_below``, IM_EB): the ball enters contact at this impact, the
      chattering it skips recorded as the phase's ``t_settle``, t + 2 v / (a (1 - e)).

    ``tail``: the free flight's test of the chatter's tail (1 made and met, 0 made and
    not met, -1 not made: after a contact phase's impact)."""
    e = ctx[IM_E]
    slow = rebound_settles(e, ctx[IM_EB], wn, elastic)
    if e >= 1.0 or not (slow or tail != 0):
        return
    rebound = e * abs(wn)
    if ctx[SURF + j * SURF_STRIDE + S_KIND] == LID:
        land_lid(ctx, p, walls, j, theta, u1, u3, rebound, e, slow, tail, t)
        return
    if not is_wall(ctx, j):
        return
    w = wall_of(ctx, j)
    sd = s_dot(ctx, p, walls, w, theta, s, u1, u2)
    mode, sgn = mode_for(ctx, p, walls, w, theta, s, sd, u3)
    n_force = normal_force(ctx, p, walls, w, mode, sgn, theta, s, sd)
    if not n_force > 0.0:
        if slow:
            leave_wall(ctx, p, walls, w, s, theta)
        return
    if tail != 0:
        tau = summed(ctx, p, walls, w, mode, sgn, theta, s, sd, rebound, e)
        if tau != NOT_SUMMED:
            total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], tau)
            set_contact(ctx, mode, float(j), s, sd, sgn, total + error, total + error)
            return
    if not slow:
        return
    settle = t + 2.0 * rebound / (n_force / ctx[PH_M] * (1.0 - e))
    set_contact(ctx, mode, float(j), s, sd, sgn, t, settle)


@inline
def lid_mode(ctx, vx, u3):
    """(mode, slip sign) of a ball on the lid moving at vx (m/s) relative to it with spin
    u3: the slip of its top is vx - r u3; rolling when it vanishes (to rounding: flat,
    static friction holds it with no force)."""
    r = ctx[IM_R]
    slip = vx - r * u3
    if abs(slip) <= 1e-12 + 1e-9 * (abs(vx) + r * abs(u3)):
        return M_ROLL, 0.0
    return M_SLIDE, (1.0 if slip > 0.0 else -1.0)


@jit
def land_lid(ctx, p, walls, j, theta, u1, u3, rebound, e, slow, tail, t):
    """:func:`land` on the lid (surface j), where it presses the ball
    (:mod:`billiard.kernels.lid`): the contact's s is the centre's x in the boundary's
    frame, its s_dot the velocity along x relative to the boundary."""
    if not lid_holds(ctx):
        return
    a = lid_press(ctx, theta)
    if not a > 0.0:
        return
    px, _, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    vx = u1 - boundary(ctx, theta)[0]
    mode, sgn = lid_mode(ctx, vx, u3)
    if tail != 0:
        tau = summed(ctx, p, walls, -1, mode, sgn, theta, px, vx, rebound, e)
        if tau != NOT_SUMMED:
            total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], tau)
            set_contact(ctx, mode, float(j), px, vx, sgn, total + error, total + error)
            return
    if not slow:
        return
    set_contact(ctx, mode, float(j), px, vx, sgn, t, t + 2.0 * rebound / (a * (1.0 - e)))


@jit
def end_chatter(ctx, p, walls, until):
    """A ball that landed at the end of a summed chatter series (its phase starts later
    than the impact it is at): move it there, at contact abscissa s with tangential
    speed sd and its spin, all as at the impact (:mod:`billiard.models.chatter`), the
    boundary moved on (samples in between: :func:`chatter_samples`). False (the state
    unchanged) when the series ends after ``until``."""
    t_start = ctx[MC_CONTACT + 4]
    if t_start > until:
        return False
    j = int(ctx[MC_CONTACT])
    tau = t_start - ctx[EN_T]
    theta = (ctx[EN_THETA] + ctx[OMEGA] * tau) % (2.0 * math.pi)
    u3 = ctx[EN_U3]
    roll = ctx[MC_MODE] == M_ROLL
    q1, q2, u1, u2, _ = contact_lab(
        ctx, p, walls, j, theta, ctx[MC_CONTACT + 1], ctx[MC_CONTACT + 2], u3, roll
    )
    set_ball(ctx, t_start, theta, q1, q2, u1, u2, u3, ctx[EN_Q3] + u3 * tau)
    ctx[EN_CLOCK] = t_start
    ctx[EN_CLOCK_ERR] = 0.0
    ctx[MC_FINAL] = t_start
    return True


# ---------------------------------------------------------------------- rows


#: ``b`` of the row of a phase on one wall w: ONE_WALL - w (< 0), the wall itself, which on
#: a chain of walls joined smoothly is not the surface's first
ONE_WALL = -2.0


@inline
def contact_row(ctx, cout, kind, t_start, t_end, a, b, mode, end, settle):
    """Start contact row MC_CROW (its lab states follow: :func:`row_state`); returns
    its offset in ``cout``. ``a``: the surface; ``b``: the other surface holding the
    ball, or for a phase on one wall w, ONE_WALL - w."""
    o = int(ctx[MC_CROW]) * CCOL
    cout[o] = kind
    cout[o + 1] = ctx[EN_IMPACTS]
    cout[o + 2] = t_start
    cout[o + 3] = t_end
    cout[o + 4] = a
    cout[o + 5] = b
    cout[o + 6] = mode
    cout[o + 7] = end
    cout[o + 8] = settle
    ctx[MC_CROW] += 1.0
    return o


@inline
def row_state(cout, o, q1, q2, u1, u2, u3):
    cout[o] = q1
    cout[o + 1] = q2
    cout[o + 2] = u1
    cout[o + 3] = u2
    cout[o + 4] = u3


@inline
def deadline(ctx, until):
    """The simulated time (s) at which a run without a time limit (``until`` = inf)
    ends in contact: ``run.contact_span`` after the last impact; else inf."""
    if math.isfinite(until):
        return math.inf
    return ctx[MC_LAST_IMPACT] + ctx[MC_SPAN]


@inline
def end_phase(ctx, mode, t_start, tau, total, error):
    """The clock and the tallies at the end of a contact phase of ``tau`` seconds (the
    new time is the compensated sum total + error); zero-length phases in a row are
    counted like zero flights, a collapse."""
    t = total + error
    ctx[EN_CLOCK] = total
    ctx[EN_CLOCK_ERR] = error
    k = MC_PHASE_TIME + int(mode) - 1
    ctx[k] = ctx[k] + (t - t_start)
    ctx[MC_FINAL] = t
    ctx[EN_ZERO] = ctx[EN_ZERO] + 1.0 if tau == 0.0 else 0.0
    if ctx[EN_ZERO] >= ZERO_FLIGHT_LIMIT:
        ctx[EN_FAULT] = 2.0  # contact phases of zero duration piled up


# ---------------------------------------------------------------------- two walls


@inline
def enter_hold(ctx, a, b, t, settle, spin):
    """Hold the ball: it moves with the boundary, held by walls
    a and b at its present centre, with spin ``spin``
    (:func:`~billiard.kernels.vertex.held_spin`)."""
    theta = ctx[EN_THETA]
    px, py, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    u1, u2, _, _ = boundary(ctx, theta)
    ctx[EN_U1] = u1
    ctx[EN_U2] = u2
    ctx[EN_U3] = spin
    set_contact(ctx, M_HELD, float(a), float(b), px, py, t, settle)


@inline
def hold_after(ctx, p, walls, index, j, theta, u3, wn, elastic, t, impulse, instant):
    """After a contact with wall j of a ball in contact with wall ``index`` (an
    impact, or with ``impulse`` False a contact that gave none; ``instant``: the
    phase on wall ``index`` lasted no time, it met wall j where it began): is it held
    by both? Yes when both walls press it and

    * the rebound speed is below the landing speed (as for landing on one wall), or
    * the phase lasted no time: the ball meets one wall and the other at one
      instant, a series of impacts at that instant that takes its velocity relative
      to the boundary to zero (e < 1: each impact shrinks its normal component
      towards one wall by e, and the two normals span the plane), or
    * the chattering between the two walls would end within ``CHATTER_TAIL`` of a
      drive period: v = e |wn| (|wn|, the speed at which the ball separates from
      wall j, after a contact without impulse) with 2 v <= CHATTER_TAIL P a (1 - e),
      a the smaller wall's normal force per unit mass, the bound of a series of
      rebounds each turned back by at least a (the time of a single wall's series,
      :mod:`billiard.models.chatter`; recorded as the phase's ``t_settle``).

    The last two hold whatever ``contact.elastic_below`` is. The chattering this
    skips would carry the ball's velocity relative to the boundary, at most v, to
    zero: it is dropped (never energy created), the spin is kept. Without them a
    ball pressed into a vertex with ``elastic_below = 0`` meets one wall and the
    other at one instant, again and again, until the collapse stop. Wall j may be the
    lid: a ball on a wall that meets the lid at their corner is held by both alike."""
    if ctx[SURF + j * SURF_STRIDE + S_KIND] == ESCAPE:
        return False
    e = ctx[IM_E]
    slow = rebound_settles(e, ctx[IM_EB], wn, elastic)
    if not slow and e >= 1.0:
        return False
    px, _, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    z_index = contact_kept(ctx, p, walls, index, px)[1]
    z_j = contact_kept(ctx, p, walls, j, px)[1]
    spin = held_spin(ctx, z_index, z_j, theta, u3)
    if math.isnan(spin):
        return False
    settle = t
    if not slow and not instant:
        n_a, n_b = hold_forces(ctx, z_index, z_j, theta, sign(spin))
        a = pmin(n_a, n_b) / ctx[PH_M]
        v = e * abs(wn) if impulse else abs(wn)
        if not 2.0 * v <= CHATTER_TAIL * chatter_period(ctx[OMEGA]) * a * (1.0 - e):
            return False
        settle = t + 2.0 * v / (a * (1.0 - e))
    enter_hold(ctx, index, j, t, settle, spin)
    return True


@inline
def continue_on(ctx, p, walls, j, px, theta, u3, t):
    """Released by the other wall, roll or slide on
    wall j from rest relative to the boundary if it presses the ball."""
    s = contact_kept(ctx, p, walls, j, px)[0]
    w = wall_of(ctx, j)
    mode, sgn = mode_for(ctx, p, walls, w, theta, s, 0.0, u3)
    if normal_force(ctx, p, walls, w, mode, sgn, theta, s, 0.0) > 0.0:
        set_contact(ctx, mode, float(j), s, 0.0, sgn, t, t)


@inline
def touches(ctx, p, walls, j, px, py):
    """(touching, z): is the centre, at (px, py) in the boundary's frame, on surface j's
    offset (a wall's or the lid's; within CORNER_GAP of it, measured vertically), and the
    tangent angle (rad) there. Surface j's warm start is left as it was."""
    base = SURF + j * SURF_STRIDE
    ws, slope = ctx[base + S_WS], ctx[base + S_WSLOPE]
    gap = gap_rate(ctx, p, walls, j, px, py, 0.0, 0.0)[0]
    ctx[base + S_WS] = ws
    ctx[base + S_WSLOPE] = slope
    return abs(gap) <= CORNER_GAP, contact_kept(ctx, p, walls, j, px)[1]


@jit
def corner(ctx, p, walls, out, row, i, j):
    """The ball, touching surfaces i and j at one instant (two walls, or a wall and the
    lid), has just met wall j (the impact of
    row ``row``; the state after it in EN_*). Where it still approaches wall i, a series
    of impacts at this instant follows, with i and j in turn (each of the impact law,
    each losing energy): resolved here as one impact with both normals. Followed until
    the ball leaves both (CORNER_ENDS: its velocity after the series), or until the
    speed relative to the boundary is CORNER_LIMIT of that at its start or
    CORNER_SERIES impacts were made: a series that does not end, whose limit is rest
    relative to the boundary (CORNER_REST: the ball moves with the boundary, the spin
    the series left). Row ``row`` then records the whole series: the velocities after
    it, the energy, and the total impulse in wall j's frame. CORNER_NONE (nothing
    changed) where the ball leaves wall i, or touches it not.

    Returns (answer, the surface of the series' last impact, the normal speed (m/s)
    before that impact, whether the low-velocity rule made it elastic)."""
    kind_i, kind_j = ctx[SURF + i * SURF_STRIDE + S_KIND], ctx[SURF + j * SURF_STRIDE + S_KIND]
    if i == j or kind_i == ESCAPE or kind_j == ESCAPE:
        return CORNER_NONE, j, 0.0, False
    theta = ctx[EN_THETA]
    px, py, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    at_i, z_i = touches(ctx, p, walls, i, px, py)
    at_j, z_j = touches(ctx, p, walls, j, px, py)
    if not (at_i and at_j):
        return CORNER_NONE, j, 0.0, False
    u1, u2, u3 = ctx[EN_U1], ctx[EN_U2], ctx[EN_U3]
    vb1, vb2, _, _ = boundary(ctx, theta)
    if (u2 - vb2) * math.cos(z_i) - (u1 - vb1) * math.sin(z_i) >= 0.0:
        return CORNER_NONE, j, 0.0, False
    start = math.sqrt((u1 - vb1) ** 2 + (u2 - vb2) ** 2)
    v1, v2, v3 = u1, u2, u3
    z, other = z_i, z_j
    quiet = 0
    answer = CORNER_REST
    # the surface of the series' last impact, its normal speed before it and whether
    # the low-velocity rule made it elastic (the landing test's inputs)
    at, last, last_wn, last_elastic = i, j, 0.0, False
    for _ in range(CORNER_SERIES):
        n1, n2, n3, rt, rn, regime, _, _, wn = impact_law(ctx, v1, v2, v3, z, vb1, vb2, False)
        if rn == 0.0 and rt == 0.0:
            quiet += 1
            if quiet == 2:
                answer = CORNER_ENDS
                break
        else:
            quiet = 0
            v1, v2, v3 = n1, n2, n3
            last, last_wn, last_elastic = at, wn, regime == ELASTIC
            if math.sqrt((v1 - vb1) ** 2 + (v2 - vb2) ** 2) <= CORNER_LIMIT * start:
                break
        z, other = other, z
        at = j if at == i else i
    if answer == CORNER_REST:
        v1, v2 = vb1, vb2
    m = ctx[IM_M]
    c, sn = math.cos(z_j), math.sin(z_j)
    o = row * NCOL
    d1, d2 = v1 - u1, v2 - u2
    u4, un = frame_velocity(v1, v2, z_j)
    out[o + 4] = v1
    out[o + 5] = v2
    out[o + 6] = v3
    out[o + 7] = u4
    out[o + 8] = un
    out[o + 12] = energy(ctx[EN_Q2], v1, v2, v3, m, ctx[IM_R], ctx[IM_K], ctx[G])
    out[o + 14] = out[o + 14] + m * (c * d1 + sn * d2)
    out[o + 15] = out[o + 15] + m * (c * d2 - sn * d1)
    ctx[EN_U1] = v1
    ctx[EN_U2] = v2
    ctx[EN_U3] = v3
    return answer, last, last_wn, last_elastic


@inline
def after_corner(ctx, p, walls, i, j, last, wn, elastic, t):
    """After a series at one instant in the corner of surfaces i and j that ended
    (:func:`corner`), its last impact on surface ``last`` with normal speed wn before
    it: held by both or landed on ``last`` as after any impact there (the rebound below
    the landing speed, or its chatter summed), else the ball flies on."""
    theta = ctx[EN_THETA]
    px, _, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    other = j if last == i else i
    u1, u2, u3 = ctx[EN_U1], ctx[EN_U2], ctx[EN_U3]
    if hold_after(ctx, p, walls, other, last, theta, u3, wn, elastic, t, True, False):
        return
    s = contact_kept(ctx, p, walls, last, px)[0]
    land(ctx, p, walls, last, s, theta, u1, u2, u3, wn, elastic, -1, t)


@inline
def corner_rest(ctx, p, walls, i, j, t):
    """After a series at one instant that does not end (:func:`corner`), the ball at rest
    relative to the boundary in the corner of walls i and j: held by both where they
    press it (:func:`~billiard.kernels.vertex.held_spin`), else on the one that presses
    it (the spin's kinetic friction pulls it off the other, or the drive does), else it
    leaves both."""
    theta = ctx[EN_THETA]
    u3 = ctx[EN_U3]
    px, _, _, _ = boundary_frame(ctx, theta, ctx[EN_Q1], ctx[EN_Q2], 0.0, 0.0)
    z_i = contact_kept(ctx, p, walls, i, px)[1]
    z_j = contact_kept(ctx, p, walls, j, px)[1]
    spin = held_spin(ctx, z_i, z_j, theta, u3)
    if not math.isnan(spin):
        # by two walls, or by a wall and the lid (hold_step's kernel takes any two)
        enter_hold(ctx, i, j, t, t, spin)
        return
    to_flight(ctx)
    n_i, n_j = hold_forces(ctx, z_i, z_j, theta, sign(u3))
    on = i if n_i >= n_j else j
    if is_wall(ctx, on):
        continue_on(ctx, p, walls, on, px, theta, u3, t)
    # left in flight, at rest relative to both surfaces: its acceleration relative to the
    # boundary takes it off both (a grazing start of the flight's locator)
    if ctx[MC_MODE] == M_FLIGHT:
        push_off(ctx, -math.sin(z_i) - math.sin(z_j), math.cos(z_i) + math.cos(z_j))


@inline
def held_lab(ctx, theta, px, py):
    """(q1, q2, u1, u2) of a ball held at (px, py) in the boundary's frame."""
    q1, q2 = to_lab_frame(ctx, theta, px, py)
    u1, u2, _, _ = boundary(ctx, theta)
    return q1, q2, u1, u2


@inline
def hold_cut(ctx, cout, tau, u3):
    """The row of the hold under way cut tau after its start with the spin u3
    (``end`` = ``cut``); the engine's state and sample count stay at its start."""
    a = int(ctx[MC_CONTACT])
    b = int(ctx[MC_CONTACT + 1])
    px, py = ctx[MC_CONTACT + 2], ctx[MC_CONTACT + 3]
    theta0 = ctx[EN_THETA]
    q1s, q2s, u1s, u2s = held_lab(ctx, theta0, px, py)
    q1, q2, u1, u2 = held_lab(ctx, theta0 + ctx[OMEGA] * tau, px, py)
    o = contact_row(ctx, cout, 1.0, ctx[MC_CONTACT + 4], ctx[EN_T] + tau, a, b, M_HELD,
                    END_CUT, ctx[MC_CONTACT + 5])  # fmt: skip
    row_state(cout, o + 9, q1s, q2s, u1s, u2s, ctx[EN_U3])
    row_state(cout, o + 14, q1, q2, u1, u2, u3)
    ctx[MC_HOLD_ON] = 0.0
    if sampling(ctx):
        ctx[SM_K] = ctx[SM_MARK]


@jit
def hold_step(ctx, p, walls, cout, until, sout, srows):
    """The held ball to a release (-1: the run goes on),
    or the status that ends the run (SAMPLES_FULL: the hold goes on at the next call;
    PAUSED after a cut asked for by MC_PHASE_ON = PHASE_CUT)."""
    a = int(ctx[MC_CONTACT])
    b = int(ctx[MC_CONTACT + 1])
    px, py = ctx[MC_CONTACT + 2], ctx[MC_CONTACT + 3]
    t_start, settle = ctx[MC_CONTACT + 4], ctx[MC_CONTACT + 5]
    za = contact_kept(ctx, p, walls, a, px)[1]
    zb = contact_kept(ctx, p, walls, b, px)[1]
    t0, theta0, u3_0 = ctx[EN_T], ctx[EN_THETA], ctx[EN_U3]
    omega = ctx[OMEGA]
    # a new hold (a plain bool: a literal would compile run_hold once more)
    start = ctx[MC_HOLD_ON] == 0.0
    if not start and ctx[MC_PHASE_ON] == PHASE_CUT:
        # a stop request in a sampled hold: cut at its last sample
        ctx[MC_PHASE_ON] = PHASE_OFF
        hold_cut(ctx, cout, ctx[VX_SAMPLE_T], ctx[VX_SAMPLE_W])
        return PAUSED
    if start:
        end_at = deadline(ctx, until)
        if t0 >= end_at:
            ctx[MC_FINAL] = t0
            return IN_CONTACT
        ctx[VX_ZA] = za
        ctx[VX_ZB] = zb
        ctx[VX_THETA0] = theta0
        ctx[VX_LIMIT] = until - t0
        ctx[VX_W] = u3_0
        ctx[VX_NEXT] = first_sample(ctx, t0, until)
    while True:
        status = run_hold(ctx, start)
        if status != PHASE_SAMPLE:
            break
        start = False
        tau = ctx[VX_SAMPLE_T]
        q1, q2, u1, u2 = held_lab(ctx, theta0 + omega * tau, px, py)
        write_sample(ctx, sout, t0 + tau, q1, q2, u1, u2, ctx[VX_SAMPLE_W], M_HELD)
        ctx[VX_NEXT] = next_sample(ctx, t0, until)
        if int(ctx[SM_ROW]) == srows:
            ctx[MC_HOLD_ON] = 1.0
            return SAMPLES_FULL
    ctx[MC_HOLD_ON] = 0.0
    q1s, q2s, u1s, u2s = held_lab(ctx, theta0, px, py)
    if status == PHASE_LIMIT:
        hold_cut(ctx, cout, ctx[VX_LIMIT], ctx[VX_W_END])
        return TIME_LIMIT
    tau = ctx[VX_END_T]
    total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], tau)
    theta = (theta0 + omega * tau) % (2.0 * math.pi)
    t = total + error
    u3 = ctx[VX_W_END]
    q1, q2, u1, u2 = held_lab(ctx, theta, px, py)
    # the spin decays linearly in time on a static boundary: the trapezoid is exact
    q3 = ctx[EN_Q3] + 0.5 * (u3_0 + u3) * tau
    o = contact_row(ctx, cout, 0.0, t_start, t, a, b, M_HELD, END_RELEASE, settle)
    row_state(cout, o + 9, q1s, q2s, u1s, u2s, u3_0)
    row_state(cout, o + 14, q1, q2, u1, u2, u3)
    set_ball(ctx, t, theta, q1, q2, u1, u2, u3, q3)
    end_phase(ctx, M_HELD, t_start, tau, total, error)
    to_flight(ctx)
    keeps = int(ctx[VX_KEEPS])
    kept = a if keeps == 0 else b
    # on the lid (of a wall-lid corner) no contact phase: the ball leaves it
    if keeps >= 0 and is_wall(ctx, kept):
        continue_on(ctx, p, walls, kept, px, theta, u3, t)
    # a ball released by both surfaces (mode flight) flies on at the boundary's
    # velocity: its acceleration relative to the boundary takes it off both (a grazing
    # start)
    if ctx[MC_MODE] == M_FLIGHT:
        push_off(ctx, -math.sin(za) - math.sin(zb), math.cos(za) + math.cos(zb))
    return -1


# ---------------------------------------------------------------------- one wall


@jit
def impact_from_contact(ctx, p, walls, out, other, index, t, tau, theta, q3):
    """The ball in contact with wall ``index``
    reaches surface ``other`` (numbered without ``index``): an impact, its row written
    (True), or a contact without impulse (False: no row, nothing counted)."""
    j = other if other < index else other + 1
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == ESCAPE:
        ctx[EN_EVENT_T] = t
        ctx[EN_STOP] = E_ESCAPED
        raise KernelError(E_ESCAPED)
    q1, q2 = ctx[EN_Q1], ctx[EN_Q2]
    u1, u2, u3 = ctx[EN_U1], ctx[EN_U2], ctx[EN_U3]
    px, _, _, _ = boundary_frame(ctx, theta, q1, q2, 0.0, 0.0)
    s_o, z = contact(ctx, p, walls, j, px)
    vb1, vb2, _, _ = boundary(ctx, theta)
    # a ball that reaches a second wall or the lid lands, is held or reflects: under
    # contact phases the low-velocity rule never relaunches it (that adds energy)
    n1, n2, n3, rt, rn, regime, _, _, wn = impact_law(ctx, u1, u2, u3, z, vb1, vb2, False)
    elastic = regime == ELASTIC
    if rn == 0.0 and rt == 0.0:
        # no impulse: no impact (billiard.models.corner.is_impact)
        if not hold_after(ctx, p, walls, index, j, theta, n3, wn, elastic, t, False, tau == 0.0):
            land(ctx, p, walls, j, s_o, theta, n1, n2, n3, wn, elastic, -1, t)
        return False
    u4, un = frame_velocity(n1, n2, z)
    e = energy(q2, n1, n2, n3, ctx[IM_M], ctx[IM_R], ctx[IM_K], ctx[G])
    n = ctx[EN_IMPACTS] + 1.0
    wall = LID_LABEL if kind == LID else ctx[base + S_WALL]
    write_row(out, int(ctx[MC_ROW]) * NCOL, n, t, q1, q2, n1, n2, n3, u4, un, tau, regime, z, e,
              wall, rt, rn, s_o, q3)  # fmt: skip
    ctx[MC_ROW] += 1.0
    ctx[EN_IMPACTS] = n
    ctx[EN_EVENT_T] = t
    ctx[MC_LAST_IMPACT] = t
    set_ball(ctx, t, theta, q1, q2, n1, n2, n3, q3)
    ctx[COUNTS + int(regime)] += 1.0
    remember_impact(ctx, t)
    collapsed = int(ctx[EN_RCOUNT]) > COLLAPSE_COUNT or ctx[EN_ZERO] >= ZERO_FLIGHT_LIMIT
    ctx[EN_FAULT] = 1.0 if collapsed else 0.0
    # the surface of this impact, for one with another at this instant (loop.impact)
    ctx[EN_LAST_J] = float(j)
    series, last, last_wn, last_elastic = corner(ctx, p, walls, out, int(ctx[MC_ROW]) - 1,
                                                 index, j)  # fmt: skip
    if series == CORNER_REST:
        corner_rest(ctx, p, walls, index, j, t)
        return True
    if series == CORNER_ENDS:
        after_corner(ctx, p, walls, index, j, last, last_wn, last_elastic, t)
        return True
    if not hold_after(ctx, p, walls, index, j, theta, n3, wn, elastic, t, True, tau == 0.0):
        land(ctx, p, walls, j, s_o, theta, n1, n2, n3, wn, elastic, -1, t)
    return True


@jit
def reach_start(ctx, p, walls, until, sout, srows):
    """Take the ball in contact to its phase's start (the end of a summed chatter
    series, its samples): -1, or the status that ends the run first."""
    if ctx[EN_T] < ctx[MC_CONTACT + 4]:
        if sampling(ctx) and ctx[SM_DONE] == 0.0:
            # the samples up to the phase's start (see chatter_samples)
            ctx[SM_MARK] = ctx[SM_K]
            ctx[SM_FROM] = ctx[EN_T]
            ctx[SM_TO] = pmin(ctx[MC_CONTACT + 4], until)
            ctx[SM_PENDING] = SRC_CHATTER
            if not chatter_samples(ctx, p, walls, sout, srows):
                return SAMPLES_FULL
        ctx[SM_DONE] = 0.0
        if not end_chatter(ctx, p, walls, until):
            if sampling(ctx):
                # as the state, the sample count stays at the impact
                ctx[SM_K] = ctx[SM_MARK]
            return TIME_LIMIT
    t0 = ctx[EN_T]
    if t0 >= deadline(ctx, until):
        ctx[MC_FINAL] = t0
        return IN_CONTACT
    return -1


@jit
def start_phase(ctx, p, walls, until, sout, srows):
    """Set up the phase of the ball in contact (up to ``run_phase``): -1, or the status
    that ends the run first."""
    code = reach_start(ctx, p, walls, until, sout, srows)
    if code >= 0:
        return code
    t0 = ctx[EN_T]
    end_at = deadline(ctx, until)
    j = int(ctx[MC_CONTACT])
    w = wall_of(ctx, j)
    roll = ctx[MC_MODE] == M_ROLL
    ctx[PH_WALL] = float(w)
    ctx[PH_LO] = pmax(ctx[MC_WALL_LO + w], ctx[MC_X_LO])
    ctx[PH_HI] = pmin(ctx[MC_WALL_HI + w], ctx[MC_X_HI])
    ctx[PH_MODE] = ROLL if roll else SLIDE
    ctx[PH_SGN] = ctx[MC_CONTACT + 3]
    ctx[PH_THETA0] = ctx[EN_THETA]
    ctx[PH_LIMIT] = until - t0
    ctx[PH_Y] = ctx[MC_CONTACT + 1]
    ctx[PH_Y + 1] = ctx[MC_CONTACT + 2]
    ctx[PH_Y + 2] = 0.0 if roll else ctx[EN_U3]
    ctx[PH_SURF] = float(j)
    ctx[PH_NEXT] = first_sample(ctx, t0, until)
    ctx[PH_STEPS] = 0.0
    ctx[PH_PAUSE] = PAUSE_STEPS
    ctx[PH_PAUSE_T] = end_at - t0
    ctx[MC_STOP_AT] = end_at - t0
    return -1


@jit
def phase_cut(ctx, p, walls, cout, tau, y):
    """The row of the phase under way cut tau after its start with the contact state
    ctx[y:y + 3] (``end`` = ``cut``): the engine's state stays at the phase's start.
    Returns the time of the cut (s)."""
    j = int(ctx[MC_CONTACT])
    w = wall_of(ctx, j)
    mode = ctx[MC_MODE]
    roll = mode == M_ROLL
    theta0 = ctx[PH_THETA0]
    theta = (theta0 + ctx[OMEGA] * tau) % (2.0 * math.pi)
    t_cut = ctx[EN_T] + tau
    o = contact_row(ctx, cout, 1.0, ctx[MC_CONTACT + 4], t_cut, j, ONE_WALL - w, mode, END_CUT,
                    ctx[MC_CONTACT + 5])  # fmt: skip
    q1, q2, u1, u2, u3 = lab_state(ctx, p, walls, w, theta0, ctx[MC_CONTACT + 1],
                                   ctx[MC_CONTACT + 2], ctx[EN_U3], roll)  # fmt: skip
    row_state(cout, o + 9, q1, q2, u1, u2, u3)
    q1, q2, u1, u2, u3 = lab_state(ctx, p, walls, w, theta, ctx[y], ctx[y + 1], ctx[y + 2], roll)
    row_state(cout, o + 14, q1, q2, u1, u2, u3)
    ctx[MC_PHASE_ON] = PHASE_OFF
    if sampling(ctx):
        # the phase's samples are no part of the state, which stays at its start
        ctx[SM_K] = ctx[SM_MARK]
    return t_cut


@jit
def answer_pause(ctx, p, walls, cout, until):
    """A pause of the phase under way, answered as the engine's pause answers it when
    no stop is requested: on (-1), or the status that ends the run (the phase cut at
    the contact span's end)."""
    tau = ctx[PH_TAU]
    if tau < ctx[MC_STOP_AT]:
        ctx[PH_PAUSE] = ctx[PH_STEPS] + PAUSE_STEPS
    elif ctx[PH_RSINCE] == math.inf:
        # moving at the contact span's end: cut there
        t_cut = phase_cut(ctx, p, walls, cout, tau, PH_Y)
        if t_cut >= deadline(ctx, until):
            ctx[MC_FINAL] = t_cut
            return IN_CONTACT
        return TIME_LIMIT
    else:
        # at rest relative to the boundary: on to the kernel's at-rest stop (within a
        # drive period), looked at after every step
        ctx[PH_PAUSE_T] = math.inf
        ctx[PH_PAUSE] = ctx[PH_STEPS] + 1.0
    ctx[MC_PHASE_ON] = PHASE_ON
    return -1


@jit
def finish_phase(ctx, p, walls, out, cout, until, status):
    """After ``run_phase``: the phase's end, its row,
    the transition (-1: the run goes on), or the status that ends the run."""
    ctx[MC_PHASE_ON] = PHASE_OFF
    if status == PHASE_LIMIT:
        phase_cut(ctx, p, walls, cout, ctx[PH_LIMIT], PH_Y)
        return TIME_LIMIT
    j = int(ctx[MC_CONTACT])
    w = wall_of(ctx, j)
    s0, sd0, sgn = ctx[MC_CONTACT + 1], ctx[MC_CONTACT + 2], ctx[MC_CONTACT + 3]
    t_start, settle = ctx[MC_CONTACT + 4], ctx[MC_CONTACT + 5]
    mode = ctx[MC_MODE]
    roll = mode == M_ROLL
    theta0, u3_0 = ctx[PH_THETA0], ctx[EN_U3]
    tau = ctx[PH_END_T]
    i = int(ctx[PH_END_I])
    s1, sd1, w1 = ctx[PH_END_Y], ctx[PH_END_Y + 1], ctx[PH_END_Y + 2]
    total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], tau)
    theta = (theta0 + ctx[OMEGA] * tau) % (2.0 * math.pi)
    t = total + error
    q1, q2, u1, u2, u3 = lab_state(ctx, p, walls, w, theta, s1, sd1, w1, roll)
    if not math.isfinite(q1 + q2 + u1 + u2 + u3):
        ctx[EN_ERR_VALUE] = t
        ctx[EN_STOP] = E_PHASE_NON_FINITE
        raise KernelError(E_PHASE_NON_FINITE)
    q3 = ctx[EN_Q3] + 0.5 * (u3_0 + u3) * tau
    w2, sd2, mode2, sgn2 = -1, 0.0, mode, sgn
    if i == 0:
        reason = END_LIFT_OFF
    elif i < 3:
        reason = END_WALL_END
        w2 = smooth_neighbour(ctx, w, i == 2)
        if w2 >= 0:
            # a smooth join: the centre's state is continuous, s_dot follows from it on
            # the next wall (whose f'' differs), and so does the contact mode; the ball
            # stays in contact if that wall presses it
            sd2 = s_dot(ctx, p, walls, w2, theta, s1, u1, u2)
            mode2, sgn2 = mode_for(ctx, p, walls, w2, theta, s1, sd2, u3)
            if normal_force(ctx, p, walls, w2, mode2, sgn2, theta, s1, sd2) > 0.0:
                reason = END_JOIN
            else:
                reason = END_LIFT_OFF
    elif i == 3:
        reason = END_SLIP if roll else END_ROLL
    else:
        reason = END_IMPACT
    o = contact_row(ctx, cout, 0.0, t_start, t, j, ONE_WALL - w, mode, reason, settle)
    q1s, q2s, u1s, u2s, u3s = lab_state(ctx, p, walls, w, theta0, s0, sd0, u3_0, roll)
    row_state(cout, o + 9, q1s, q2s, u1s, u2s, u3s)
    row_state(cout, o + 14, q1, q2, u1, u2, u3)
    set_ball(ctx, t, theta, q1, q2, u1, u2, u3, q3)
    end_phase(ctx, mode, t_start, tau, total, error)
    if reason == END_LIFT_OFF or reason == END_WALL_END:
        # the centre is on the offset curve with a tangent velocity, the wall no longer
        # pressing it: the flight starts grazing the wall, its own equations lift it off
        fp = walls[1][w](s1, p)
        push_off(ctx, -fp, 1.0)
        to_flight(ctx)
    elif reason == END_JOIN:
        base = SURF + j * SURF_STRIDE
        ctx[base + S_WALL] = float(w2)
        ctx[base + S_SLOPE_AT] = math.nan  # the slope memo was the other wall's
        ctx[base + S_WS] = s1
        set_contact(ctx, mode2, float(j), s1, sd2, sgn2, t, t)
    elif reason == END_SLIP:
        f = forces_of(ctx, p, walls, w, M_ROLL, 0.0, theta, s1, sd1)[3]
        set_contact(ctx, M_SLIDE, float(j), s1, sd1, -1.0 if f > 0.0 else 1.0, t, t)
    elif reason == END_ROLL:
        _, _, n_force, f = forces_of(ctx, p, walls, w, M_ROLL, 0.0, theta, s1, sd1)
        if abs(f) <= ctx[PH_MUS] * n_force:
            set_contact(ctx, M_ROLL, float(j), s1, sd1, 0.0, t, t)
        else:
            set_contact(ctx, M_SLIDE, float(j), s1, sd1, -sgn, t, t)
    if reason == END_WALL_END:
        # at the container's end of x rather than the wall's: the ball leaves sideways
        lo, hi = ctx[PH_LO], ctx[PH_HI]
        low_end = s1 <= 0.5 * (lo + hi)
        if (low_end and lo > ctx[MC_WALL_LO + w]) or (not low_end and hi < ctx[MC_WALL_HI + w]):
            ctx[EN_ERR_VALUE] = s1
            ctx[EN_STOP] = E_LEFT
            raise KernelError(E_LEFT)
    if reason == END_IMPACT:
        to_flight(ctx)
        impact_from_contact(ctx, p, walls, out, i - 4, j, t, tau, theta, q3)
    return -1


@inline
def smooth_neighbour(ctx, w, high):
    """The wall across a smooth join at wall w's high (``high``) or low end, where the
    phase on w (on the surface of the ball's contact) reached that end of the wall's
    interval, not the container's end: -1 if none."""
    base = SURF + int(ctx[MC_CONTACT]) * SURF_STRIDE
    if ctx[base + S_KIND] != CURVED:
        return -1
    if high:
        if w < int(ctx[base + S_LAST]) and ctx[PH_HI] == ctx[MC_WALL_HI + w]:
            return w + 1
    elif w > int(ctx[base + S_FIRST]) and ctx[PH_LO] == ctx[MC_WALL_LO + w]:
        return w - 1
    return -1


@inline
def phase_sample(ctx, p, walls, sout):
    """The sample run_phase handed out (PH_SAMPLE_T after the phase's start)."""
    w = wall_of(ctx, int(ctx[MC_CONTACT]))
    mode = ctx[MC_MODE]
    tau = ctx[PH_SAMPLE_T]
    theta = ctx[PH_THETA0] + ctx[OMEGA] * tau
    y = PH_SAMPLE_Y
    q1, q2, u1, u2, u3 = lab_state(ctx, p, walls, w, theta, ctx[y], ctx[y + 1], ctx[y + 2],
                                   mode == M_ROLL)  # fmt: skip
    write_sample(ctx, sout, ctx[EN_T] + tau, q1, q2, u1, u2, u3, mode)


@inline
def contact_step(ctx, p, walls, out, cout, until, sout, srows):
    """A phase of the ball in contact with one wall, to its end or a pause: -1 when the
    run goes on, else the status that ends this call (PAUSED, SAMPLES_FULL: the phase
    goes on at the next)."""
    on = ctx[MC_PHASE_ON]
    if on == PHASE_CUT:
        phase_cut(ctx, p, walls, cout, ctx[PH_TAU], PH_Y)
        return PAUSED
    if on == PHASE_OFF:
        code = start_phase(ctx, p, walls, until, sout, srows)
        if code >= 0:
            return code
        ctx[MC_PHASE_ON] = PHASE_ON
    elif on == PHASE_PAUSED:
        code = answer_pause(ctx, p, walls, cout, until)
        if code >= 0:
            return code
    # one call site, a plain bool (a literal would compile run_phase once more per value)
    start = on == PHASE_OFF
    while True:
        status = run_phase(ctx, p, walls, start)
        if status != PHASE_SAMPLE:
            break
        start = False
        phase_sample(ctx, p, walls, sout)
        ctx[PH_NEXT] = next_sample(ctx, ctx[EN_T], until)
        if int(ctx[SM_ROW]) == srows:
            # the phase goes on from its sample at the next call
            return SAMPLES_FULL
    if status == PHASE_PAUSE:
        ctx[MC_PHASE_ON] = PHASE_PAUSED
        return PAUSED
    return finish_phase(ctx, p, walls, out, cout, until, status)


# ---------------------------------------------------------------------- the lid


@inline
def lid_start(ctx):
    """(px0, vx0, spin, slip sign) at the start of the phase on the lid."""
    return ctx[MC_CONTACT + 1], ctx[MC_CONTACT + 2], ctx[EN_U3], ctx[MC_CONTACT + 3]


@inline
def lid_row(ctx, p, walls, cout, kind, tau, reason):
    """The row of the phase on the lid tau after its start (``kind`` 1.0: cut), the
    surface the lid, no other; returns the state at its end (q1, q2, u1, u2, u3, the
    angle turned, theta)."""
    j = int(ctx[MC_CONTACT])
    px0, vx0, w0, sgn = lid_start(ctx)
    theta0 = ctx[EN_THETA]
    theta = (theta0 + ctx[OMEGA] * tau) % (2.0 * math.pi)
    px, vx, u3, turned = lid_motion(ctx, theta0, px0, vx0, w0, sgn, tau)
    o = contact_row(ctx, cout, kind, ctx[MC_CONTACT + 4], ctx[EN_T] + tau, j, -1.0, ctx[MC_MODE],
                    reason, ctx[MC_CONTACT + 5])  # fmt: skip
    q1, q2, u1, u2, _ = contact_lab(ctx, p, walls, j, theta0, px0, vx0, w0, False)
    row_state(cout, o + 9, q1, q2, u1, u2, w0)
    q1, q2, u1, u2, _ = contact_lab(ctx, p, walls, j, theta, px, vx, u3, False)
    row_state(cout, o + 14, q1, q2, u1, u2, u3)
    return q1, q2, u1, u2, u3, turned, theta


@inline
def lid_cut(ctx, p, walls, cout, tau):
    """The row of the phase on the lid cut tau after its start (``end`` = ``cut``); the
    engine's state and sample count stay at its start."""
    lid_row(ctx, p, walls, cout, 1.0, tau, END_CUT)
    ctx[MC_PHASE_ON] = PHASE_OFF
    if sampling(ctx):
        ctx[SM_K] = ctx[SM_MARK]


@jit
def lid_step(ctx, p, walls, out, cout, until, sout, srows):
    """The ball pressed against the lid (:mod:`billiard.kernels.lid`), to the phase's
    end in closed form: the lid releases it (N = 0: ``lift-off``, a grazing start), it
    stops slipping (``roll``, a rolling phase follows), or it reaches a wall (an impact
    from contact, the wall-lid corner's hold). -1 when the run goes on, else the status
    that ends this call (SAMPLES_FULL: on from its next sample at the next call; PAUSED
    after a cut asked for by MC_PHASE_ON = PHASE_CUT, at its last sample)."""
    on = ctx[MC_PHASE_ON]
    if on == PHASE_CUT:
        lid_cut(ctx, p, walls, cout, ctx[PH_TAU])
        return PAUSED
    if on == PHASE_OFF:
        code = reach_start(ctx, p, walls, until, sout, srows)
        if code >= 0:
            return code
        ctx[PH_TAU] = 0.0
        ctx[PH_NEXT] = first_sample(ctx, ctx[EN_T], until)
        ctx[MC_PHASE_ON] = PHASE_ON
    j = int(ctx[MC_CONTACT])
    t0, theta0 = ctx[EN_T], ctx[EN_THETA]
    px0, vx0, w0, sgn = lid_start(ctx)
    # the phase's end, each event in closed form (the wall's by bisection of its gap)
    end = lid_release(ctx, theta0)
    reason = END_LIFT_OFF
    if sgn != 0.0:
        tau = lid_slip_end(ctx, theta0, vx0 - ctx[IM_R] * w0, end)
        if tau < end:
            end, reason = tau, END_ROLL
    tau = lid_wall_reach(ctx, p, walls, j, theta0, px0, vx0, w0, sgn, end)
    if tau <= end:
        end, reason = tau, END_IMPACT
    limit = until - t0
    while ctx[PH_NEXT] <= pmin(end, limit):
        tau = ctx[PH_NEXT]
        px, vx, u3, _ = lid_motion(ctx, theta0, px0, vx0, w0, sgn, tau)
        q1, q2, u1, u2, _ = contact_lab(ctx, p, walls, j, theta0 + ctx[OMEGA] * tau, px, vx, u3,
                                        False)  # fmt: skip
        write_sample(ctx, sout, t0 + tau, q1, q2, u1, u2, u3, ctx[MC_MODE])
        ctx[PH_TAU] = tau
        ctx[PH_NEXT] = next_sample(ctx, t0, until)
        if int(ctx[SM_ROW]) == srows:
            return SAMPLES_FULL
    if end > limit:
        lid_cut(ctx, p, walls, cout, limit)
        return TIME_LIMIT
    ctx[MC_PHASE_ON] = PHASE_OFF
    mode, t_start = ctx[MC_MODE], ctx[MC_CONTACT + 4]
    total, error = compensated_add(ctx[EN_CLOCK], ctx[EN_CLOCK_ERR], end)
    q1, q2, u1, u2, u3, turned, theta = lid_row(ctx, p, walls, cout, 0.0, end, reason)
    t = total + error
    cout[int(ctx[MC_CROW] - 1.0) * CCOL + 3] = t  # the compensated clock's end
    q3 = ctx[EN_Q3] + turned
    set_ball(ctx, t, theta, q1, q2, u1, u2, u3, q3)
    end_phase(ctx, mode, t_start, end, total, error)
    to_flight(ctx)
    if reason == END_ROLL:
        px, _, _, _ = boundary_frame(ctx, theta, q1, q2, 0.0, 0.0)
        vx = u1 - boundary(ctx, theta)[0]
        set_contact(ctx, M_ROLL, float(j), px, vx, 0.0, t, t)
    elif reason == END_IMPACT:
        px, py, _, _ = boundary_frame(ctx, theta, q1, q2, 0.0, 0.0)
        wall = wall_gap(ctx, p, walls, px, py)[1]
        impact_from_contact(ctx, p, walls, out, wall if wall < j else wall - 1, j, t, end,
                            theta, q3)  # fmt: skip
    # released (lift-off): in flight at the lid with no normal speed relative to it, its
    # acceleration away from the lid opens the gap (a grazing start)
    if reason == END_LIFT_OFF:
        push_off(ctx, 0.0, -1.0)  # under the fixed-step search only: away from the lid
    return -1


@jit
def run_machine(ctx, p, walls, nears, out, rows, cout, crows, sctx, sout, srows):
    """Advance the trajectory until impact number ``ctx[EN_TARGET]``: ``rows`` impact
    rows in ``out``, ``crows`` contact rows in ``cout``, ``srows`` sample rows in
    ``sout``, counted in MC_ROW, MC_CROW and SM_ROW, which the caller sets to zero
    before a call. ``walls`` = (f, f', f'', f''') of the curve's walls, ``nears`` their
    nearest-point functions (:func:`~billiard.kernels.loop.run_flights`, method rk4);
    ``sctx`` is the sample flight's state
    (:mod:`billiard.kernels.samples`; samples are made when ``ctx[SM_DT]`` > 0).

    Returns a status: DONE, FULL, CONTACTS_FULL, SAMPLES_FULL, TIME_LIMIT
    (``ctx[EN_UNTIL]`` comes first), COLLAPSE (``ctx[EN_FAULT]``: 1 impacts piled up,
    2 phases of zero duration, 3 contacts without impulse piled up), IN_CONTACT (no
    impact for the contact span, at MC_FINAL) or PAUSED (a long phase, or a phase cut
    by a stop request: MC_PHASE_ON). A documented stop raises KernelError, the rows
    written so far counted."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx, p, out, cout = borrow(ctx), borrow(p), borrow(out), borrow(cout)
    sctx, sout = borrow(sctx), borrow(sout)
    flight_walls = (walls[0], walls[1], walls[2])
    until = ctx[EN_UNTIL]
    if ctx[SM_PENDING] != 0.0:
        code = pending_samples(ctx, p, walls, sctx, sout, srows)
        if code >= 0:
            return code
    while ctx[EN_IMPACTS] < ctx[EN_TARGET]:
        row = int(ctx[MC_ROW])
        if row == rows:
            return FULL
        if int(ctx[MC_CROW]) == crows:
            return CONTACTS_FULL
        mode = ctx[MC_MODE]
        if mode == M_FLIGHT:
            ctx[EN_SETTLES] = 0.0
            ctx[MC_FLYING] = 1.0
            ctx[MC_FLIGHT_FROM] = ctx[EN_T]
            if sampling(ctx):
                # one flight a call, sampled when it ends
                ctx[EN_ONE] = 1.0
                save_flight_start(ctx, ctx[EN_T], ctx[EN_THETA], ctx[EN_Q1], ctx[EN_Q2],
                                  ctx[EN_U1], ctx[EN_U2], ctx[EN_U3])  # fmt: skip
            code, written = run_flights(ctx, p, flight_walls, nears, out[row * NCOL :], rows - row)
            ctx[MC_FLYING] = 0.0
            ctx[MC_ROW] = float(row + written)
            if written > 0 or ctx[EN_T] != ctx[MC_FLIGHT_FROM]:
                # at the last impact (its time in MC_LAST_IMPACT: loop.impact) or at a
                # contact without impulse after it
                ctx[MC_FINAL] = ctx[EN_T]
            series = CORNER_NONE
            if ctx[EN_SETTLES] >= SETTLES_CORNER:
                # an impact at the instant of one with another wall (loop.impact)
                i = int(ctx[EN_SETTLES] // SETTLES_CORNER) - 1
                j = int(ctx[EN_LAST_J])
                series, last, last_wn, last_elastic = corner(
                    ctx, p, walls, out, int(ctx[MC_ROW]) - 1, i, j
                )
                if series == CORNER_REST:
                    corner_rest(ctx, p, walls, i, j, ctx[EN_T])
                elif series == CORNER_ENDS:
                    after_corner(ctx, p, walls, i, j, last, last_wn, last_elastic, ctx[EN_T])
            if ctx[EN_SETTLES] != 0.0 and series == CORNER_NONE:
                j = int(ctx[EN_LAST_J])
                # the free flight's test of the chatter's tail (loop.SETTLES_TAIL)
                tail = 1 if int(ctx[EN_SETTLES]) & 2 != 0 else 0
                land(ctx, p, walls, j, ctx[EN_LAST_S], ctx[EN_THETA], ctx[EN_U1], ctx[EN_U2],
                     ctx[EN_U3], ctx[EN_LAST_WN], ctx[EN_LAST_REGIME] == ELASTIC, tail,
                     ctx[EN_T])  # fmt: skip
            if sampling(ctx):
                start_flight_samples(ctx, sctx, until if code == TIME_LIMIT else ctx[EN_T])
                after = -1 if code == LAND or code == FLOWN else code
                if not flight_samples(ctx, sctx, sout, srows):
                    ctx[SM_AFTER] = float(after)
                    return SAMPLES_FULL
                if after >= 0:
                    return after
                continue
            if code != LAND:
                return code
            continue
        if mode == M_HELD:
            code = hold_step(ctx, p, walls, cout, until, sout, srows)
        elif ctx[SURF + int(ctx[MC_CONTACT]) * SURF_STRIDE + S_KIND] == LID:
            code = lid_step(ctx, p, walls, out, cout, until, sout, srows)
        else:
            code = contact_step(ctx, p, walls, out, cout, until, sout, srows)
        if code >= 0:
            return code
        if ctx[EN_FAULT] != 0.0:
            return COLLAPSE
    return DONE
