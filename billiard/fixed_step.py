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
from collections.abc import Mapping

from billiard.boundary import Boundary
from billiard.errors import SimulationError
from billiard.events import MAX_FLIGHT_TIME, Event
from billiard.flight import RK4Flight
from billiard.status import Status
from billiard.surfaces import Surface, WarmStart
from billiard.walls import Wall, nearest_newton

__all__ = ["DEPARTURE_LIMIT", "FixedStepLocator"]

#: Consecutive impacts found at the previous impact's departure point that stop a run:
#: the fixed step is too coarse for the scene.
DEPARTURE_LIMIT = 3
#: An impact found within this fraction of a step after the previous one is a departure.
DEPARTURE_FRACTION = 1e-6


class FixedStepLocator:
    """The paper's fixed-step detection for ``method = "rk4"`` (module docstring)."""

    #: |gap| (m) at which the Baraff-style search accepts the impact time.
    GAP_TOLERANCE = 1e-12
    #: shortest step interval (s) the search refines to.
    TIME_TOLERANCE = 1e-15

    def __init__(
        self,
        boundary: Boundary,
        flight: RK4Flight,
        gravity: float = 0.0,
        warm: list[WarmStart] | None = None,
    ):
        self.boundary = boundary
        self.flight = flight
        self.h = flight.max_step
        self.walls = boundary.walls
        self.r = boundary.radius
        self.lid = boundary.lid
        self.escape = boundary.escape
        self.offsets = boundary.offsets
        # places of the lid and the escape level in Boundary.surfaces
        self.lid_index = boundary.surfaces.index(self.lid) if self.lid is not None else -1
        self.escape_index = boundary.surfaces.index(self.escape) if self.escape is not None else -1
        self.drive = boundary.drive
        self._feet = [0.0] * len(self.walls)
        #: consecutive impacts found at the previous impact's departure point
        self._departures = 0
        self.theta0 = 0.0

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
            and len(feet) == len(self.walls)
            and all(isinstance(s, float) and math.isfinite(s) for s in feet)
            and isinstance(count, list)
            and len(count) == 1
            and count[0] in range(DEPARTURE_LIMIT)
        ):
            raise ValueError(
                "FixedStepLocator memory must be {'feet': [s, ...], 'departures': [n]}, "
                f"got {memory!r}"
            )
        self._feet = list(feet)
        self._departures = int(count[0])

    def _clearance(
        self, tau: float, y: tuple[float, float, float, float]
    ) -> tuple[float, Surface, float, float, int]:
        """(distance to the boundary minus r, the surface, contact abscissa s, angle z,
        the surface's place in ``Boundary.surfaces``).

        The distance is signed, negative for a centre below the curve, so that a step
        that carries the ball right through the wall still counts as a contact.
        """
        theta = self.theta0 + self.drive.omega * tau
        px, py, _, _ = self.drive.to_boundary_frame(theta, *y)
        nearest = (math.inf, 0, 0.0)
        for i, wall in enumerate(self.walls):
            s, d = self._wall_distance(i, wall, px, py)
            if d < nearest[0]:
                nearest = (d, i, s)
        d, i, s = nearest
        if py < max(wall.f(px, wall.p) for wall in self.walls):
            d = -d  # the centre is outside the container
        wall = self.walls[i]
        best = (d - self.r, self.offsets[i], s, math.atan(wall.df(s, wall.p)), i)
        if self.lid is not None and self.lid.level - py < best[0]:
            best = (self.lid.level - py, self.lid, px, math.pi, self.lid_index)
        if self.escape is not None and py >= self.escape.level:
            best = (-math.inf, self.escape, px, math.pi, self.escape_index)
        return best

    def _wall_distance(self, i: int, wall: Wall, px: float, py: float) -> tuple[float, float]:
        """Newton-Raphson on the nearest-point condition of one wall (30 iterations at
        most), from the previous foot and from the vertical projection; the nearer point
        wins."""
        f, p = wall.f, wall.p
        lo, hi = wall.lo, wall.hi
        best_s, best_d = 0.0, math.inf
        for start in (self._feet[i], px):
            s, _ = nearest_newton(wall, start, px, py, iterations=30)
            if s is None:
                continue
            s = min(max(s, lo), hi)
            dx, dy = px - s, py - f(s, p)
            dist = math.sqrt(dx * dx + dy * dy)
            if dist < best_d:
                best_s, best_d = s, dist
        if best_d == math.inf:  # Newton failed from both starts: global search
            near_pt = self.boundary.nearest_point(px, py)
            wall_pt = near_pt if near_pt.wall == i else None
            best_s = wall_pt.s if wall_pt else min(max(px, lo), hi)
            dx, dy = px - best_s, py - f(best_s, p)
            best_d = math.sqrt(dx * dx + dy * dy)
        self._feet[i] = best_s
        return best_s, best_d

    def locate(self, theta0: float, q1: float, q2: float, u1: float, u2: float, u3: float) -> Event:
        self.theta0 = theta0
        flight = self.flight
        flight.begin(q1, q2, u1, u2, u3)
        h = self.h
        y = (q1, q2, u1, u2)
        gap0 = self._clearance(0.0, y)[0]
        n = 0
        while n * h < MAX_FLIGHT_TIME:
            tau = n * h
            y_next = flight.step(y, h)
            found = self._clearance(tau + h, y_next)
            if found[0] <= 0.0:
                event = self._locate_in_step(tau, y, gap0, h, found)
                self._count_departure(event.tau)
                return event
            y, gap0 = y_next, found[0]
            n += 1
        raise SimulationError(f"no impact found within {MAX_FLIGHT_TIME:g} s of flight")

    def _count_departure(self, tau: float) -> None:
        """Count an impact found at the previous impact's departure point; stop the run
        at DEPARTURE_LIMIT of them in a row."""
        h = self.h
        if tau >= DEPARTURE_FRACTION * h:
            self._departures = 0
            return
        self._departures += 1
        if self._departures >= DEPARTURE_LIMIT:
            self._departures = 0
            finer = float(f"{h / 10:.0e}")
            raise SimulationError(
                f"run.step = {h:g} s is too coarse for this scene (use run.step <= "
                f"{finer:g} s): {DEPARTURE_LIMIT} impacts in a row were found within "
                f"{DEPARTURE_FRACTION * h:.0e} s of the previous one, where the ball had "
                f"just left the wall (it comes back within one step)",
                Status.SOLVER_FAILED,
            )

    def _locate_in_step(
        self,
        tau: float,
        y: tuple[float, float, float, float],
        gap_lo: float,
        h: float,
        found: tuple[float, Surface, float, float],
    ) -> Event:
        """Shrink the step from its start until the gap is within GAP_TOLERANCE:
        regula falsi (Illinois) while the start is clear, bisection otherwise."""
        lo, hi = 0.0, h
        g_lo, g_hi = gap_lo, found[0]
        best = (hi, found)
        side = 0
        for _ in range(400):
            if g_lo > 0.0 and math.isfinite(g_hi):
                step = hi - g_hi * (hi - lo) / (g_hi - g_lo)
                if not lo < step < hi:
                    step = 0.5 * (lo + hi)
            else:
                step = 0.5 * (lo + hi)
            found = self._clearance(tau + step, self.flight.step(y, step))
            g = found[0]
            if abs(g) <= self.GAP_TOLERANCE:
                best = (step, found)
                break
            if g > 0.0:
                lo, g_lo = step, g
                if side == -1:
                    g_hi *= 0.5
                side = -1
            else:
                hi, g_hi = step, g
                best = (hi, found)
                if side == 1:
                    g_lo *= 0.5
                side = 1
            if hi - lo < self.TIME_TOLERANCE:
                break
        step, (_, surface, s, z, index) = best
        q1, q2, u1, u2 = self.flight.step(y, step)
        theta = (self.theta0 + self.drive.omega * (tau + step)) % (2.0 * math.pi)
        return Event(tau + step, surface, q1, q2, u1, u2, theta, s, z, index)
