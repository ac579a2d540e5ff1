"""A contact phase over the state vector: the ball rolling or sliding on one wall
(``contact.model = "phases"``), integrated by Dormand-Prince 5(4) with its fourth-order
continuous extension, its end located by Illinois regula falsi on the dense output.
:class:`billiard.models.contact.ContactModel` runs these functions interpreted; the
equations and the transition functions they integrate are
:mod:`~billiard.kernels.contact_forces`.

The phase's constants and its integration state live in the ``PH_*`` slots of ``ctx``
(:mod:`~billiard.kernels.layout`), so a phase is resumable: :func:`advance` returns at
every sample time (``PHASE_SAMPLE``) and goes on from there when called again, and
returns ``PHASE_END`` or ``PHASE_LIMIT`` when the phase is over. No callables: the wall's
f, f', f'', f''' come in ``walls = (f, df, d2f, d3f)``, the other surfaces (walls, lid,
escape level) are the surface blocks of ``ctx`` other than ``PH_SURF``.

Every operation is the one the phase's former Python performed, in the same order:
sums accumulate from 0.0 left to right (CPython's ``sum`` of floats, from its integer
start 0, gives the same bits, also for -0.0 terms); ``max`` and ``min`` are written as
Python evaluates them (the first of equal or unordered values is kept); the step-size
factor ``err**-0.2`` stays a power.
"""

from __future__ import annotations

import math

from . import drive
from .contact_forces import at_rest, conditions, n_conditions, n_y, rhs
from .decorators import borrow, inline, jit
from .illinois import narrow, secant_point
from .layout import (
    E_AT_REST,
    E_PHASE_STEPS,
    EN_STOP,
    OMEGA,
    PH_CNEW,
    PH_CPREV,
    PH_CTMP,
    PH_END_I,
    PH_END_T,
    PH_END_Y,
    PH_ERR,
    PH_H,
    PH_HMAX,
    PH_HSTEP,
    PH_KS,
    PH_LIMIT,
    PH_NEXT,
    PH_PAUSE,
    PH_PAUSE_T,
    PH_RSINCE,
    PH_RSPAN,
    PH_RTOL,
    PH_SAMPLE_T,
    PH_SAMPLE_Y,
    PH_STAGE,
    PH_STEPS,
    PH_TA,
    PH_TAU,
    PH_TB,
    PH_Y,
    PH_YB,
    PH_YD,
    PH_YI,
    PHASE_END,
    PHASE_LIMIT,
    PHASE_PAUSE,
    PHASE_SAMPLE,
    STAGE_EMIT,
    STAGE_SKIP,
    STAGE_STEP,
    KernelError,
)

#: time resolution (s) of a phase's end
EVENT_TOL = 1e-13
#: A phase that starts touching another wall (its gap zero to rounding, possibly just
#: below zero, as in the wedge's vertex) ends with an impact there when the centre then
#: goes deeper into it than this (m; the impact locator's resolution): at once, or where
#: the gap returns to zero if the ball first moved away (:func:`touched_root`).
CONTACT_GAP = 1e-12
#: absolute error allowed per step on s (m), s_dot (m/s) and u3 (rad/s), added to rtol
#: times the size of each
ATOL = (1e-12, 1e-12, 1e-9)

# Dormand-Prince 5(4) (Dormand & Prince 1980) and its 4th-order continuous extension
# (Shampine 1986; the coefficients scipy's RK45 uses). Flat tuples of one type, which
# numba indexes at run time: row i of A starts at i (i - 1) / 2, row q of P at 4 q.
C = (0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0)
A = (
    *(1 / 5,),
    *(3 / 40, 9 / 40),
    *(44 / 45, -56 / 15, 32 / 9),
    *(19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
    *(9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
)
B = (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84)
E = (-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40)
P = (
    *(1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432),
    *(0.0, 0.0, 0.0, 0.0),
    *(0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799),
    *(0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072),
    *(
        0.0,
        127303824393 / 49829197408,
        -318862633887 / 49829197408,
        701980252875 / 199316789632,
    ),
    *(0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844),
    *(0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423),
)


@inline
def pmax(a, b):
    """Python's ``max(a, b)``: b only when it is greater (a NaN b never is)."""
    return b if b > a else a


@inline
def pmin(a, b):
    """Python's ``min(a, b)``: b only when it is less."""
    return b if b < a else a


@inline
def dense(ctx, t, out):
    """The continuous extension of the last step at t into ctx[out:out + 3]."""
    ta, hs = ctx[PH_TA], ctx[PH_HSTEP]
    x = (t - ta) / hs
    ny = n_y(ctx)
    if x == 1.0:
        for j in range(ny):
            ctx[out + j] = ctx[PH_YB + j]
        return
    w0 = x * (P[0] + x * (P[1] + x * (P[2] + x * P[3])))
    w1 = x * (P[4] + x * (P[5] + x * (P[6] + x * P[7])))
    w2 = x * (P[8] + x * (P[9] + x * (P[10] + x * P[11])))
    w3 = x * (P[12] + x * (P[13] + x * (P[14] + x * P[15])))
    w4 = x * (P[16] + x * (P[17] + x * (P[18] + x * P[19])))
    w5 = x * (P[20] + x * (P[21] + x * (P[22] + x * P[23])))
    w6 = x * (P[24] + x * (P[25] + x * (P[26] + x * P[27])))
    for j in range(ny):
        k = PH_KS + j
        acc = 0.0
        acc += w0 * ctx[k]
        acc += w1 * ctx[k + 3]
        acc += w2 * ctx[k + 6]
        acc += w3 * ctx[k + 9]
        acc += w4 * ctx[k + 12]
        acc += w5 * ctx[k + 15]
        acc += w6 * ctx[k + 18]
        ctx[out + j] = ctx[PH_Y + j] + hs * acc


@inline
def condition_at(ctx, p, walls, i, t):
    """Condition i at t on the dense output (all conditions are evaluated, as the warm
    starts of the other surfaces depend on every evaluation)."""
    dense(ctx, t, PH_YD)
    conditions(ctx, p, walls, t, PH_YD, PH_CTMP)
    return ctx[PH_CTMP + i]


@inline
def first_root(ctx, p, walls, i, a, b, fa):
    """The first time in (a, b] where condition i, positive at a (or zero and falling),
    reaches zero or below: Illinois regula falsi, to EVENT_TOL."""
    fb = condition_at(ctx, p, walls, i, b)
    if fa <= 0.0:
        return a
    side = 0
    for _ in range(200):
        if b - a <= EVENT_TOL:
            break
        m = secant_point(a, b, fa, fb)
        fm = condition_at(ctx, p, walls, i, m)
        a, b, fa, fb, side = narrow(a, b, fa, fb, m, fm, side)
    return b


@inline
def touched_root(ctx, p, walls, i, a, b, fa):
    """The impact on another surface touched at a (condition i, its gap, zero to
    rounding there, possibly below: the wedge's vertex, a wall meeting the lid) and
    entered deeper than CONTACT_GAP by b.
    A ball that goes into that wall at once meets it at a. A ball that first moves away
    from it (leaving the vertex along its own wall) and is turned back within the step
    meets it where the gap falls back to zero: the impact at a would have no impulse, and
    the phase that follows would end at a again, a cycle at one instant. Told apart by
    the gap halfway to where the centre is CONTACT_GAP inside the wall: still inside
    (entered at once), or outside (away and back)."""
    if fa + CONTACT_GAP <= 0.0:
        return a
    # the first time in (a, b] the centre is CONTACT_GAP inside the wall
    lo, hi = a, b
    flo = fa + CONTACT_GAP
    fhi = condition_at(ctx, p, walls, i, b) + CONTACT_GAP
    side = 0
    for _ in range(200):
        if hi - lo <= EVENT_TOL:
            break
        m = secant_point(lo, hi, flo, fhi)
        fm = condition_at(ctx, p, walls, i, m) + CONTACT_GAP
        lo, hi, flo, fhi, side = narrow(lo, hi, flo, fhi, m, fm, side)
    mid = 0.5 * (a + hi)
    f_mid = condition_at(ctx, p, walls, i, mid)
    if f_mid <= 0.0:
        return a
    return first_root(ctx, p, walls, i, mid, hi, f_mid)


@inline
def begin(ctx, p, walls):
    """Start a phase from y = ctx[PH_Y:] at tau = 0 (constants, wall, mode, limit and the
    first sample time PH_NEXT set): the first derivative, step and conditions."""
    ctx[PH_TAU] = 0.0
    rhs(ctx, p, walls, 0.0, PH_Y, PH_KS)
    scale = pmax(pmax(abs(ctx[PH_KS]), abs(ctx[PH_KS + 1])), 1e-3)
    limit = ctx[PH_LIMIT]
    ctx[PH_H] = pmin(limit, 1e-3 / scale + 1e-4) if limit > 0.0 else 0.0
    conditions(ctx, p, walls, 0.0, PH_Y, PH_CPREV)
    ctx[PH_STEPS] = 0.0
    omega = ctx[OMEGA]
    static = drive.static(ctx)
    # the step is at most 1/20 of the drive period, so that the conditions, which the
    # drive moves, cannot change sign twice unseen within a step
    ctx[PH_HMAX] = math.inf if static else 0.1 * math.pi / abs(omega)
    ctx[PH_RSPAN] = 0.0 if static else 2.0 * math.pi / abs(omega)
    ctx[PH_RSINCE] = 0.0 if at_rest(ctx, PH_KS) else math.inf
    ctx[PH_STAGE] = STAGE_STEP


@inline
def step(ctx, p, walls):
    """One accepted step from PH_TAU, and the first end within it (PH_END_T, PH_END_I,
    PH_END_Y; PH_END_I = -1 when the phase goes on)."""
    tau, limit = ctx[PH_TAU], ctx[PH_LIMIT]
    h = pmin(pmin(ctx[PH_H], limit - tau), ctx[PH_HMAX])
    ny = n_y(ctx)
    rtol = ctx[PH_RTOL]
    err = 0.0
    accepted = False
    for _ in range(60):
        for i in range(1, 6):
            row = i * (i - 1) // 2
            for j in range(ny):
                acc = 0.0
                for q in range(i):
                    acc += A[row + q] * ctx[PH_KS + 3 * q + j]
                ctx[PH_YI + j] = ctx[PH_Y + j] + h * acc
            rhs(ctx, p, walls, tau + C[i] * h, PH_YI, PH_KS + 3 * i)
        for j in range(ny):
            acc = 0.0
            for q in range(6):
                acc += B[q] * ctx[PH_KS + 3 * q + j]
            ctx[PH_YB + j] = ctx[PH_Y + j] + h * acc
        rhs(ctx, p, walls, tau + h, PH_YB, PH_KS + 18)
        err = 0.0
        for j in range(ny):
            acc = 0.0
            for q in range(7):
                acc += E[q] * ctx[PH_KS + 3 * q + j]
            e = h * acc
            sc = ATOL[j] + rtol * pmax(abs(ctx[PH_Y + j]), abs(ctx[PH_YB + j]))
            err = pmax(err, abs(e) / sc)
        if err <= 1.0:
            accepted = True
            break
        h *= pmax(0.2, 0.9 * err**-0.2)
    if not accepted:
        ctx[EN_STOP] = E_PHASE_STEPS
        raise KernelError(E_PHASE_STEPS)
    ctx[PH_STEPS] += 1.0
    ctx[PH_H] = h
    ctx[PH_ERR] = err
    ctx[PH_TA] = tau
    ctx[PH_HSTEP] = h
    t_b = tau + h
    ctx[PH_TB] = t_b
    conditions(ctx, p, walls, t_b, PH_YB, PH_CNEW)
    end_t, end_i = t_b, -1
    for i in range(n_conditions(ctx)):
        a, b = ctx[PH_CPREV + i], ctx[PH_CNEW + i]
        t_root = -1.0
        if i >= 4 and b < -CONTACT_GAP and (a < 0.0 or (tau == 0.0 and a <= CONTACT_GAP)):
            # another wall touched at the start (the wedge's vertex: its gap is 0 to
            # rounding, either sign) and then entered
            t_root = touched_root(ctx, p, walls, i, tau, t_b, a)
        elif (a > 0.0 and 0.0 >= b) or (a == 0.0 and b < 0.0):
            t_root = first_root(ctx, p, walls, i, tau, t_b, a)
        elif i == 0 and tau == 0.0 and a < 0.0:
            # no normal force from the start: a phase begun where another one's end met
            # the lift-off (rolling's friction limit mu_s N - |F| reaches zero with N
            # where F = 0, and its root, an ulp earlier, left N just below zero) lifts
            # off at once; else the wall would hold the ball with N < 0
            t_root = tau
        if t_root >= 0.0 and (end_i < 0 or t_root < end_t):
            end_t, end_i = t_root, i
    ctx[PH_END_T] = end_t
    ctx[PH_END_I] = float(end_i)
    if end_i >= 0:
        dense(ctx, end_t, PH_END_Y)
    else:
        for j in range(ny):
            ctx[PH_END_Y + j] = ctx[PH_YB + j]
    ctx[PH_STAGE] = STAGE_EMIT


@inline
def accept(ctx):
    """Go on from the end of the last step: a new step proposal, the rest bookkeeping,
    and the skip of whole drive periods at rest (or the stop of a run without a time
    limit: at rest for good)."""
    tau = ctx[PH_TB]
    ctx[PH_TAU] = tau
    for j in range(3):
        ctx[PH_Y + j] = ctx[PH_YB + j]
        ctx[PH_KS + j] = ctx[PH_KS + 18 + j]
    for i in range(n_conditions(ctx)):
        ctx[PH_CPREV + i] = ctx[PH_CNEW + i]
    err = ctx[PH_ERR]
    factor = 5.0 if err == 0.0 else pmin(5.0, pmax(0.2, 0.9 * err**-0.2))
    ctx[PH_H] *= factor
    if not at_rest(ctx, PH_KS):
        ctx[PH_RSINCE] = math.inf
    elif ctx[PH_RSINCE] == math.inf:
        ctx[PH_RSINCE] = tau
    limit, span = ctx[PH_LIMIT], ctx[PH_RSPAN]
    steady = ctx[PH_STEPS] > 4.0 and tau - ctx[PH_RSINCE] >= span
    ctx[PH_STAGE] = STAGE_STEP
    if math.isinf(limit) and steady:
        # at rest relative to the boundary, with every condition kept, for a whole drive
        # period (or, on a static boundary, a few steps): the drive is periodic, so this
        # repeats for ever
        ctx[EN_STOP] = E_AT_REST
        raise KernelError(E_AT_REST)
    if span > 0.0 and steady:
        # the same argument with a time limit: whole drive periods repeat the one just
        # simulated exactly, so they are skipped (samples at the rest state)
        whole = (limit - tau) / span
        whole -= whole % 1.0  # math.floor, as a float (whole >= 0)
        if whole < 1.0:
            ctx[PH_RSINCE] = tau
            return
        ctx[PH_TAU] = tau + whole * span
        ctx[PH_STAGE] = STAGE_SKIP


@inline
def hand_out(ctx, t, y):
    """A sample at t of the state ctx[y:y + 3]."""
    ctx[PH_SAMPLE_T] = t
    for j in range(3):
        ctx[PH_SAMPLE_Y + j] = ctx[y + j]
    return PHASE_SAMPLE


@inline
def advance(ctx, p, walls):
    """Run the phase begun by :func:`begin` to its end (``PHASE_END``), its time limit
    (``PHASE_LIMIT``), the next sample time PH_NEXT (``PHASE_SAMPLE``: the caller
    reports it, sets PH_NEXT to the following one and calls again) or a pause between
    two steps (``PHASE_PAUSE``, after PH_PAUSE steps or at PH_PAUSE_T: the caller moves
    PH_PAUSE on and calls again, or ends the phase where it is, at PH_TAU with PH_Y).

    Raises:
        KernelError: ``E_PHASE_STEPS`` (60 rejected steps), ``E_AT_REST`` (no time
            limit and at rest relative to the boundary from PH_RSINCE), or a surface's
            ``E_INVERSION``.
    """
    while True:
        stage = ctx[PH_STAGE]
        if stage == STAGE_EMIT:
            ts = ctx[PH_NEXT]
            if ts <= ctx[PH_END_T]:
                if ts > ctx[PH_TA]:
                    dense(ctx, ts, PH_YD)
                    return hand_out(ctx, ts, PH_YD)
                return hand_out(ctx, ts, PH_Y)
            if ctx[PH_END_I] >= 0.0:
                return PHASE_END
            accept(ctx)
        elif stage == STAGE_SKIP:
            ts = ctx[PH_NEXT]
            if ts <= ctx[PH_TAU]:
                return hand_out(ctx, ts, PH_Y)
            ctx[PH_RSINCE] = ctx[PH_TAU]
            ctx[PH_STAGE] = STAGE_STEP
        elif ctx[PH_TAU] < ctx[PH_LIMIT]:
            if ctx[PH_STEPS] >= ctx[PH_PAUSE] or ctx[PH_TAU] >= ctx[PH_PAUSE_T]:
                # between two steps: nothing of the integration is touched
                return PHASE_PAUSE
            step(ctx, p, walls)
        else:
            return PHASE_LIMIT


@jit
def run_phase(ctx, p, walls, start):
    """:func:`begin` (when ``start``) and :func:`advance` as one compiled function: the
    entry :class:`billiard.models.contact.ContactModel` calls, once per phase and once
    per sample, when the kernels are compiled."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx, p = borrow(ctx), borrow(p)
    if start:
        begin(ctx, p, walls)
    return advance(ctx, p, walls)
