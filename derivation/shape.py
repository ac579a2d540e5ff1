"""Can a derived curve hold the ball? Numeric checks on the generated wall functions.

Run on the module exactly as the runtime will load it (parameters at their values), before
it is put in place. Pure Python with ``math`` and numpy: no sympy.

The usable range is found by walking outward from x = 0 (where the runtime starts its
search for the container) on each side until the curve has risen ``RISE`` above the lowest
point met, within ``REACH`` of x = 0. On that range, widened by ``MARGIN``, every wall (each
smooth piece, continued past its kinks as the runtime evaluates it) must give a real,
finite height, slope and second derivative; and the curve must be convex there. A plane
(one straight wall: a floor, as for a ball bouncing on a shaken plate, or a tilted plane,
as in the impact validation) has no bottom but is accepted: the ball bounces on it.
Walls joined smoothly (C1 or C2) are checked as one chain (:func:`chained`), as the
runtime makes one surface of them; on the same range, the maximum of the chains' formulas
must be the curve (:func:`join_problem`: true at a valley), and every join is checked for
the parameters' values (:func:`chain_problem`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence

import numpy as np

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


def interval_text(lo: float, hi: float) -> str:
    """The interval (lo, hi) of x (m) in words: ``x < 1 m``, ``0 m < x < 1 m``, ``all x``."""
    if lo == -math.inf and hi == math.inf:
        return "all x"
    if lo == -math.inf:
        return f"x < {hi:g} m"
    if hi == math.inf:
        return f"x > {lo:g} m"
    return f"{lo:g} m < x < {hi:g} m"


def _piece(wall: dict) -> str:
    lo, hi = wall["lo"], wall["hi"]
    if lo == -math.inf and hi == math.inf:
        return ""
    return f"its piece for {interval_text(lo, hi)} "


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
    walked = _walk(curve)
    if isinstance(walked, str):
        return walked
    ends, failure = walked
    if failure is not None:
        return None if curve.straight else failure
    return _convexity_problem(walls, ends[0] - MARGIN, ends[1] + MARGIN)


def usable_range(walls: Sequence[dict]) -> tuple[float, float]:
    """The range of x (m) that :func:`shape_problem` checks the walls on: from x = 0 outward
    on each side until the curve has risen ``RISE`` above its lowest point (``REACH`` where
    it never does), widened by ``MARGIN``."""
    walked = _walk(_Curve(walls))
    if isinstance(walked, str):  # not real somewhere: shape_problem says where
        return -REACH, REACH
    ends, _ = walked
    return ends[0] - MARGIN, ends[1] + MARGIN


def _walk(curve: _Curve) -> tuple[list[float], str | None] | str:
    """The ends of the usable range (m) and why the curve does not open upward (or None),
    walking outward from x = 0; or a one-line problem where a height is not real."""
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
    return ends, failure


def join_problem(walls: Sequence[dict], xs: Iterable[float] | None = None) -> str | None:
    """Where the maximum of the walls' formulas is not the curve, in one line, or None.

    Where walls meet at a kink, the container is the intersection of the regions above
    each (their offset surfaces, each continued past its interval: see
    :mod:`billiard.geometry.boundary`). That is the curve only where no wall's formula
    lies above the piece that holds x: true at a convex kink (the wedge's vertex). Walls
    joined smoothly are passed here as one chain (:func:`chained`): on one side of a
    smooth (C^1) join, such as ``20*x**2 + 10*x*abs(x)``, the right piece 30 x^2 lies
    above the left piece 10 x^2, and the maximum of the two would be another curve.

    ``walls``: dicts with ``lo``, ``hi`` (m), ``f`` and ``df`` (functions of x, parameters
    bound); ``xs``: the abscissas (m) to compare at, by default :func:`usable_range`
    sampled as the shape check samples it. Walls whose formula is not real and finite at
    an x are skipped there (the shape and geometry checks report those).
    """
    if len(walls) < 2:
        return None
    if xs is None:
        left, right = usable_range(walls)
        xs = [0.0] + [x for p in _POINTS for x in (-p, p) if left <= x <= right]
    grid = np.array(list(xs), dtype=float)
    heights = np.array([_heights(wall["f"], grid) for wall in walls])  # NaN: not real
    lo = np.array([[wall["lo"]] for wall in walls])
    hi = np.array([[wall["hi"]] for wall in walls])
    holds = (lo <= grid) & (grid <= hi)
    # the curve: the piece that holds x (at a join both, with the same height); NaN where
    # one is not real, -inf where none holds x (neither compares above anything)
    curve = np.where(holds, heights, -np.inf).max(axis=0)
    with np.errstate(invalid="ignore"):
        excess = heights - curve
        allowance = 1e-12 * np.maximum(1.0, np.maximum(np.abs(heights), np.abs(curve)))
        above = ~holds & (excess > allowance)  # see rounding_allowance
    if not above.any():
        return None
    j, k = np.unravel_index(np.argmax(np.where(above, excess, -np.inf)), above.shape)
    return _join_message(walls, int(j), float(grid[k]), float(excess[j, k]))


def chained(walls: Sequence[dict]) -> list[dict]:
    """The walls joined into chains at their smooth joins (``smooth_hi``: C1 or C2, as the
    runtime makes one surface of them): per chain a wall dict whose functions are those of
    the wall holding x (the lower at a join), its end walls continued past its ends."""
    groups: list[list[dict]] = []
    for wall in walls:
        if groups and groups[-1][-1].get("smooth_hi", False):
            groups[-1].append(wall)
        else:
            groups.append([wall])
    chains = []
    for group in groups:
        if len(group) == 1:
            chains.append(group[0])
            continue

        def holder(x: float, group: list[dict] = group) -> dict:
            for wall in group[:-1]:
                if x <= wall["hi"]:
                    return wall
            return group[-1]

        chain = {"lo": group[0]["lo"], "hi": group[-1]["hi"]}
        chain["smooth_hi"] = group[-1].get("smooth_hi", False)
        for key in ("f", "df", "d2f"):
            if all(key in wall for wall in group):
                chain[key] = lambda x, key=key, holder=holder: holder(x)[key](x)
        chains.append(chain)
    return chains


def chain_problem(walls: Sequence[dict], xs: Iterable[float] | None = None) -> str | None:
    """What is wrong with the chain of walls for these parameter values, in one line, or None.

    The joins were classified by the derivation at the parameters' defaults (or for every
    value): each is checked again here, where the values are known. At every join the
    height must be continuous; a join derived smooth (``smooth_hi``) must have a
    continuous slope, one derived a kink must have the slope jump up (a valley). Then, as
    in :func:`join_problem`, the maximum of the chains must be the curve.
    """
    for left, right in zip(walls, walls[1:], strict=False):
        at = left["hi"]
        fl, fr = _real(left["f"], at), _real(right["f"], at)
        sl, sr = _real(left["df"], at), _real(right["df"], at)
        if None in (fl, fr, sl, sr):
            return f"its height or slope is not real and finite at the join x = {at:.6g} m"
        if abs(fr - fl) > rounding_allowance(fl, fr):
            return (
                f"the height jumps by {fr - fl:.3g} m at the join x = {at:.6g} m (from "
                f"{fl:.6g} m to {fr:.6g} m): the pieces must meet"
            )
        tolerance = 1e-9 * (1.0 + abs(sl) + abs(sr))
        if left.get("smooth_hi", False) and abs(sr - sl) > tolerance:
            return (
                f"the join at x = {at:.6g} m was derived smooth, but with these parameter "
                f"values its slope jumps ({sl:.6g} -> {sr:.6g}); derive the curve with "
                "these values as its defaults"
            )
        if not left.get("smooth_hi", False) and sr < sl - tolerance:
            return (
                f"the join at x = {at:.6g} m is a concave kink (slope {sl:.6g} -> {sr:.6g}): "
                "the ball could touch the corner point, which the contact model excludes"
            )
    return join_problem(chained(walls), xs)


def _heights(fn: Callable[[float], float], xs: np.ndarray) -> list[float]:
    """fn at each of xs, NaN where it is not real and finite."""
    try:
        values = [float(fn(x)) for x in xs.tolist()]  # a complex value: TypeError
    except (ArithmeticError, ValueError, TypeError):
        checked = [_real(fn, x) for x in xs.tolist()]
        return [math.nan if v is None else v for v in checked]
    return [v if math.isfinite(v) else math.nan for v in values]


def rounding_allowance(*values: float) -> float:
    """How far two evaluations of one quantity (a height in m, or its slope, f'' or f''')
    may differ by rounding alone: 1e-12 of the largest value, taken as at least 1.

    A generated function's value carries rounding errors of order 1e-16 of its largest
    term (terms taken as at least 1: ``cosh(x) - 1`` cancels, as in the convexity check),
    and two formulas of one piece (``aa*x**2 - bb*x**2`` and ``(aa - bb)*x**2``) differ by
    a few such errors: the allowance leaves a factor 10^4 for that. For heights it is also
    far below any length the engine resolves (gap tolerances of 1e-12 m and up, a ball's
    radius of 1e-3 m), so a formula within it of the curve changes no run.
    """
    return 1e-12 * max(1.0, *(abs(v) for v in values))  # join_problem: the same, in numpy


def _join_message(walls: Sequence[dict], j: int, x: float, excess: float) -> str:
    """One line: wall j's formula lies above the curve at x, by ``excess`` (m)."""
    wall = walls[j]
    k = j - 1 if x < wall["lo"] else j + 1  # the neighbour across the join on x's side
    at = wall["lo"] if x < wall["lo"] else wall["hi"]
    left, right = (walls[k], wall) if k < j else (wall, walls[k])
    slopes = (_real(left["df"], at), _real(right["df"], at))
    if None in slopes:
        why = "its pieces' formulas cross there"
    else:
        sl, sr = slopes
        if abs(sr - sl) <= 1e-9 * (1.0 + abs(sl) + abs(sr)):
            why = (
                "the join is smooth (C1: the slope is continuous, f'' jumps), and smooth "
                "joins are not supported yet"
            )
        elif sr < sl:
            why = f"the join is a concave kink (slope {sl:.6g} -> {sr:.6g})"
        else:
            why = (
                "the formulas of the pieces either side of this kink cross again away from "
                "it, which is not supported yet"
            )
    return (
        f"at the join x = {at:.6g} m, the formula of {_span(wall)} lies above "
        f"{_span(walls[k])} (by {excess:.3g} m at x = {x:.6g} m), so the pointwise maximum "
        f"of the walls is not the curve: {why}"
    )


def _span(wall: dict) -> str:
    lo, hi = wall["lo"], wall["hi"]
    if lo == -math.inf:
        return f"the piece for x < {hi:g} m"
    if hi == math.inf:
        return f"the piece for x > {lo:g} m"
    return f"the piece for {lo:g} < x < {hi:g} m"


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
