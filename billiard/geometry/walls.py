"""A wall: one smooth piece of a boundary curve, as plain generated functions and the
parameter array they take (no closures, so compiled code can take the same data).

The generated curve modules (``billiard.generated.curves.*`` and the user's curves) list
their walls in ``WALLS``; :func:`billiard.geometry.curves.load_curve` binds the parameters into
:class:`Wall` objects. Every function takes the parameter array ``p`` last:
``wall.f(x, wall.p)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

__all__ = ["CURVE_FORMAT", "Wall", "curve_height"]

#: The layout of generated curve modules this runtime reads (their ``FORMAT``).
CURVE_FORMAT = 7

Params = tuple[float, ...]


@dataclass(frozen=True, slots=True)
class Wall:
    """One smooth wall of the boundary curve, valid for x in [lo, hi]: the curve's height
    at x is that of the wall holding x. A wall ending at a kink is extended smoothly beyond
    it (there the curve is the maximum of the walls either side).

    Attributes:
        index: the wall's number in its curve.
        lo, hi: the interval of x where this wall is the curve (m).
        p: the curve's parameter values, in the order of the module's PARAMETER_NAMES.
        f, df, d2f: height f(x, p) (m), slope, second derivative (1/m).
        near, dnear: the nearest-point condition g(s, px, py, p) (m) and dg/ds.
        poly: coefficients (highest power first) of the polynomial whose real roots are
            the candidate nearest points, poly(px, py, p); None when there is none.
        d3f: third derivative f'''(x, p) (1/m^2), for the equations of sustained contact
            (billiard.generated.contact).
        smooth_hi: the join at ``hi`` with the next wall is smooth (C1 or C2: height and
            slope continuous), so the two are one chain: one offset surface, and a ball in
            contact passes from one to the other; else a kink (or no join).
    """

    index: int
    lo: float
    hi: float
    p: Params
    f: Callable[[float, Params], float]
    df: Callable[[float, Params], float]
    d2f: Callable[[float, Params], float]
    near: Callable[[float, float, float, Params], float]
    dnear: Callable[[float, float, float, Params], float]
    poly: Callable[[float, float, Params], tuple[float, ...]] | None
    d3f: Callable[[float, Params], float]
    smooth_hi: bool = False

    def height(self, x: float) -> float:
        """f(x) (m): not for hot loops, which call ``self.f(x, self.p)`` directly."""
        return self.f(x, self.p)


def curve_height(walls: Sequence[Wall], x: float) -> float:
    """Height (m) at x of the curve made of ``walls`` (in order, their intervals covering
    every x): that of the wall holding x, the larger at a join (equal to rounding)."""
    return max(w.f(x, w.p) for w in walls if w.lo <= x <= w.hi)


def nearest_newton(
    wall: Wall, s: float, px: float, py: float, iterations: int = 50
) -> tuple[float | None, bool]:
    """Newton's method on a wall's nearest-point condition
    g(s) = (s - px) + (f(s) - py) f'(s) = 0 from the start s (m), for the global nearest
    point: the kernel :func:`billiard.kernels.fixed_step.nearest_newton`, which the
    fixed-step locator runs, interpreted.

    Returns ``(s, True)`` when a step fell below 1e-15 relative, ``(s, False)`` when the
    iterations ran out first, and ``(None, False)`` when it met g'(s) <= 0 (a maximum of
    the distance nearby) or a non-finite s.
    """
    from billiard.kernels.interpreted import fixed_step

    s, how = fixed_step.nearest_newton(wall.near, wall.dnear, wall.p, s, px, py, iterations)
    if how == fixed_step.NEWTON_FAILED:
        return None, False
    return s, how == fixed_step.NEWTON_CONVERGED
