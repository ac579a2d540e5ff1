"""The container: the boundary's walls as offset-curve surfaces for a ball of radius r,
the lid or escape level, and the drive; the rest position, the global nearest point,
and the checks of a scene's geometry.

All geometry is done in the boundary frame B, where the wall is the fixed curve
y = f(x) and the ball centre is p = q - D(t) e_drive (see :mod:`billiard.geometry.drive`). A
curve with kinks is the maximum of its walls, so the container is the intersection of
the regions above the (extended) walls and the ball is inside exactly when every wall's
gap is >= 0 (see :mod:`billiard.geometry.surfaces`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.derivation.shape import chain_problem
from billiard.errors import GeometryError
from billiard.geometry.drive import Drive
from billiard.geometry.surfaces import (
    EscapeLevel,
    FlatLid,
    OffsetLine,
    OffsetWall,
    Surface,
    WarmStart,
    offset_stretch,
)
from billiard.geometry.wall_functions import plain_wall_functions
from billiard.geometry.walls import Wall, curve_height, nearest_newton
from billiard.kernels.interpreted import kernel_errors
from billiard.kernels.interpreted import rest as _rest
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.names import (
    put_surface_block,
    put_warm_s,
    read_surface,
    surface_block,
    surface_ctx,
    warm_start,
    write_surface,
)

__all__ = ["Boundary", "Drive", "NearestPoint"]

# Curvature bounds sampled on a grid are enlarged by this factor to cover the gaps between
# the samples (they feed rigorous-by-construction no-contact time bounds).
_BOUND_SAFETY = 1.25
_SAMPLES = 4001


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
        walls: the curve's walls (:class:`billiard.geometry.walls.Wall`).
        radius: ball radius r (m).
        drive: the boundary's motion.
        ceiling: height of a flat lid (m), or None for an open container.
        escape_height: height (m) above which a ball in an open container is lost.
        curve: the curve's name or expression, for messages.
    """

    def __init__(
        self,
        walls: Sequence[Wall],
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
            self._check_joins(curve)
            self.validate_radius()
            #: the walls in chains joined smoothly (a wall alone between kinks: its own)
            self.chains = _chains(self.walls)
            self.offsets: tuple[OffsetWall, ...] = tuple(
                OffsetLine(c[0], radius, c[0].index)
                if len(c) == 1 and self._is_straight(c[0])
                else OffsetWall(c[0], radius, c[0].index, chain=c)
                for c in self.chains
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
    def from_scene(cls, scene: Any, walls: Sequence[Wall]) -> Boundary:
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
        """Height of the boundary curve at x: that of the wall holding x."""
        return curve_height(self.walls, x)

    def initial_warm(self) -> list[WarmStart]:
        """Fresh warm starts of the offset inversion, one per surface (the engine keeps
        them in its state; see :mod:`billiard.geometry.surfaces`)."""
        return [surface.initial_warm() for surface in self.surfaces]

    def offset_height(self, x: float, warm: list[WarmStart] | None = None) -> float:
        """Lowest admissible centre height at abscissa x (m): the maximum of the offsets.
        ``warm``: the warm starts to use and update (default: fresh ones)."""
        warm = self.initial_warm() if warm is None else warm
        return max(o.height(x, warm[i]) for i, o in enumerate(self.offsets))

    @staticmethod
    def _is_straight(wall: Wall) -> bool:
        xs = (-1.0, -0.1, -1e-3, 0.0, 1e-3, 0.1, 1.0)
        try:
            slopes = {float(wall.df(x, wall.p)) for x in xs}
            bends = [float(wall.d2f(x, wall.p)) for x in xs]
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

    def _wall_samples(
        self, lo: float = -math.inf, hi: float = math.inf, margin: float = 0.0
    ) -> np.ndarray:
        xl, xr = self.x_range
        lo = max(lo, xl - margin)
        hi = min(hi, xr + margin)
        if not hi > lo:
            return np.array([])
        xs = np.linspace(lo, hi, _SAMPLES)
        extra = [x for x in (0.0,) if lo <= x <= hi]
        return np.concatenate([xs, extra])

    def _check_joins(self, curve: str) -> None:
        """Raise GeometryError where the maximum of the walls is not the curve on the
        container's range (a smooth join, or parameters that put another piece's formula
        on top): the runtime would simulate that maximum, another curve, without a word.
        Checked here, where the parameters' values and the container are known."""
        if len(self.walls) < 2:
            return
        problem = chain_problem(
            [
                {
                    "lo": w.lo,
                    "hi": w.hi,
                    "f": lambda x, w=w: w.f(x, w.p),
                    "df": lambda x, w=w: w.df(x, w.p),
                    "d2f": lambda x, w=w: w.d2f(x, w.p),
                    "smooth_hi": w.smooth_hi,
                }
                for w in self.walls
            ],
            (float(x) for x in self._wall_samples()),
        )
        if problem is not None:
            raise GeometryError(f"{_curve_name(curve)}: {problem}")

    def validate_radius(self) -> None:
        """Raise GeometryError when the ball is too large for the boundary's curvature on
        the reachable part: the contact would not be a single point."""
        r = self.radius
        worst: tuple[float, float] | None = None
        for wall in self.walls:
            for x in self._wall_samples(wall.lo, wall.hi):
                f2 = float(wall.d2f(x, wall.p))
                if f2 <= 0.0:
                    continue
                fp = float(wall.df(x, wall.p))
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
            for s in self._wall_samples(margin=2.0 * self.radius):
                # a chain: the wall holding s (its end walls continued past its ends)
                wall = off.piece(float(s))
                fp = wall.df(float(s), off.p)
                f2 = wall.d2f(float(s), off.p)
                dxds = offset_stretch(fp, f2, self.radius)
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

    def resting_position(self, warm: list[WarmStart] | None = None) -> tuple[float, float]:
        """Lowest point (X, Y) of the admissible region in the boundary frame: the centre
        of a ball at rest touching the bottom (minimum over X of max_i F_i(X))."""
        warm = self.initial_warm() if warm is None else warm
        xl, xr = self.x_range
        xs = np.linspace(xl, xr, _SAMPLES)
        hs = self._offset_heights(xs, warm)
        k = int(np.argmin(hs))
        a = float(xs[max(k - 1, 0)])
        b = float(xs[min(k + 1, len(xs) - 1)])
        candidates = [float(xs[k])]
        # a smooth minimum of one wall: f'(s) = 0, where X = s
        for wall in self.walls:

            def df(x: float, wall: Wall = wall) -> float:
                return wall.df(x, wall.p)

            def d2f(x: float, wall: Wall = wall) -> float:
                return wall.d2f(x, wall.p)

            if df(a) < 0.0 < df(b):
                candidates.append(_newton_polish(df, d2f, _bisect(df, a, b)))
        # a kink between two walls: F_i(X) = F_j(X)
        for i, oi in enumerate(self.offsets):
            for j in range(i + 1, len(self.offsets)):
                oj = self.offsets[j]

                def diff(
                    x: float,
                    oi: OffsetWall = oi,
                    oj: OffsetWall = oj,
                    wi: WarmStart = warm[i],
                    wj: WarmStart = warm[j],
                ) -> float:
                    return oi.height(x, wi) - oj.height(x, wj)

                if diff(a) * diff(b) < 0.0:
                    x = _bisect(diff, a, b)
                    # one secant polish makes a symmetric kink land on x = 0 exactly
                    d0, d1 = diff(x), diff(x + 1e-7)
                    if d1 != d0:
                        x -= d0 * 1e-7 / (d1 - d0)
                    candidates.append(x)
        best = min(candidates, key=lambda x: self.offset_height(x, warm))
        return best, self.offset_height(best, warm)

    def _offset_heights(self, xs: np.ndarray, warm: list[WarmStart]) -> Sequence[float]:
        """:meth:`offset_height` at each abscissa of ``xs`` in turn, the warm starts
        carried from one to the next and left where the last one put them: the scan of
        :func:`billiard.kernels.rest.offset_heights`, compiled when the kernels are."""
        ps = [offset.p for offset in self.offsets]
        if any(p != ps[0] for p in ps):
            # the kernels take one parameter array for all walls (a curve's walls share it)
            return [self.offset_height(float(x), warm) for x in xs]
        ctx = surface_ctx(len(self.offsets))
        for j, offset in enumerate(self.offsets):
            # each surface's own block (its surface 0), as block j (a chain's own block
            # names its walls as the curve does)
            put_surface_block(ctx, j, surface_block(offset.ctx, 0))
            wall = read_surface(offset.ctx, 0, "wall") if len(offset.chain) > 1 else j
            write_surface(ctx, j, wall=float(wall), warm_s=warm[j][0])
        try:
            if _jit.ENABLED:
                from billiard.geometry.wall_functions import WallFunction, WallTable
                from billiard.kernels.rest import offset_heights

                walls = WallTable(
                    tuple(WallFunction(getattr(w, name)) for w in self.walls)
                    for name in ("f", "df", "d2f")
                )
                state = np.array(ctx, dtype=np.float64)
                out = np.empty(len(xs), dtype=np.float64)
                p = np.array(ps[0], dtype=np.float64)
                try:
                    # once per scene: its call may compile, within the compile notices
                    with _jit.compiling(offset_heights):
                        offset_heights(state, p, walls, len(self.offsets), xs, out)
                finally:
                    ctx = state.tolist()
                heights: Sequence[float] = out
            else:
                heights = [0.0] * len(xs)
                walls = plain_wall_functions(self.walls)
                _rest.offset_heights(ctx, ps[0], walls, len(self.offsets), xs.tolist(), heights)
        except kernel_errors() as exc:
            raise _stop(exc, ctx) from None
        for j, offset in enumerate(self.offsets):
            if isinstance(offset, OffsetLine):
                continue
            # where the surface's own calls would have left its warm start
            warm[j][0] = warm_start(ctx, j)[0]
            put_warm_s(offset.ctx, 0, warm[j][0])
            if len(offset.chain) > 1:
                write_surface(offset.ctx, 0, wall=read_surface(ctx, j, "wall"))
        return heights

    # ------------------------------------------------------------------ nearest point

    def nearest_point(self, px: float, py: float) -> NearestPoint:
        """Global Euclidean nearest point of the curve (all walls on their intervals).

        Candidates are the real roots of each wall's nearest-point polynomial (when the
        wall has one), else Newton solutions of the nearest-point condition from several
        starts, plus the finite interval ends. Not for the hot path (uses numpy.roots).
        """
        best: NearestPoint | None = None
        for i, wall in enumerate(self.walls):
            lo, hi = wall.lo, wall.hi
            cands: list[float] = [e for e in (lo, hi) if _finite(e)]
            poly = wall.poly(px, py, wall.p) if wall.poly is not None else None
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
                    s, converged = nearest_newton(wall, float(s0), px, py)
                    if converged:
                        cands.append(s)
            for s in cands:
                if lo < s < hi:
                    polished, _ = nearest_newton(wall, s, px, py)
                    s = s if polished is None else polished
                s = min(max(s, lo), hi)
                if not _finite(s):
                    continue
                fs = wall.f(s, wall.p)
                dx, dy = px - s, py - fs
                d = math.sqrt(dx * dx + dy * dy)
                if best is None or d < best.distance:
                    best = NearestPoint(s, d, math.atan(wall.df(s, wall.p)), i, False)
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

    def check_initial_position(
        self, q1: float, q2: float, theta: float, warm: list[WarmStart] | None = None
    ) -> None:
        """Raise GeometryError when a ball centred at (q1, q2) (lab) overlaps a wall, the
        lid, or starts above the escape height."""
        warm = self.initial_warm() if warm is None else warm
        px, py, _, _ = self.drive.to_boundary_frame(theta, q1, q2, 0.0, 0.0)
        where = f"initial position q1 = {q1:.6g} m, q2 = {q2:.6g} m"
        if self.lid is not None and py > self.lid.level + 1e-12:
            raise GeometryError(
                f"{where} puts the ball {py - self.lid.level:.3g} m into the lid "
                f"(ceiling = {self.ceiling:g} m)"
            )
        if self.escape is not None and py >= self.escape.level:
            raise GeometryError(f"{where} is above escape_height = {self.escape_height:g} m")
        worst = min(o.gap_rate(px, py, 0.0, 0.0, warm[i])[0] for i, o in enumerate(self.offsets))
        if worst < -1e-12:
            near = self.nearest_point(px, py)
            depth = self.radius + near.distance if near.below else self.radius - near.distance
            raise GeometryError(f"{where} puts the ball {depth:.3g} m into the wall")


def _chains(walls: Sequence[Wall]) -> tuple[tuple[Wall, ...], ...]:
    """The walls in runs joined smoothly (``Wall.smooth_hi``): one surface each."""
    chains: list[list[Wall]] = []
    for wall in walls:
        if chains and chains[-1][-1].smooth_hi:
            chains[-1].append(wall)
        else:
            chains.append([wall])
    return tuple(tuple(chain) for chain in chains)


def _curve_name(curve: str) -> str:
    return f"boundary curve {curve!r}" if curve else "the boundary curve"


def _undefined_curve(walls: Sequence[dict], curve: str, exc: BaseException) -> str:
    """One line for a curve that cannot be evaluated where the ball can go: the first x,
    walking outward from 0, where a wall's height or derivatives are not real and finite."""
    name = _curve_name(curve)
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
