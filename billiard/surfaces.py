"""The surfaces a ball centre must stay on the positive side of: the offset curve of each
wall, the lid, and the escape level of an open container (all in the boundary's frame).

Contact is detected with the *offset curve* of each smooth wall: the locus of the ball
centre when the ball touches the wall,

    X(s) = s - r f'(s) / sqrt(1 + f'(s)^2),    Y(s) = f(s) + r / sqrt(1 + f'(s)^2).

While r times the curvature stays below 1, X(s) is increasing, so the offset curve is a
graph Y = F(X) with F'(X) = f'(s) (it runs parallel to the wall). The vertical gap
G = p_y - F(p_x) then has the sign of the true clearance (distance minus r), is smooth
in time along a flight, and costs one short Newton solve, whereas the Euclidean distance
needs the global nearest point of the curve.

The surfaces hold no state: every query that inverts the offset curve takes ``warm``,
the caller's warm start of that surface, a list ``[s, slope]`` (the foot of the last
point evaluated, where Newton starts next, and the slope there, which the time bound
uses), and updates it in place. The engine keeps one per surface in its state, so that a
checkpoint holds them and a resumed run repeats the same floating-point operations.
"""

from __future__ import annotations

import math

from billiard.errors import SimulationError
from billiard.walls import Wall

__all__ = [
    "EscapeLevel",
    "FlatLid",
    "OffsetLine",
    "OffsetWall",
    "Surface",
    "WarmStart",
    "offset_curvature",
    "offset_stretch",
]

#: a surface's warm start, ``[s, slope]`` (m, dimensionless)
WarmStart = list

# Newton on the offset inversion stops once a step is below this (m); the error left after
# that step is of order curvature * step^2, far below a double's resolution.
_FOOT_STEP_TOL = 1e-11


class Surface:
    """A surface the ball centre must stay on the positive side of (gap G >= 0).

    ``gap_rate(px, py, vx, vy, warm)`` returns (G, dG/dt) for a centre at p moving with
    velocity v relative to the boundary; ``gap_accel`` returns d2G/dt2 for a relative
    acceleration a. ``max_gap_deceleration`` bounds -d2G/dtau2 over a window of length
    tau, given bounds on the relative acceleration; the event locator uses it to skip
    stretches of flight that provably cannot touch this surface.
    """

    label: str = ""
    kind: str = "wall"

    def initial_warm(self) -> WarmStart:
        """A fresh warm start ``[s, slope]`` for this surface."""
        return [0.0, 0.0]

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        raise NotImplementedError

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        raise NotImplementedError

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        """(s, z, cos z) of the contact point for a ball centre at abscissa px on the
        offset curve: s is the contact point's abscissa on the boundary, z the tangent
        angle there. ``dG/dt * cos z`` is the relative normal velocity along c2."""
        raise NotImplementedError

    def max_gap_deceleration(
        self,
        px: float,
        vx: float,
        tau: float,
        ax: float,
        ay_down: float,
        ay_up: float,
        warm: WarmStart,
    ) -> float:
        raise NotImplementedError


class OffsetWall(Surface):
    """Offset curve of one smooth, curved wall: gap, its rates and curvature bounds.

    Args:
        wall: the wall's functions and parameters (:class:`billiard.walls.Wall`).
        radius: the ball's radius r (m).
        index: the wall's number, also its label in records.
        bend_bound, bend_abs_bound: sup of max(F'', 0) and of |F''| (1/m) over the
            reachable range, set by :class:`billiard.boundary.Boundary`.
    """

    def __init__(
        self, wall: Wall, radius: float, index: int, bend_bound: float = 0.0,
        bend_abs_bound: float = 0.0,
    ):  # fmt: skip
        self.wall = wall
        self.p = wall.p
        self.f, self.df, self.d2f = wall.f, wall.df, wall.d2f
        self.lo, self.hi = wall.lo, wall.hi
        self.r = float(radius)
        self.index = index
        self.label = str(index)
        self.bend_bound = bend_bound
        self.bend_abs_bound = bend_abs_bound

    def foot(self, x: float, s: float) -> float:
        """Abscissa s of the wall point whose offset point has abscissa x (Newton on
        X(s) = x from the start s, dX/ds = 1 - r f''/(1 + f'^2)^(3/2) > 0)."""
        df, d2f, r, p = self.df, self.d2f, self.r, self.p
        for _ in range(60):
            fp = df(s, p)
            q = 1.0 + fp * fp
            w = r / math.sqrt(q)
            ds = (s - fp * w - x) / (1.0 - d2f(s, p) * w / q)
            s -= ds
            if abs(ds) < _FOOT_STEP_TOL:
                return s
        raise SimulationError(f"offset-curve inversion did not converge at x = {x!r} m")

    def height(self, x: float, warm: WarmStart) -> float:
        """F(x): height of the ball centre touching this wall at abscissa x (m)."""
        s = self.foot(x, warm[0])
        warm[0] = s
        fp = self.df(s, self.p)
        return self.f(s, self.p) + self.r / math.sqrt(1.0 + fp * fp)

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        p = self.p
        s = self.foot(px, warm[0])
        fp = self.df(s, p)
        warm[0], warm[1] = s, fp
        return py - self.f(s, p) - self.r / math.sqrt(1.0 + fp * fp), vy - fp * vx

    def curvature_term(self, s: float) -> float:
        """F''(X) at foot s: f''(s) / (dX/ds) (1/m)."""
        return offset_curvature(self.df(s, self.p), self.d2f(s, self.p), self.r)

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        s = self.foot(px, warm[0])
        warm[0] = s
        return ay - self.df(s, self.p) * ax - self.curvature_term(s) * vx * vx

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        s = self.foot(px, warm[0])
        warm[0] = s
        z = math.atan(self.df(s, self.p))
        return s, z, math.cos(z)

    def max_gap_deceleration(
        self,
        px: float,
        vx: float,
        tau: float,
        ax: float,
        ay_down: float,
        ay_up: float,
        warm: WarmStart,
    ) -> float:
        # -G'' = -a_y + F'(p_x) a_x + F''(p_x) v_x^2. Over the window p_x moves by at most
        # dx from px, and |v_x| <= |v_x0| + a_x tau. The slope known is that of the last
        # point evaluated, somewhere in the window: |F'| <= |F'_last| + sup|F''| 2 dx.
        dx = abs(vx) * tau + 0.5 * ax * tau * tau
        vmax = abs(vx) + ax * tau
        return (
            ay_down
            + (abs(warm[1]) + 2.0 * self.bend_abs_bound * dx) * ax
            + self.bend_bound * vmax * vmax
        )


def offset_stretch(fp: float, f2: float, r: float) -> float:
    """dX/ds = 1 - r f''/(1 + f'^2)^(3/2) of the offset curve at a wall point with slope
    ``fp`` and second derivative ``f2`` (1/m), ball radius r (m): positive while the ball
    fits the curvature. The one place this formula is written."""
    q = 1.0 + fp * fp
    return 1.0 - r * f2 / (q * math.sqrt(q))


def offset_curvature(fp: float, f2: float, r: float) -> float:
    """Curvature term F''(X) = f'' / (dX/ds) of the offset curve (1/m)."""
    return f2 / offset_stretch(fp, f2, r)


class OffsetLine(OffsetWall):
    """Offset of a straight wall y = b x + c: the parallel line y = b x + c + r sqrt(1+b^2)."""

    def __init__(self, wall: Wall, radius: float, index: int):
        super().__init__(wall, radius, index)
        b = float(self.df(0.0, self.p))
        self.b = b
        root = math.sqrt(1.0 + b * b)
        self.intercept = float(self.f(0.0, self.p)) + self.r * root
        self.shift = self.r * b / root  # foot s = X + shift
        self.z = math.atan(b)
        self.cos_z = math.cos(self.z)

    def initial_warm(self) -> WarmStart:
        return [0.0, self.b]

    def foot(self, x: float, s: float) -> float:
        return x + self.shift

    def height(self, x: float, warm: WarmStart) -> float:
        return self.b * x + self.intercept

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        b = self.b
        return py - b * px - self.intercept, vy - b * vx

    def curvature_term(self, s: float) -> float:
        return 0.0

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        return ay - self.b * ax

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        return px + self.shift, self.z, self.cos_z

    def max_gap_deceleration(
        self,
        px: float,
        vx: float,
        tau: float,
        ax: float,
        ay_down: float,
        ay_up: float,
        warm: WarmStart,
    ) -> float:
        return ay_down + abs(self.b) * ax


class FlatLid(Surface):
    """The flat lid y = ceiling; the ball centre stays below ceiling - r. Tangent angle pi."""

    kind = "lid"

    def __init__(self, ceiling: float, radius: float):
        self.ceiling = float(ceiling)
        self.level = float(ceiling) - float(radius)
        self.label = "lid"

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        return self.level - py, -vy

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        return -ay

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        # c2 = (0, -1) points down into the container; G' = -v_y is already the normal
        # velocity, so the factor reported is 1 (not cos(pi)).
        return px, math.pi, 1.0

    def max_gap_deceleration(
        self,
        px: float,
        vx: float,
        tau: float,
        ax: float,
        ay_down: float,
        ay_up: float,
        warm: WarmStart,
    ) -> float:
        return max(0.0, ay_up)


class EscapeLevel(FlatLid):
    """Open container: crossing y = escape_height with the centre ends the run."""

    kind = "escape"

    def __init__(self, height: float):
        self.ceiling = float(height)
        self.level = float(height)
        self.label = "escape"
