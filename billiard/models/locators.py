"""Impact locators by method name (``run.method``), as scipy's ``METHODS``: classes, each
built from the boundary, the flight model, g (m/s^2) and the engine's warm starts; each
names its kind in the kernels (``LOC_KIND``) and writes its block (``write``)."""

from __future__ import annotations

from billiard.models.event_locator import EventLocator
from billiard.models.rk4_locator import FixedStepLocator

__all__ = ["LOCATORS"]

LOCATORS: dict[str, type[EventLocator] | type[FixedStepLocator]] = {
    "event": EventLocator,
    "rk4": FixedStepLocator,
}
