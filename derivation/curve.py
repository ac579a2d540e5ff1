"""Geometry of a boundary curve y = f(x), for any expression f in sympy.

For each smooth piece ("wall") of the curve this derives the slope f', the second
derivative f'' (curvature kappa = f''/(1+f'^2)^(3/2)), the third derivative f''' (the
equations of sustained contact need it), the tangent angle z = atan f', the
nearest-point condition between a ball centre (px, py) and the curve,

    g(s) = (s - px) + (f(s) - py) f'(s) = 0,

its derivative dg/ds for Newton's method, and, where g becomes a polynomial in s after
clearing denominators and square roots, that polynomial: its real roots are the
candidate nearest points (a cubic for the parabola, a quartic for the hyperbola).

Curves with kinks, written with abs(), are split at the zeros of the arguments of abs
into walls; each wall is a smooth function valid on an interval and extended smoothly
beyond it. Only convex kinks (slope jumping up) are accepted: then the curve is the
maximum of its walls, the inside of the container is the intersection of the regions
above them, and a ball can never touch the kink itself.
"""

from __future__ import annotations

from dataclasses import dataclass

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


def _abs_arguments(expr: sm.Basic) -> list[sm.Basic]:
    return sorted({a.args[0] for a in expr.atoms(sm.Abs)}, key=sm.default_sort_key)


def split_walls(expr: sm.Basic, defaults: dict) -> tuple[list[sm.Basic], list[tuple]]:
    """Split f at the kinks of abs(): return breakpoints and (lo, hi, smooth f) pieces.

    Breakpoints are kept symbolic in the parameters; their order and the sign of each abs
    argument on each interval are decided with the parameters' default values.
    """
    args = _abs_arguments(expr)
    if not args:
        return [], [(-sm.oo, sm.oo, expr)]
    points = []
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
    breakpoints = [p[1] for p in points]
    numeric = [p[0] for p in points]
    edges = [-sm.oo, *breakpoints, sm.oo]
    nedges = [-1e300, *numeric, 1e300]
    pieces = []
    for i in range(len(edges) - 1):
        lo, hi = nedges[i], nedges[i + 1]
        if lo == -1e300:
            mid = hi - 1.0
        elif hi == 1e300:
            mid = lo + 1.0
        else:
            mid = 0.5 * (lo + hi)
        repl = {}
        for a in args:
            sign = sm.sign(a.subs(defaults).subs(x, mid))
            repl[sm.Abs(a)] = a if sign >= 0 else -a
        pieces.append((edges[i], edges[i + 1], expr.xreplace(repl)))
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
    return breakpoints, pieces


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


def nearest_polynomial(near: sm.Basic) -> list[sm.Basic] | None:
    """Polynomial in s whose real roots contain the nearest points, or None."""
    numer = sm.together(near).as_numer_denom()[0]
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
    walls = []
    for lo, hi, f in pieces:
        fs = f.subs(x, s)
        df = sm.diff(fs, s)
        d2f = sm.diff(df, s)
        d3f = sm.diff(d2f, s)
        near = (s - px) + (fs - py) * df
        dnear = sm.diff(near, s)
        walls.append(Wall(lo, hi, fs, df, d2f, d3f, near, dnear, nearest_polynomial(near)))
    return CurveDerivation(
        name, text, expression, parameters, parameter_symbols, breakpoints, walls
    )


__all__ = [
    "derive_curve",
    "split_walls",
    "nearest_polynomial",
    "PAPER_CURVES",
    "x",
    "s",
    "px",
    "py",
    "CurveDerivationError",
]
