"""A report of what was derived for one curve (``billiard derive --name --curve --report``).

Markdown (LaTeX between ``$$``, as GitHub renders it) and a standalone HTML page whose
equations are MathML, which browsers render natively (Chromium since version 109): the
page loads nothing, so it renders offline. Sections: the pieces (walls) and their joins,
the offset curve of the ball's centre and where it is valid (radius of curvature above
the ball's radius), the equations of flight, contact and impact in readable form, and
exact checks of the code the runtime runs (``generated/``) for that curve.

The checks call the generated functions with sympy symbols in place of numbers (their
``math`` replaced by sympy's functions), so they check the code that runs, not a second
copy of the derivation, and cost a few seconds: no Kane derivation is redone.
"""

from __future__ import annotations

import html
import math
import types
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import sympy as sm

from . import shape
from .contact import derive_contact, printable
from .curve import JOIN_MEANING, CurveDerivation, x

#: File names written into the report's folder.
MARKDOWN, HTML = "report.md", "report.html"
#: How many evenly spaced abscissas the radius of curvature is compared with r at.
POINTS = 4001

m, r, k, g, e = sm.symbols("m r k g e", positive=True)
mu_k, sgn = sm.symbols("mu_k sgn", real=True)
u1, u2, u3, vb1, vb2 = sm.symbols("u1 u2 u3 vb1 vb2", real=True)
q2, s, s_dot = sm.symbols("q2 s s_dot", real=True)
fp, f2, f3, f0 = sm.symbols("fp f2 f3 f0", real=True)
w_t, w_n = sm.symbols("w_t w_n", real=True)
_tan_half = sm.Symbol("tau", real=True)  # tan(z/2): sin and cos become rational in it
z = sm.Symbol("z", real=True)
_t = sm.Symbol("t", real=True)


def _short_forms(wt: sm.Basic, wn: sm.Basic) -> dict[str, sm.Basic]:
    """The impulses a reader checks by hand (boundary frame, sphere I = k m r^2), from the
    pre-impact slip wt and normal velocity wn of the contact point relative to the wall."""
    rn = -(1 + e) * m * wn
    return {
        "stick R_n": rn,
        "stick R_t": -k * m * wt / (1 + k),
        "slip R_n": rn,
        "slip R_t": -mu_k * sgn * rn,
    }


#: The textbook forms the generated impact code is compared with (a test plants a wrong
#: one here to see the check fail).
TEXTBOOK: Callable[[sm.Basic, sm.Basic], dict[str, sm.Basic]] = _short_forms


@dataclass
class Check:
    """One exact check: what was compared, and whether it held."""

    name: str
    compared: str
    passed: bool


@dataclass
class Section:
    title: str
    blocks: list[tuple] = field(default_factory=list)  # ("p", text) | ("eq", lhs, rhs) | table

    def text(self, words: str) -> None:
        self.blocks.append(("p", words))

    def eq(self, lhs, rhs) -> None:
        self.blocks.append(("eq", sm.sympify(lhs), sm.sympify(rhs)))

    def table(self, header: list[str], rows: list[list[str]]) -> None:
        self.blocks.append(("table", header, rows))


@dataclass
class CurveReport:
    name: str
    text: str
    radius: float
    sections: list[Section]
    checks: list[Check]
    refusal: str | None

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


# --- the generated code, called with symbols -------------------------------------------

_SYMPY_MATH = types.SimpleNamespace(
    sqrt=sm.sqrt, sin=sm.sin, cos=sm.cos, tan=sm.tan, atan=sm.atan, atan2=sm.atan2,
    exp=sm.exp, log=sm.log, sinh=sm.sinh, cosh=sm.cosh, tanh=sm.tanh, pi=sm.pi,
    fabs=sm.Abs, copysign=lambda a, b: sm.Abs(a) * sm.sign(b), inf=sm.oo,
)  # fmt: skip


def symbolic(fn: Callable) -> Callable:
    """A generated function that computes with sympy expressions: its ``math`` is sympy's,
    and its float constants (``0.5``) become exact rationals in the result."""
    sym = types.FunctionType(fn.__code__, {**fn.__globals__, "math": _SYMPY_MATH})

    def call(*args):
        out = sym(*args)
        if isinstance(out, tuple):
            return tuple(sm.nsimplify(o, rational=True) for o in out)
        return sm.nsimplify(out, rational=True)

    return call


def _zero(expr: sm.Basic) -> bool:
    """Exactly zero? sin z and cos z become rational in tan(z/2), so a trigonometric
    identity is decided by rational cancellation (cheap); the rest by sympy's simplify."""
    half = {
        sm.sin(z): 2 * _tan_half / (1 + _tan_half**2),
        sm.cos(z): (1 - _tan_half**2) / (1 + _tan_half**2),
    }
    expr = sm.cancel(sm.together(sm.sympify(expr).xreplace(half)))
    return expr == 0 or sm.simplify(expr) == 0


# --- the checks ----------------------------------------------------------------------------


def impact_checks() -> list[Check]:
    """The generated impact impulses equal the short forms in the boundary's frame."""
    from billiard.generated import ball

    wt, wn = symbolic(ball.contact_velocity)(u1, u2, u3, z, vb1, vb2, r)
    forms = TEXTBOOK(wt, wn)
    stick = symbolic(ball.impact_stick)(u1, u2, u3, z, vb1, vb2, m, r, k, e)
    slip = symbolic(ball.impact_slip)(u1, u2, u3, z, vb1, vb2, m, r, k, e, mu_k, sgn)
    got = {"stick R_t": stick[3], "stick R_n": stick[4], "slip R_t": slip[3], "slip R_n": slip[4]}
    checks = []
    for key, value in got.items():
        regime, name = key.split()
        checks.append(
            Check(
                f"{regime} impact: {name} = {sm.sstr(forms[key].xreplace({wt: w_t, wn: w_n}))}",
                f"generated impact_{regime} {name} minus the short form, with w_t, w_n the "
                "generated contact_velocity; exact (sin z, cos z rational in tan(z/2))",
                _zero(value - forms[key]),
            )
        )
    return checks


def flight_check() -> Check:
    """The generated flight equals the textbook form m dv/dt = -m g n2 - (c_lin + c_quad
    |v|) v."""
    from billiard.generated import ball

    c_lin, c_quad = sm.symbols("c_lin c_quad", real=True)
    got = symbolic(ball.flight_rhs_drag)(u1, u2, m, g, c_lin, c_quad)
    drag = (c_lin + c_quad * sm.sqrt(u1**2 + u2**2)) / m
    textbook = (-drag * u1, -g - drag * u2)
    return Check(
        "flight: dv/dt = -g n2 - (c_lin + c_quad |v|) v / m",
        "generated flight_rhs_drag minus the textbook form, both components; exact",
        all(_zero(a - b) for a, b in zip(got, textbook, strict=True)),
    )


def flight_energy_check() -> Check:
    """Without drag, d/dt of the generated energy along the generated flight is 0."""
    from billiard.generated import ball

    energy = symbolic(ball.energy)(q2, u1, u2, u3, m, r, k, g)
    du1, du2 = symbolic(ball.flight_rhs_drag)(u1, u2, m, g, 0, 0)
    rate = energy.diff(q2) * u2 + energy.diff(u1) * du1 + energy.diff(u2) * du2
    return Check(
        "flight without drag conserves the energy: dE/dt = 0",
        "generated energy differentiated along generated flight_rhs_drag (c_lin = c_quad "
        "= 0, spin constant); exact",
        _zero(rate),
    )


def rolling_energy_check() -> Check:
    """Rolling on a still wall without drag conserves the energy in the boundary's frame:
    the generated contact_energy along roll_rhs, with the spin from roll_spin. The
    equations see the wall only through f, f', f'', f''' at s, whose rates along the
    motion are f' s_dot, f'' s_dot, f''' s_dot: so this holds for every wall of every
    curve, this one's included."""
    from billiard.generated import contact

    spin = symbolic(contact.roll_spin)(s_dot, fp, f2, r)
    energy = symbolic(contact.contact_energy)(s_dot, spin, f0, fp, f2, m, r, k, g)
    s_ddot = symbolic(contact.roll_rhs)(s_dot, fp, f2, f3, 0, 0, 0, 0, m, r, k, g, 0, 0)[0]
    rate = (
        energy.diff(f0) * fp * s_dot
        + energy.diff(fp) * f2 * s_dot
        + energy.diff(f2) * f3 * s_dot
        + energy.diff(s_dot) * s_ddot
    )
    return Check(
        "rolling on a still wall without drag conserves the energy: dE_B/dt = 0",
        "generated contact_energy (spin from roll_spin) differentiated along generated "
        "roll_rhs (boundary at rest, c_lin = c_quad = 0), f, f', f'' advancing at f' s_dot, "
        "f'' s_dot, f''' s_dot; exact",
        _zero(rate),
    )


def offset_checks(cd: CurveDerivation, defaults: dict) -> list[Check]:
    """Per wall: the generated offset curve is at distance r from the wall along its
    normal, and is the wall itself as r -> 0."""
    from billiard.generated import contact

    centre = symbolic(contact.centre_state)
    checks = []
    for j, w in enumerate(cd.walls):
        f, df, d2f = (sm.sympify(v).subs(defaults) for v in (w.f, w.df, w.d2f))
        c1, c2 = centre(s, 0, f, df, d2f, 0, 0, 0, 0, r)[:2]
        label = f"wall {j}" if len(cd.walls) > 1 else "the curve"
        limit = [c1.subs(r, 0) - s, c2.subs(r, 0) - f]
        checks.append(
            Check(
                f"{label}: as r -> 0 the offset curve is the curve",
                "generated centre_state at r = 0 minus (s, f(s)); exact",
                all(_zero(v) for v in limit),
            )
        )
        normal = sm.Matrix([-df, 1]) / sm.sqrt(1 + df**2)
        gap = sm.Matrix([c1 - s, c2 - f]) - r * normal
        checks.append(
            Check(
                f"{label}: the offset curve is r along the normal of the curve",
                "generated centre_state minus (s, f(s)) + r (-f', 1)/sqrt(1 + f'^2); exact",
                all(_zero(v) for v in gap),
            )
        )
    return checks


# --- numbers: walls, joins, validity --------------------------------------------------------


def numeric_walls(cd: CurveDerivation, defaults: dict) -> list[dict]:
    """The walls as :mod:`shape` takes them (functions of x in m, parameters bound)."""
    walls = []
    for w in cd.walls:
        fns = {
            key: sm.lambdify(s, sm.sympify(getattr(w, key)).subs(defaults), "math")
            for key in ("f", "df", "d2f")
        }
        lo, hi = (float(sm.sympify(v).subs(defaults)) for v in (w.lo, w.hi))
        smooth = len(walls) < len(cd.joins) and cd.joins[len(walls)] in ("C1", "C2")
        walls.append({"lo": lo, "hi": hi, **fns, "smooth_hi": smooth})
    return walls


def joins(walls: list[dict], classes: list[str]) -> list[tuple[float, float, float, str]]:
    """(x, slope left, slope right, kind) at each join between neighbouring walls, the
    kind the derivation's exact class (:data:`JOIN_MEANING`)."""
    out = []
    for left, right, kind in zip(walls, walls[1:], classes, strict=False):
        at = left["hi"]
        sl, sr = float(left["df"](at)), float(right["df"](at))
        out.append((at, sl, sr, f"{kind}: {JOIN_MEANING[kind]}"))
    return out


def validity(walls: list[dict], radius: float, points: int = POINTS) -> dict:
    """Where on the usable range (:func:`shape.usable_range`) the radius of curvature
    (1 + f'^2)^(3/2) / |f''| of the curve is above ``radius`` (m): there the ball touches
    the curve at one point and its centre follows the offset curve."""
    left, right = shape.usable_range(walls)
    xs = np.linspace(left, right, points)
    rho = np.full_like(xs, np.inf)
    for w in walls:
        held = (xs >= w["lo"]) & (xs <= w["hi"])
        for i in np.flatnonzero(held):
            try:  # a complex value: TypeError
                at = float(xs[i])  # a Python float: 1/0 raises, as in the runtime
                df, d2f = float(w["df"](at)), float(w["d2f"](at))
            except (ArithmeticError, ValueError, TypeError):
                rho[i] = math.nan  # not real here: the ball cannot follow the curve
                continue
            value = (1 + df * df) ** 1.5 / abs(d2f) if d2f != 0 else math.inf
            rho[i] = min(rho[i], value)  # NaN (f' not finite) stays NaN
    bad = ~(rho > radius)
    spans = []
    i = 0
    while i < len(xs):
        if bad[i]:
            j = i
            while j + 1 < len(xs) and bad[j + 1]:
                j += 1
            spans.append((float(xs[i]), float(xs[j])))
            i = j + 1
        else:
            i += 1
    finite = np.isfinite(rho)  # a straight wall's infinite rho has no place to name
    smallest = (
        (float(rho[finite].min()), float(xs[finite][rho[finite].argmin()]))
        if finite.any()
        else None
    )
    undefined = int(np.isnan(rho).sum())
    return {
        "range": (left, right),
        "too_tight": spans,
        "smallest": smallest,
        "undefined": undefined,
    }


# --- the report --------------------------------------------------------------------------


def curve_report(cd: CurveDerivation, radius: float, refusal: str | None = None) -> CurveReport:
    """Everything the report says about ``cd`` for a ball of ``radius`` (m); ``refusal``:
    why ``billiard derive`` refused the curve (the report is written all the same)."""
    defaults = {p: sm.Rational(cd.parameters[p.name]) for p in cd.parameter_symbols}
    walls = numeric_walls(cd, defaults)
    sections = []

    head = Section("The curve")
    head.eq(sm.Function("f")(x), cd.expression)
    if cd.parameters:
        values = ", ".join(f"{n} = {v}" for n, v in sorted(cd.parameters.items()))
        head.text(f"Parameters: {values} (SI). The report uses these values.")
    head.text(
        f"Ball radius r = {radius:g} m (the default scene's ball; `--radius` sets another). "
        "Lengths in m, times in s, masses in kg."
    )
    if refusal is not None:
        head.text(f"**Refused:** `billiard derive` did not write this curve: {refusal}.")
    sections.append(head)

    pieces = Section("Pieces and joins")
    pieces.text(
        "The curve is a chain of walls, smooth pieces each valid on an interval (split at "
        "the zeros of abs() arguments and at the bounds of a Piecewise's conditions; a "
        "zero of an abs() argument where the curve is C2 stays inside one wall). The "
        "height at x is that of the wall holding x. Walls joined smoothly (C1, C2) are one "
        "surface for the ball, which rolls across the join; at a kink it can touch both."
    )
    pieces.table(
        ["wall", "interval", "f(x) on it"],
        [
            [str(j), shape.interval_text(wd["lo"], wd["hi"]), f"`{sm.sstr(w.f.subs(s, x))}`"]
            for j, (w, wd) in enumerate(zip(cd.walls, walls, strict=True))
        ],
    )
    found = joins(walls, cd.joins)
    if found:
        pieces.table(
            ["join at x (m)", "slope left", "slope right", "kind"],
            [[f"{a:g}", f"{sl:.6g}", f"{sr:.6g}", kind] for a, sl, sr, kind in found],
        )
    else:
        pieces.text("One wall: the curve has no join.")
    join_issue = shape.chain_problem(walls)
    shape_issue = shape.shape_problem(shape.chained(walls))
    sections.append(pieces)

    offset = Section("The offset curve and where it is valid")
    offset.text(
        "In contact the ball's centre lies on the offset curve C(s) = W(s) + r c2(s), a "
        "radius from the wall point W(s) = (s, f(s)) along the inward normal c2, as the "
        "generated `centre_state` computes it:"
    )
    from billiard.generated import contact as gen_contact

    centre = symbolic(gen_contact.centre_state)
    for j, w in enumerate(cd.walls):
        f, df, d2f = (sm.sympify(v).subs(defaults) for v in (w.f, w.df, w.d2f))
        c1, c2 = centre(s, 0, f, df, d2f, 0, 0, 0, 0, r)[:2]
        if len(cd.walls) > 1:
            offset.text(f"Wall {j} ({shape.interval_text(walls[j]['lo'], walls[j]['hi'])}):")
        offset.eq(sm.Symbol("C_x"), c1)
        offset.eq(sm.Symbol("C_y"), c2)
        rho = (1 + df**2) ** sm.Rational(3, 2) / sm.Abs(d2f)
        offset.eq(sm.Symbol("rho"), sm.oo if rho.has(sm.zoo) else rho)  # a straight wall
    valid = validity(walls, radius)
    left, right = valid["range"]
    offset.text(
        "The ball touches the curve at a single point, and its centre follows the offset "
        "curve, where the radius of curvature rho = (1 + f'^2)^(3/2) / |f''| is above r = "
        f"{radius:g} m. Checked at {POINTS} points of the range the ball can reach, "
        f"{left:.6g} m <= x <= {right:.6g} m:"
    )
    if valid["smallest"] is None:
        offset.text("The walls are straight (f'' = 0): rho is infinite, valid everywhere.")
    else:
        small, where = valid["smallest"]
        offset.text(f"The smallest radius of curvature is {small:.6g} m, at x = {where:.6g} m.")
    if valid["undefined"]:
        offset.text(
            f"At {valid['undefined']} of the points f' or f'' is not real and finite; they "
            "count as not valid."
        )
    if valid["too_tight"]:
        spans = "; ".join(f"{a:.6g} m <= x <= {b:.6g} m" for a, b in valid["too_tight"])
        offset.text(f"**Not valid** (rho <= r) on {spans}: the ball cannot follow the curve there.")
    else:
        offset.text(f"Valid on the whole range: rho > r = {radius:g} m everywhere.")
    if found:
        offset.text(
            "At a kink the offset curves of the two walls meet at a corner: the ball touches "
            "both walls at once there and never the kink itself."
        )
    sections.append(offset)

    sections += _equation_sections(cd, defaults)

    checks = impact_checks() + [flight_check(), flight_energy_check(), rolling_energy_check()]
    checks += offset_checks(cd, defaults)
    checks.append(
        Check(
            "the curve can hold a ball",
            "derivation/shape.py shape_problem on the walls (numeric)",
            shape_issue is None,
        )
    )
    checks.append(
        Check(
            "the maximum of the walls is the curve (joins)",
            "derivation/shape.py chain_problem on the walls (numeric)"
            + ("" if join_issue is None else f": {join_issue}"),
            join_issue is None,
        )
    )
    return CurveReport(cd.name, cd.text, radius, sections, checks, refusal)


def _equation_sections(cd: CurveDerivation, defaults: dict) -> list[Section]:
    from billiard.generated import ball

    t = _t
    flight = Section("Flight")
    flight.text(
        "Between contacts the ball flies under gravity and Fowles drag (c_lin, c_quad), "
        "in the lab frame; the curve does not enter. u1, u2 the centre's velocity, u3 the "
        "spin (constant in flight). Generated `flight_rhs_drag`:"
    )
    du1, du2 = symbolic(ball.flight_rhs_drag)(u1, u2, m, g, *sm.symbols("c_lin c_quad"))
    # d/dt of plain symbols, unevaluated: both printers subscript u_1 (not so a u_1(t))
    flight.eq(sm.Derivative(sm.Symbol("u_1"), t, evaluate=False), du1)
    flight.eq(sm.Derivative(sm.Symbol("u_2"), t, evaluate=False), du2)

    geometry = Section("Contact: the wall's geometry for this curve")
    geometry.text(
        "The contact equations see the wall only through f', f'', f''' at the contact "
        "abscissa s (in the boundary's frame). For this curve:"
    )
    for j, w in enumerate(cd.walls):
        if len(cd.walls) > 1:
            geometry.text(f"Wall {j}:")
        geometry.eq(sm.Symbol("f'"), sm.sympify(w.df).subs(defaults))
        geometry.eq(sm.Symbol("f''"), sm.sympify(w.d2f).subs(defaults))
        geometry.eq(sm.Symbol("f'''"), sm.sympify(w.d3f).subs(defaults))
        geometry.eq(sm.Symbol("z"), sm.atan(sm.sympify(w.df).subs(defaults)))
    contact = derive_contact()
    geometry.text("with the tangent angle z, L = |dW/ds| and their rates:")
    for key, value in contact.geometry.items():
        geometry.eq(printable(key), printable(value))

    rolling = Section("Contact: rolling and sliding")
    rolling.text(
        "Kane's method with the no-slip constraint (rolling) or Coulomb friction F = "
        "-mu_k N sgn (sliding); c_drag = c_lin + c_quad |v|; ab1, ab2 the boundary's "
        "acceleration. Insert the geometry above for this curve."
    )
    s_ddot = sm.Derivative(sm.Symbol("s"), (t, 2), evaluate=False)
    spin_dot = sm.Derivative(sm.Symbol("u_3"), t, evaluate=False)
    rolling.text("Rolling: the spin follows the no-slip condition, and")
    rolling.eq(sm.Symbol("u_3"), printable(contact.roll_spin))
    for lhs, expr in zip(
        (s_ddot, sm.Symbol("F"), sm.Symbol("N")), [contact.roll[i] for i in (0, 2, 3)], strict=True
    ):
        rolling.eq(lhs, printable(expr))
    rolling.text("Sliding (F = -mu_k N sgn):")
    for lhs, expr in zip((s_ddot, spin_dot, sm.Symbol("N")), contact.slide[:3], strict=True):
        rolling.eq(lhs, printable(expr))

    impact = Section("Impact")
    impact.text(
        "In the boundary's frame at the contact (tangent c1, inward normal c2, z = atan f'(s) "
        "of the wall hit), w_t and w_n are the slip and the normal velocity of the ball's "
        "contact point relative to the boundary before the impact (w_n < 0 approaching), "
        "vb1, vb2 the boundary's velocity. The impulse R = R_t c1 + R_n c2 (N s), e the "
        "restitution, k = 2/5 for a solid sphere:"
    )
    wt, wn = symbolic(ball.contact_velocity)(u1, u2, u3, z, vb1, vb2, r)
    impact.eq(w_t, wt)
    impact.eq(w_n, wn)
    # unevaluated, so that -(1 + e) stays as a reader writes it
    rn = sm.Mul(-1, 1 + e, m, w_n, evaluate=False)
    forms = {
        "stick R_n": rn,
        "stick R_t": sm.Mul(-1, k, m, w_t, 1 / (1 + k), evaluate=False),
        "slip R_n": rn,
        "slip R_t": sm.Mul(-1, mu_k, sgn, sm.Symbol("R_n"), evaluate=False),
    }
    impact.text("Sticking (the contact point stops slipping, valid while |R_t| <= mu_s R_n):")
    impact.eq(sm.Symbol("R_n"), forms["stick R_n"])
    impact.eq(sm.Symbol("R_t"), forms["stick R_t"])
    impact.text("Slipping throughout (kinetic friction against the initial slip):")
    impact.eq(sm.Symbol("R_n"), forms["slip R_n"])
    impact.eq(sm.Symbol("R_t"), forms["slip R_t"])
    return [flight, geometry, rolling, impact]


# --- writing -----------------------------------------------------------------------------


def _latex(expr: sm.Basic) -> str:
    return sm.latex(expr)


def markdown(report: CurveReport) -> str:
    out = [f"# Derivation report: curve `{report.name}`", ""]
    out.append(
        f"Written by `billiard derive --name {report.name} --curve '{report.text}' --report "
        "DIR`. Checks: " + ("all passed." if report.passed else "**some failed** (see the end).")
    )
    out.append("")
    for section in report.sections:
        out += [f"## {section.title}", ""]
        for block in section.blocks:
            if block[0] == "p":
                out += [block[1], ""]
            elif block[0] == "eq":
                out += ["$$", f"{_latex(block[1])} = {_latex(block[2])}", "$$", ""]
            else:
                _, header, rows = block
                out.append("| " + " | ".join(header) + " |")
                out.append("|" + "---|" * len(header))
                out += ["| " + " | ".join(row) + " |" for row in rows]
                out.append("")
    out += ["## Checks", "", "| check | compared | result |", "|---|---|---|"]
    for c in report.checks:
        out.append(f"| {c.name} | {c.compared} | {'passed' if c.passed else '**FAILED**'} |")
    return "\n".join(out).rstrip() + "\n"


_STYLE = """
body { font-family: sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em; }
.eq { overflow-x: auto; margin: 0.6em 0; }
table { border-collapse: collapse; margin: 0.8em 0; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: left; }
.passed { color: #176317; } .failed { color: #b00; font-weight: bold; }
"""


def _inline(text: str) -> str:
    """Markdown's `code` and **bold** in a paragraph, as HTML."""
    out = []
    for i, part in enumerate(html.escape(text).split("`")):
        if i % 2:  # inside `code`: no bold (x**2)
            out.append(f"<code>{part}</code>")
        else:
            bold = part.split("**")
            out += [f"<strong>{b}</strong>" if j % 2 else b for j, b in enumerate(bold)]
    return "".join(out)


def _mathml(lhs: sm.Basic, rhs: sm.Basic) -> str:
    left = sm.mathml(lhs, printer="presentation")
    right = sm.mathml(rhs, printer="presentation")
    return f'<math display="block"><mrow>{left}<mo>=</mo>{right}</mrow></math>'


def html_page(report: CurveReport) -> str:
    body = [f"<h1>Derivation report: curve <code>{html.escape(report.name)}</code></h1>"]
    verdict = "all passed." if report.passed else "<strong>some failed</strong> (see the end)."
    body.append(
        f"<p>Written by <code>billiard derive --name {html.escape(report.name)} --curve "
        f"'{html.escape(report.text)}' --report DIR</code>. Checks: {verdict}</p>"
    )
    for section in report.sections:
        body.append(f"<h2>{html.escape(section.title)}</h2>")
        for block in section.blocks:
            if block[0] == "p":
                body.append(f"<p>{_inline(block[1])}</p>")
            elif block[0] == "eq":
                body.append(f'<div class="eq">{_mathml(block[1], block[2])}</div>')
            else:
                _, header, rows = block
                body.append(_table(header, rows))
    body.append("<h2>Checks</h2>")
    rows = [[c.name, c.compared, "passed" if c.passed else "FAILED"] for c in report.checks]
    body.append(_table(["check", "compared", "result"], rows, result_column=2))
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; '
        "style-src 'unsafe-inline'; img-src data:\">"
        '<link rel="icon" href="data:,">'
        f"<title>Derivation report: {html.escape(report.name)}</title>"
        f"<style>{_STYLE}</style></head>\n<body>\n" + "\n".join(body) + "\n</body></html>\n"
    )


def _table(header: list[str], rows: list[list[str]], result_column: int | None = None) -> str:
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>"]
    for row in rows:
        cells = []
        for i, cell in enumerate(row):
            css = ""
            if i == result_column:
                css = ' class="passed"' if cell == "passed" else ' class="failed"'
            cells.append(f"<td{css}>{_inline(cell)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    return "\n".join(out) + "</table>"


def write_report(report: CurveReport, directory: Path) -> list[Path]:
    """Write report.md and report.html into ``directory`` (made if missing)."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / MARKDOWN, directory / HTML]
    paths[0].write_text(markdown(report), encoding="utf-8")
    paths[1].write_text(html_page(report), encoding="utf-8")
    return paths


def report_curve(
    cd: CurveDerivation, radius: float, directory: Path, refusal: str | None = None
) -> CurveReport:
    """The report of ``cd`` for a ball of ``radius`` (m), written into ``directory``;
    ``refusal``: why ``billiard derive`` refused the curve, said in the report."""
    report = curve_report(cd, radius, refusal)
    write_report(report, directory)
    return report
