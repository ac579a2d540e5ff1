"""Boundary geometry in the boundary's own frame: contact gaps, nearest points, rest position.

The boundary translates with the drive, D(t) = A sin(w t + phase) along n1 (horizontal) or
n2 (vertical). All geometry is done in the boundary frame B, where the wall is the fixed
curve y = f(x) and the ball centre is p = q - D(t) e_drive.

Contact is detected with the *offset curve* of each smooth wall: the locus of the ball
centre when the ball touches the wall,

    X(s) = s - r f'(s) / sqrt(1 + f'(s)^2),    Y(s) = f(s) + r / sqrt(1 + f'(s)^2).

While r times the curvature stays below 1, X(s) is increasing, so the offset curve is a
graph Y = F(X) with F'(X) = f'(s) (it runs parallel to the wall). The vertical gap
G = p_y - F(p_x) then has the sign of the true clearance (distance minus r), is smooth
in time along a flight, and costs one short Newton solve, whereas the Euclidean distance
needs the global nearest point of the curve. A curve with kinks is the maximum of its
walls, so the container is the intersection of the regions above the (extended) walls
and the ball is inside exactly when every wall's G is >= 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard.errors import GeometryError, SimulationError

__all__ = [
    "Boundary",
    "Drive",
    "EscapeLevel",
    "FlatLid",
    "NearestPoint",
    "OffsetLine",
    "OffsetWall",
    "Surface",
]

# Newton on the offset inversion stops once a step is below this (m); the error left after
# that step is of order curvature * step^2, far below a double's resolution.
_FOOT_STEP_TOL = 1e-11
# Curvature bounds sampled on a grid are enlarged by this factor to cover the gaps between
# the samples (they feed rigorous-by-construction no-contact time bounds).
_BOUND_SAFETY = 1.25
_SAMPLES = 4001


@dataclass(frozen=True)
class Drive:
    """Sinusoidal translation of the boundary, D = amplitude * sin(theta) along one axis.

    The drive angle theta = omega t + phase is carried by the engine as a state variable
    (reduced modulo 2 pi) so that it stays accurate at large t.
    """

    amplitude: float
    omega: float
    phase: float
    horizontal: bool

    @classmethod
    def from_scene(cls, drive: Any) -> Drive:
        return cls(
            amplitude=float(drive.amplitude),
            omega=float(drive.omega),
            phase=float(drive.phase),
            horizontal=drive.direction == "horizontal",
        )

    def angle(self, t: float) -> float:
        """Drive angle omega t + phase, reduced to [0, 2 pi)."""
        return (self.omega * t + self.phase) % (2.0 * math.pi)

    @property
    def period(self) -> float:
        """Drive period (s); infinite for a boundary at rest."""
        if self.amplitude == 0.0 or self.omega == 0.0:
            return math.inf
        return 2.0 * math.pi / self.omega

    @property
    def peak_acceleration(self) -> float:
        return self.amplitude * self.omega * self.omega

    def displacement(self, theta: float) -> float:
        return self.amplitude * math.sin(theta)

    def velocity(self, theta: float) -> float:
        return self.amplitude * self.omega * math.cos(theta)

    def acceleration(self, theta: float) -> float:
        return -self.amplitude * self.omega * self.omega * math.sin(theta)

    def boundary_velocity(self, theta: float) -> tuple[float, float]:
        """Lab-frame velocity (vb1, vb2) of the boundary."""
        v = self.velocity(theta)
        return (v, 0.0) if self.horizontal else (0.0, v)

    def to_boundary_frame(
        self, theta: float, q1: float, q2: float, u1: float, u2: float
    ) -> tuple[float, float, float, float]:
        """Ball centre position and velocity relative to the boundary: (px, py, vx, vy)."""
        d = self.amplitude * math.sin(theta)
        v = self.amplitude * self.omega * math.cos(theta)
        if self.horizontal:
            return q1 - d, q2, u1 - v, u2
        return q1, q2 - d, u1, u2 - v

    def to_lab_frame(self, theta: float, px: float, py: float) -> tuple[float, float]:
        d = self.amplitude * math.sin(theta)
        return (px + d, py) if self.horizontal else (px, py + d)


class Surface:
    """A surface the ball centre must stay on the positive side of (gap G >= 0).

    ``gap_rate(px, py, vx, vy)`` returns (G, dG/dt) for a centre at p moving with velocity
    v relative to the boundary; ``gap_accel`` returns d2G/dt2 for a relative acceleration
    a. ``max_gap_deceleration`` bounds -d2G/dt2 over a window of length tau, given bounds
    on the relative acceleration; the event locator uses it to skip stretches of flight
    that provably cannot touch this surface.
    """

    label: str = ""
    kind: str = "wall"

    def gap_rate(self, px: float, py: float, vx: float, vy: float) -> tuple[float, float]:
        raise NotImplementedError

    def gap_accel(self, px: float, py: float, vx: float, vy: float, ax: float, ay: float) -> float:
        raise NotImplementedError

    def contact(self, px: float) -> tuple[float, float, float]:
        """(s, z, cos z) of the contact point for a ball centre at abscissa px on the
        offset curve: s is the contact point's abscissa on the boundary, z the tangent
        angle there. ``dG/dt * cos z`` is the relative normal velocity along c2."""
        raise NotImplementedError

    def max_gap_deceleration(
        self, px: float, vx: float, tau: float, ax: float, ay_down: float, ay_up: float
    ) -> float:
        raise NotImplementedError


class OffsetWall(Surface):
    """Offset curve of one smooth, curved wall: gap, its rates and curvature bounds."""

    def __init__(self, wall: dict, radius: float, index: int):
        self.f: Callable[[float], float] = wall["f"]
        self.df: Callable[[float], float] = wall["df"]
        self.d2f: Callable[[float], float] = wall["d2f"]
        self.lo = float(wall["lo"])
        self.hi = float(wall["hi"])
        self.r = float(radius)
        self.index = index
        self.label = str(index)
        self.s = 0.0  # warm start of the offset inversion: the previous foot
        self.slope = 0.0  # f'(s) at the previous foot (the last point evaluated)
        # sup of max(F'', 0) and of |F''| on the reachable range; set by Boundary.
        self.bend_bound = 0.0
        self.bend_abs_bound = 0.0

    def foot(self, x: float, s: float | None = None) -> float:
        """Abscissa s of the wall point whose offset point has abscissa x (Newton on
        X(s) = x, dX/ds = 1 - r f''/(1 + f'^2)^(3/2) > 0)."""
        df, d2f, r = self.df, self.d2f, self.r
        if s is None:
            s = x
        for _ in range(60):
            fp = df(s)
            q = 1.0 + fp * fp
            w = r / math.sqrt(q)
            ds = (s - fp * w - x) / (1.0 - d2f(s) * w / q)
            s -= ds
            if abs(ds) < _FOOT_STEP_TOL:
                return s
        raise SimulationError(f"offset-curve inversion did not converge at x = {x!r} m")

    def height(self, x: float) -> float:
        """F(x): height of the ball centre touching this wall at abscissa x."""
        s = self.foot(x, self.s)
        self.s = s
        fp = self.df(s)
        return self.f(s) + self.r / math.sqrt(1.0 + fp * fp)

    def gap_rate(self, px: float, py: float, vx: float, vy: float) -> tuple[float, float]:
        s = self.foot(px, self.s)
        self.s = s
        fp = self.df(s)
        self.slope = fp
        return py - self.f(s) - self.r / math.sqrt(1.0 + fp * fp), vy - fp * vx

    def curvature_term(self, s: float) -> float:
        """F''(X) at foot s: f''(s) / (dX/ds)."""
        fp = self.df(s)
        q = 1.0 + fp * fp
        f2 = self.d2f(s)
        return f2 / (1.0 - self.r * f2 / (q * math.sqrt(q)))

    def gap_accel(self, px: float, py: float, vx: float, vy: float, ax: float, ay: float) -> float:
        s = self.foot(px, self.s)
        self.s = s
        return ay - self.df(s) * ax - self.curvature_term(s) * vx * vx

    def contact(self, px: float) -> tuple[float, float, float]:
        s = self.foot(px, self.s)
        self.s = s
        z = math.atan(self.df(s))
        return s, z, math.cos(z)

    def max_gap_deceleration(
        self, px: float, vx: float, tau: float, ax: float, ay_down: float, ay_up: float
    ) -> float:
        # -G'' = -a_y + F'(p_x) a_x + F''(p_x) v_x^2. Over the window p_x moves by at most
        # dx from px, and |v_x| <= |v_x0| + a_x tau. The slope known is that of the last
        # point evaluated, somewhere in the window: |F'| <= |F'_last| + sup|F''| 2 dx.
        dx = abs(vx) * tau + 0.5 * ax * tau * tau
        vmax = abs(vx) + ax * tau
        return (
            ay_down
            + (abs(self.slope) + 2.0 * self.bend_abs_bound * dx) * ax
            + self.bend_bound * vmax * vmax
        )


class OffsetLine(OffsetWall):
    """Offset of a straight wall y = b x + c: the parallel line y = b x + c + r sqrt(1+b^2)."""

    def __init__(self, wall: dict, radius: float, index: int):
        super().__init__(wall, radius, index)
        b = float(self.df(0.0))
        self.b = b
        self.slope = b
        root = math.sqrt(1.0 + b * b)
        self.intercept = float(self.f(0.0)) + self.r * root
        self.shift = self.r * b / root  # foot s = X + shift
        self.z = math.atan(b)
        self.cos_z = math.cos(self.z)

    def foot(self, x: float, s: float | None = None) -> float:
        return x + self.shift

    def height(self, x: float) -> float:
        return self.b * x + self.intercept

    def gap_rate(self, px: float, py: float, vx: float, vy: float) -> tuple[float, float]:
        b = self.b
        return py - b * px - self.intercept, vy - b * vx

    def curvature_term(self, s: float) -> float:
        return 0.0

    def gap_accel(self, px: float, py: float, vx: float, vy: float, ax: float, ay: float) -> float:
        return ay - self.b * ax

    def contact(self, px: float) -> tuple[float, float, float]:
        return px + self.shift, self.z, self.cos_z

    def max_gap_deceleration(
        self, px: float, vx: float, tau: float, ax: float, ay_down: float, ay_up: float
    ) -> float:
        return ay_down + abs(self.b) * ax


class FlatLid(Surface):
    """The flat lid y = ceiling; the ball centre stays below ceiling - r. Tangent angle pi."""

    kind = "lid"

    def __init__(self, ceiling: float, radius: float):
        self.ceiling = float(ceiling)
        self.level = float(ceiling) - float(radius)
        self.label = "lid"

    def gap_rate(self, px: float, py: float, vx: float, vy: float) -> tuple[float, float]:
        return self.level - py, -vy

    def gap_accel(self, px: float, py: float, vx: float, vy: float, ax: float, ay: float) -> float:
        return -ay

    def contact(self, px: float) -> tuple[float, float, float]:
        # c2 = (0, -1) points down into the container; G' = -v_y is already the normal
        # velocity, so the factor reported is 1 (not cos(pi)).
        return px, math.pi, 1.0

    def max_gap_deceleration(
        self, px: float, vx: float, tau: float, ax: float, ay_down: float, ay_up: float
    ) -> float:
        return max(0.0, ay_up)


class EscapeLevel(FlatLid):
    """Open container: crossing y = escape_height with the centre ends the run."""

    kind = "escape"

    def __init__(self, height: float):
        self.ceiling = float(height)
        self.level = float(height)
        self.label = "escape"


class NearestPoint(tuple):
    """Euclidean nearest point of the boundary curve to a point p (boundary frame).

    A tuple ``(s, distance, z)``: the abscissa of the nearest curve point (m), the
    distance |p - (s, f(s))| (m) and the tangent angle atan f'(s) there (rad). Also has
    the attributes ``wall`` (index of the wall it lies on) and ``below`` (p lies below
    the curve, outside the container).
    """

    wall: int
    below: bool

    def __new__(cls, s: float, distance: float, z: float, wall: int, below: bool) -> NearestPoint:
        point = super().__new__(cls, (s, distance, z))
        point.wall = wall
        point.below = below
        return point

    @property
    def s(self) -> float:
        return self[0]

    @property
    def distance(self) -> float:
        return self[1]

    @property
    def z(self) -> float:
        return self[2]


def _finite(x: float) -> bool:
    return math.isfinite(x)


class Boundary:
    """The container: smooth walls (as offset curves for a ball of radius r), an optional
    lid, and the drive. Built once per run; also validates the geometry.

    Args:
        walls: wall dicts as in docs/design.md (lo, hi, f, df, d2f, near, dnear, poly).
        radius: ball radius r (m).
        drive: the boundary's motion.
        ceiling: height of a flat lid (m), or None for an open container.
        escape_height: height (m) above which a ball in an open container is lost.
        curve: the curve's name or expression, for messages.
    """

    def __init__(
        self,
        walls: Sequence[dict],
        radius: float,
        drive: Drive,
        ceiling: float | None = None,
        escape_height: float = 1.0,
        curve: str = "",
    ):
        if not walls:
            raise GeometryError("the boundary curve has no walls")
        self.walls = tuple(walls)
        self.radius = float(radius)
        self.drive = drive
        self.ceiling = None if ceiling is None else float(ceiling)
        self.escape_height = float(escape_height)
        self.top = self.ceiling if self.ceiling is not None else self.escape_height
        try:
            self.x_range = self._container_range()
            self.validate_radius()
            self.offsets: tuple[OffsetWall, ...] = tuple(
                OffsetLine(w, radius, i) if self._is_straight(w) else OffsetWall(w, radius, i)
                for i, w in enumerate(self.walls)
            )
            self._bound_offset_curvature()
        except GeometryError:
            raise
        except (ArithmeticError, ValueError, TypeError) as exc:
            raise GeometryError(_undefined_curve(self.walls, curve, exc)) from None
        self.lid: FlatLid | None = (
            FlatLid(self.ceiling, self.radius) if self.ceiling is not None else None
        )
        self.escape: EscapeLevel | None = (
            None if self.ceiling is not None else EscapeLevel(self.escape_height)
        )
        self.surfaces: tuple[Surface, ...] = self.offsets + tuple(
            s for s in (self.lid, self.escape) if s is not None
        )

    @classmethod
    def from_scene(cls, scene: Any, walls: Sequence[dict]) -> Boundary:
        return cls(
            walls,
            scene.ball.radius,
            Drive.from_scene(scene.drive),
            scene.boundary.ceiling,
            scene.boundary.escape_height,
            curve=scene.boundary.curve,
        )

    # ------------------------------------------------------------------ curve helpers

    def curve_height(self, x: float) -> float:
        """Height of the boundary curve at x: the maximum of the walls."""
        return max(w["f"](x) for w in self.walls)

    def offset_height(self, x: float) -> float:
        """Lowest admissible centre height at abscissa x: the maximum of the offsets."""
        return max(o.height(x) for o in self.offsets)

    @staticmethod
    def _is_straight(wall: dict) -> bool:
        xs = (-1.0, -0.1, -1e-3, 0.0, 1e-3, 0.1, 1.0)
        try:
            slopes = {float(wall["df"](x)) for x in xs}
            bends = [float(wall["d2f"](x)) for x in xs]
        except (ValueError, ZeroDivisionError, OverflowError):
            return False
        return len(slopes) == 1 and all(b == 0.0 for b in bends)

    def _container_range(self) -> tuple[float, float]:
        """Abscissas where the curve reaches the top (lid or escape height)."""
        top = self.top
        x0 = 0.0
        if not self.curve_height(x0) < top:
            raise GeometryError(
                f"the boundary curve at x = 0 is at {self.curve_height(0.0):.4g} m, not below "
                f"the top of the container ({top:g} m)"
            )

        def excess(x: float) -> float:
            return self.curve_height(x) - top

        ends = []
        for sign in (-1.0, 1.0):
            step = 1e-3
            while step < 1e3 and excess(sign * step) < 0.0:
                step *= 2.0
            if step >= 1e3:
                ends.append(sign * 1e3)  # effectively unbounded sideways
                continue
            lo, hi = sign * step / 2.0, sign * step
            if step == 1e-3:
                lo = x0
            for _ in range(200):  # bisection: excess(lo) < 0 <= excess(hi)
                mid = 0.5 * (lo + hi)
                if excess(mid) < 0.0:
                    lo = mid
                else:
                    hi = mid
                if abs(hi - lo) <= 1e-12:
                    break
            ends.append(hi)
        return ends[0], ends[1]

    def _wall_samples(self, wall: dict, margin: float = 0.0) -> np.ndarray:
        xl, xr = self.x_range
        lo = max(wall["lo"], xl - margin)
        hi = min(wall["hi"], xr + margin)
        if not hi > lo:
            return np.array([])
        xs = np.linspace(lo, hi, _SAMPLES)
        extra = [x for x in (0.0,) if lo <= x <= hi]
        return np.concatenate([xs, extra])

    def validate_radius(self) -> None:
        """Raise GeometryError when the ball is too large for the boundary's curvature on
        the reachable part: the contact would not be a single point."""
        r = self.radius
        worst: tuple[float, float] | None = None
        for wall in self.walls:
            for x in self._wall_samples(wall):
                f2 = float(wall["d2f"](x))
                if f2 <= 0.0:
                    continue
                fp = float(wall["df"](x))
                rho = (1.0 + fp * fp) ** 1.5 / f2
                if worst is None or rho < worst[0]:
                    worst = (rho, float(x))
        if worst is not None and r >= worst[0]:
            rho, x = worst
            span = self.x_range[1] - self.x_range[0]
            if abs(x) < 1e-9 * span:
                x = 0.0
            raise GeometryError(
                f"ball radius {r:g} m exceeds the boundary's radius of curvature "
                f"{rho:.3g} m at x = {x:.3g}: single-point contact fails"
            )

    def _bound_offset_curvature(self) -> None:
        # The offset walls are extended over the whole container (a wedge's left wall is
        # evaluated on the right too), so sample each wall over the full range.
        for off in self.offsets:
            if isinstance(off, OffsetLine):
                continue
            pos = 0.0
            absolute = 0.0
            for s in self._wall_samples(
                {"lo": -math.inf, "hi": math.inf}, margin=2.0 * self.radius
            ):
                fp = off.df(float(s))
                q = 1.0 + fp * fp
                f2 = off.d2f(float(s))
                dxds = 1.0 - self.radius * f2 / (q * math.sqrt(q))
                if dxds <= 0.0:
                    continue
                bend = f2 / dxds
                pos = max(pos, bend)
                absolute = max(absolute, abs(bend))
            off.bend_bound = _BOUND_SAFETY * pos
            off.bend_abs_bound = _BOUND_SAFETY * absolute

    @property
    def smallest_offset_radius(self) -> float:
        """Smallest radius of curvature of the offset curves (m), inf for straight walls;
        a length scale for the event locator's substeps."""
        bend = max((o.bend_bound for o in self.offsets), default=0.0)
        return math.inf if bend == 0.0 else _BOUND_SAFETY / bend

    # ------------------------------------------------------------------ rest position

    def resting_position(self) -> tuple[float, float]:
        """Lowest point (X, Y) of the admissible region in the boundary frame: the centre
        of a ball at rest touching the bottom (minimum over X of max_i F_i(X))."""
        xl, xr = self.x_range
        xs = np.linspace(xl, xr, _SAMPLES)
        hs = [self.offset_height(float(x)) for x in xs]
        k = int(np.argmin(hs))
        a = float(xs[max(k - 1, 0)])
        b = float(xs[min(k + 1, len(xs) - 1)])
        candidates = [float(xs[k])]
        # a smooth minimum of one wall: f'(s) = 0, where X = s
        for wall in self.walls:
            df, d2f = wall["df"], wall["d2f"]
            if df(a) < 0.0 < df(b):
                candidates.append(_newton_polish(df, d2f, _bisect(df, a, b)))
        # a kink between two walls: F_i(X) = F_j(X)
        for i, oi in enumerate(self.offsets):
            for oj in self.offsets[i + 1 :]:

                def diff(x: float, oi: OffsetWall = oi, oj: OffsetWall = oj) -> float:
                    return oi.height(x) - oj.height(x)

                if diff(a) * diff(b) < 0.0:
                    x = _bisect(diff, a, b)
                    # one secant polish makes a symmetric kink land on x = 0 exactly
                    d0, d1 = diff(x), diff(x + 1e-7)
                    if d1 != d0:
                        x -= d0 * 1e-7 / (d1 - d0)
                    candidates.append(x)
        best = min(candidates, key=self.offset_height)
        return best, self.offset_height(best)

    # ------------------------------------------------------------------ nearest point

    def nearest_point(self, px: float, py: float) -> NearestPoint:
        """Global Euclidean nearest point of the curve (all walls on their intervals).

        Candidates are the real roots of each wall's nearest-point polynomial (when the
        wall has one), else Newton solutions of the nearest-point condition from several
        starts, plus the finite interval ends. Not for the hot path (uses numpy.roots).
        """
        best: NearestPoint | None = None
        for i, wall in enumerate(self.walls):
            lo, hi = wall["lo"], wall["hi"]
            cands: list[float] = [e for e in (lo, hi) if _finite(e)]
            poly = wall["poly"](px, py) if wall.get("poly") is not None else None
            if poly is not None:
                coeffs = np.array([float(c) for c in poly])
                nz = np.flatnonzero(coeffs)
                coeffs = coeffs[nz[0] :] if nz.size else coeffs
                roots = np.roots(coeffs) if coeffs.size > 1 else np.array([])
                for root in roots:
                    if abs(root.imag) <= 1e-7 * (1.0 + abs(root.real)):
                        cands.append(float(root.real))
            else:
                xl, xr = self.x_range
                starts = [px] + list(np.linspace(max(lo, xl), min(hi, xr), 17))
                for s0 in starts:
                    s = _nearest_newton(wall, float(s0), px, py)
                    if s is not None:
                        cands.append(s)
            for s in cands:
                s = _nearest_newton(wall, s, px, py, polish=True) if lo < s < hi else s
                s = min(max(s, lo), hi)
                if not _finite(s):
                    continue
                fs = wall["f"](s)
                d = math.hypot(px - s, py - fs)
                if best is None or d < best.distance:
                    best = NearestPoint(s, d, math.atan(wall["df"](s)), i, False)
        assert best is not None
        return NearestPoint(best.s, best.distance, best.z, best.wall, py < self.curve_height(px))

    def clearance(self, px: float, py: float) -> float:
        """Signed clearance of a ball centred at p: Euclidean distance to the curve minus r
        (negative inside the wall), and the lid's clearance, whichever is smaller."""
        near = self.nearest_point(px, py)
        gap = (-near.distance if near.below else near.distance) - self.radius
        if self.lid is not None:
            gap = min(gap, self.lid.level - py)
        return gap

    # ------------------------------------------------------------------ validation

    def check_initial_position(self, q1: float, q2: float, theta: float) -> None:
        """Raise GeometryError when a ball centred at (q1, q2) (lab) overlaps a wall, the
        lid, or starts above the escape height."""
        px, py, _, _ = self.drive.to_boundary_frame(theta, q1, q2, 0.0, 0.0)
        where = f"initial position q1 = {q1:.6g} m, q2 = {q2:.6g} m"
        if self.lid is not None and py > self.lid.level + 1e-12:
            raise GeometryError(
                f"{where} puts the ball {py - self.lid.level:.3g} m into the lid "
                f"(ceiling = {self.ceiling:g} m)"
            )
        if self.escape is not None and py >= self.escape.level:
            raise GeometryError(f"{where} is above escape_height = {self.escape_height:g} m")
        worst = min(o.gap_rate(px, py, 0.0, 0.0)[0] for o in self.offsets)
        if worst < -1e-12:
            near = self.nearest_point(px, py)
            depth = self.radius + near.distance if near.below else self.radius - near.distance
            raise GeometryError(f"{where} puts the ball {depth:.3g} m into the wall")


def _undefined_curve(walls: Sequence[dict], curve: str, exc: BaseException) -> str:
    """One line for a curve that cannot be evaluated where the ball can go: the first x,
    walking outward from 0, where a wall's height or derivatives are not real and finite."""
    name = f"boundary curve {curve!r}" if curve else "the boundary curve"
    xs = [0.0]
    for e in range(-48, 25):  # 1e-6 m ... 1e3 m, 8 points per factor of ten
        xs += [-(10.0 ** (e / 8)), 10.0 ** (e / 8)]
    for x in xs:
        for wall in walls:
            for key in ("f", "df", "d2f"):
                try:
                    value = wall[key](x)
                    ok = isinstance(value, (int, float)) and math.isfinite(value)
                except (ArithmeticError, ValueError, TypeError):
                    ok = False
                if not ok:
                    return (
                        f"{name} is not real and finite at x = {x:.6g} m, where the ball can "
                        "go (check its expression and parameters)"
                    )
    detail = " ".join(str(exc).split()) or type(exc).__name__
    return f"{name} cannot be evaluated where the ball can go: {detail}"


def _bisect(fn: Callable[[float], float], a: float, b: float) -> float:
    fa = fn(a)
    for _ in range(200):
        m = 0.5 * (a + b)
        fm = fn(m)
        if (fm < 0.0) == (fa < 0.0):
            a, fa = m, fm
        else:
            b = m
        if b - a <= 1e-15 * max(1.0, abs(a)):
            break
    return 0.5 * (a + b)


def _newton_polish(fn: Callable[[float], float], dfn: Callable[[float], float], x: float) -> float:
    for _ in range(20):
        d = dfn(x)
        if d == 0.0:
            break
        step = fn(x) / d
        x -= step
        if step == 0.0 or abs(step) < 1e-300:
            break
    return x


def _nearest_newton(
    wall: dict, s: float, px: float, py: float, polish: bool = False
) -> float | None:
    """Newton on the nearest-point condition g(s) = (s - px) + (f(s) - py) f'(s) = 0.

    Returns None when it meets g' <= 0 (a maximum of the distance nearby) or does not
    converge; with polish=True it returns the start point in those cases instead.
    """
    near, dnear = wall["near"], wall["dnear"]
    s0 = s
    for _ in range(50):
        d = dnear(s, px, py)
        if not d > 0.0:
            return s0 if polish else None
        step = near(s, px, py) / d
        s -= step
        if not _finite(s):
            return s0 if polish else None
        if abs(step) <= 1e-15 * (1.0 + abs(s)):
            return s
    return s if polish else None
