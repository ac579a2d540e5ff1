"""Finding the next impact of a flight: the event-driven locator (``method = "event"``).

Two locators share one interface, ``locate(theta0, q1, q2, u1, u2, u3) -> Event``: the
flight starts at tau = 0 with the drive angle theta0 and ends at the returned event.

:class:`EventLocator` (``method = "event"``)
    Works on the vertical offset gap G(tau) = p_y - F(p_x) of every wall, the lid's gap
    and, for an open container, the escape level (see :mod:`billiard.boundary`); each is a
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
    found again, while a hop that ends within the same substep is. A surface with G <= 0
    and dG/dtau < 0 at tau = 0 (the second wall at a wedge's vertex) is an immediate
    impact.

    For drag-free flight the trajectory is the exact parabola, so the impact time is
    exact to floating point; with air forces each probe inside a step re-integrates from
    the step start with one step of the exact length.

The paper's fixed-step scheme is :class:`billiard.fixed_step.FixedStepLocator`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

from billiard.boundary import Boundary
from billiard.errors import SimulationError
from billiard.flight import FlightModel
from billiard.surfaces import Surface, WarmStart

__all__ = ["Event", "EventLocator", "Locator"]

# The longest flight the locators follow before giving up (s of simulated time).
MAX_FLIGHT_TIME = 1.0e3
# Substeps: the first of a flight and every root bracket are at most this fraction of the
# drive period ...
_DRIVE_FRACTION = 1.0 / 20.0
# ... and of rho / |v_rel|, rho the smallest offset radius of curvature ...
_TURN_FRACTION = 0.5
# ... and never longer than this (s), for a boundary at rest.
_LONGEST_BRACKET = 0.05
# Proven-clear substeps grow up to this length (s).
_LONGEST_STEP = 0.2
# How many times a substep may be halved when the bound cannot prove it clear.
_MAX_SPLITS = 8
# A gap this small (m) is contact to within rounding: G is a difference of heights of
# order 0.1 m, so its rounding error is ~1e-17 m; a surface that close at the start of a
# flight and moving away is being left, not approached.
CONTACT_TOLERANCE = 1e-13
# Rounding noise of a computed gap (m): below this a gap's sign carries no information.
GAP_NOISE = 1e-16


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
    """Impact detection on offset-curve gaps for ``method = "event"`` (module docstring)."""

    def __init__(
        self,
        boundary: Boundary,
        flight: FlightModel,
        gravity: float,
        warm: list[WarmStart] | None = None,
    ):
        self.boundary = boundary
        self.surfaces = boundary.surfaces
        #: the engine's warm starts, one per surface (see billiard.surfaces)
        self.warm = boundary.initial_warm() if warm is None else warm
        self.flight = flight
        drive = boundary.drive
        self.amplitude = drive.amplitude
        self.omega = drive.omega
        self.horizontal = drive.horizontal
        self.drive_accel = drive.peak_acceleration
        self.g = float(gravity)
        self.h_first = min(_LONGEST_BRACKET, _DRIVE_FRACTION * drive.period, flight.max_step)
        self.h_longest = min(_LONGEST_STEP, flight.max_step)
        self.turn_length = _TURN_FRACTION * boundary.smallest_offset_radius
        self.h_bracket = self.h_first
        self._split = False
        self.theta0 = 0.0

    def memory(self) -> dict[str, list[float]]:
        """What the locator carries from one flight to the next, for a checkpoint: nothing
        (every search starts afresh; the surfaces keep their own warm starts)."""
        return {}

    def restore_memory(self, memory: Mapping[str, list[float]]) -> None:
        if memory:
            raise ValueError("EventLocator carries no memory between flights")

    # ------------------------------------------------------------------ kinematics

    def _relative(
        self, tau: float, y: tuple[float, float, float, float]
    ) -> tuple[float, float, float, float]:
        """Centre position and velocity relative to the boundary at flight time tau."""
        q1, q2, u1, u2 = y
        theta = self.theta0 + self.omega * tau
        a = self.amplitude
        d = a * math.sin(theta)
        v = a * self.omega * math.cos(theta)
        if self.horizontal:
            return q1 - d, q2, u1 - v, u2
        return q1, q2 - d, u1, u2 - v

    def _relative_acceleration(self, tau: float, u1: float, u2: float) -> tuple[float, float]:
        a1, a2 = self.flight.acceleration(u1, u2)
        # the boundary accelerates by -A w^2 sin(theta) along the drive
        ab = -self.drive_accel * math.sin(self.theta0 + self.omega * tau)
        return (a1 - ab, a2) if self.horizontal else (a1, a2 - ab)

    def _gap(self, j: int, tau: float) -> tuple[float, float]:
        y = self.flight.state(tau)
        return self.surfaces[j].gap_rate(*self._relative(tau, y), self.warm[j])

    def _event(self, tau: float, j: int) -> Event:
        q1, q2, u1, u2 = self.flight.state(tau)
        px = self._relative(tau, (q1, q2, u1, u2))[0]
        surface = self.surfaces[j]
        s, z, _ = surface.contact(px, self.warm[j])
        theta = (self.theta0 + self.omega * tau) % (2.0 * math.pi)
        return Event(tau, surface, q1, q2, u1, u2, theta, s, z, j)

    # ------------------------------------------------------------------ main loop

    def locate(self, theta0: float, q1: float, q2: float, u1: float, u2: float, u3: float) -> Event:
        """Follow the flight starting at (q1, q2, u1, u2), drive angle theta0, to the first
        time the ball touches a wall or the lid (or crosses the escape level)."""
        self.theta0 = theta0
        flight = self.flight
        surfaces = self.surfaces
        warm = self.warm
        flight.begin(q1, q2, u1, u2, u3)
        ta = 0.0
        ya = (q1, q2, u1, u2)
        rel_a = self._relative(0.0, ya)
        gaps_a = [surf.gap_rate(*rel_a, warm[j]) for j, surf in enumerate(surfaces)]
        leaving = [False] * len(surfaces)

        # At tau = 0 a surface in contact (to within rounding) is either being left
        # (dG > 0: the impact just resolved) or hit again at once (G <= 0, dG < 0: e.g. the
        # other wall of a wedge's vertex).
        immediate = None
        for j, (g0, dg0) in enumerate(gaps_a):
            if g0 > CONTACT_TOLERANCE or (g0 > 0.0 and dg0 < 0.0):
                continue
            if dg0 == 0.0:
                ax, ay = self._relative_acceleration(0.0, u1, u2)
                dg0 = surfaces[j].gap_accel(*rel_a, ax, ay, warm[j])
            if dg0 >= 0.0:
                leaving[j] = True
            elif immediate is None or dg0 < immediate[1]:
                immediate = (j, dg0)
        if immediate is not None:
            return self._event(0.0, immediate[0])

        h = self.h_first
        while ta < MAX_FLIGHT_TIME:
            tb = flight.advance(ta, ta + h)
            yb = flight.state(tb)
            rel_b = self._relative(tb, yb)
            gaps_b = [surf.gap_rate(*rel_b, warm[j]) for j, surf in enumerate(surfaces)]
            span = tb - ta
            px, _, vx, vy = rel_a
            speed = math.sqrt(vx * vx + vy * vy)
            self.h_bracket = self.h_first
            if speed * self.h_bracket > self.turn_length:
                self.h_bracket = self.turn_length / speed
            bounds = self._accel_bounds(ya, span)
            self._split = False
            first = None
            for j, surf in enumerate(surfaces):
                m = surf.max_gap_deceleration(px, vx, span, *bounds, warm[j])
                ga, dga = gaps_a[j]
                gb, dgb = gaps_b[j]
                tau = self._scan(j, ta, ga, dga, tb, gb, dgb, m, _MAX_SPLITS, leaving[j])
                if tau is not None and (first is None or tau < first[0]):
                    first = (tau, j)
            if first is not None:
                return self._event(*first)
            for j in range(len(surfaces)):
                if leaving[j] and gaps_b[j][0] > 0.0:
                    leaving[j] = False
            h = 0.5 * span if self._split else min(2.0 * span, self.h_longest)
            # aim the next substep at the predicted contact (G extrapolated with the
            # curvature seen over this substep): end just before it while it is far, and
            # just after it once it is within a bracket's length
            for j in range(len(surfaces)):
                if leaving[j] and gaps_b[j][0] <= 0.0:
                    continue
                ga, dga = gaps_a[j]
                gb, dgb = gaps_b[j]
                tc = _first_positive_root(gb, dgb, 0.5 * (dgb - dga) / span)
                if tc < h:
                    hb = self.h_bracket
                    h = max(tc - 0.5 * hb if tc > hb else tc + 0.5 * hb, 1e-3 * hb)
            ta, ya, rel_a, gaps_a = tb, yb, rel_b, gaps_b
        raise SimulationError(f"no impact found within {MAX_FLIGHT_TIME:g} s of flight")

    def _accel_bounds(
        self, y: tuple[float, float, float, float], window: float
    ) -> tuple[float, float, float]:
        """Bounds over a window on the ball's acceleration relative to the boundary:
        (sup |a_x|, sup -a_y, sup a_y), from gravity, the drive, and the air forces at
        the largest speed the ball can reach in the window."""
        speed = math.sqrt(y[2] * y[2] + y[3] * y[3]) + 2.0 * self.g * window
        aero = self.flight.aero_bound(speed)
        if self.horizontal:
            return self.drive_accel + aero, self.g + aero, aero - self.g
        return aero, self.g + self.drive_accel + aero, self.drive_accel + aero - self.g

    # ------------------------------------------------------------------ one substep

    def _scan(
        self,
        j: int,
        ta: float,
        ga: float,
        dga: float,
        tb: float,
        gb: float,
        dgb: float,
        m: float,
        splits: int,
        leaving: bool = False,
    ) -> float | None:
        """First time in (ta, tb] at which the ball reaches ``j``, or None.

        G and dG/dtau are known at both ends; m >= -d2G/dtau2 on the substep. ``leaving``:
        the ball is separating from this surface at ta (G ~ 0, dG/dtau >= 0); otherwise
        it is clear of it there (G > 0).
        """
        if leaving:
            return self._scan_leaving(j, ta, ga, dga, tb, gb, dgb, m, splits)
        if gb <= 0.0:
            if tb - ta <= self.h_bracket or splits == 0:
                return self._root(j, ta, ga, dga, tb, gb, dgb)
        elif _provably_clear(ga, dga, gb, dgb, tb - ta, m):
            return None
        elif dga < 0.0 < dgb and splits > 0:
            # grazing candidate: a minimum of the gap inside the substep
            tm = self._rate_root(j, ta, dga, tb, dgb)
            gm, dgm = self._gap(j, tm)
            first = self._scan(j, ta, ga, dga, tm, gm, dgm, m, splits - 1)
            if first is not None or gm <= 0.0:
                return first
            return self._scan(j, tm, gm, dgm, tb, gb, dgb, m, splits - 1)
        elif splits == 0:
            return None
        # look closer: halve the substep and scan both halves in order (a sign change in
        # the first half always yields its root there)
        self._split = True
        tm = 0.5 * (ta + tb)
        gm, dgm = self._gap(j, tm)
        if gm <= 0.0:
            return self._scan(j, ta, ga, dga, tm, gm, dgm, m, splits - 1)
        first = self._scan(j, ta, ga, dga, tm, gm, dgm, m, splits - 1)
        if first is not None:
            return first
        return self._scan(j, tm, gm, dgm, tb, gb, dgb, m, splits - 1)

    def _scan_leaving(
        self,
        j: int,
        ta: float,
        ga: float,
        dga: float,
        tb: float,
        gb: float,
        dgb: float,
        m: float,
        splits: int,
    ) -> float | None:
        """:meth:`_scan` for a surface the ball is separating from at ta."""
        span = tb - ta
        if gb > 0.0 and _provably_clear(max(ga, 0.0), dga, gb, dgb, span, m):
            return None
        # Restart the search where the ball has certainly risen off the surface: the top
        # of the bound's parabola G_a + G'_a t - m t^2 / 2 (G_a ~ 0), before which G > 0
        # is proven. A hop that ends inside the substep is then found like any contact.
        proven = m > 0.0 and dga > 0.0 and dga / m < span
        tp = ta + dga / m if proven else ta + 0.5 * span
        gp, dgp = self._gap(j, tp)
        if gp > 0.0:
            return self._scan(j, tp, gp, dgp, tb, gb, dgb, m, splits)
        if proven or splits == 0:
            return tp  # the contact never opened beyond rounding
        self._split = True
        return self._scan_leaving(j, ta, ga, dga, tp, gp, dgp, m, splits - 1)

    def _root(
        self,
        j: int,
        lo: float,
        glo: float,
        dglo: float,
        hi: float,
        ghi: float,
        dghi: float,
    ) -> float:
        """Earliest time with G <= 0 in a bracket with G(lo) > 0 >= G(hi), to rounding:
        safeguarded Newton (bisection when it leaves the bracket or stalls).

        The search stops when the bracket is a few ulps wide or when G changes by less
        than its rounding noise across it; the right end (where G <= 0 was measured) is
        returned.
        """
        t = _quadratic_start(lo, glo, dglo, hi, dghi)
        if not lo < t < hi:
            t = hi - ghi * (hi - lo) / (ghi - glo)  # regula falsi
            if not lo < t < hi:
                t = 0.5 * (lo + hi)
        dx = dx_old = hi - lo
        for _ in range(200):
            g, dg = self._gap(j, t)
            if g > 0.0:
                lo = t
            else:
                hi = t
            width = hi - lo
            if width <= 4.0 * math.ulp(hi) or width * abs(dg) <= GAP_NOISE:
                return hi
            step = g / dg if dg != 0.0 else math.inf
            tiny = max(2.0 * math.ulp(t), 0.5 * GAP_NOISE / abs(dg)) if dg != 0.0 else 0.0
            if abs(step) < tiny:
                # Newton has converged to rounding: step just across the root so that the
                # bracket closes from both sides
                t = t + tiny if g > 0.0 else t - tiny
                if not lo < t < hi:
                    t = lo + 0.5 * width
                continue
            newton = t - step
            if not lo < newton < hi or abs(2.0 * g) > abs(dx_old * dg):
                # Newton leaves the bracket or does not halve the step: bisect
                dx_old, dx = dx, 0.5 * width
                t = lo + dx
                continue
            dx_old, dx = dx, step
            t = newton
        raise SimulationError("the impact time did not converge")

    def _rate_root(self, j: int, a: float, da: float, b: float, db: float) -> float:
        """Root of dG/dtau in (a, b), where it changes sign: the gap's extremum
        (Illinois; precise to ~1e-13 s, so G there is exact to ~G'' * 1e-26 m)."""
        side = 0
        for _ in range(200):
            t = b - db * (b - a) / (db - da)
            if not a < t < b:
                t = 0.5 * (a + b)
            _, d = self._gap(j, t)
            if d == 0.0:
                return t
            if (d < 0.0) == (da < 0.0):
                a, da = t, d
                if side == -1:
                    db *= 0.5
                side = -1
            else:
                b, db = t, d
                if side == 1:
                    da *= 0.5
                side = 1
            if b - a <= 1e-13 + 4.0 * math.ulp(b):
                return 0.5 * (a + b)
        raise SimulationError("the gap's extremum did not converge")


def _quadratic_start(lo: float, glo: float, dglo: float, hi: float, dghi: float) -> float:
    """First root after lo of the quadratic with value glo and slope dglo at lo whose
    slope changes linearly to dghi at hi: a good first guess when the gap curves strongly
    across the bracket (a short hop); nan when it has no root in (lo, hi)."""
    tc = _first_positive_root(glo, dglo, 0.5 * (dghi - dglo) / (hi - lo))
    return lo + tc if tc < hi - lo else math.nan


def _provably_clear(ga: float, dga: float, gb: float, dgb: float, h: float, m: float) -> bool:
    """True when G > 0 on the whole substep of length h, given G and dG/dtau at both ends
    (both G > 0) and m >= -d2G/dtau2 on it.

    From each end, G is above a parabola: L_a(t) = ga + dga t - m t^2 / 2 and
    L_b(t) = gb - dgb (h - t) - m (h - t)^2 / 2, so G >= max(L_a, L_b). Both are concave,
    so the minimum of their maximum is at an end (where it is ga or gb > 0) or where they
    cross; L_a - L_b is linear in t, so there is at most one crossing.
    """
    slope = dga - dgb - m * h
    if slope == 0.0:
        return True  # one parabola lies above the other throughout
    tc = (gb - ga - dgb * h - 0.5 * m * h * h) / slope
    if not 0.0 < tc < h:
        return True
    return ga + dga * tc - 0.5 * m * tc * tc > 0.0


def _first_positive_root(c0: float, c1: float, c2: float) -> float:
    """Smallest positive root of c0 + c1 t + c2 t^2 (inf when there is none)."""
    if c2 == 0.0:
        return -c0 / c1 if c1 < 0.0 < c0 or c0 < 0.0 < c1 else math.inf
    disc = c1 * c1 - 4.0 * c2 * c0
    if disc < 0.0:
        return math.inf
    root = math.sqrt(disc)
    q = -0.5 * (c1 + math.copysign(root, c1))
    roots = [x for x in (q / c2, c0 / q if q != 0.0 else math.inf) if x > 0.0]
    return min(roots, default=math.inf)
