"""Write docs/derivation.md from the derivation itself (sympy's LaTeX inside Markdown).

Each stage shows the derivation's objects, then the textbook form a reader can check by
hand (:mod:`.textbook`) with the name of the test that proves the two equal. Equations
are broken into rows that fit the page; an equation longer than a few rows (the solved
impact and contact expressions) goes to the appendix, where the textbook forms stand in
for it in the text.
"""

from __future__ import annotations

import sympy as sm

from . import textbook
from .ball import BallDerivation, plain
from .contact import ContactDerivation, printable
from .curve import CurveDerivation
from .expr import BUILTIN_CURVES

#: Longest row of LaTeX source on the page (a row of 100 source characters renders
#: narrower than GitHub's Markdown column at normal zoom; tests/derivation/test_textbook.py
#: says why and checks it).
WIDTH = 100
#: The width long expressions are broken to, leaving room for the label, the signs and
#: the brackets that breaking adds.
BREAK = 84
#: An equation longer than this many rows goes to the appendix.
MAX_ROWS = 6
#: Which textbook stages follow which step of the derivation, by the step's title.
STAGES_AFTER = {
    "Equations of motion in flight": ("flight",),
    "Drag-free flight in closed form": ("flight_exact",),
    "Impact: generalized impulse equals the jump in generalized momentum": ("kinematics",),
    "Impact, first hypothesis: no slip": ("impact_stick",),
    "Impact, second hypothesis: slip": ("impact_slip",),
    "Sustained contact: the wall's local geometry": ("geometry",),
    "Sustained contact: the state for the transitions": ("contact_kinematics",),
    "Rolling: the no-slip constraint and Kane's equations": ("rolling",),
    "Sliding: Coulomb friction and Kane's equations": ("sliding",),
}
_CODE = {
    "kinematics": "generated/ball.py: frame_velocity, contact_velocity",
    "flight": "generated/ball.py: flight_rhs_drag, flight_rhs_magnus, forcing_drag",
    "flight_exact": "generated/ball.py: flight_exact",
    "impact_stick": "generated/ball.py: impact_stick",
    "impact_slip": "generated/ball.py: impact_slip",
    "geometry": "generated/contact.py, which takes the wall's f', f'', f''' through these",
    "contact_kinematics": (
        "generated/contact.py: slip_velocity, roll_spin, s_dot_of_velocity, contact_energy"
    ),
    "rolling": "generated/contact.py: roll_rhs",
    "sliding": "generated/contact.py: slide_rhs",
}


def _tex(expr) -> str:
    return sm.latex(expr, mat_delim="(", fold_func_brackets=True)


def _wrap(head: str, inner, width: int, tail: str = "") -> list[str]:
    """head ( inner ) tail, the inner expression broken into rows; the head and the
    closing bracket share the first and last row where they fit."""
    rows = _rows(inner, width - 4)
    if len(head) + 8 + len(rows[0]) <= width:
        rows[0] = rf"{head} \Bigl( {rows[0]}".lstrip()
    else:
        rows.insert(0, rf"{head} \Bigl(".lstrip())
    close = rf"\Bigr){tail}"
    if len(rows) > 1 and len(rows[-1]) + 1 + len(close) <= width:
        rows[-1] = f"{rows[-1]} {close}"
    else:
        rows.append(close)
    return rows


def _rows(expr, width: int) -> list[str]:
    """*expr* in LaTeX broken into rows of at most about *width* characters: a sum at its
    terms, a quotient as 1/denominator times its numerator, a product at its largest
    factor. A row that cannot be broken stays whole (the page test then refuses it)."""
    text = _tex(expr)
    width = max(width, 40)  # no narrower: a few rows of nesting stay within the page
    if len(text) <= width or not isinstance(expr, sm.Expr):
        return [text]
    if expr.is_Add:
        rows: list[str] = []
        current = ""
        for i, term in enumerate(expr.as_ordered_terms()):
            negative = term.as_coeff_Mul()[0].is_negative
            parts = _rows(-term if negative else term, width - 2)
            sign = "- " if negative else ("+ " if i else "")
            parts[0] = sign + parts[0]
            for j, part in enumerate(parts):
                if j == 0 and current and len(current) + 1 + len(part) <= width:
                    current = f"{current} {part}"
                else:
                    if current:
                        rows.append(current)
                    current = part
        rows.append(current)
        return rows
    num, den = sm.fraction(expr)
    if den != 1:
        return _wrap(rf"\frac{{1}}{{{_tex(den)}}}", num, width)
    if expr.is_Mul:
        factors = sorted(expr.args, key=lambda f: len(_tex(f)))
        big, rest = factors[-1], sm.Mul(*factors[:-1])
        head = "-" if rest == -1 else ("" if rest == 1 else _tex(rest))
        if big.is_Add:
            return _wrap(head, big, width)
        if big.is_Pow and big.base.is_Add and big.exp.is_Integer and big.exp > 0:
            return _wrap(head, big.base, width, f"^{{{big.exp}}}")
    if expr.is_Pow and expr.base.is_Add and expr.exp.is_Integer and expr.exp > 0:
        return _wrap("", expr.base, width, f"^{{{expr.exp}}}")
    return [text]


def _names(label: str, n: int) -> list[str]:
    """Names of the n entries of a vector labelled (a, b, c)_{sub}, else [label]_i."""
    if label.startswith("("):
        inner, _, sub = label[1:].partition(")")
        parts = [p.strip() for p in inner.replace(r",\ ", ",").split(",")]
        if len(parts) == n:
            return [f"{{{p}}}{sub}" if sub else p for p in parts]
    return [rf"\left[{label}\right]_{{{i + 1}}}" for i in range(n)]


def _equations(label: str, expr) -> list[list[str]]:
    """The rows of each displayed equation for label = expr: one equation, or one per
    entry of a vector or matrix too wide for one row."""
    text = _tex(expr)
    if len(label) + 3 + len(text) <= WIDTH or not isinstance(expr, sm.MatrixBase):
        return [_rows_of(label, expr)]
    entries = list(expr)
    names = _names(label, len(entries))
    return [_rows_of(name, entry) for name, entry in zip(names, entries, strict=True)]


def _rows_of(label: str, expr) -> list[str]:
    if len(label) + 3 + len(_tex(expr)) <= WIDTH:
        return [f"{label} = {_tex(expr)}"]
    rows = _rows(expr, max(BREAK - len(label), 40))
    return [f"{label} = {rows[0]}", *rows[1:]] if len(rows) == 1 else [f"{label} ={{}}", *rows]


def _display(rows: list[str]) -> list[str]:
    """A $$ block: one row as is, several as an aligned environment, a row per line."""
    if len(rows) == 1:
        return ["$$", rows[0], "$$", ""]
    body = [rf"{rows[0]} & {rows[1]} \\"] + [rf"& {row} \\" for row in rows[2:-1]]
    if len(rows) > 2:
        body.append(f"& {rows[-1]}")
    else:
        body[0] = body[0].removesuffix(r" \\")
    return ["$$", r"\begin{aligned}", *body, r"\end{aligned}", "$$", ""]


def _textbook(stage: textbook.Stage, code: str) -> list[str]:
    out = [f"**Textbook form.** {stage.text}", ""]
    if stage.intermediates:
        out += ["Named quantities:", ""]
        for symbol, definition in stage.intermediates:
            name, value = textbook.latex(symbol), textbook.latex(definition)
            if name != value:  # u_s, the code's s_dot, is no new quantity
                out += _display([f"{name} = {value}"])
    for form in stage.forms:
        out += _display([form.latex()])
    out += [
        f"`tests/derivation/test_textbook.py::{stage.test}` proves with sympy, exactly, that "
        f"the derived expressions and the generated code ({code}) equal these forms.",
        "",
    ]
    return out


def _steps(steps, first: int, show, appendix: list[str]) -> list[str]:
    stages = {st.title: st for st in textbook.stages()}
    out = []
    for i, step in enumerate(steps, first):
        out += [f"## {i}. {step.title}", "", step.text, ""]
        moved = []
        for label, expr in step.equations:
            equations = _equations(label, show(expr))
            if max(len(rows) for rows in equations) > MAX_ROWS:
                if not moved:
                    appendix += [f"### A.{i}. {step.title}", ""]
                moved.append(label)
                for rows in equations:
                    appendix += _display(rows)
            else:
                for rows in equations:
                    out += _display(rows)
        if moved:
            out += [
                f"The solved {', '.join(f'${m}$' for m in moved)} run to many rows; they are "
                f"printed in full in the appendix (A.{i}). The textbook form below is the "
                "same result, short.",
                "",
            ]
        for title in STAGES_AFTER.get(step.title, ()):
            out += _textbook(stages[title], _CODE[title])
    return out


def derivation_markdown(
    d: BallDerivation, cd: ContactDerivation, curves: list[CurveDerivation]
) -> str:
    out = [
        "# Derivation of the model",
        "",
        "This page is written by `billiard derive` from the derivation code "
        "(`derivation/ball.py`, `derivation/contact.py`, `derivation/curve.py`, "
        "`derivation/textbook.py`); do not edit it by hand. The sections follow the code "
        "from top to bottom. Each stage ends with its **textbook form**: the short "
        "equations a reader can check by hand (Newton's and Euler's laws, the impulse "
        "balances), with named intermediate quantities, and the test that proves by sympy "
        "that the derivation and the generated code equal them exactly. Expressions too "
        "long to read are in the appendix. Symbols: `m` mass, "
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
    appendix: list[str] = []
    out += _steps(d.steps, 1, plain, appendix)
    out += _steps(cd.steps, len(d.steps) + 1, printable, appendix)
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
        out += [f"### {cd.name}: $f(x) = {_tex(cd.expression)}$", ""]
        values = ", ".join(f"{k} = {v}" for k, v in sorted(cd.parameters.items()))
        out.append(f"Parameters: {values} (SI).")
        out.append("")
        stages = textbook.curve_stages(cd.name) if cd.name in BUILTIN_CURVES else ()
        for j, w in enumerate(cd.walls):
            if len(cd.walls) > 1:
                out += [f"Wall {j}, on ${_tex(w.lo)} < x < {_tex(w.hi)}$:", ""]
            for label, expr in (("f'(s)", w.df), ("f''(s)", w.d2f), ("f'''(s)", w.d3f)):
                for rows in _equations(label, expr):
                    out += _display(rows)
            for rows in _equations("g(s)", w.near):
                out += _display(rows)
            if w.poly is not None:
                poly = sm.Add(
                    *[c * sm.Symbol("s") ** (len(w.poly) - 1 - i) for i, c in enumerate(w.poly)]
                )
                out += [
                    f"Candidate nearest points: real roots of this degree-{len(w.poly) - 1} "
                    "polynomial P(s):",
                    "",
                ]
                for rows in _equations("P(s)", poly):
                    out += _display(rows)
            if stages:
                out += _textbook(stages[j], f"generated/curves/{cd.name}.py: df, d2f, d3f, poly")
    if appendix:
        out += [
            "## Appendix A. The solved expressions in full",
            "",
            "The derivation's solutions as sympy returns them, broken into rows; A.n belongs "
            "to section n. They equal the textbook forms of their sections exactly.",
            "",
            *appendix,
        ]
    return "\n".join(out).rstrip() + "\n"
