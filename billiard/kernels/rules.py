"""The engine's bookkeeping rules: the compensated clock and the limits that stop a run
that makes no progress (an inelastic collapse, flights of zero duration).

Two criteria, both meaning that the ball has stopped flying and is in sustained
contact, which an impact-only model cannot represent:

* COLLAPSE_COUNT (200) impacts within COLLAPSE_SPAN (1e-6 s) of simulated time:
  flights of 5e-9 s on average. Under an acceleration a toward the wall (gravity
  plus the drive's, 10 to 1000 m/s^2) a hop of duration t rises a t^2 / 8, below
  1e-14 m here, far below the locators' resolution of the gap (1e-12 m): these
  are no longer flights. This is what an inelastic collapse looks like: the
  flight times of a ball bouncing on a table with e < 1 form a geometric series
  (ratio about e^2) whose sum converges to the time the ball comes to rest, so
  the impacts accumulate at that point; the criterion stops it within a few
  hundred impacts of the flights falling below 1e-6 s. 1e-6 s is also
  negligible against any drive period (0.01 to 1 s). The paper scenes never
  have two impacts within 1e-6 s in 25,000 impacts each (their shortest flights
  are 5e-6 s, in the wedge's vertex).
* ZERO_FLIGHT_LIMIT (1,000) consecutive impacts with a time of flight of
  exactly zero, which do not advance the clock at all.

Under contact phases, contacts without impulse enter the same window, and contact
phases of zero duration count as zero flights.
"""

from __future__ import annotations

__all__ = ["COLLAPSE_COUNT", "COLLAPSE_SPAN", "ZERO_FLIGHT_LIMIT", "compensated_add"]

#: Inelastic collapse: this many impacts ...
COLLAPSE_COUNT = 200
#: ... within this much simulated time (s) stop the run.
COLLAPSE_SPAN = 1e-6
#: So does this many consecutive impacts (or contact phases) of zero duration.
ZERO_FLIGHT_LIMIT = 1_000


def compensated_add(clock: float, error: float, tau: float) -> tuple[float, float]:
    """Add a duration tau (s) to the engine's clock by Neumaier's compensated summation:
    (new sum, new running error); the time is their sum. The clock is a sum of tens of
    thousands of durations: kept this way it stays the correctly rounded sum."""
    total = clock + tau
    if abs(clock) >= abs(tau):
        return total, error + ((clock - total) + tau)
    return total, error + ((tau - total) + clock)
