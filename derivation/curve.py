"""Geometry of a boundary curve y = f(x), for any expression f in sympy.

For each smooth piece ("wall") of the curve this derives the slope f', the second
derivative f'' (curvature kappa = f''/(1+f'^2)^(3/2)), the third derivative f''' (the
equations of sustained contact need it), the tangent angle z = atan f', the
nearest-point condition between a ball centre (px, py) and the curve,

    g(s) = (s - px) + (f(s) - py) f'(s) = 0,

its derivative dg/ds for Newton's method, and, where g becomes a polynomial in s after
clearing denominators and square roots, that polynomial: its real roots are the
candidate nearest points (a cubic for the parabola, a quartic for the hyperbola).

Curves written with abs(), or as ``Piecewise((expr, condition), ...)`` (conditions
comparing x with numbers and parameters), are an ordered chain of pieces: split at the
zeros of the arguments of abs and at the bounds of the conditions into walls; each wall
is a smooth function valid on an interval and extended smoothly beyond it. A zero where
the curve is C^2 (``abs(x)**3`` at 0) is no kink: the curve stays one wall there, whose
functions keep abs(). Only convex kinks (slope jumping up) are accepted.

Each join between two walls is classified exactly (:func:`classify_joins`): ``C2`` (height,
slope and f'' continuous), ``C1`` (height and slope continuous, f'' jumps) or ``kink`` (the
slope jumps up: a convex corner, a valley); a height that jumps (a Piecewise whose pieces
do not meet) or a slope that jumps down (a ridge) is refused with a one-line reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sm
from sympy.solvers.solvers import unrad

from .expr import PAPER_CURVES

x = sm.Symbol("x", real=True)
s = sm.Symbol("s", real=True)
px, py = sm.symbols("px py", real=True)


class CurveDerivationError(ValueError):
    """A curve that the derivation cannot handle, with a one-line reason."""


@dataclass
class Wall:
    lo: sm.Basic  # interval of x where this wall is the curve
    hi: sm.Basic
    f: sm.Basic
    df: sm.Basic
    d2f: sm.Basic
    d3f: sm.Basic  # f''', for the contact equations
    near: sm.Basic  # nearest-point condition g(s)
    dnear: sm.Basic
    poly: list[sm.Basic] | None  # coefficients, highest power of s first


@dataclass
class CurveDerivation:
    name: str
    text: str
    expression: sm.Basic
    parameters: dict[str, str]  # name -> default value (exact decimal text)
    parameter_symbols: list[sm.Symbol]
    breakpoints: list[sm.Basic]
    walls: list[Wall]
    #: per breakpoint: "C2", "C1" or "kink" (:func:`classify_joins`)
    joins: list[str] = field(default_factory=list)
    #: per breakpoint: whether its class holds for every value of the parameters (else it
    #: was decided at the defaults, and the runtime checks it for the scene's values)
    joins_exact: list[bool] = field(default_factory=list)


def _abs_arguments(expr: sm.Basic) -> list[sm.Basic]:
    return sorted({a.args[0] for a in expr.atoms(sm.Abs)}, key=sm.default_sort_key)


def _condition_bounds(expr: sm.Basic) -> list[sm.Basic]:
    """The bounds that a Piecewise's conditions compare x with (free of x)."""
    bounds = set()
    for rel in expr.atoms(sm.core.relational.Relational):
        for side in (rel.lhs, rel.rhs):
            if not side.has(x):
                bounds.add(side)
    return sorted(bounds, key=sm.default_sort_key)


def _branch(expr: sm.Piecewise, defaults: dict, at: float) -> sm.Basic:
    """The piece of a Piecewise that holds at x = at (parameters at their defaults)."""
    point = sm.nsimplify(at, rational=True)
    for value, condition in expr.args:
        held = condition.subs(defaults).subs(x, point)
        if held == sm.true:
            return value
    raise CurveDerivationError(
        f"no piece of the Piecewise holds at x = {at:g} m: the conditions must cover every x "
        "(end with a piece whose condition is True)"
    )


def split_walls(expr: sm.Basic, defaults: dict) -> tuple[list[sm.Basic], list[tuple]]:
    """Split f at the kinks of abs(): return the kinks and (lo, hi, smooth f) walls.

    Breakpoints are kept symbolic in the parameters; their order and the sign of each abs
    argument on each interval are decided with the parameters' default values.

    A zero of an abs argument where the curve is C^2 for every value of the parameters
    (``abs(x)**3`` at 0) is no kink: the pieces either side of it stay one wall, which
    keeps abs() (:func:`_smooth_join`). Split there, a ball rolling through the join would
    meet the other wall, and the engine would count an impact (with the low-velocity
    rule's relaunch) where the curve has no corner.
    """
    if isinstance(expr, sm.Piecewise) and len(expr.args) == 1:
        if expr.args[0][1] != sm.true:
            raise CurveDerivationError("the Piecewise does not hold at every x")
        expr = expr.args[0][0]  # one piece, for every x
    piecewise = isinstance(expr, sm.Piecewise)
    if not piecewise and expr.has(sm.Piecewise):
        raise CurveDerivationError("Piecewise must be the whole expression")
    args = sorted(
        {a for branch in _branches(expr) for a in _abs_arguments(branch)}, key=sm.default_sort_key
    )
    if not args and not piecewise:
        return [], [(-sm.oo, sm.oo, expr)]
    points = []
    for bound in _condition_bounds(expr) if piecewise else []:
        value = bound.subs(defaults)
        if not value.is_real:
            raise CurveDerivationError(f"the Piecewise bound {bound} is not a real number")
        points.append((float(value), bound))
    for a in args:
        if a.has(sm.Abs):
            raise CurveDerivationError("nested abs() is not supported")
        if not a.is_polynomial(x):
            raise CurveDerivationError(f"abs({a}) needs a polynomial argument in x")
        for root in sm.solve(sm.Eq(a, 0), x):
            value = root.subs(defaults)
            if value.is_real:
                points.append((float(value), root))
    points.sort(key=lambda p: p[0])
    # one breakpoint per point (abs(x**2 - 1) and abs(x + 1) share x = -1): an interval
    # of zero width is no wall
    points = [p for i, p in enumerate(points) if i == 0 or p[0] != points[i - 1][0]]
    breakpoints = [p[1] for p in points]
    numeric = [p[0] for p in points]
    edges = [-sm.oo, *breakpoints, sm.oo]
    nedges = [-1e300, *numeric, 1e300]
    pieces = []
    signs = []  # per interval: abs(a) -> a or -a, as a's sign there
    for i in range(len(edges) - 1):
        lo, hi = nedges[i], nedges[i + 1]
        if lo == -1e300:
            mid = hi - 1.0
        elif hi == 1e300:
            mid = lo + 1.0
        else:
            mid = 0.5 * (lo + hi)
        repl = {}
        if piecewise:
            repl[expr] = _branch(expr, defaults, mid)
        for a in args:
            sign = sm.sign(a.subs(defaults).subs(x, mid))
            repl[sm.Abs(a)] = a if sign >= 0 else -a
        signs.append(repl)
        chosen = repl[expr] if piecewise else expr
        pieces.append((edges[i], edges[i + 1], chosen.xreplace(repl)))
    _check_heights(pieces, breakpoints, numeric, defaults)
    # Convex kinks only: slope must not drop across a breakpoint.
    for i, b in enumerate(numeric):
        left = _slope(pieces[i][2], defaults, b, "-")
        right = _slope(pieces[i + 1][2], defaults, b, "+")
        if left is None or right is None:
            raise CurveDerivationError(
                f"cusp at x = {b:g} m: the slope is infinite or undefined there, so the "
                "contact direction at the bottom is not defined"
            )
        if left > right:
            raise CurveDerivationError(
                f"concave kink at x = {b:g} m (slope {left:g} -> {right:g}): "
                "the ball could touch the corner point, which the contact model excludes"
            )
    walls = []
    kinks = []
    for first, last, wall in _wall_runs(expr, breakpoints, signs, defaults):
        if first > 0:
            kinks.append(breakpoints[first - 1])
        walls.append((edges[first], edges[last + 1], wall))
    return kinks, walls


def _branches(expr: sm.Basic) -> list[sm.Basic]:
    """The pieces' expressions of a Piecewise, or [expr]."""
    if isinstance(expr, sm.Piecewise):
        return [value for value, _ in expr.args]
    return [expr]


def _check_heights(
    pieces: list[tuple], breakpoints: list[sm.Basic], numeric: list[float], defaults: dict
) -> None:
    """Refuse a curve whose height jumps at a join (a Piecewise whose pieces do not meet),
    decided exactly at the parameters' defaults, in one line naming the join and the jump."""
    for i, b in enumerate(breakpoints):
        at = b.subs(defaults)
        left = _side_value(pieces[i][2].subs(defaults), at, "-")
        right = _side_value(pieces[i + 1][2].subs(defaults), at, "+")
        if left is None or right is None:
            raise CurveDerivationError(f"the height is not finite at the join x = {numeric[i]:g} m")
        jump = sm.simplify(right - left)
        if jump != 0:
            raise CurveDerivationError(
                f"the height jumps by {float(jump):.6g} m at the join x = {numeric[i]:g} m "
                f"(from {float(left):.6g} m to {float(right):.6g} m): the pieces must meet"
            )


def _side_value(piece: sm.Basic, at: sm.Basic, side: str) -> sm.Basic | None:
    """piece at x = at, exactly (its limit from ``side`` where the value is undefined as
    written), or None where it is not real and finite."""
    value = piece.subs(x, at)
    if not (value.is_real and value.is_finite):
        try:
            value = sm.limit(piece, x, at, side)
        except (NotImplementedError, ValueError, TypeError):
            return None
    if not (value.is_real and value.is_finite):
        return None
    return value


def classify_joins(
    walls: list[tuple], breakpoints: list[sm.Basic], defaults: dict
) -> tuple[list[str], list[bool]]:
    """Each join's class, "C2", "C1" or "kink", and whether it holds for every value of the
    parameters (decided symbolically) or at their defaults only (decided exactly there).

    ``walls``: (lo, hi, f) of the walls in order; ``breakpoints``: the joins between them.
    The limits of f' and f'' from both sides are compared: equal slopes make a C1 join
    (C2 if f'' is equal too), a slope that jumps up a kink (the slope jumping down is
    refused before: :func:`split_walls`).
    """
    classes, exact = [], []
    for i, b in enumerate(breakpoints):
        left, right = walls[i][2], walls[i + 1][2]
        kind, holds = "kink", True
        for order in (1, 2):
            jump = sm.diff(right, x, order) - sm.diff(left, x, order)
            symbolic = sm.simplify(_classical(jump).subs(x, b))
            if symbolic == 0:
                continue  # equal for every value of the parameters
            at = b.subs(defaults)
            values = [
                _side_value(_classical(sm.diff(piece, x, order)).subs(defaults), at, side)
                for piece, side in ((left, "-"), (right, "+"))
            ]
            if None not in values and sm.simplify(values[1] - values[0]) == 0:
                holds = False  # equal at the defaults only
                continue
            if order == 2:
                kind = "C1"
            break
        else:
            kind = "C2"
        classes.append(kind)
        exact.append(holds)
    return classes, exact


def _smooth_join(left: sm.Basic, right: sm.Basic, at: sm.Basic, defaults: dict) -> bool:
    """Is the curve C^2 at the zero ``at`` of an abs argument, for every value of the
    parameters (the pieces either side of it have the same height, slope and f'' there),
    with a finite f''' on both sides? Decided exactly in sympy; a join that sympy cannot
    show to be C^2 stays a breakpoint.

    Why C^2 and not C^1: a ball in contact moves its centre along the wall's offset curve
    at the speed (L - r z_s) ds/dt, and the contact equations keep ds/dt continuous. Where
    f'' jumps, z_s jumps, and so would the centre's speed: one wall through
    ``10*x*abs(x) + 20*x**2`` (C^1 at 0) changed a rolling ball's energy by 13 % at every
    pass. Such a join stays two walls. A finite f''' too: ``abs(x)**2.5`` is C^2 at 0,
    but its f''' is infinite there (it stays split, and the shape check refuses it)."""
    jump = right - left
    for order in (0, 1, 2):
        value = sm.diff(jump, x, order).subs(x, at)
        if value.has(sm.nan, sm.zoo, sm.oo, -sm.oo) or sm.simplify(value) != 0:
            return False
    where = at.subs(defaults)
    for piece in (left, right):
        value = sm.diff(piece, x, 3).subs(defaults).subs(x, where)
        if not (value.is_real and value.is_finite):
            return False
    return True


def _wall_runs(
    expr: sm.Basic, breakpoints: list[sm.Basic], signs: list[dict], defaults: dict
) -> list[tuple[int, int, sm.Basic]]:
    """The walls: runs (first, last) of intervals whose joins are smooth, each with its
    expression (abs(a) replaced by a or -a where a keeps one sign all along the run).

    A wall is continued past its ends (for the container's geometry) by its expression,
    which must stay smooth there: where an argument whose abs the wall keeps also changes
    sign at one of its ends, the continuation must join smoothly too, or the joins inside
    the wall where that argument changes sign are split after all.
    """
    n = len(breakpoints)
    piecewise = isinstance(expr, sm.Piecewise)
    pieces = [(sign[expr] if piecewise else expr).xreplace(sign) for sign in signs]
    # a Piecewise's pieces are only merged where they are the same formula
    smooth = [
        (not piecewise or signs[j][expr] == signs[j + 1][expr])
        and _smooth_join(pieces[j], pieces[j + 1], b, defaults)
        for j, b in enumerate(breakpoints)
    ]
    while True:
        runs = []
        first = 0
        for j, joined in enumerate(smooth):
            if not joined:
                runs.append((first, j))
                first = j + 1
        runs.append((first, n))
        walls = []
        changed = False
        for first, last in runs:
            run = range(first, last + 1)
            kept = [k for k in signs[first] if any(signs[i][k] != signs[first][k] for i in run)]
            base = signs[first][expr] if piecewise else expr
            wall = base.xreplace({k: signs[first][k] for k in signs[first] if k not in kept})
            walls.append((first, last, wall))
            for j in (first - 1, last):  # the joins at the wall's ends
                ends = [k for k in kept if 0 <= j < n and signs[j][k] != signs[j + 1][k]]
                if ends and not _smooth_join(
                    wall.xreplace({k: signs[j][k] for k in ends}),
                    wall.xreplace({k: signs[j + 1][k] for k in ends}),
                    breakpoints[j],
                    defaults,
                ):
                    for i in range(first, last):
                        if any(signs[i][k] != signs[i + 1][k] for k in ends):
                            smooth[i] = False
                    changed = True
        if not changed:
            return walls


def _slope(piece: sm.Basic, defaults: dict, at: float, side: str) -> float | None:
    """Slope of a piece at a kink, approached from ``side`` ('-' or '+'), or None if it
    is not real and finite there (a cusp)."""
    slope = sm.diff(piece, x).subs(defaults)
    value = slope.subs(x, at)
    if not (value.is_real and value.is_finite):  # e.g. 0/0 as written: take the limit
        try:
            value = sm.limit(slope, x, sm.nsimplify(at), side)
        except (NotImplementedError, ValueError, TypeError):
            return None
    if not (value.is_real and value.is_finite):
        return None
    return float(value)


def _classical(derivative: sm.Basic) -> sm.Basic:
    """A derivative of a wall that keeps abs() as a plain function: without sympy's
    DiracDelta terms. They vanish away from the zeros of abs's argument, and at them too,
    since such a wall is C^2 there (:func:`_smooth_join`): each comes with a factor that
    vanishes with the argument (``abs(x)**3``: 2 x**2 DiracDelta(x) in f'')."""
    return derivative.replace(sm.DiracDelta, lambda *args: sm.S.Zero)


#: Largest root index (the denominator of a fractional power of s) whose radicals are
#: cleared into a polynomial: clearing multiplies the degree by it, so ``x**2.0000001``
#: (s**(20000001/10000000)) would ask for a polynomial of degree 10^7, which sympy
#: builds for minutes and gigabytes. Such a wall gets no polynomial: its nearest point
#: is found numerically, as for exp or sin.
MAX_ROOT_INDEX = 12


def _root_index(expr: sm.Basic) -> int:
    """The least common multiple of the denominators of the fractional powers in
    ``expr`` (1 when there are none)."""
    index = 1
    for power in expr.atoms(sm.Pow):
        exponent = power.exp
        if exponent.is_Rational and not exponent.is_Integer:
            index = sm.ilcm(index, exponent.q)
    return int(index)


def nearest_polynomial(near: sm.Basic) -> list[sm.Basic] | None:
    """Polynomial in s whose real roots contain the nearest points, or None (also when
    clearing its radicals would need a root index over :data:`MAX_ROOT_INDEX`)."""
    numer = sm.together(near).as_numer_denom()[0]
    if _root_index(numer) > MAX_ROOT_INDEX:
        return None
    numer = sm.expand(numer)
    if numer.is_polynomial(s):
        poly = numer
    else:
        try:
            cleared = unrad(numer, s)
        except (NotImplementedError, ValueError):
            return None
        if cleared is None:  # no radicals to clear, and not polynomial (exp, sin, ...)
            return None
        poly, cov = cleared
        if cov or not poly.is_polynomial(s):
            return None
    # Factors free of the centre (px, py) cannot locate a nearest point, which moves with
    # the centre: they come from cleared denominators such as 1 + beta s^2. Drop them.
    _, factors = sm.factor_list(sm.expand(poly), s)
    kept = [fac**mult for fac, mult in factors if fac.has(px) or fac.has(py)]
    p = sm.Poly(sm.expand(sm.Mul(*kept)), s)
    coeffs = [sm.factor_terms(cf) for cf in p.all_coeffs()]
    return coeffs


def derive_curve(
    name: str,
    text: str,
    expression: sm.Basic,
    parameters: dict[str, str],
    parameter_symbols: list[sm.Symbol],
) -> CurveDerivation:
    defaults = {p: sm.Rational(parameters[p.name]) for p in parameter_symbols}
    breakpoints, pieces = split_walls(expression, defaults)
    joins, joins_exact = classify_joins(pieces, breakpoints, defaults)
    walls = []
    for lo, hi, f in pieces:
        fs = f.subs(x, s)
        df = _classical(sm.diff(fs, s))
        d2f = _classical(sm.diff(df, s))
        d3f = _classical(sm.diff(d2f, s))
        near = (s - px) + (fs - py) * df
        dnear = _classical(sm.diff(near, s))
        walls.append(Wall(lo, hi, fs, df, d2f, d3f, near, dnear, nearest_polynomial(near)))
    return CurveDerivation(
        name,
        text,
        expression,
        parameters,
        parameter_symbols,
        breakpoints,
        walls,
        joins,
        joins_exact,
    )


#: What each join class means, for the chain's description.
JOIN_MEANING = {
    "C2": "smooth: height, slope and f'' continuous",
    "C1": "smooth: height and slope continuous, f'' jumps",
    "kink": "a corner: the slope jumps up (a valley)",
}


def _decimal_text(expr: sm.Basic) -> str:
    """expr as text, its fractions as decimals (0.0063, not 63/10000)."""
    fractions = {q: sm.Float(q, 15) for q in expr.atoms(sm.Rational) if not q.is_Integer}
    return sm.sstr(expr.xreplace(fractions), full_prec=False)


def chain_lines(cd: CurveDerivation) -> list[str]:
    """The curve as a chain, in words: each piece with its interval of x (m) and formula,
    and between pieces the join with its class; symbolic bounds are followed by their value
    at the parameters' defaults."""
    defaults = {p: sm.Rational(cd.parameters[p.name]) for p in cd.parameter_symbols}

    def at(bound: sm.Basic) -> str:
        value = float(bound.subs(defaults))
        text = sm.sstr(bound)
        return f"{value:g} m" if bound.is_number else f"{text} = {value:g} m"

    lines = [f"chain: {len(cd.walls)} piece(s), {len(cd.breakpoints)} join(s)"]
    for i, wall in enumerate(cd.walls):
        if wall.lo == -sm.oo and wall.hi == sm.oo:
            where = "all x"
        elif wall.lo == -sm.oo:
            where = f"x < {at(wall.hi)}"
        elif wall.hi == sm.oo:
            where = f"x > {at(wall.lo)}"
        else:
            where = f"{at(wall.lo)} < x < {at(wall.hi)}"
        lines.append(f"  piece {i}: {where}: f = {_decimal_text(wall.f.subs(s, x))}")
        if i < len(cd.breakpoints):
            kind = cd.joins[i]
            proven = "" if cd.joins_exact[i] else " (at the parameters' defaults)"
            lines.append(
                f"  join at x = {at(cd.breakpoints[i])}: {kind}, {JOIN_MEANING[kind]}{proven}"
            )
    return lines


__all__ = [
    "chain_lines",
    "derive_curve",
    "split_walls",
    "classify_joins",
    "nearest_polynomial",
    "PAPER_CURVES",
    "x",
    "s",
    "px",
    "py",
    "CurveDerivationError",
]
