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
from collections.abc import Sequence

from billiard.geometry.walls import Wall
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.interpreted import surfaces as _surfaces
from billiard.kernels.names import (
    put_warm_s,
    read_surface,
    surface_constants,
    surface_ctx,
    warm_start,
    write_surface,
    write_surface_slots,
)

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

offset_stretch = _surfaces.offset_stretch
offset_curvature = _surfaces.offset_curvature

# a surface keeps its block in its own ctx as the kernels' surface 0
_KernelError = _L.KernelError
_gap_rate = _surfaces.gap_rate
_gap_accel = _surfaces.gap_accel
_contact = _surfaces.contact
_max_gap_deceleration = _surfaces.max_gap_deceleration
_offset_height = _surfaces.offset_height


class Surface:
    """A surface the ball centre must stay on the positive side of (gap G >= 0).

    ``gap_rate(px, py, vx, vy, warm)`` returns (G, dG/dt) for a centre at p moving with
    velocity v relative to the boundary; ``gap_accel`` returns d2G/dt2 for a relative
    acceleration a. ``max_gap_deceleration`` bounds -d2G/dtau2 over a window of length
    tau, given bounds on the relative acceleration; the event locator uses it to skip
    stretches of flight that provably cannot touch this surface.

    The arithmetic is the kernels' (:mod:`billiard.kernels.surfaces`, run interpreted):
    a surface keeps its constants as the kernels' block of surface 0 in ``ctx`` (a list
    of floats; :meth:`block` gives them to the event locator's state vector), and the
    warm start passed in is copied into that block and back around a call.
    """

    label: str = ""
    kind: str = "wall"
    #: the curve's parameters and wall functions, as the kernels take them
    _p: tuple = ()
    _walls: tuple = ((), (), ())

    def _new_ctx(self, kind: float) -> list[float]:
        ctx = surface_ctx(1)
        write_surface(ctx, 0, kind=kind, slope_at=math.nan)  # no slope memo
        self.ctx = ctx
        return ctx

    def block(self) -> list[float]:
        """The constants of this surface's block of the kernels' state vector (the
        slots before the warm start), without a slope memo: the memo's value stays in
        this ctx (and a block may be given to another surface's slot)."""
        return surface_constants(self.ctx, 0, slope_at=math.nan)

    def initial_warm(self) -> WarmStart:
        """A fresh warm start ``[s, slope]`` for this surface."""
        return [0.0, 0.0]

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        return _gap_rate(self.ctx, self._p, self._walls, 0, px, py, vx, vy)

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        return _gap_accel(self.ctx, self._p, self._walls, 0, px, py, vx, vy, ax, ay)

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
        ctx = self.ctx
        write_surface(ctx, 0, warm_slope=warm[1])
        return _max_gap_deceleration(ctx, 0, px, vx, tau, ax, ay_down, ay_up)


class OffsetWall(Surface):
    """Offset curve of one smooth, curved wall: gap, its rates and curvature bounds.

    Args:
        wall: the wall's functions and parameters (:class:`billiard.geometry.walls.Wall`).
        radius: the ball's radius r (m).
        index: the wall's number, also its label in records.
        bend_bound, bend_abs_bound: sup of max(F'', 0) and of |F''| (1/m) over the
            reachable range, set by :class:`billiard.geometry.boundary.Boundary`.
    """

    def __init__(
        self, wall: Wall, radius: float, index: int, bend_bound: float = 0.0,
        bend_abs_bound: float = 0.0, chain: Sequence[Wall] = (),
    ):  # fmt: skip
        ctx = self._bind(wall, radius, index, _L.CURVED)
        write_surface(ctx, 0, a=self.r)
        self.bend_bound = bend_bound
        self.bend_abs_bound = bend_abs_bound
        if len(chain) > 1:
            #: the walls joined smoothly into this one surface (``wall`` first), in order
            self.chain = tuple(chain)
            self._chain(ctx)

    def _chain(self, ctx: list[float]) -> None:
        """A chain of walls: its own ctx indexes them as the engine does, by their index
        in the curve (the functions of walls outside the chain are never called)."""
        chain = self.chain
        if len(chain) > _L.MAX_CHAIN:
            raise ValueError(
                f"{len(chain)} walls joined smoothly in a row; at most {_L.MAX_CHAIN} are supported"
            )
        first, last = chain[0].index, chain[-1].index
        table = {w.index: w for w in chain}
        self._walls = tuple(
            tuple(getattr(table.get(i, chain[0]), name) for i in range(last + 1))
            for name in ("f", "df", "d2f")
        )
        self.lo, self.hi = chain[0].lo, chain[-1].hi
        write_surface(ctx, 0, wall=float(first), first_wall=float(first), last_wall=float(last))
        write_surface_slots(ctx, 0, "joins", [w.hi for w in chain[:-1]])

    def _bind(self, wall: Wall, radius: float, index: int, kind: float) -> list[float]:
        self.wall = wall
        self.p = wall.p
        self.f, self.df, self.d2f = wall.f, wall.df, wall.d2f
        self.lo, self.hi = wall.lo, wall.hi
        self.r = float(radius)
        self.index = index
        self.label = str(index)
        #: the ``wall`` column of an impact on this surface: the wall's index
        self.code = index
        self._p = wall.p
        self._walls = ((wall.f,), (wall.df,), (wall.d2f,))
        self.chain = (wall,)
        return self._new_ctx(kind)

    def block(self) -> list[float]:
        # in the locator's state vector, the wall's place in the curve's wall functions
        # (in the surface's own ctx, the only one: 0; a chain's own ctx has the curve's)
        if len(self.chain) > 1:
            return surface_constants(self.ctx, 0, slope_at=math.nan)
        return surface_constants(self.ctx, 0, slope_at=math.nan, wall=float(self.index))

    def piece(self, s: float) -> Wall:
        """The wall of the chain holding s (the lower at a join)."""
        for wall in self.chain[:-1]:
            if s <= wall.hi:
                return wall
        return self.chain[-1]

    @property
    def bend_bound(self) -> float:
        """sup of max(F'', 0) over the reachable range (1/m)."""
        return read_surface(self.ctx, 0, "b")

    @bend_bound.setter
    def bend_bound(self, value: float) -> None:
        write_surface(self.ctx, 0, b=value)

    @property
    def bend_abs_bound(self) -> float:
        """sup of |F''| over the reachable range (1/m)."""
        return read_surface(self.ctx, 0, "c")

    @bend_abs_bound.setter
    def bend_abs_bound(self, value: float) -> None:
        write_surface(self.ctx, 0, c=value)

    def foot(self, x: float, s: float) -> float:
        """Abscissa s of the wall point whose offset point has abscissa x (Newton on
        X(s) = x from the start s, dX/ds = 1 - r f''/(1 + f'^2)^(3/2) > 0)."""
        try:
            return _surfaces.foot(self.ctx, self._p, self._walls, _L.SURF, x, s, math.nan)
        except _KernelError as exc:
            raise _stop(exc, self.ctx) from None

    def height(self, x: float, warm: WarmStart) -> float:
        """F(x): height of the ball centre touching this wall at abscissa x (m)."""
        ctx = self.ctx
        put_warm_s(ctx, 0, warm[0])
        try:
            height = _offset_height(ctx, self._p, self._walls, 0, x)
        except _KernelError as exc:
            raise _stop(exc, ctx) from None
        warm[0] = warm_start(ctx, 0)[0]
        return height

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        ctx = self.ctx
        put_warm_s(ctx, 0, warm[0])
        try:
            gap = _gap_rate(ctx, self._p, self._walls, 0, px, py, vx, vy)
        except _KernelError as exc:
            raise _stop(exc, ctx) from None
        warm[0], warm[1] = warm_start(ctx, 0)
        return gap

    def curvature_term(self, s: float) -> float:
        """F''(X) at foot s: f''(s) / (dX/ds) (1/m)."""
        wall = self.piece(s)
        return offset_curvature(wall.df(s, self.p), wall.d2f(s, self.p), self.r)

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        ctx = self.ctx
        put_warm_s(ctx, 0, warm[0])
        try:
            accel = _gap_accel(ctx, self._p, self._walls, 0, px, py, vx, vy, ax, ay)
        except _KernelError as exc:
            raise _stop(exc, ctx) from None
        warm[0] = warm_start(ctx, 0)[0]
        return accel

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        ctx = self.ctx
        put_warm_s(ctx, 0, warm[0])
        try:
            s, z = _contact(ctx, self._p, self._walls, 0, px)
        except _KernelError as exc:
            raise _stop(exc, ctx) from None
        warm[0] = s
        return s, z, math.cos(z)


class OffsetLine(OffsetWall):
    """Offset of a straight wall y = b x + c: the parallel line y = b x + c + r sqrt(1+b^2)."""

    # a straight wall does not bend (its block holds the line's constants instead)
    bend_bound = 0.0
    bend_abs_bound = 0.0

    def __init__(self, wall: Wall, radius: float, index: int):
        ctx = self._bind(wall, radius, index, _L.LINE)
        b = float(self.df(0.0, self.p))
        self.b = b
        root = math.sqrt(1.0 + b * b)
        self.intercept = float(self.f(0.0, self.p)) + self.r * root
        self.shift = self.r * b / root  # foot s = X + shift
        self.z = math.atan(b)
        self.cos_z = math.cos(self.z)
        write_surface(ctx, 0, a=b, b=self.intercept, c=self.shift, d=self.z)

    def initial_warm(self) -> WarmStart:
        return [0.0, self.b]

    def foot(self, x: float, s: float) -> float:
        return x + self.shift

    def height(self, x: float, warm: WarmStart) -> float:
        return _offset_height(self.ctx, self._p, self._walls, 0, x)

    def gap_rate(
        self, px: float, py: float, vx: float, vy: float, warm: WarmStart
    ) -> tuple[float, float]:
        return _gap_rate(self.ctx, self._p, self._walls, 0, px, py, vx, vy)

    def curvature_term(self, s: float) -> float:
        return 0.0

    def gap_accel(
        self, px: float, py: float, vx: float, vy: float, ax: float, ay: float, warm: WarmStart
    ) -> float:
        return _gap_accel(self.ctx, self._p, self._walls, 0, px, py, vx, vy, ax, ay)

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        s, z = _contact(self.ctx, self._p, self._walls, 0, px)
        return s, z, self.cos_z


class FlatLid(Surface):
    """The flat lid y = ceiling; the ball centre stays below ceiling - r. Tangent angle pi."""

    kind = "lid"

    def __init__(self, ceiling: float, radius: float):
        self.ceiling = float(ceiling)
        self.level = float(ceiling) - float(radius)
        self.label = "lid"
        #: the ``wall`` column of an impact on the lid (walls count from 0)
        self.code = int(_L.LID_LABEL)
        write_surface(self._new_ctx(_L.LID), 0, a=self.level)

    def contact(self, px: float, warm: WarmStart) -> tuple[float, float, float]:
        # c2 = (0, -1) points down into the container; G' = -v_y is already the normal
        # velocity, so the factor reported is 1 (not cos(pi)).
        s, z = _contact(self.ctx, self._p, self._walls, 0, px)
        return s, z, 1.0


class EscapeLevel(FlatLid):
    """Open container: crossing y = escape_height with the centre ends the run."""

    kind = "escape"

    def __init__(self, height: float):
        self.ceiling = float(height)
        self.level = float(height)
        self.label = "escape"
        write_surface(self._new_ctx(_L.ESCAPE), 0, a=self.level)
