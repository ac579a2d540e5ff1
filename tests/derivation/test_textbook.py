"""The textbook forms of docs/derivation.md equal the derivation and the generated code,
exactly, by sympy.

For every stage (kinematics, flight, each impact regime, the contact geometry and
kinematics, rolling, sliding) and every built-in curve, each textbook form
(``billiard.derivation.textbook``) is checked twice: against the derivation's sympy
expressions, and against the committed generated functions, run on sympy symbols (their
``math`` calls become sympy functions, their float literals exact rationals). Equality is
exact: :func:`textbook.is_zero` cancels the difference as a rational function after the
Weierstrass substitution for sin z, cos z and with square roots reduced by their
radicands (no numerical sampling). Each check can fail: ``test_a_wrong_form_is_caught``
breaks every form in turn and sees the check refuse it.
"""

from __future__ import annotations

import functools
import re
import types

import pytest
import sympy as sm
from billiard.derivation import build, textbook
from billiard.derivation.ball import plain
from billiard.derivation.expr import PAPER_CURVES

S = textbook.S

_MATH = types.SimpleNamespace(
    sin=sm.sin, cos=sm.cos, tan=sm.tan, atan=sm.atan, sqrt=sm.sqrt, pow=sm.Pow, pi=sm.pi,
    inf=sm.oo, fabs=sm.Abs,
)  # fmt: skip


def derived():
    return build.derivations()


def _exact(value):
    """A generated float literal as the exact rational it prints (0.5 -> 1/2)."""
    expr = sm.sympify(value)
    floats = {}
    for f in expr.atoms(sm.Float):
        exact = sm.Rational(float(f)).limit_denominator(10**6)
        assert float(exact) == float(f), f"literal {f} is no simple rational"
        floats[f] = exact
    return expr.xreplace(floats)


@functools.cache
def code(name: str) -> types.SimpleNamespace:
    """The committed generated module *name* (``ball``, ``contact``, ``curves/wedge``),
    executed with sympy in place of ``math``."""
    source = (build.GENERATED / f"{name}.py").read_text()
    assert "\nimport math\n" in source
    namespace = {"math": _MATH, "__name__": f"symbolic_{name.replace('/', '_')}"}
    exec(compile(source.replace("\nimport math\n", "\n"), name, "exec"), namespace)
    return types.SimpleNamespace(**namespace)


def call(function, *names):
    """*function* called on the real symbols *names*, each result exact."""
    result = function(*(S[n] for n in names))
    if isinstance(result, tuple):
        return [_exact(v) for v in result]
    return [_exact(result)]


def assert_equal(stage, values, substitute=None):
    """Every form of *stage* holds with the derived *values* (in the stage's unknowns'
    order); *substitute* maps the derivation's symbols to the code's arguments first."""
    residuals = stage.residuals(values)
    for name, residual in residuals.items():
        if substitute is not None:
            residual = substitute(residual)
        assert textbook.is_zero(residual), f"{stage.title}: {name} differs by {residual}"


# --- the ball: kinematics, flight, impacts -------------------------------------------------


def test_kinematics_equals_textbook():
    d, _ = derived()
    stage = textbook.stage("kinematics")
    assert_equal(stage, [*plain(d.frame_velocity), *plain(d.contact_velocity)])
    ball = code("ball")
    values = call(ball.frame_velocity, "u1", "u2", "z") + call(
        ball.contact_velocity, "u1", "u2", "u3", "z", "vb1", "vb2", "r"
    )
    assert_equal(stage, values)


def test_flight_equals_textbook():
    d, _ = derived()
    stage = textbook.stage("flight")
    assert_equal(stage, list(plain(d.rhs_magnus)))
    no_magnus = {S["c_magnus"]: 0}
    drag_only = [textbook.canonical(v) for v in plain(d.rhs_drag)]
    assert_equal(stage, drag_only, lambda res: res.xreplace(no_magnus))
    ball = code("ball")
    spin = call(ball.forcing_drag, "u1", "u2", "u3", "m", "g", "c_lin", "c_quad")[2] / (
        S["k"] * S["m"] * S["r"] ** 2
    )
    magnus = call(ball.flight_rhs_magnus, "u1", "u2", "u3", "m", "g", "c_lin", "c_quad", "c_magnus")
    assert_equal(stage, [*magnus, spin])
    drag = call(ball.flight_rhs_drag, "u1", "u2", "m", "g", "c_lin", "c_quad")
    assert_equal(stage, [*drag, spin], lambda res: res.xreplace(no_magnus))


def test_flight_exact_equals_textbook():
    d, _ = derived()
    stage = textbook.stage("flight_exact")
    assert_equal(stage, list(plain(d.flight_exact)))
    assert_equal(stage, call(code("ball").flight_exact, "t", "q1", "q2", "u1", "u2", "g"))


IMPACT_ARGS = ("u1", "u2", "u3", "z", "vb1", "vb2", "m", "r", "k", "e")


def test_impact_stick_equals_textbook():
    d, _ = derived()
    stage = textbook.stage("impact_stick")
    assert_equal(stage, list(d.stick))
    assert_equal(stage, call(code("ball").impact_stick, *IMPACT_ARGS))


def test_impact_slip_equals_textbook():
    d, _ = derived()
    stage = textbook.stage("impact_slip")
    assert_equal(stage, list(d.slip))
    assert_equal(stage, call(code("ball").impact_slip, *IMPACT_ARGS, "mu_k", "sgn"))


def test_impact_regimes_for_a_solid_sphere_and_the_elastic_rule():
    """The issue's short forms: for a solid sphere (k = 2/5) the sticking impulse is
    -(2/7) m w_t; the elastic regime (the low-velocity rule, e = 1) reverses w_n."""
    d, _ = derived()
    wt, wn = (textbook.canonical(v) for v in plain(d.contact_velocity))
    stick = [textbook.canonical(v) for v in d.stick]
    solid = {S["k"]: sm.Rational(2, 5)}
    assert textbook.is_zero((stick[3] + sm.Rational(2, 7) * S["m"] * wt).xreplace(solid))
    post = {S[n]: v for n, v in zip(("u1", "u2", "u3"), stick[:3], strict=True)}
    assert textbook.is_zero(wn.xreplace(post).xreplace({S["e"]: 1}) + wn)  # w_n+ = -w_n-
    assert textbook.is_zero(wt.xreplace(post))  # no slip after a sticking impact


# --- sustained contact ------------------------------------------------------------------


def test_contact_geometry_equals_textbook():
    _, cd = derived()
    stage = textbook.stage("geometry")
    order = [sm.Symbol(n, real=True) for n in ("z", "L", "z_s", "L_s", "z_ss")]
    assert_equal(stage, [cd.geometry[key] for key in order])


def _as_code(drag_speed: list):
    """Map the derivation's contact symbols (z, L, z_s, L_s, z_ss, c_drag) onto the
    generated code's arguments (fp, f2, f3, c_lin, c_quad), by the textbook geometry.
    The drag speed |v|, a square root in the code, becomes the symbol V on both sides; its
    radicands are collected in *drag_speed* to be checked against the textbook's |v|^2."""
    geometry = textbook.stage("geometry")
    values = dict(zip(geometry.unknowns, (f.rhs for f in geometry.forms), strict=True))
    (kappa, kappa_value), = geometry.intermediates  # fmt: skip
    to_code = {S[n]: values[u].xreplace({kappa: kappa_value}) for n, u in zip(
        ("z", "L", "z_s", "L_s", "z_ss"), geometry.unknowns, strict=True)}  # fmt: skip
    V = sm.Symbol("V", positive=True)
    to_code[S["c_drag"]] = S["c_lin"] + S["c_quad"] * V

    def substitute(residual):
        expr = residual.xreplace(to_code)
        roots = {
            a: V
            for a in expr.atoms(sm.Pow)
            if a.exp == sm.S.Half and a.base.has(S["vb1"], S["vb2"])
        }
        drag_speed.extend(a.base for a in roots)
        return expr.xreplace(roots)

    return substitute


def _check_drag_speed(radicands):
    """Each drag speed the code computes is the centre's lab speed, |v|^2 =
    |V_B + ell u_s c1|^2, in the code's arguments."""
    ell = S["L"] - S["r"] * S["z_s"]
    z, s_dot = S["z"], S["s_dot"]
    lab = (S["vb1"] + ell * s_dot * sm.cos(z)) ** 2 + (S["vb2"] + ell * s_dot * sm.sin(z)) ** 2
    speed = []
    lab_code = _as_code(speed)(textbook.canonical(lab))
    for radicand in radicands:
        assert textbook.is_zero(radicand - lab_code), f"drag speed^2 {radicand}"


CONTACT_ARGS = "s_dot fp f2 f3 ab1 ab2 vb1 vb2 m r k g c_lin c_quad".split()


def test_contact_kinematics_equals_textbook():
    _, cd = derived()
    stage = textbook.stage("contact_kinematics")
    assert_equal(stage, [cd.slip, cd.roll_spin, cd.s_dot, cd.energy])
    contact = code("contact")
    values = (
        call(contact.slip_velocity, "s_dot", "u3", "fp", "f2", "r")
        + call(contact.roll_spin, "s_dot", "fp", "f2", "r")
        + call(contact.s_dot_of_velocity, "u1", "u2", "fp", "f2", "vb1", "vb2", "r")
        + call(contact.contact_energy, "s_dot", "u3", "f0", "fp", "f2", "m", "r", "k", "g")
    )
    assert_equal(stage, values, _as_code([]))


def test_rolling_equals_textbook():
    _, cd = derived()
    stage = textbook.stage("rolling")
    assert_equal(stage, list(cd.roll))
    s_ddot, normal, friction = call(code("contact").roll_rhs, *CONTACT_ARGS)
    radicands: list = []
    assert_equal(stage, [s_ddot, S["spin_dot"], friction, normal], _as_code(radicands))
    assert radicands, "the code's drag speed was not found"
    _check_drag_speed(radicands)


def test_sliding_equals_textbook():
    _, cd = derived()
    stage = textbook.stage("sliding")
    assert_equal(stage, list(cd.slide))
    values = call(code("contact").slide_rhs, *CONTACT_ARGS, "mu_k", "sgn")
    radicands: list = []
    assert_equal(stage, values, _as_code(radicands))
    assert radicands, "the code's drag speed was not found"
    _check_drag_speed(radicands)


# --- the built-in curves -------------------------------------------------------------------


@pytest.mark.parametrize("name", list(PAPER_CURVES))
def test_builtin_curve_equals_textbook(name):
    text, params = PAPER_CURVES[name]
    derivation = build.curve_from_text(name, text, params)
    stages = textbook.curve_stages(name)
    assert len(derivation.walls) == len(stages)
    module = code(f"curves/{name}")
    p = tuple(sm.Symbol(n, real=True) for n in module.PARAMETER_NAMES)
    s, px, py = (sm.Symbol(n, real=True) for n in ("s", "px", "py"))

    def polynomial(coefficients):
        n = len(coefficients) - 1
        return sum((c * s ** (n - i) for i, c in enumerate(coefficients)), sm.S.Zero)

    for i, (wall, stage) in enumerate(zip(derivation.walls, stages, strict=True)):
        x = sm.Symbol("x", real=True)
        derived_values = [
            *(textbook.canonical(v).xreplace({x: s}) for v in (wall.df, wall.d2f, wall.d3f)),
            polynomial(wall.poly),
        ]
        assert_equal(stage, derived_values)
        functions = [getattr(module, f"{f}_{i}") for f in ("df", "d2f", "d3f")]
        code_values = [_exact(f(s, p)) for f in functions]
        code_values.append(polynomial([_exact(c) for c in getattr(module, f"poly_{i}")(px, py, p)]))
        assert_equal(stage, code_values)


def _curve_values(stage):
    """The textbook f', f'', f''' of a curve's wall, its intermediates expanded."""
    values = {}
    for form in stage.forms[:3]:
        expr = form.rhs
        for symbol, definition in reversed(stage.intermediates):
            expr = expr.xreplace({symbol: definition})
        values[form.lhs] = textbook.canonical(expr)
    return [values[u] for u in stage.unknowns[:3]]


@pytest.mark.parametrize("name", list(PAPER_CURVES))
def test_rolling_and_sliding_on_each_builtin_curve(name):
    """Rolling and sliding on each wall of each built-in curve: the generated contact code
    fed the generated curve's f', f'', f''' equals the textbook forms fed the textbook
    derivatives. Without quadratic drag (c_quad = 0), whose speed would nest the curve's
    roots in another root; the drag speed is checked for any wall above."""
    module = code(f"curves/{name}")
    contact = code("contact")
    p = tuple(sm.Symbol(n, real=True) for n in module.PARAMETER_NAMES)
    s = sm.Symbol("s", real=True)
    no_quad = {S["c_quad"]: 0}
    for i, wall in enumerate(textbook.curve_stages(name)):
        walls = [_exact(getattr(module, f"{f}_{i}")(s, p)) for f in ("df", "d2f", "d3f")]
        by_hand = dict(zip((S["fp"], S["f2"], S["f3"]), _curve_values(wall), strict=True))
        args = [S[a] for a in CONTACT_ARGS]
        args[1:4] = walls
        args[CONTACT_ARGS.index("c_quad")] = 0
        for phase, function, extra in (
            ("rolling", contact.roll_rhs, ()),
            ("sliding", contact.slide_rhs, (S["mu_k"], S["sgn"])),
        ):
            values = [_exact(v) for v in function(*args, *extra)]
            if phase == "rolling":
                values = [values[0], S["spin_dot"], values[2], values[1]]
            to_code = _as_code([])

            def on_curve(residual, to_code=to_code, by_hand=by_hand):
                return to_code(residual.xreplace(no_quad)).xreplace(no_quad).xreplace(by_hand)

            assert_equal(textbook.stage(phase), values, on_curve)


# --- every check can fail -----------------------------------------------------------------


def _all_stages():
    return [*textbook.stages(), *(st for n in PAPER_CURVES for st in textbook.curve_stages(n))]


def test_a_wrong_form_is_caught():
    """Each form with its right-hand side's sign flipped (or, where it is 0, one added)
    is refused by the same check that accepts the true form: none passes vacuously."""
    d, cd = derived()
    values = {
        "kinematics": [*plain(d.frame_velocity), *plain(d.contact_velocity)],
        "flight": list(plain(d.rhs_magnus)),
        "flight_exact": list(plain(d.flight_exact)),
        "impact_stick": list(d.stick),
        "impact_slip": list(d.slip),
        "geometry": [cd.geometry[sm.Symbol(n, real=True)] for n in "z L z_s L_s z_ss".split()],
        "contact_kinematics": [cd.slip, cd.roll_spin, cd.s_dot, cd.energy],
        "rolling": list(cd.roll),
        "sliding": list(cd.slide),
    }
    checked = 0
    for stage in textbook.stages():
        for j, form in enumerate(stage.forms):
            wrong = -form.rhs if form.rhs != 0 else form.rhs + 1
            forms = list(stage.forms)
            forms[j] = textbook.Form(form.name, form.lhs, wrong)
            broken = textbook.Stage(
                stage.title, stage.text, stage.unknowns, stage.intermediates, tuple(forms),
                stage.test,
            )  # fmt: skip
            residual = broken.residuals(values[stage.title])[form.name]
            assert not textbook.is_zero(residual), f"{stage.title}: {form.name} not caught"
            checked += 1
    assert checked == sum(len(st.forms) for st in textbook.stages())


# --- the page ------------------------------------------------------------------------------

#: Longest row of LaTeX source, in characters, in a displayed equation of
#: docs/derivation.md. GitHub's Markdown column is about 980 px wide at 100 % zoom and
#: MathJax sets display math at about 16-18 px, an italic letter about 0.5-0.6 em wide: some
#: 100 glyphs fit across. Source characters overstate glyphs (\frac, \left, braces and
#: sub- and superscript markup take room in the source, little or none on the page; a
#: fraction stacks), so a row of at most 100 source characters is narrower than the page.
MAX_ROW = 100


def _display_rows(markdown: str) -> list[str]:
    """Every rendered row of displayed ($$ ... $$) and inline ($...$) math: a display
    block splits into rows at its line breaks (\\\\), and its source lines join. In an
    aligned block every row starts where the first row's "&" stands, so each row counts
    with what precedes that "&"."""
    rows = []
    for block in re.findall(r"\$\$(.*?)\$\$", markdown, flags=re.S):
        flat = " ".join(line.strip() for line in block.strip().splitlines())
        if r"\begin{aligned}" in flat:
            flat = flat.replace(r"\begin{aligned}", "").replace(r"\end{aligned}", "")
            first, *rest = (row.strip() for row in flat.split(r"\\"))
            label = first.partition("&")[0]
            rows += [first, *(label + row for row in rest)]
        else:
            rows += [row.strip() for row in flat.split(r"\\")]
    text = re.sub(r"\$\$.*?\$\$", "", markdown, flags=re.S)
    rows += re.findall(r"\$([^$\n]+)\$", text)
    return rows


def _page() -> str:
    """The committed page (test_ball's byte-for-byte check keeps it equal to what the
    derivation writes)."""
    return (build.repo_root() / "docs" / "derivation.md").read_text()


def test_derivation_page_rows_fit_a_page():
    rows = _display_rows(_page())
    assert len(rows) > 100
    wide = [row for row in rows if len(row) > MAX_ROW]
    assert not wide, f"{len(wide)} rows wider than {MAX_ROW}: {wide[0][:200]}"


def test_width_check_sees_a_wide_row():
    """A long row is seen in a plain display block, and in an aligned one a continuation
    row counts with its label."""
    label = "y_{" + "1" * 60 + "} ={} "
    page = (
        "text\n\n$$\n" + "a + " * 30 + "b\n$$\n\n$$\nx \\\\\ny\n$$\n\n"
        f"$$\n\\begin{{aligned}}\n{label}& a \\\\\n& " + "b + " * 12 + "c\n\\end{aligned}\n$$\n"
    )
    rows = _display_rows(page)
    assert [len(r) > MAX_ROW for r in rows] == [True, False, False, False, True]


def test_page_shows_every_form_and_names_its_test():
    page = _page()
    names = {n for n in globals() if n.startswith("test_")}
    for stage in _all_stages():
        assert stage.test in names, f"{stage.title}: no test {stage.test}"
        assert f"test_textbook.py::{stage.test}" in page, f"{stage.title}: test not named"
        for form in stage.forms:
            assert form.latex() in page, f"{stage.title}: {form.name} not on the page"
