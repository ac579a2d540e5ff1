"""Trajectory samples (``billiard run --sample DT``): rows of :data:`~.layout.SCOL` floats
(t, q1, q2, u1, u2, u3, energy, motion code) at the times t0 + k dt, written by the state
machine (:mod:`billiard.kernels.machine`) into its sample buffer ``sout``.

A flight's samples come from a second flight state, the sample ctx ``sctx`` (the
flight model's constants, its own step proposal), restarted at the flight's start
(``SM_BALL``) and advanced to each sample time: the flight model's closed form, or its
integrator with steps of its own, so that a sample never changes the flight the impact
search integrates. They are written when the flight ends (an impact, a contact without
impulse, the run's time limit or an escape), up to its end. An emission that fills the
buffer stays pending (``SM_PENDING``) and goes on at the next call.

A sample's count ``SM_K`` is engine state (checkpoints carry it): the k of the next
sample is SM_K, and sample k lies at ``SM_T0 + k * SM_DT``.
"""

from __future__ import annotations

from . import fixed_step, flight
from .ball import energy
from .decorators import inline, jit
from .layout import (
    FL_KIND,
    FL_U3,
    FLIGHT_RK4,
    IM_K,
    IM_M,
    IM_R,
    M_FLIGHT,
    RK_H,
    SCOL,
    SF_TA,
    SF_TB,
    SF_YA,
    SF_YB,
    SM_BALL,
    SM_DT,
    SM_FROM,
    SM_K,
    SM_PENDING,
    SM_REACHED,
    SM_ROW,
    SM_T0,
    SM_TO,
    SRC_FLIGHT,
    G,
)


@inline
def sample_time(ctx, k):
    """The time (s) of sample k."""
    return ctx[SM_T0] + k * ctx[SM_DT]


@inline
def write_sample(ctx, sout, t, q1, q2, u1, u2, u3, mode):
    """Sample row SM_ROW of ``sout``, its energy computed, and the count moved on."""
    o = int(ctx[SM_ROW]) * SCOL
    sout[o] = t
    sout[o + 1] = q1
    sout[o + 2] = q2
    sout[o + 3] = u1
    sout[o + 4] = u2
    sout[o + 5] = u3
    sout[o + 6] = energy(q2, u1, u2, u3, ctx[IM_M], ctx[IM_R], ctx[IM_K], ctx[G])
    sout[o + 7] = mode
    ctx[SM_ROW] += 1.0
    ctx[SM_K] += 1.0


# ---------------------------------------------------------------------- the sample flight


@inline
def flight_begin(sctx, q1, q2, u1, u2, u3):
    """Start the sample flight at tau = 0 (``FlightModel.begin``; the fixed-step RK4
    keeps its last step in the SF_* slots, as ``RK4Flight`` keeps it on the object)."""
    if sctx[FL_KIND] == FLIGHT_RK4:
        sctx[FL_U3] = u3
        sctx[SF_TA] = 0.0
        sctx[SF_TB] = 0.0
        sctx[SF_YA] = q1
        sctx[SF_YA + 1] = q2
        sctx[SF_YA + 2] = u1
        sctx[SF_YA + 3] = u2
        for i in range(4):
            sctx[SF_YB + i] = sctx[SF_YA + i]
        return
    flight.begin(sctx, q1, q2, u1, u2, u3)


@inline
def flight_advance(sctx, tau_a, tau_target):
    """One step of the sample flight from tau_a towards tau_target; returns its end."""
    if sctx[FL_KIND] != FLIGHT_RK4:
        return flight.advance(sctx, tau_a, tau_target)
    h = min(sctx[RK_H], tau_target - tau_a)
    sctx[SF_TA] = tau_a
    for i in range(4):
        sctx[SF_YA + i] = sctx[SF_YB + i]
    sctx[SF_TB] = tau_target if h == tau_target - tau_a else tau_a + h
    q1, q2, u1, u2 = fixed_step.rk4_step(
        sctx, sctx[SF_YA], sctx[SF_YA + 1], sctx[SF_YA + 2], sctx[SF_YA + 3], h
    )
    sctx[SF_YB] = q1
    sctx[SF_YB + 1] = q2
    sctx[SF_YB + 2] = u1
    sctx[SF_YB + 3] = u2
    return sctx[SF_TB]


@inline
def flight_state(sctx, tau):
    """(q1, q2, u1, u2) of the sample flight at tau (in its current step)."""
    if sctx[FL_KIND] != FLIGHT_RK4:
        return flight.state(sctx, tau)
    if tau == sctx[SF_TB]:
        return sctx[SF_YB], sctx[SF_YB + 1], sctx[SF_YB + 2], sctx[SF_YB + 3]
    return fixed_step.rk4_step(
        sctx, sctx[SF_YA], sctx[SF_YA + 1], sctx[SF_YA + 2], sctx[SF_YA + 3], tau - sctx[SF_TA]
    )


# ---------------------------------------------------------------------- a flight's samples


@inline
def save_flight_start(ctx, t, theta, q1, q2, u1, u2, u3):
    """The state a flight starts from (its samples restart the sample flight there)."""
    ctx[SM_BALL] = t
    ctx[SM_BALL + 1] = theta
    ctx[SM_BALL + 2] = q1
    ctx[SM_BALL + 3] = q2
    ctx[SM_BALL + 4] = u1
    ctx[SM_BALL + 5] = u2
    ctx[SM_BALL + 6] = u3


@jit
def start_flight_samples(ctx, sctx, t_to):
    """Make the samples of the flight from SM_BALL up to t_to (s) pending."""
    flight_begin(sctx, ctx[SM_BALL + 2], ctx[SM_BALL + 3], ctx[SM_BALL + 4], ctx[SM_BALL + 5],
                 ctx[SM_BALL + 6])  # fmt: skip
    ctx[SM_REACHED] = 0.0
    ctx[SM_FROM] = ctx[SM_BALL]
    ctx[SM_TO] = t_to
    ctx[SM_PENDING] = SRC_FLIGHT


#: :func:`next_emitted`: a sample to write, the emission done, the buffer full
EMIT = 0
EMITTED = 1
BUFFER_FULL = 2


@inline
def next_emitted(ctx, srows):
    """(EMIT, its time in s) for the pending emission's next sample in [SM_FROM, SM_TO]
    (those before SM_FROM skipped, counted); (EMITTED, t) when none is left (nothing
    pending then); (BUFFER_FULL, t) when the buffer has no room for it."""
    while True:
        ts = sample_time(ctx, ctx[SM_K])
        if ts > ctx[SM_TO]:
            ctx[SM_PENDING] = 0.0
            return EMITTED, ts
        if ts >= ctx[SM_FROM]:
            return (BUFFER_FULL if int(ctx[SM_ROW]) == srows else EMIT), ts
        ctx[SM_K] += 1.0


@jit
def flight_samples(ctx, sctx, sout, srows):
    """Write the pending flight samples in [SM_FROM, SM_TO] while the buffer has room:
    True when all are written (nothing pending), False when the buffer is full."""
    t_start, u3 = ctx[SM_BALL], ctx[SM_BALL + 6]
    while True:
        status, ts = next_emitted(ctx, srows)
        if status != EMIT:
            return status == EMITTED
        tau = ts - t_start
        if tau < 0.0:
            tau = 0.0
        reached = ctx[SM_REACHED]
        while reached < tau:
            reached = flight_advance(sctx, reached, tau)
        ctx[SM_REACHED] = reached
        q1, q2, u1, u2 = flight_state(sctx, tau)
        write_sample(ctx, sout, ts, q1, q2, u1, u2, u3, M_FLIGHT)
