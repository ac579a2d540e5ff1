"""Many trajectories at once: the impacts model (``contact.model = "impacts"``, method
``event``) advanced for a batch of trajectories, one state vector ``ctx`` each, and
measured on the way, with nothing per impact leaving the kernel.

Each trajectory runs :func:`billiard.kernels.loop.step`, the step under ``billiard
run``, over its own row of ``ctxs`` and ``params``: the same operations in the same
order, so a trajectory of the batch makes, bit for bit, the impacts a run of the same
scene makes (on the CPU). Under ``contact.model = "phases"`` (method ``event``) a
trajectory runs the state machine under such a run instead
(:func:`billiard.kernels.machine.run_machine`), called as
:meth:`billiard.engine.driver.Driver.run` calls it, chunk after
chunk (:func:`run_batch_phases`), and ends as that run ends: at rest, in contact, at its
time limit or stopped. :func:`run_batch` runs a range of trajectories without the
GIL, so that threads on disjoint ranges use all cores (:mod:`billiard.engine.ensemble`;
numba's ``prange`` cannot take the tuple of first-class wall functions into its
parallel region, and a range returns control often enough for Ctrl-C); the CUDA twin
of these files launches :func:`measure` once per GPU thread (:mod:`billiard.engine.gpu`).

What is kept per trajectory (``stats``, slots ``ST_*``): how the run ended, the impacts
simulated and measured (those after ``transient``), running means and sums of squared
deviations of the impact height q2 and the time of flight (Welford's update), the
highest impact, the low-velocity-rule and lid impacts, the period of the post-impact
state and the time one period takes. ``ring`` holds the last ``ring.shape[0]`` measured
impacts' (t, q1, q2, v1, v2, omega, tof) (``R_*``; impact m of the measured ones in
slot m % width), from which the period is found and the last K heights and times of
flight are read (:func:`tail`: on the GPU on the device, so that a trajectory's ring
never leaves it).

The period test is :func:`billiard.sweep.attractor.find_period`'s, with the same
arithmetic: the smallest k <= ``max_period`` (and <= half the window) for which the last
``window`` scaled states (q1, q2, T v1, T v2, T r omega) and drive-time offsets repeat
every k impacts within ``tolerance`` (m), T = sqrt(L / g), L = 1 cm.
"""

from __future__ import annotations

import math

import numpy as np

from .decorators import borrow, inline, jit
from .layout import (
    CCOL,
    E_AT_REST,
    EN_CLOCK,
    EN_CLOCK_ERR,
    EN_FAULT,
    EN_IMPACTS,
    EN_Q1,
    EN_Q2,
    EN_Q3,
    EN_RCOUNT,
    EN_RHEAD,
    EN_STOP,
    EN_T,
    EN_TARGET,
    EN_THETA,
    EN_U1,
    EN_U2,
    EN_U3,
    EN_ZERO,
    IN_CONTACT,
    LID_LABEL,
    MC_CROW,
    MC_MODE,
    MC_ROW,
    NCOL,
    PAUSED,
    S_SLOPE,
    S_SLOPE_AT,
    SCOL,
    SM_ROW,
    SURF,
    SURF_STRIDE,
    TIME_LIMIT,
)
from .loop import step
from .machine import run_machine
from .surfaces import gap_rate

#: stats slots: how the run ended (RUN_*), the stop's code (a KernelError code, 0 for an
#: arithmetic fault), impacts simulated, impacts measured ...
ST_STATUS = 0
ST_CODE = 1
ST_TOTAL = 2
ST_MEASURED = 3
#: ... running mean and sum of squared deviations of q2 (m, m^2), highest q2 (m) ...
ST_H_MEAN = 4
ST_H_M2 = 5
ST_H_MAX = 6
#: ... of the time of flight (s, s^2) ...
ST_TOF_MEAN = 7
ST_TOF_M2 = 8
#: ... impacts under the low-velocity rule, impacts on the lid ...
ST_ELASTIC = 9
ST_LID = 10
#: ... the period (impacts; 0: none) and the sum of its times of flight (s)
ST_PERIOD = 11
ST_PERIOD_TIME = 12
#: ... the ball's motion state when the run ended (MC_MODE: 0 flight, 1 roll, 2 slide,
#: 3 held; flight under the impacts model)
ST_MODE = 13
NSTAT = 14

#: ST_STATUS: the run reached its impacts, its duration (the next impact comes after
#: EN_UNTIL), stopped (a kernel stop, an arithmetic fault or an inelastic collapse), or
#: has not ended (a GPU thread that stopped in a kernel stop leaves this); under
#: contact phases also: the ball came to rest relative to the boundary for good
#: (``Status.AT_REST``), or stayed in contact for the contact span (``IN_CONTACT``)
RUN_COMPLETE = 0.0
RUN_TIME_LIMIT = 1.0
RUN_FAILED = 2.0
RUN_AT_REST = 3.0
RUN_IN_CONTACT = 4.0
RUN_PENDING = -1.0

#: ring columns
R_T = 0
R_Q1 = 1
R_Q2 = 2
R_V1 = 3
R_V2 = 4
R_OMEGA = 5
R_TOF = 6
RCOL = 7

#: consts slots, per trajectory: drive frequency (Hz) and phase (rad), ball radius (m),
#: gravity (m/s^2) of its scene, the period test's tolerance (m), longest period
#: (impacts) and window (impacts)
C_FREQUENCY = 0
C_PHASE = 1
C_RADIUS = 2
C_GRAVITY = 3
C_TOLERANCE = 4
C_MAX_PERIOD = 5
C_WINDOW = 6
NCONST = 7

#: the period test's length scale L (m)
_L = 0.01


@inline
def record(row, ring, stats):
    """Add the impact ``row`` (one row of :func:`step`) to the measurements."""
    m = int(stats[ST_MEASURED])
    count = m + 1.0
    q2 = row[3]
    tof = row[9]
    delta = q2 - stats[ST_H_MEAN]
    stats[ST_H_MEAN] += delta / count
    stats[ST_H_M2] += delta * (q2 - stats[ST_H_MEAN])
    if m == 0 or q2 > stats[ST_H_MAX]:
        stats[ST_H_MAX] = q2
    delta = tof - stats[ST_TOF_MEAN]
    stats[ST_TOF_MEAN] += delta / count
    stats[ST_TOF_M2] += delta * (tof - stats[ST_TOF_MEAN])
    if row[10] == 2.0:  # regime: elastic (the low-velocity rule)
        stats[ST_ELASTIC] += 1.0
    if row[13] == LID_LABEL:
        stats[ST_LID] += 1.0
    slot = m % ring.shape[0]
    ring[slot, R_T] = row[1]
    ring[slot, R_Q1] = row[2]
    ring[slot, R_Q2] = q2
    ring[slot, R_V1] = row[4]
    ring[slot, R_V2] = row[5]
    ring[slot, R_OMEGA] = row[6]
    ring[slot, R_TOF] = tof
    stats[ST_MEASURED] = count


@inline
def drive_offset(t, frequency, phase, scale):
    """The time offset of t within the drive period, scaled to metres (``scale`` = L / T),
    as :func:`billiard.sweep.attractor.scaled_states` computes it."""
    period = 1.0 / frequency
    cycles = t * frequency + phase / (2.0 * math.pi)
    return (cycles - math.floor(cycles)) * period * scale


@inline
def repeats(ring, first, count, k, consts):
    """Do the ``count`` measured states from ``first`` on repeat every k impacts within
    the tolerance (states and drive phase)?"""
    width = ring.shape[0]
    tolerance = consts[C_TOLERANCE]
    big_t = math.sqrt(_L / consts[C_GRAVITY])
    rim = big_t * consts[C_RADIUS]
    frequency = consts[C_FREQUENCY]
    driven = frequency > 0.0
    scale = _L / big_t
    cycle = 0.0
    if driven:
        cycle = (1.0 / frequency) * scale
    for i in range(count - k):
        a = (first + i) % width
        b = (first + i + k) % width
        if abs(ring[b, R_Q1] - ring[a, R_Q1]) > tolerance:
            return False
        if abs(ring[b, R_Q2] - ring[a, R_Q2]) > tolerance:
            return False
        if abs(big_t * ring[b, R_V1] - big_t * ring[a, R_V1]) > tolerance:
            return False
        if abs(big_t * ring[b, R_V2] - big_t * ring[a, R_V2]) > tolerance:
            return False
        if abs(rim * ring[b, R_OMEGA] - rim * ring[a, R_OMEGA]) > tolerance:
            return False
        if driven:
            phase = consts[C_PHASE]
            oa = drive_offset(ring[a, R_T], frequency, phase, scale)
            ob = drive_offset(ring[b, R_T], frequency, phase, scale)
            d = abs(ob - oa)
            if min(d, cycle - d) > tolerance:
                return False
    return True


@inline
def find_period(ring, stats, consts):
    """Set ST_PERIOD (0: none) and ST_PERIOD_TIME from the ring."""
    measured = int(stats[ST_MEASURED])
    width = ring.shape[0]
    count = min(int(consts[C_WINDOW]), measured, width)
    first = measured - count
    stats[ST_PERIOD] = 0.0
    stats[ST_PERIOD_TIME] = 0.0
    for k in range(1, min(int(consts[C_MAX_PERIOD]), count // 2) + 1):
        if repeats(ring, first, count, k, consts):
            stats[ST_PERIOD] = k
            total = 0.0
            for i in range(measured - k, measured):
                total += ring[i % width, R_TOF]
            stats[ST_PERIOD_TIME] = total
            return


@inline
def measure(ctx, p, walls, row, ring, stats, consts, transient, total, target):
    """Advance one trajectory towards ``total`` impacts (or its EN_UNTIL), measuring
    those after ``transient``, and pause at impact ``target`` (< ``total``) with
    ST_STATUS still RUN_PENDING: a later call goes on from there, so a long run is made
    in rounds. ``row`` is scratch for one impact's row (NCOL floats); ``stats`` starts
    as zeros with ST_STATUS = RUN_PENDING, and a trajectory that has ended is left as it
    is. A kernel stop raises out of here with ST_STATUS left at RUN_PENDING."""
    if stats[ST_STATUS] != RUN_PENDING:
        return
    if ctx[EN_STOP] != 0.0:
        # a stop in an earlier call that nothing caught (a GPU thread just ends there):
        # the run failed then, and is not stepped on from its stopped state
        settle(ctx, stats)
        return
    stop = min(total, target)
    while ctx[EN_IMPACTS] < stop:
        if not step(ctx, p, walls, row, 0):
            find_period(ring, stats, consts)
            stats[ST_STATUS] = RUN_TIME_LIMIT
            return
        stats[ST_TOTAL] = ctx[EN_IMPACTS]
        if ctx[EN_IMPACTS] > transient:
            record(row, ring, stats)
        if ctx[EN_FAULT] != 0.0:
            # an inelastic collapse: the engine stops the run after this impact
            stats[ST_STATUS] = RUN_FAILED
            return
    finish(ctx, ring, stats, consts, total)


@inline
def finish(ctx, ring, stats, consts, total):
    """A trajectory that made its ``total`` impacts: its period found, complete."""
    if ctx[EN_IMPACTS] >= total:
        find_period(ring, stats, consts)
        stats[ST_STATUS] = RUN_COMPLETE


@inline
def settle(ctx, stats):
    """A trajectory that a kernel stop ended, ST_STATUS still RUN_PENDING: RUN_FAILED,
    ST_CODE the stop's code from ``ctx[EN_STOP]`` (0 for an arithmetic fault). Called
    where the CPU catches the stop, by :func:`measure` for a stop that nothing caught (a
    GPU thread just ends there), and on the GPU after a batch's last launch
    (:func:`billiard.engine.gpu.reduce_kernel`), so that no state vector leaves the
    device for its code."""
    if stats[ST_STATUS] == RUN_PENDING:
        stats[ST_STATUS] = RUN_FAILED
        stats[ST_CODE] = ctx[EN_STOP]


@jit
def measure_guarded(ctx, p, walls, row, ring, stats, consts, transient, total, target):
    """:func:`measure`, a kernel stop or arithmetic fault caught: ST_STATUS RUN_FAILED,
    ST_CODE the stop's code (0 for an arithmetic fault)."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx, p, row, ring, stats = borrow(ctx), borrow(p), borrow(row), borrow(ring), borrow(stats)
    consts = borrow(consts)
    try:
        measure(ctx, p, walls, row, ring, stats, consts, transient, total, target)
    except Exception:  # noqa: BLE001 - numba catches any exception or none
        settle(ctx, stats)


@inline
def tail(ring, stats, heights, tofs):
    """The last ``heights.shape[0]`` measured impact heights (m) and times of flight
    (s) of one trajectory, read from its ring into ``heights`` and ``tofs``, oldest
    first, NaN before its first measured impact (fewer measured than kept). The one
    reading of a ring's tail: :func:`tails` on the CPU, the GPU's reduction on the
    device."""
    keep = heights.shape[0]
    width = ring.shape[0]
    measured = int(stats[ST_MEASURED])
    for j in range(keep):
        m = measured - keep + j
        if m >= 0:
            slot = m % width
            heights[j] = ring[slot, R_Q2]
            tofs[j] = ring[slot, R_TOF]
        else:
            heights[j] = math.nan
            tofs[j] = math.nan


@jit
def tails(rings, stats, heights, tofs):
    """:func:`tail` of every trajectory i (``rings[i]``, ``stats[i]``) into
    ``heights[i]`` and ``tofs[i]`` (n x keep each)."""
    for i in range(rings.shape[0]):
        tail(rings[i], stats[i], heights[i], tofs[i])


@jit
def run_batch(ctxs, params, walls, rows, rings, stats, consts, transient, total, target, lo, hi):
    """:func:`measure` up to impact ``target`` for trajectories lo <= i < hi
    (``ctxs[i]``, ``params[i]``, scratch ``rows[i]``, ``rings[i]``, ``stats[i]``,
    ``consts[i]``). Compiled without the GIL: threads calling it on disjoint ranges run
    on all cores."""
    for i in range(lo, hi):
        measure_guarded(
            ctxs[i], params[i], walls, rows[i], rings[i], stats[i], consts[i], transient, total,
            target,
        )  # fmt: skip


#: impact and contact rows of one call of the state machine: scratch that the
#: trajectories of a range share, one after another (their rows are measured, then
#: dropped). Any size gives the same trajectories: a call returns FULL between events.
MACHINE_ROWS = 64
MACHINE_CONTACTS = 64


@inline
def machine_call(ctx, p, walls, nears, out, cout, sout):
    """One call of the state machine up to impact ``ctx[EN_TARGET]``, its impact rows
    into ``out`` and its contact rows into ``cout`` from their starts (no samples:
    ``sout`` is never written, the trajectory's ctx stands for the sample flight's):
    the one place the batch spells :func:`~billiard.kernels.machine.run_machine`'s
    arguments. Returns its status."""
    ctx[MC_ROW] = 0.0
    ctx[MC_CROW] = 0.0
    ctx[SM_ROW] = 0.0
    return run_machine(ctx, p, walls, nears, out, out.size // NCOL, cout, cout.size // CCOL,
                       ctx, sout, 0)  # fmt: skip


@jit
def machine_guarded(ctx, p, walls, nears, out, cout, sout):
    """:func:`machine_call`, a kernel stop or arithmetic fault caught: -1 (the stop's
    code in EN_STOP; 0 for an arithmetic fault)."""
    code = -1
    try:
        code = machine_call(ctx, p, walls, nears, out, cout, sout)
    except Exception:  # noqa: BLE001 - numba catches any exception or none
        code = -1
    return code


@inline
def measure_phases(
    ctx, p, walls, nears, out, cout, sout, ring, stats, consts, transient, total, target
):
    """:func:`measure` on the state machine, the loop of
    :meth:`~billiard.engine.driver.Driver.run` (a collapse detected
    after an impact stops the run; a paused phase goes on), each impact measured as it
    comes. A ball at rest for good ends RUN_AT_REST, one in contact for the contact
    span RUN_IN_CONTACT (neither with a period), another kernel stop RUN_FAILED (its
    code in ST_CODE); ST_MODE follows the motion state."""
    if stats[ST_STATUS] != RUN_PENDING:
        return
    stop = min(total, target)
    while ctx[EN_IMPACTS] < stop:
        if ctx[EN_FAULT] != 0.0:
            stats[ST_STATUS] = RUN_FAILED
            return
        before = int(ctx[EN_IMPACTS])
        ctx[EN_TARGET] = stop
        code = machine_guarded(ctx, p, walls, nears, out, cout, sout)
        # the rows written, a stop's included (a run hands them out before its stop)
        for r in range(int(ctx[EN_IMPACTS]) - before):
            n = before + r + 1
            stats[ST_TOTAL] = n
            if n > transient:
                record(out[r * NCOL :], ring, stats)
        stats[ST_MODE] = ctx[MC_MODE]
        if code < 0:
            if ctx[EN_STOP] == E_AT_REST:
                stats[ST_STATUS] = RUN_AT_REST
            else:
                stats[ST_STATUS] = RUN_FAILED
                stats[ST_CODE] = ctx[EN_STOP]
            return
        if code == TIME_LIMIT:
            find_period(ring, stats, consts)
            stats[ST_STATUS] = RUN_TIME_LIMIT
            return
        if code == IN_CONTACT:
            stats[ST_STATUS] = RUN_IN_CONTACT
            return
        if code != PAUSED and ctx[EN_FAULT] != 0.0:
            # an inelastic collapse, or contact phases of zero duration piled up
            stats[ST_STATUS] = RUN_FAILED
            return
    finish(ctx, ring, stats, consts, total)


@jit
def run_batch_phases(
    ctxs, params, walls, nears, rings, stats, consts, transient, total, target, lo, hi
):
    """:func:`run_batch` for trajectories of a contact-phases scene, on the state
    machine (``walls``: the curve's wall functions and their first three derivatives,
    ``nears`` the walls' nearest-point functions); the rows of each call go through
    scratch made here, once per range. Compiled without the GIL."""
    out = np.empty(MACHINE_ROWS * NCOL)
    cout = np.empty(MACHINE_CONTACTS * CCOL)
    sout = np.empty(SCOL)
    for i in range(lo, hi):
        measure_phases(
            ctxs[i], params[i], walls, nears, out, cout, sout, rings[i], stats[i], consts[i],
            transient, total, target,
        )  # fmt: skip


@jit
def run_rows(ctx, p, walls, out, total):
    """Every impact of one trajectory up to ``total`` (or its EN_UNTIL) as rows of
    ``out`` (``total * NCOL`` floats), the loop of :func:`measure` without the
    measurements: the records a run makes. Returns the rows written; a kernel stop
    raises."""
    # the caller owns the arrays throughout: no reference counting inside
    ctx, p, out = borrow(ctx), borrow(p), borrow(out)
    row = 0
    while ctx[EN_IMPACTS] < total:
        if not step(ctx, p, walls, out[row * NCOL :], 0):
            break
        row += 1
        if ctx[EN_FAULT] != 0.0:
            break
    return row


@jit
def start(ctx, p, walls, template, ball, px, py, offsets):
    """``ctx`` := ``template`` with the ball ``ball`` = (t, theta, q1, q2, u1, u2, u3)
    and a fresh event count (``billiard.engine.ctx.write_ball``), its warm starts then
    moved by the check of the start position the engine's set-up makes (the gap of each
    of the first ``offsets`` surfaces at the centre (px, py), relative to the boundary,
    at rest). Returns the smallest of those gaps (m; NaN when one cannot be computed)."""
    for i in range(template.shape[0]):
        ctx[i] = template[i]
    ctx[EN_T] = ball[0]
    ctx[EN_THETA] = ball[1]
    ctx[EN_Q1] = ball[2]
    ctx[EN_Q2] = ball[3]
    ctx[EN_U1] = ball[4]
    ctx[EN_U2] = ball[5]
    ctx[EN_U3] = ball[6]
    ctx[EN_Q3] = 0.0
    ctx[EN_IMPACTS] = 0.0
    ctx[EN_CLOCK] = ball[0]
    ctx[EN_CLOCK_ERR] = 0.0
    ctx[EN_ZERO] = 0.0
    ctx[EN_RCOUNT] = 0.0
    ctx[EN_RHEAD] = 0.0
    ctx[EN_FAULT] = 0.0
    worst = math.inf
    try:
        for j in range(offsets):
            gap, _ = gap_rate(ctx, p, walls, j, px, py, 0.0, 0.0)
            worst = min(worst, gap)
    except Exception:  # noqa: BLE001 - numba catches any exception or none
        return math.nan
    # the set-up checks on the surfaces' own state vectors: their slope memos stay
    # there (a memo is the value f' would return: it changes no result, only the slots)
    for j in range(offsets):
        base = SURF + j * SURF_STRIDE
        ctx[base + S_SLOPE_AT] = template[base + S_SLOPE_AT]
        ctx[base + S_SLOPE] = template[base + S_SLOPE]
    return worst


@jit
def start_batch(ctxs, params, walls, template, balls, px, py, offsets, gaps):
    """:func:`start` for every trajectory i, its smallest gap into ``gaps[i]``."""
    for i in range(ctxs.shape[0]):
        gaps[i] = start(ctxs[i], params[i], walls, template, balls[i], px[i], py[i], offsets)
