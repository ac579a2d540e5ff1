"""The paper's impact detection, kept as the baseline of ``method = "rk4"``.

Fixed RK4 steps; after each step the Euclidean distance to the curve from Newton-Raphson
on the nearest-point condition; an impact when distance <= r, located Baraff-style by
re-integrating from the step start with shorter steps until |gap| <= 1e-12 m. The
distance is taken negative for a centre below the curve, so that a coarse step cannot
carry the ball through a wall unnoticed. It can miss an impact that starts and ends
between two steps (a grazing impact); that is the method's known weakness.

A step too coarse for the scene is detected: when the ball comes back to the wall
within one step, the search takes the point the ball has just left for the next impact
(a *departure*: found within a millionth of a step after the previous impact). An
isolated departure happens at the default step (one in 3,000 impacts of the wedge); a
chain of :data:`DEPARTURE_LIMIT` in a row means the step cannot resolve the ball's hops
(with ``run.step = 0.003`` the parabola made 278 such impacts in its first 300, pumping
the spin to 400 rad/s), and the run stops with a message naming a finer step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, MutableSequence

from billiard.geometry.boundary import Boundary
from billiard.geometry.surfaces import WarmStart
from billiard.geometry.wall_functions import plain_wall_functions
from billiard.kernels.interpreted import fixed_step as _fixed_step
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.names import (
    copy,
    new_ctx,
    put_surface_block,
    read,
    read_slots,
    write,
    write_block,
    write_slots,
)
from billiard.models.event_locator import LOCATOR, Event
from billiard.models.flight import RK4Flight

__all__ = ["DEPARTURE_LIMIT", "FixedStepLocator", "answer_foot", "fixed_step_constants"]

#: Consecutive impacts found at the previous impact's departure point that stop a run:
#: the fixed step is too coarse for the scene.
DEPARTURE_LIMIT = _fixed_step.DEPARTURE_LIMIT
#: An impact found within this fraction of a step after the previous one is a departure.
DEPARTURE_FRACTION = _fixed_step.DEPARTURE_FRACTION


def fixed_step_constants(ctx: list[float], boundary: Boundary, step: float) -> None:
    """Write the fixed-step locator's constants for ``boundary`` into a state vector
    (the drive's and the surfaces' are the event locator's): the step (s), the radius,
    the walls and their intervals, where the lid and the escape level are."""
    boundary.drive.write(ctx)
    surfaces = boundary.surfaces
    write(ctx, "locator.surfaces", float(len(surfaces)))
    for j, surface in enumerate(surfaces):
        put_surface_block(ctx, j, surface.block())
    walls = boundary.walls
    lid, escape = boundary.lid, boundary.escape
    write_block(
        ctx,
        "rk4",
        step=float(step),
        radius=boundary.radius,
        walls=float(len(walls)),
        lid=float(surfaces.index(lid)) if lid is not None else -1.0,
        escape=float(surfaces.index(escape)) if escape is not None else -1.0,
        answers=0.0,
    )
    write_slots(ctx, "rk4.lo", [wall.lo for wall in walls])
    write_slots(ctx, "rk4.hi", [wall.hi for wall in walls])


def answer_foot(ctx: MutableSequence[float], boundary: Boundary) -> None:
    """Answer the search's question (``E_FOOT``): the foot on wall ``RK_ASK[2]`` of the
    curve's global nearest point of (px, py) (``Boundary.nearest_point``, polynomial
    roots), or the vertical projection when that point is on another wall.

    Raises:
        SimulationError: the search asked more than ``RK_MAX_ANSWERS`` questions.
    """
    from billiard.errors import SimulationError

    n = int(read(ctx, "rk4.answers"))
    if n >= _L.RK_MAX_ANSWERS:
        raise SimulationError(
            f"the fixed-step search needed the global nearest point more than "
            f"{_L.RK_MAX_ANSWERS} times in one flight"
        )
    px, py, i = read_slots(ctx, "rk4.ask")
    wall = boundary.walls[int(i)]
    near = boundary.nearest_point(px, py)
    s = near.s if near.wall == int(i) else min(max(px, wall.lo), wall.hi)
    write_slots(ctx, "rk4.answer", (px, py, i, s), at=4 * n)
    write(ctx, "rk4.answers", float(n + 1))


class FixedStepLocator:
    """The paper's fixed-step detection for ``method = "rk4"`` (module docstring): the
    kernels' search (:func:`billiard.kernels.fixed_step.locate`, run interpreted) over a
    state vector of its own, which also holds its memory between flights.

    Raises:
        ValueError: a flight model other than :class:`RK4Flight`.
    """

    #: the kernels' code of this search (``LOC_KIND``)
    kind = _L.LOC_RK4

    def __init__(
        self,
        boundary: Boundary,
        flight: RK4Flight,
        gravity: float = 0.0,
        warm: list[WarmStart] | None = None,
    ):
        if not isinstance(flight, RK4Flight):
            raise ValueError("the fixed-step locator drives the RK4 flight model only")
        self.boundary = boundary
        self.surfaces = boundary.surfaces
        self.flight = flight
        self.h = flight.max_step
        ctx = new_ctx()
        write_block(ctx, "locator", kind=self.kind, gravity=float(gravity))
        fixed_step_constants(ctx, boundary, self.h)
        self.ctx = ctx
        walls = boundary.walls
        self._p = walls[0].p
        self._walls = plain_wall_functions(walls)
        self._nears = (tuple(w.near for w in walls), tuple(w.dnear for w in walls))

    def write(self, ctx: MutableSequence[float]) -> None:
        """Write the drive block, the locator's constants (its kind first) and the
        fixed-step detection's constants and memory into a state vector, as its own
        ``ctx`` holds them."""
        copy(ctx, self.ctx, *LOCATOR)
        copy(ctx, self.ctx, "rk4")

    @property
    def _feet(self) -> list[float]:
        return list(read_slots(self.ctx, "rk4.feet", len(self.boundary.walls)))

    @property
    def _departures(self) -> int:
        return int(read(self.ctx, "rk4.departures"))

    @property
    def theta0(self) -> float:
        """The drive angle at the start of the latest flight (rad)."""
        return read(self.ctx, "locator.theta0")

    def memory(self) -> dict[str, list[float]]:
        """What the locator carries from one flight to the next, for a checkpoint: the
        Newton warm starts (feet) of the walls' nearest points and the count of
        consecutive departures (a one-element list, as the engine state stores lists of
        floats)."""
        return {"feet": list(self._feet), "departures": [float(self._departures)]}

    def restore_memory(self, memory: Mapping[str, list[float]]) -> None:
        # a checkpoint written before departures were counted has only the feet
        ok = set(memory) in ({"feet"}, {"feet", "departures"})
        feet = memory.get("feet") if ok else None
        count = memory.get("departures", [0.0]) if ok else None
        if not (
            isinstance(feet, list)
            and len(feet) == len(self.boundary.walls)
            and all(isinstance(s, float) and math.isfinite(s) for s in feet)
            and isinstance(count, list)
            and len(count) == 1
            and count[0] in range(DEPARTURE_LIMIT)
        ):
            raise ValueError(
                "FixedStepLocator memory must be {'feet': [s, ...], 'departures': [n]}, "
                f"got {memory!r}"
            )
        write_slots(self.ctx, "rk4.feet", feet)
        write(self.ctx, "rk4.departures", float(int(count[0])))

    def locate(self, theta0: float, q1: float, q2: float, u1: float, u2: float, u3: float) -> Event:
        ctx = self.ctx
        self.flight.begin(q1, q2, u1, u2, u3)
        copy(ctx, self.flight.ctx, "flight.kind", "flight.step")
        while True:
            try:
                tau, j, q1, q2, u1, u2, theta, s, z = _fixed_step.locate(
                    ctx, self._p, self._walls, self._nears, theta0, q1, q2, u1, u2, u3
                )
                break
            except _L.KernelError as exc:
                if exc.args[0] != _L.E_FOOT:
                    raise _stop(exc, ctx) from None
                answer_foot(ctx, self.boundary)
        return Event(tau, self.surfaces[j], q1, q2, u1, u2, theta, s, z, j)
