"""A hold by two walls over the state vector: the ball in a vertex, its centre fixed in
the boundary's frame, only its spin u3 free (``contact.model = "phases"``).
:class:`billiard.models.hold.VertexHold` runs these functions interpreted; the physics is
described there.

The forces are exact functions of the drive angle: a release (a normal force falling
through zero) is located by Illinois regula falsi on them, to ``EVENT_TOL``, within
steps of at most 1/64 drive period; the spin integrates the kinetic friction by
Simpson's rule over each step (exact on a static boundary, where the forces are
constant and the spin stops at a known time). Without spin for a whole drive period
the hold repeats itself: whole periods are skipped (samples at the rest state), or,
without a time limit, the ball is at rest for good.

The hold's inputs and state live in the ``VX_*`` slots of ``ctx``, its constants in the
phase's (``PH_M`` .. ``PH_MUK``) and the drive's, so a hold is resumable: :func:`advance`
returns at every sample time (``PHASE_SAMPLE``) and goes on from there when called
again, and returns ``PHASE_END`` (a release) or ``PHASE_LIMIT`` when the hold is over.

Every operation is the one the hold's former Python performed, in the same order:
``min`` as Python evaluates it (:func:`~billiard.kernels.contact.pmin`), ``math.floor``
of the periods skipped as ``x - x % 1.0`` (a float, as numba's ``floor`` would be an
integer), and a root's far end evaluated before its near end is looked at (an
evaluation that raises raises here too).
"""

from __future__ import annotations

import math

from . import drive
from .contact import EVENT_TOL, pmin
from .decorators import borrow, inline, jit
from .illinois import narrow, secant_point
from .impact import CHATTER_TAIL, chatter_period
from .layout import (
    E_AT_REST,
    EN_STOP,
    OMEGA,
    PH_CLIN,
    PH_CQUAD,
    PH_G,
    PH_K,
    PH_M,
    PH_MUK,
    PH_R,
    PHASE_END,
    PHASE_LIMIT,
    PHASE_SAMPLE,
    STAGE_EMIT,
    STAGE_SKIP,
    STAGE_STEP,
    VX_END_T,
    VX_H,
    VX_KEEPS,
    VX_LIMIT,
    VX_NEXT,
    VX_RSINCE,
    VX_RSPAN,
    VX_SAMPLE_T,
    VX_SAMPLE_W,
    VX_SIGMA,
    VX_STAGE,
    VX_STOPS,
    VX_TAU,
    VX_THETA0,
    VX_W,
    VX_W_END,
    VX_ZA,
    VX_ZB,
    KernelError,
)

#: :data:`VX_KEEPS` of a step without a release
NO_RELEASE = -2.0


@inline
def sign(x):
    """0 for a zero x, else +-1 (the sign of the kinetic friction a spin x meets)."""
    return 0.0 if x == 0.0 else math.copysign(1.0, x)


@inline
def forces(ctx, za, zb, theta, sigma):
    """(N_a, N_b): the normal forces (N) of the two walls, tangent angles za and zb (rad)
    at their contact points, at drive angle theta, spin sign sigma; -inf for both when
    the walls are parallel (they cannot hold the ball together)."""
    vb1, vb2, ab1, ab2 = drive.boundary_motion(ctx, theta)
    m = ctx[PH_M]
    drag = ctx[PH_CLIN] + ctx[PH_CQUAD] * math.sqrt(vb1 * vb1 + vb2 * vb2)
    # the centre moves with the boundary: m a_b = m g + D + contact forces
    rx = m * ab1 + drag * vb1
    ry = m * (ab2 + ctx[PH_G]) + drag * vb2
    mu = ctx[PH_MUK] * sigma
    ca, sa, cb, sb = math.cos(za), math.sin(za), math.cos(zb), math.sin(zb)
    # columns: n - mu sigma t for each wall, n = (-sin z, cos z), t = (cos z, sin z)
    a11, a21 = -sa - mu * ca, ca - mu * sa
    a12, a22 = -sb - mu * cb, cb - mu * sb
    det = a11 * a22 - a12 * a21
    if det == 0.0:
        return -math.inf, -math.inf
    return (rx * a22 - ry * a12) / det, (a11 * ry - a21 * rx) / det


@inline
def holds(ctx, za, zb, theta, u3):
    """Do both walls press a ball with spin u3 (rad/s) at drive angle theta?"""
    n_a, n_b = forces(ctx, za, zb, theta, sign(u3))
    return n_a > 0.0 and n_b > 0.0


@inline
def spin_rate(ctx, n_a, n_b, sigma):
    """du3/dt (rad/s^2) from the kinetic friction of both walls."""
    return -ctx[PH_MUK] * sigma * (n_a + n_b) / (ctx[PH_K] * ctx[PH_M] * ctx[PH_R])


@inline
def held_spin(ctx, za, zb, theta, u3):
    """The spin (rad/s) with which both walls hold a ball arriving with spin u3 at drive
    angle theta, or NaN where they cannot hold it.

    Both walls press the ball with its spin's kinetic friction: it keeps u3. Where that
    friction would pull the ball off a wall (a normal force below zero) but the walls
    press a ball without spin, the spin is stopped by the same friction within
    t* = k m r |u3| / (mu_k (N_a + N_b)) (N of the spinless hold), during which the
    centre moves by about a t*^2, nothing a step resolves: when t* is at most
    ``CHATTER_TAIL`` of a drive period, the tolerance to which a chatter series is
    summed, the ball is held without spin (the spin's energy goes to friction, never
    energy created). Otherwise a ball rolling into a vertex with a sliver of spin meets
    one wall and the other again and again, each time at the spin-down's scale."""
    if holds(ctx, za, zb, theta, u3):
        return u3
    if u3 == 0.0 or ctx[PH_MUK] == 0.0:
        return math.nan
    n_a, n_b = forces(ctx, za, zb, theta, 0.0)
    if not (n_a > 0.0 and n_b > 0.0):
        return math.nan
    # the time the spinless hold's kinetic friction takes to stop the spin
    stop = abs(u3 / spin_rate(ctx, n_a, n_b, 1.0))
    if stop <= CHATTER_TAIL * chatter_period(ctx[OMEGA]):
        return 0.0
    return math.nan


@inline
def spin_decays(ctx, sigma):
    """Does kinetic friction slow the spin (a spin, and walls with friction)? Without
    friction the walls exert no torque: the spin stays as it is."""
    return sigma != 0.0 and ctx[PH_MUK] != 0.0


@inline
def normal(ctx, tau, sigma):
    """(N_a, N_b) of the hold tau seconds after its start."""
    return forces(ctx, ctx[VX_ZA], ctx[VX_ZB], ctx[VX_THETA0] + ctx[OMEGA] * tau, sigma)


@inline
def normal_i(ctx, tau, sigma, i):
    """The normal force of wall i (0 or 1) of the hold at tau."""
    n_a, n_b = normal(ctx, tau, sigma)
    return n_a if i == 0 else n_b


@inline
def rate(ctx, tau, sigma):
    """du3/dt at tau."""
    n_a, n_b = normal(ctx, tau, sigma)
    return spin_rate(ctx, n_a, n_b, sigma)


@inline
def spin_at(ctx, tau_a, w_a, tau, sigma):
    """The spin at tau from w_a at tau_a: Simpson's rule on [tau_a, tau]; a spin that
    would change sign has stopped."""
    if sigma == 0.0:
        return 0.0
    h = tau - tau_a
    mid = 0.5 * (tau_a + tau)
    w = w_a + h / 6.0 * (
        rate(ctx, tau_a, sigma) + 4.0 * rate(ctx, mid, sigma) + rate(ctx, tau, sigma)
    )
    return w if w * sigma > 0.0 else 0.0


@inline
def first_root(ctx, i, sigma, a, b, fa):
    """The first time in (a, b] where wall i's normal force, positive at a (or zero or
    below there: a is returned), reaches zero or below: Illinois regula falsi, to
    EVENT_TOL."""
    fb = normal_i(ctx, b, sigma, i)
    if fa <= 0.0:
        return a
    side = 0
    for _ in range(200):
        if b - a <= EVENT_TOL:
            break
        m = secant_point(a, b, fa, fb)
        fm = normal_i(ctx, m, sigma, i)
        a, b, fa, fb, side = narrow(a, b, fa, fb, m, fm, side)
    return b


@inline
def begin(ctx):
    """Start a hold at tau = 0 (constants, VX_ZA, VX_ZB, VX_THETA0, VX_LIMIT, the spin in
    VX_W and the first sample time VX_NEXT set): its step, sign and rest bookkeeping."""
    omega = ctx[OMEGA]
    static = drive.static(ctx)
    sigma = sign(ctx[VX_W])
    ctx[VX_SIGMA] = sigma
    ctx[VX_H] = math.inf if static else 2.0 * math.pi / abs(omega) / 64.0
    ctx[VX_TAU] = 0.0
    # at rest from the start without a spin, or with one that frictionless walls leave
    # as it is (no torque: it never stops, and nothing else changes)
    ctx[VX_RSINCE] = math.inf if spin_decays(ctx, sigma) else 0.0
    ctx[VX_RSPAN] = 0.0 if static else 2.0 * math.pi / abs(omega)
    ctx[VX_STAGE] = STAGE_STEP


@inline
def step(ctx):
    """One step from VX_TAU: its end (VX_END_T: the step's end, the time limit, when a
    static boundary stops the spin (VX_STOPS) or the first release, VX_KEEPS) and the
    spin there (VX_W_END)."""
    tau, w, sigma, limit = ctx[VX_TAU], ctx[VX_W], ctx[VX_SIGMA], ctx[VX_LIMIT]
    t_b = pmin(tau + ctx[VX_H], limit)
    stops = math.inf
    if spin_decays(ctx, sigma) and drive.static(ctx):
        # static boundary: constant forces, the spin stops at a known time
        stops = tau + abs(w / rate(ctx, tau, sigma))
        t_b = pmin(stops, limit)
    prev_a, prev_b = normal(ctx, tau, sigma)
    new_a, new_b = normal(ctx, t_b, sigma) if math.isfinite(t_b) else (prev_a, prev_b)
    end_t, keeps = t_b, NO_RELEASE
    for i in range(2):
        n_prev = prev_a if i == 0 else prev_b
        n_new = new_a if i == 0 else new_b
        if n_new <= 0.0 < n_prev or n_prev <= 0.0:
            t_i = first_root(ctx, i, sigma, tau, t_b, n_prev)
            if keeps == NO_RELEASE or t_i < end_t:
                end_t, keeps = t_i, float(1 - i)
            elif t_i == end_t:
                keeps = -1.0  # both walls release at once
    w_end = spin_at(ctx, tau, w, end_t, sigma) if math.isfinite(end_t) else w
    if end_t == stops:
        w_end = 0.0
    ctx[VX_STOPS] = stops
    ctx[VX_END_T] = end_t
    ctx[VX_KEEPS] = keeps
    ctx[VX_W_END] = w_end
    ctx[VX_STAGE] = STAGE_EMIT


@inline
def go_on(ctx):
    """After the samples of a step: end the hold (``PHASE_END``, ``PHASE_LIMIT``) or go
    on from the step's end (-1): from where the spin stopped, found by bisection when a
    shaken boundary stopped it within the step."""
    end_t = ctx[VX_END_T]
    if ctx[VX_KEEPS] != NO_RELEASE:
        return PHASE_END
    if end_t >= ctx[VX_LIMIT]:
        return PHASE_LIMIT
    ctx[VX_STAGE] = STAGE_STEP
    stops = ctx[VX_STOPS]
    if end_t == stops:
        ctx[VX_TAU], ctx[VX_W], ctx[VX_SIGMA], ctx[VX_RSINCE] = stops, 0.0, 0.0, stops
        return -1
    tau, w, sigma, w_end = ctx[VX_TAU], ctx[VX_W], ctx[VX_SIGMA], ctx[VX_W_END]
    if sigma != 0.0 and w_end == 0.0:
        # the spin stopped within this step: find when, then hold without friction
        lo, hi = tau, end_t
        for _ in range(200):
            if hi - lo <= 1e-13:
                break
            mid = 0.5 * (lo + hi)
            if spin_at(ctx, tau, w, mid, sigma) == 0.0:
                hi = mid
            else:
                lo = mid
        ctx[VX_TAU], ctx[VX_W], ctx[VX_SIGMA], ctx[VX_RSINCE] = hi, 0.0, 0.0, hi
        return -1
    ctx[VX_TAU], ctx[VX_W] = end_t, w_end
    return -1


@inline
def hand_out(ctx, t, w):
    """A sample at t of the spin w."""
    ctx[VX_SAMPLE_T] = t
    ctx[VX_SAMPLE_W] = w
    return PHASE_SAMPLE


@inline
def advance(ctx):
    """Run the hold begun by :func:`begin` to a release (``PHASE_END``), its time limit
    (``PHASE_LIMIT``) or the next sample time VX_NEXT (``PHASE_SAMPLE``: the caller
    reports it, sets VX_NEXT to the following one and calls again).

    Raises:
        KernelError: ``E_AT_REST``: no time limit, and no spin for a drive period (on
            a static boundary: at once) from VX_RSINCE.
    """
    while True:
        stage = ctx[VX_STAGE]
        if stage == STAGE_EMIT:
            ts = ctx[VX_NEXT]
            if ts <= ctx[VX_END_T]:
                w = spin_at(ctx, ctx[VX_TAU], ctx[VX_W], ts, ctx[VX_SIGMA])
                return hand_out(ctx, ts, w)
            status = go_on(ctx)
            if status >= 0:
                return status
        elif stage == STAGE_SKIP:
            ts = ctx[VX_NEXT]
            if ts <= ctx[VX_TAU]:
                # the spin while at rest: none, or a frictionless hold's, unchanged
                return hand_out(ctx, ts, 0.0 if ctx[VX_SIGMA] == 0.0 else ctx[VX_W])
            ctx[VX_RSINCE] = ctx[VX_TAU]
            step(ctx)
        else:
            tau, limit = ctx[VX_TAU], ctx[VX_LIMIT]
            since, span = ctx[VX_RSINCE], ctx[VX_RSPAN]
            if math.isinf(limit) and tau - since >= span:
                ctx[EN_STOP] = E_AT_REST
                raise KernelError(E_AT_REST)
            if span > 0.0 and tau - since >= span:
                # at rest through a whole period: the next ones repeat it exactly
                whole = (limit - tau) / span
                whole -= whole % 1.0  # math.floor, as a float
                if whole < 1.0:
                    ctx[VX_RSINCE] = tau
                else:
                    ctx[VX_TAU] = tau + whole * span
                    ctx[VX_STAGE] = STAGE_SKIP
                    continue
            step(ctx)


@jit
def run_hold(ctx, start):
    """:func:`begin` (when ``start``) and :func:`advance` as one compiled function: the
    entry :class:`billiard.models.hold.VertexHold` calls, once per hold and once per sample,
    when the kernels are compiled."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx = borrow(ctx)
    if start:
        begin(ctx)
    return advance(ctx)
