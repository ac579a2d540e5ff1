"""Finding the next impact of a flight: the event-driven locator (``method = "event"``).

Two locators share one interface, ``locate(theta0, q1, q2, u1, u2, u3) -> Event``: the
flight starts at tau = 0 with the drive angle theta0 and ends at the returned event.

:class:`EventLocator` (``method = "event"``)
    Works on the vertical offset gap G(tau) = p_y - F(p_x) of every wall, the lid's gap
    and, for an open container, the escape level (see :mod:`billiard.geometry.boundary`); each is a
    smooth function of the flight time with an analytic rate dG/dtau = v_y - F'(p_x) v_x.

    The flight is marched in substeps [a, b] with G and dG/dtau known at both ends, and a
    bound M >= -d2G/dtau2 over the substep (from bounds on the relative acceleration, on
    the speed, and on the offset curve's curvature sampled once per run). Then G is above
    both parabolas G_a + G'_a t - M t^2/2 and G_b - G'_b (h - t) - M (h - t)^2/2, whose
    maximum has its minimum at one computable point: when that is positive the substep
    is *proven* clear. Otherwise, for each surface:

    * G goes from > 0 to <= 0: a root is bracketed. Brackets longer than
      min(drive period / 20, rho / (2 |v_rel|)), rho the offset curves' smallest radius of
      curvature, are first halved (each half checked in order); the root of a short one is
      refined by safeguarded Newton (bisection fallback) until the bracket is a few ulps
      wide or G's rounding noise spans it.
    * G > 0 at both ends and dG/dtau goes from < 0 to > 0: a grazing candidate. The
      minimum is located (root of dG/dtau); if G_min <= 0 the root lies between the
      substep start and the minimum, else both halves are checked again.
    * no sign pattern and no proof: the substep is halved (up to 8 times; the bound
      tightens four-fold per halving) and both halves are checked in order.

    Substeps double while they are proven clear and halve after one had to be split;
    the next one is also aimed at the contact predicted by extrapolating G. A flight high
    above the walls thus costs a few evaluations, and a contact that dips 1e-7 m deep
    between two samples is still found. The returned time is the right end of the final
    bracket, where G <= 0 was measured: the first representable time of contact.

    The search is rigorous given the bound M (the offset curvature in it is sampled on a
    dense grid and enlarged by 25 %), except in two places that rely on the short time
    scale of a bracket: a bracket is assumed to hold a single crossing, and the halving
    gives up after 8 levels (a ball skimming a wall closer than the bound can resolve).

    Right after an impact the wall just hit sits at G ~ 0 with dG/dtau > 0: it is marked
    *leaving*, and its search starts at the top of the bound's parabola
    G'_a t - M t^2 / 2, before which G > 0 is proven: the impact just resolved is never
    found again, while a hop that ends within the same substep is. A wall left at a
    lift-off, a release or an impact with no rebound sits at G ~ 0 with dG/dtau ~ 0 (to
    rounding) and an acceleration away from it: a *grazing start*, G opening as t^2 (or
    t^3 at a lift-off, where the normal force crosses zero); its search restarts where
    G > 0 is measured within half a bracket (a bracket holds at most one crossing), and
    G <= 0 there is a landing searched for by halving. A surface with G <= 0 and
    dG/dtau < 0 at tau = 0 (the second wall at a wedge's vertex) is an immediate
    impact.

    For drag-free flight the trajectory is the exact parabola, so the impact time is
    exact to floating point; with air forces each probe inside a step re-integrates from
    the step start with one step of the exact length.

The paper's fixed-step scheme is :class:`billiard.models.rk4_locator.FixedStepLocator`.
"""

from __future__ import annotations

from collections.abc import Mapping, MutableSequence
from dataclasses import dataclass
from typing import Protocol

from billiard.geometry.boundary import Boundary
from billiard.geometry.surfaces import Surface, WarmStart
from billiard.geometry.wall_functions import plain_wall_functions
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import locate as _locate
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.names import (
    copy,
    new_ctx,
    put_surface_block,
    read,
    warm_start,
    write_block,
    write_surface,
)
from billiard.models.flight import FlightModel

__all__ = ["LOCATOR", "Event", "EventLocator", "Locator"]

# The search's own constants are the kernels' (billiard/kernels/locate.py).
MAX_FLIGHT_TIME = _locate.MAX_FLIGHT_TIME
CONTACT_TOLERANCE = _locate.CONTACT_TOLERANCE
GAP_NOISE = _locate.GAP_NOISE
# Substeps: the first of a flight and every root bracket are at most this fraction of the
# drive period ...
_DRIVE_FRACTION = 1.0 / 20.0
# ... and of rho / |v_rel|, rho the smallest offset radius of curvature ...
_TURN_FRACTION = 0.5
# ... and never longer than this (s), for a boundary at rest.
_LONGEST_BRACKET = 0.05
# Proven-clear substeps grow up to this length (s).
_LONGEST_STEP = 0.2
#: what a locator writes into the engine's state vector (the first and the last name of
#: :func:`billiard.kernels.names.copy`): the drive block and the locator's constants (its
#: kind first; its theta0 and later are the search's own)
LOCATOR = ("drive", "locator.longest_bracket")


@dataclass(slots=True)
class Event:
    """The end of a flight: the ball touches ``surface`` at flight time ``tau``.

    ``q1, q2, u1, u2`` are the lab-frame position and velocity of the centre then,
    ``theta`` the drive angle, ``s`` the contact point's abscissa on the boundary and ``z``
    the tangent angle there (pi for the lid); ``index`` is the surface's place in
    ``Boundary.surfaces`` (and in the engine's warm starts).
    """

    tau: float
    surface: Surface
    q1: float
    q2: float
    u1: float
    u2: float
    theta: float
    s: float
    z: float
    index: int = -1


class Locator(Protocol):
    """What the engine needs of an impact locator: the next event of a flight, and its
    memory between flights (for checkpoints)."""

    def locate(
        self, theta0: float, q1: float, q2: float, u1: float, u2: float, u3: float
    ) -> Event: ...

    def memory(self) -> dict[str, list[float]]: ...

    def restore_memory(self, memory: Mapping[str, list[float]]) -> None: ...


class EventLocator:
    """Impact detection on offset-curve gaps for ``method = "event"`` (module docstring).

    The search is the kernels' (:func:`billiard.kernels.locate.locate`, run interpreted)
    over a state vector of this locator's own: the drive, the substep lengths and one
    block per surface (:meth:`billiard.geometry.surfaces.Surface.block`). A search copies the
    flight model's slots and the engine's warm starts in, and back out when it ends, so
    that the flight model and the warm starts hold what the search left, as they did
    when it ran on them directly.

    Raises:
        ValueError: a flight model the kernels do not have, or one whose gravity is not
            the locator's.
    """

    #: the kernels' code of this search (``LOC_KIND``)
    kind = _L.LOC_EVENT

    def __init__(
        self,
        boundary: Boundary,
        flight: FlightModel,
        gravity: float,
        warm: list[WarmStart] | None = None,
    ):
        self.boundary = boundary
        self.surfaces = boundary.surfaces
        #: the engine's warm starts, one per surface (see billiard.geometry.surfaces)
        self.warm = boundary.initial_warm() if warm is None else warm
        self.flight = flight
        drive = boundary.drive
        self.amplitude = drive.amplitude
        self.omega = drive.omega
        self.horizontal = drive.horizontal
        self.drive_accel = drive.peak_acceleration
        self.g = float(gravity)
        flight_ctx = getattr(flight, "ctx", None)
        if flight_ctx is None or len(self.surfaces) > _L.MAX_SURFACES:
            raise ValueError(
                f"the event locator takes the kernels' flight models and at most "
                f"{_L.MAX_SURFACES} surfaces, not {type(flight).__name__}"
            )
        flight_g = read(flight_ctx, "locator.gravity")
        if flight_g != self.g:
            raise ValueError(f"a flight model with gravity {flight_g!r}, not {self.g!r}")
        self.h_first = min(_LONGEST_BRACKET, _DRIVE_FRACTION * drive.period, flight.max_step)
        self.h_longest = min(_LONGEST_STEP, flight.max_step)
        self.turn_length = _TURN_FRACTION * boundary.smallest_offset_radius
        ctx = new_ctx()
        drive.write(ctx)
        write_block(
            ctx,
            "locator",
            kind=self.kind,
            gravity=self.g,
            first_substep=self.h_first,
            longest_substep=self.h_longest,
            turn=self.turn_length,
            longest_bracket=self.h_first,
            surfaces=float(len(self.surfaces)),
        )
        for j, surface in enumerate(self.surfaces):
            put_surface_block(ctx, j, surface.block())
        self.ctx = ctx
        walls = boundary.walls
        self._p = walls[0].p
        self._walls = plain_wall_functions(walls)

    def write(self, ctx: MutableSequence[float]) -> None:
        """Write the drive block and the locator's constants (its kind first) into a
        state vector, as its own ``ctx`` holds them."""
        copy(ctx, self.ctx, *LOCATOR)

    @property
    def h_bracket(self) -> float:
        """The longest root bracket of the latest substep (s)."""
        return read(self.ctx, "locator.longest_bracket")

    @property
    def theta0(self) -> float:
        """The drive angle at the start of the latest flight (rad)."""
        return read(self.ctx, "locator.theta0")

    def memory(self) -> dict[str, list[float]]:
        """What the locator carries from one flight to the next, for a checkpoint: nothing
        (every search starts afresh; the surfaces keep their own warm starts)."""
        return {}

    def restore_memory(self, memory: Mapping[str, list[float]]) -> None:
        if memory:
            raise ValueError("EventLocator carries no memory between flights")

    def locate(self, theta0: float, q1: float, q2: float, u1: float, u2: float, u3: float) -> Event:
        """Follow the flight starting at (q1, q2, u1, u2), drive angle theta0, to the first
        time the ball touches a wall or the lid (or crosses the escape level)."""
        ctx = self.ctx
        flight_ctx = self.flight.ctx
        warm = self.warm
        copy(ctx, flight_ctx, "flight")
        for i, w in enumerate(warm):
            write_surface(ctx, i, warm_s=w[0], warm_slope=w[1])
        try:
            tau, j, q1, q2, u1, u2, theta, s, z = _locate.locate(
                ctx, self._p, self._walls, theta0, q1, q2, u1, u2, u3
            )
        except _L.KernelError as exc:
            raise _stop(exc, ctx) from None
        finally:
            # what the search left: the flight's current step and the warm starts
            copy(flight_ctx, ctx, "flight")
            for i, w in enumerate(warm):
                w[0], w[1] = warm_start(ctx, i)
        return Event(tau, self.surfaces[j], q1, q2, u1, u2, theta, s, z, j)
