"""Can a derived curve hold the ball? Numeric checks on the generated wall functions.

Run on the module exactly as the runtime will load it (parameters at their values), before
it is put in place. Pure Python with ``math``: no sympy.

The usable range is found by walking outward from x = 0 (where the runtime starts its
search for the container) on each side until the curve has risen ``RISE`` above the lowest
point met, within ``REACH`` of x = 0. On that range, widened by ``MARGIN``, every wall (each
smooth piece, continued past its kinks as the runtime evaluates it) must give a real,
finite height, slope and second derivative; and the curve must be convex there. A plane
(one straight wall: a floor, as for a ball bouncing on a shaken plate, or a tilted plane,
as in the impact validation) has no bottom but is accepted: the ball bounces on it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

#: How far (m) the curve must rise above its bottom on both sides.
RISE = 0.05
#: How far (m) from x = 0 the rise is looked for.
REACH = 100.0
#: Extra width (m) checked beyond the usable range (more than a ball's diameter).
MARGIN = 0.01
_RATIO = 1.01  # spacing of the walk: 1 % of |x|
_FIRST = 1e-6
_QUANTITIES = (("f", "height f"), ("df", "slope f'"), ("d2f", "second derivative f''"))


def _side_points() -> list[float]:
    points = []
    x = _FIRST
    while x < REACH:
        points.append(x)
        x *= _RATIO
    points.append(REACH)
    return points


_POINTS = _side_points()


def _real(fn: Callable[[float], float], x: float) -> float | None:
    try:
        value = fn(x)
    except (ArithmeticError, ValueError, TypeError):
        return None
    if isinstance(value, complex) or not isinstance(value, (int, float)):
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _piece(wall: dict) -> str:
    lo, hi = wall["lo"], wall["hi"]
    if lo == -math.inf and hi == math.inf:
        return ""
    if lo == -math.inf:
        return f"its piece for x < {hi:g} m "
    if hi == math.inf:
        return f"its piece for x > {lo:g} m "
    return f"its piece for {lo:g} < x < {hi:g} m "


class _Curve:
    def __init__(self, walls: Sequence[dict]):
        self.walls = walls
        self.straight = len(walls) == 1  # until a curved point is met

    def height(self, x: float) -> float | str:
        """max of the walls at x, or a one-line problem."""
        heights = []
        for wall in self.walls:
            values = {}
            for key, label in _QUANTITIES:
                value = _real(wall[key], x)
                if value is None:
                    what = _piece(wall)
                    if what:
                        return (
                            f"{what}has no real, finite {label} at x = {x:.6g} m (each "
                            "piece is evaluated on the whole range)"
                        )
                    return f"its {label} is not real and finite at x = {x:.6g} m"
                values[key] = value
            if values["d2f"] != 0.0:
                self.straight = False
            heights.append(values["f"])
        return max(heights)


def shape_problem(walls: Sequence[dict]) -> str | None:
    """Why these walls cannot hold a ball (one line, without the curve's name), or None."""
    curve = _Curve(walls)
    h0 = curve.height(0.0)
    if isinstance(h0, str):
        return h0
    ends: list[float] = []
    failure: str | None = None
    for sign, side in ((-1.0, "left"), (1.0, "right")):
        lowest, end, limit = h0, None, REACH
        for step in _POINTS:
            x = sign * step
            if step > limit:
                break
            h = curve.height(x)
            if isinstance(h, str):
                return h
            if end is None:
                lowest = min(lowest, h)
                if h >= lowest + RISE:
                    end = x
                    limit = step + MARGIN
        if end is None:
            failure = failure or (
                f"it does not open upward on the {side}: between x = 0 and x = "
                f"{sign * REACH:g} m it never rises {RISE:g} m above its lowest point, so "
                "there is no bottom for the ball to stay in"
            )
            ends.append(sign * REACH)
        else:
            ends.append(end)
    if failure is not None:
        return None if curve.straight else failure
    return _convexity_problem(walls, ends[0] - MARGIN, ends[1] + MARGIN)


def _convexity_problem(walls: Sequence[dict], left: float, right: float) -> str | None:
    """The first place, walking outward from x = 0, where the curve is not convex."""
    sides = (
        [0.0] + [-p for p in _POINTS if p <= -left],
        [0.0] + [p for p in _POINTS if p <= right],
    )
    for xs in sides:
        for wall in walls:
            previous = None
            for x in xs:
                if not wall["lo"] <= x <= wall["hi"]:
                    continue
                f, df, d2f = (float(wall[k](x)) for k in ("f", "df", "d2f"))
                if d2f < -1e-9 * (1.0 + df * df) ** 1.5:
                    return (
                        f"it is not convex at x = {x:.6g} m (f'' = {d2f:.3g} 1/m): it must "
                        f"bend upward wherever the ball can touch it (within {RISE:g} m of "
                        "its bottom)"
                    )
                if previous is not None:
                    (xa, fa, da), (xb, fb, db) = sorted([previous, (x, f, df)])
                    secant = (fb - fa) / (xb - xa)
                    # rounding: heights carry errors of order 1e-16 times their terms
                    # (taken as at least 1 m: cosh(x) - 1 cancels), divided by the spacing
                    slack = 1e-9 * (1.0 + abs(da) + abs(db)) + 1e-14 * max(
                        1.0, abs(fa), abs(fb)
                    ) / (xb - xa)
                    if not da - slack <= secant <= db + slack:
                        return (
                            f"it is not convex or not continuous between x = {xa:.6g} m and "
                            f"{xb:.6g} m: it must bend upward wherever the ball can touch it"
                        )
                previous = (x, f, df)
    return None
