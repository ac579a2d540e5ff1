"""The sum of a chatter series and its error bound (billiard/models/chatter.py), against a
series summed flight by flight here under an acceleration that changes linearly."""

from __future__ import annotations

import math

import pytest

from billiard.models.chatter import CHATTER_TAIL, CHATTER_TOL, bracket, summed


def series(v: float, e: float, a0: float, jerk: float) -> float:
    """The time (s) until a ball leaving a wall at v (m/s) comes to rest on it, e its
    restitution, the acceleration into the wall a0 + jerk t: each flight's end is the
    root of v tau - a0 tau^2 / 2 - jerk (t tau^2 / 2 + tau^3 / 6) (bisection)."""
    t = 0.0
    while v > 0.0:
        a = a0 + jerk * t

        def gap(tau: float, v: float = v, a: float = a) -> float:
            return v - a * tau / 2 - jerk * tau * tau / 6

        lo, hi = 0.0, 4 * v / a
        assert gap(hi) < 0.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if gap(mid) > 0.0 else (lo, mid)
        tau = 0.5 * (lo + hi)
        if tau < 1e-18:
            return t
        t += tau
        v = e * (a * tau + jerk * tau * tau / 2 - v)  # e times the arrival speed
    return t


@pytest.mark.parametrize("jerk", [0.0, 2e3, -2e3])
@pytest.mark.parametrize("e", [0.2, 0.5, 0.9])
def test_the_bracket_holds_the_series_and_its_constant_acceleration_sum(e, jerk):
    v, a0 = 1e-6, 5.0
    t0 = 2 * v / (a0 * (1 - e))
    lo, hi = bracket(v, e, a0, abs(jerk), 2 * t0)
    exact = series(v, e, a0, jerk)
    if jerk == 0.0:
        assert lo == hi == t0 and exact == pytest.approx(t0, rel=1e-12)
        return
    assert lo <= exact <= hi and lo <= t0 <= hi
    # the stated first-order width, 4 J T0^2 / (a0 (1 - e)); the drift is real (the
    # bound is the worst case: a at its extreme throughout, about 100 times the drift)
    width = 4 * abs(jerk) * t0 * t0 / (a0 * (1 - e))
    assert hi - lo == pytest.approx(width, rel=0.05)
    assert abs(exact - t0) > 1e-5 * t0


def test_no_bound_where_the_acceleration_may_vanish_or_the_series_outlasts_the_window():
    assert bracket(1e-3, 0.5, 1.0, 1e3, 1e-3) == (0.0, math.inf)  # a_lo = 0
    assert bracket(1e-3, 0.5, 10.0, 0.0, 1e-4) == (0.0, math.inf)  # T0 = 4e-4 > window
    assert bracket(0.0, 0.5, 10.0, 0.0, 1e-4) == (0.0, 0.0)  # e = 0: at rest at once


def test_summed_accepts_a_short_tail_and_refuses_a_vanishing_acceleration():
    period = 0.05
    # a linear acceleration: T0 comes back when the bound is within CHATTER_TOL
    tau = summed(1e-8, 0.5, lambda s: 5.0 + 100.0 * s, period)
    assert tau == 2 * 1e-8 / (5.0 * 0.5)
    # the same tail, but a going to zero within the window (2 T0 = 1.6e-8 s): refused
    assert summed(1e-8, 0.5, lambda s: 5.0 - 5e8 * s, period) is None
    # a longer tail under the same jerk, within CHATTER_TAIL of a long period: its bound
    # exceeds CHATTER_TOL of the period
    v, long = 1e-3, 1e3
    t0 = 2 * v / (5.0 * 0.5)
    assert t0 <= CHATTER_TAIL * long
    assert 4 * 100.0 * t0 * t0 / (5.0 * 0.5) > CHATTER_TOL * long
    assert summed(v, 0.5, lambda s: 5.0 + 100.0 * s, long) is None
    assert summed(v, 0.5, lambda s: 5.0, long) == t0  # constant: exact
    # a series longer than CHATTER_TAIL of the period is followed impact by impact
    assert t0 > CHATTER_TAIL * period and summed(v, 0.5, lambda s: 5.0, period) is None
    # not pressed: no landing
    assert summed(1e-8, 0.5, lambda s: -1.0, period) is None
