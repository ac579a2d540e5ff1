"""Which attractor a trajectory has reached, from its post-transient impacts.

Period. A driven billiard's state is the ball's state and the drive's phase, so an orbit
is periodic with period k when the post-impact state *and the drive phase* repeat every
k impacts. The period counts impacts per repetition of the whole state. The parabola's
"period-one orbit" of the paper hits the left and the right side alternately, once per
half drive period: its heights and times of flight repeat at every impact, but the state
repeats only after two impacts (one drive period). Here it has period 2, one drive
period (``drive_periods = 1``).

Two post-impact states count as the same when every entry of the scaled state

    (q1, q2, T v1, T v2, T r omega, (L / T) dt_drive)

differs by less than the tolerance (m): positions in metres, velocities and the spin's
rim speed times T = sqrt(L / g) (the free-fall time over L = 1 cm, 32 ms), and the drive
phase as the time offset dt_drive within the drive period (s) times L / T. The default
tolerance 1e-5 m is 10 µm in position, 0.3 mm/s in speed and 32 µs in drive time. The
test runs over the last ``window`` post-transient impacts (default 256), for periods
1 ... ``max_period`` (at most half the window).

Classes, decided in this order:

``failed``
    the run stopped early (``Result.stop_reason``).
``resting``
    the run ended because the ball rests on the boundary, moving with it
    (``Status.AT_REST``, under ``contact.model = "phases"``); or the ball never rises
    more than ``rest_band`` (default 1 cm, about three ball diameters) above its resting
    height and at least half its impacts are under the low-velocity rule: it chatters at
    the bottom (the impacts model's relaunches of a resting ball).
``rolling`` / ``sliding`` / ``held``
    under ``contact.model = "phases"``: the ball stays in contact with the boundary
    without impacts, rolling, sliding or held by two walls (the wedge's vertex): the run
    ended so (``Status.IN_CONTACT``), or reached its duration in that contact motion with
    no impact after the transient (``Result.final_mode``).
``periodic``
    a period k was found.
``chaotic`` / ``quasi-periodic``
    no period: with a Lyapunov exponent (``--lyapunov``) above ``chaos_threshold``
    (0.01 per impact) chaotic, otherwise quasi-periodic (which also takes periods longer
    than ``max_period`` and transients longer than the sweep's).
``aperiodic``
    no period and no exponent asked for.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = [
    "CLASSES",
    "CONTACT_CLASSES",
    "PERIOD_WINDOW",
    "classify",
    "contact_class",
    "find_period",
]

#: Attractor classes, in the order of their codes in the result file (new ones are added
#: at the end, so that a class keeps its code).
CLASSES = (
    "failed",
    "resting",
    "periodic",
    "quasi-periodic",
    "chaotic",
    "aperiodic",
    "invalid",
    "rolling",
    "sliding",
    "held",
)
#: ``Result.final_mode`` of a ball in contact -> its class.
CONTACT_CLASSES = {"roll": "rolling", "slide": "sliding", "held": "held"}

_L = 0.01  # m
#: post-transient impacts the period test looks at (the last ones)
PERIOD_WINDOW = 256


def scaled_states(
    columns: Mapping[str, np.ndarray], frequency: float, phase: float, radius: float, g: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """The scaled post-impact states (n x 5, m), the drive-time offsets within the drive
    period (n, s) scaled to metres, and the drive period's scaled length (m; 0 when the
    boundary is not driven)."""
    big_t = math.sqrt(_L / g)
    states = np.column_stack(
        [
            columns["q1"],
            columns["q2"],
            big_t * columns["v1"],
            big_t * columns["v2"],
            big_t * radius * columns["omega"],
        ]
    )
    if frequency <= 0.0:
        return states, np.zeros(len(states)), 0.0
    period = 1.0 / frequency
    cycles = columns["t"] * frequency + phase / (2.0 * math.pi)
    offset = (cycles - np.floor(cycles)) * period
    return states, offset * (_L / big_t), period * (_L / big_t)


def find_period(
    columns: Mapping[str, np.ndarray],
    *,
    frequency: float,
    phase: float,
    radius: float,
    g: float,
    tolerance: float,
    max_period: int,
    window: int = PERIOD_WINDOW,
) -> int:
    """The smallest k <= max_period for which the last ``window`` post-impact states
    (with the drive phase) repeat every k impacts within ``tolerance``; 0 if none."""
    states, drive, cycle = scaled_states(columns, frequency, phase, radius, g)
    states, drive = states[-window:], drive[-window:]
    n = len(states)
    for k in range(1, min(max_period, n // 2) + 1):
        if np.max(np.abs(states[k:] - states[:-k])) > tolerance:
            continue
        if cycle > 0.0:
            d = np.abs(drive[k:] - drive[:-k])
            d = np.minimum(d, cycle - d)
            if np.max(d) > tolerance:
                continue
        return k
    return 0


def contact_class(status: Any, final_mode: str | None, measured: int) -> str | None:
    """The class of a run that ended with the ball on the boundary instead of in an
    impact sequence, or None for a run to classify by its impacts (:func:`classify`).

    Args:
        status: the run's :class:`~billiard.status.Status`.
        final_mode: ``Result.final_mode`` (``flight``, ``roll``, ``slide``, ``held``).
        measured: impacts after the transient.
    """
    from billiard.status import Status

    if status == Status.AT_REST:
        return "resting"
    contact = CONTACT_CLASSES.get(final_mode or "")
    if status == Status.IN_CONTACT:
        # no impact for run.contact_span: the contact motion is where the ball ended up
        return contact or "rolling"
    if status == Status.TIME_LIMIT and measured == 0 and contact is not None:
        # the duration came while the ball was in contact, and no impact since the
        # transient: it has stayed on the boundary; a run with impacts after the
        # transient is classified by them (an orbit may contain contact phases)
        return contact
    return None


def classify(
    *,
    failed: bool,
    period: int,
    rise: float,
    elastic_share: float,
    rest_band: float,
    lyapunov: float | None,
    chaos_threshold: float,
) -> str:
    """The class of a point (see the module docstring); ``rise`` is the highest
    post-transient impact's height above the resting height (m)."""
    if failed:
        return "failed"
    if rise <= rest_band and elastic_share >= 0.5:
        return "resting"
    if period > 0:
        return "periodic"
    if lyapunov is None or not math.isfinite(lyapunov):
        return "aperiodic"
    return "chaotic" if lyapunov > chaos_threshold else "quasi-periodic"
