"""Write docs/derivation.md from the derivation itself (sympy's LaTeX inside Markdown)."""

from __future__ import annotations

import sympy as sm

from .ball import BallDerivation, plain
from .contact import ContactDerivation, printable
from .curve import CurveDerivation


def _latex(expr) -> str:
    expr = plain(expr) if isinstance(expr, (sm.Basic, sm.MatrixBase)) else expr
    return sm.latex(expr, mat_delim="(")


def derivation_markdown(
    d: BallDerivation, cd: ContactDerivation, curves: list[CurveDerivation]
) -> str:
    out = [
        "# Derivation of the model",
        "",
        "This page is written by `billiard derive` from the derivation code "
        "(`derivation/ball.py`, `derivation/contact.py`, `derivation/curve.py`); do not edit "
        "it by hand. The sections follow the code from top to bottom. Symbols: `m` mass, "
        "`r` radius, `k` inertia factor (I = k m r^2), `g` gravity, `c_lin`, `c_quad` Fowles "
        "drag coefficients, `c_magnus` Magnus coefficient, `z` tangent angle of the boundary "
        "at the contact, `vb1`, `vb2` the boundary's velocity, `e` restitution, `mu_k` "
        "kinetic friction, `sgn` the sign of the slip velocity before the impact, "
        "`u1p, u2p, u3p` the speeds after the impact. "
        "In sustained contact: `s` the contact point's abscissa in the boundary's frame, "
        "`u_s = ds/dt`, `f', f'', f'''` the wall's derivatives at s, `N` and `F` the contact "
        "force's components along c2 and c1, `ab1, ab2` the boundary's acceleration, "
        "`mu_k` kinetic friction and `sgn` the sign of the slip. SI units.",
        "",
    ]
    for i, step in enumerate(d.steps, 1):
        out += [f"## {i}. {step.title}", "", step.text, ""]
        for label, expr in step.equations:
            out += ["$$", f"{label} = {_latex(expr)}", "$$", ""]
    for i, step in enumerate(cd.steps, len(d.steps) + 1):
        out += [f"## {i}. {step.title}", "", step.text, ""]
        for label, expr in step.equations:
            out += ["$$", f"{label} = {_latex(printable(expr))}", "$$", ""]
    n = len(d.steps) + len(cd.steps) + 1
    out += [
        f"## {n}. Boundary curves and the nearest point",
        "",
        "For a ball centre (px, py) the nearest point s of a smooth wall y = f(x) makes the "
        "line from (s, f(s)) to the centre normal to the curve: g(s) = (s - px) + (f(s) - py) "
        "f'(s) = 0. Newton's method uses dg/ds = 1 + f'^2 + (f - py) f''. Clearing "
        "denominators and square roots turns g into a polynomial whose real roots are the "
        "candidates. The tangent angle at the contact is z = atan f'(s), and the ball's "
        "single-point contact requires r below the radius of curvature "
        "(1 + f'^2)^{3/2} / |f''|. Curves with abs() are split at their kinks into walls; "
        "where abs() leaves the curve C^2 (abs(x)**3 at 0) the curve stays one wall.",
        "",
    ]
    for cd in curves:
        out += [f"### {cd.name}: $f(x) = {sm.latex(cd.expression)}$", ""]
        values = ", ".join(f"{k} = {v}" for k, v in sorted(cd.parameters.items()))
        out.append(f"Parameters: {values} (SI).")
        out.append("")
        for j, w in enumerate(cd.walls):
            if len(cd.walls) > 1:
                out += [f"Wall {j}, on ${sm.latex(w.lo)} < x < {sm.latex(w.hi)}$:", ""]
            out += [
                "$$",
                f"f'(s) = {sm.latex(w.df)},\\qquad f''(s) = {sm.latex(w.d2f)},"
                f"\\qquad f'''(s) = {sm.latex(w.d3f)}",
                "$$",
                "",
                "$$",
                f"g(s) = {sm.latex(w.near)}",
                "$$",
                "",
            ]
            if w.poly is not None:
                poly = sm.Add(
                    *[c * sm.Symbol("s") ** (len(w.poly) - 1 - i) for i, c in enumerate(w.poly)]
                )
                out += [
                    f"Candidate nearest points: real roots of this degree-{len(w.poly) - 1} "
                    "polynomial:",
                    "",
                    "$$",
                    f"{sm.latex(poly)} = 0",
                    "$$",
                    "",
                ]
    return "\n".join(out).rstrip() + "\n"
