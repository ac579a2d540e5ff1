"""The engine's bookkeeping rules, one source for the compiled impact loop and the
interpreted engine: the compensated clock and the limits that stop a run that makes no
progress (an inelastic collapse, flights of zero duration).
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
