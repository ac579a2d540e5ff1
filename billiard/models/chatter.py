"""The sum of a chatter series: when a ball bouncing on a wall that presses it comes to
rest on it, with a bound on the error (``contact.model = "phases"``).

After an impact the ball leaves the wall with the normal speed v = e |w_n| relative to
it. At a constant normal acceleration a > 0 into the wall (a = N / m, the normal force
per unit mass that would hold the ball on the wall) each flight lasts 2 v_k / a and
returns at v_k, so the rebounds form the geometric series v_k = e^k v and the remaining
flights take

    T0 = 2 v / (a (1 - e))

in all: the impacts accumulate at t + T0 and the ball lies on the wall from then on.

The drive (and the ball's motion along a curved wall) changes a while the series runs.
Let a stay within [a_lo, a_hi], 0 < a_lo, over the whole remaining chatter. A flight that
leaves at v_k lasts between 2 v_k / a_hi and 2 v_k / a_lo (compare the height with the
parabolas of the two constant accelerations); its apex lies between v_k^2 / (2 a_hi) and
v_k^2 / (2 a_lo) (the work of a on the way up), so it returns at a speed between
v_k / rho and v_k rho, rho = sqrt(a_hi / a_lo), and leaves again at e times that. With
e rho < 1 the series converges, and the true time to rest T lies in

    [2 v / (a_hi (1 - e / rho)),  2 v / (a_lo (1 - e rho))],

which contains T0 (a constant a0 in [a_lo, a_hi] is one of the accelerations allowed).
Over a window of W seconds, |a - a0| <= J W where J bounds |da/dt| there; to first
order in delta = J W / a0 the bracket's width is 2 T0 delta / (1 - e), and with
W = 2 T0 (the window must hold the whole bracket: checked)

    |T - T0| <= width ~= 4 J T0^2 / (a0 (1 - e)).

J is measured: a at the impact, half the window on and at the window's end (the wall's
state carried along at its tangential speed, the drive's angle advanced), the larger of
the two difference quotients, doubled. The window is at most 2e-6 of a drive period
(:data:`billiard.kernels.impact.CHATTER_TAIL`), over which a sinusoidal drive's a is a
straight line to a relative 1e-5: the doubling covers a derivative that changes sign in
the window. The series is summed (:func:`summed`) when the width is at most
``CHATTER_TOL`` of the drive period; the ball then enters contact at t + T0, its state
relative to the wall that at the impact (its normal speed dropped), which it carries
through the chatter's at most 1e-6 of a period: the position along the wall lags by at
most |s_dot| T0, and the energy relative to the wall never grows.
"""

from __future__ import annotations

from collections.abc import Callable

from billiard.kernels.interpreted import impact as _impact

__all__ = ["CHATTER_TAIL", "CHATTER_TOL", "bracket", "summed"]

#: The longest chatter summed, as a fraction of the drive period (the kernels' test
#: of the free flight, ``impact.chatter_tail``, uses the same).
CHATTER_TAIL = _impact.CHATTER_TAIL
#: The largest error of the accumulation time accepted, as a fraction of the drive
#: period (1 s without a drive frequency): 1e-8 of 0.05 s is 5e-10 s.
CHATTER_TOL = _impact.CHATTER_TOL


def bracket(v: float, e: float, a0: float, jerk: float, window: float) -> tuple[float, float]:
    """The times (s) within which a chatter series ends (see the module's docstring):
    rebound speed ``v`` (m/s), restitution ``e`` < 1, acceleration into the wall ``a0``
    (m/s^2) at its start, changing at most ``jerk`` (m/s^3) over ``window`` seconds.
    (0, inf) when the bound does not hold: the acceleration may vanish in the window,
    the series may not converge, or it may outlast the window
    (:func:`billiard.kernels.impact.chatter_bracket`)."""
    return _impact.chatter_bracket(v, e, a0, jerk, window)


def summed(v: float, e: float, accel: Callable[[float], float], period: float) -> float | None:
    """The time (s) the chatter series after an impact takes to end, T0, when it is at
    most ``CHATTER_TAIL`` of ``period`` (s) and its error bound at most ``CHATTER_TOL``
    of it, else None. ``v``: the rebound's normal speed (m/s); ``e`` < 1;
    ``accel(tau)``: the acceleration into the wall (m/s^2) tau seconds after the impact
    (the kernels' :func:`~billiard.kernels.impact.chatter_time` and
    :func:`~billiard.kernels.impact.chatter_bounded`, which the state machine runs)."""
    a0 = accel(0.0)
    t0 = _impact.chatter_time(v, e, a0, period)
    if t0 == _impact.NOT_SUMMED:
        return None
    if t0 == 0.0:
        return 0.0
    if not _impact.chatter_bounded(v, e, a0, accel(t0), accel(2.0 * t0), t0, period):
        return None
    return t0
