"""Impact locators by method name (``run.method``), as scipy's ``METHODS``: each is built
from the boundary, the flight model, g (m/s^2) and the engine's warm starts."""

from __future__ import annotations

from collections.abc import Callable

from billiard.geometry.boundary import Boundary
from billiard.geometry.surfaces import WarmStart
from billiard.models.event_locator import EventLocator, Locator
from billiard.models.flight import FlightModel, RK4Flight
from billiard.models.rk4_locator import FixedStepLocator

__all__ = ["LOCATORS"]


def _fixed_step(
    boundary: Boundary, flight: FlightModel, gravity: float, warm: list[WarmStart]
) -> FixedStepLocator:
    if not isinstance(flight, RK4Flight):
        raise ValueError("the fixed-step locator drives the RK4 flight model only")
    return FixedStepLocator(boundary, flight, gravity, warm)


LOCATORS: dict[str, Callable[[Boundary, FlightModel, float, list[WarmStart]], Locator]] = {
    "event": EventLocator,
    "rk4": _fixed_step,
}
