"""The derivation's results in the short forms a reader can check by hand.

Kane's method hands back long expressions; a student checks a model against the forms of
a mechanics textbook: Newton's second law for the centre, Euler's equation for the spin,
impulse balances for an impact. This module writes those forms, independently of
``ball.py`` and ``contact.py`` (no Kane objects here), with named intermediate quantities
that keep every equation short: w_t, w_n the contact point's velocity relative to the
boundary before an impact, ell = L - r z_s the centre's path length per unit s on the
offset curve, A_t, A_n the boundary's acceleration along c1, c2, and so on.

``docs/derivation.md`` prints each form beside the test that proves, by sympy, that the
derived expressions and the generated code equal it exactly
(``tests/derivation/test_textbook.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sm

# Every symbol by name, real; the comparison maps the derivation's symbols onto these by
# name (their assumptions differ between ball.py and contact.py: mu_k is nonnegative in
# one and real in the other).
_NAMES = (
    "m r k g c_lin c_quad c_magnus z vb1 vb2 ab1 ab2 d1 d2 e mu_k sgn t q1 q2 u1 u2 u3 "
    "u1p u2p u3p Rt Rn s s_dot s_ddot spin_dot f0 fp f2 f3 L L_s z_s z_ss N F c_drag"
)
S = {name: sm.Symbol(name, real=True) for name in _NAMES.split()}


def canonical(expr):
    """*expr* with every free symbol replaced by the real symbol of the same name."""
    expr = sm.sympify(expr)
    return expr.xreplace({a: sm.Symbol(a.name, real=True) for a in expr.free_symbols})


@dataclass(frozen=True)
class Form:
    """One textbook equation ``lhs = rhs``.

    ``lhs`` and ``rhs`` hold the stage's unknowns and intermediates as symbols, so that
    the page prints them short.
    """

    name: str  # the generated value it checks, as named in the code
    lhs: sm.Basic
    rhs: sm.Basic

    def latex(self) -> str:
        return f"{latex(self.lhs)} = {latex(self.rhs)}"


@dataclass(frozen=True)
class Stage:
    """A stage of the derivation: its forms, the unknowns the derivation solves for (in
    the order of its result vector), the intermediates the forms use (symbol, definition
    in the derivation's symbols) and the test that proves them."""

    title: str
    text: str
    unknowns: tuple[sm.Symbol, ...]
    intermediates: tuple[tuple[sm.Symbol, sm.Basic], ...]
    forms: tuple[Form, ...]
    test: str

    def residuals(self, values) -> dict[str, sm.Basic]:
        """lhs - rhs of each form, by its name, with the derived *values* (a sequence in
        the order of :attr:`unknowns`) put in for the unknowns and the intermediates
        expanded, in :func:`canonical` symbols: each is zero when the derivation equals
        the textbook."""
        if len(values) != len(self.unknowns):
            raise ValueError(f"{self.title}: {len(values)} values for {len(self.unknowns)}")
        known = dict(zip(self.unknowns, (sm.sympify(v) for v in values), strict=True))
        out = {}
        for form in self.forms:
            expr = form.lhs - form.rhs
            # later intermediates may use earlier ones and the unknowns: expand them last
            # to first, then put in the unknowns
            for symbol, definition in reversed(self.intermediates):
                expr = expr.xreplace({symbol: definition})
            out[form.name] = canonical(expr.xreplace(known))
        return out


def latex(expr) -> str:
    """*expr* in LaTeX as the page prints it: f', f'', f''' for the code's fp, f2, f3,
    u_s for s_dot, the drag factor written out."""
    shown = canonical(expr).xreplace(_DISPLAY)
    return sm.latex(shown, fold_func_brackets=True)


def _sym(latex_name: str) -> sm.Symbol:
    return sm.Symbol(latex_name, real=True)


# Intermediates, printed by their LaTeX names.
W_T, W_N = _sym("w_t^-"), _sym("w_n^-")
R_T, R_N = _sym("R_t"), _sym("R_n")
SPEED = _sym(r"|\mathbf{v}|")
C_D = _sym("c_d")
ELL, ELL_S = _sym(r"\ell"), _sym(r"\ell_s")
KAPPA = _sym(r"\kappa")
A_T, A_N = _sym("A_t"), _sym("A_n")
V_T, V_N = _sym("v_t"), _sym("v_n")
G_T = _sym("G_t")
A_REL = _sym("a_t")
HEIGHT = _sym("h")
U1P, U2P, U3P = _sym("u_1^+"), _sym("u_2^+"), _sym("u_3^+")
DU1, DU2, DU3 = _sym(r"\dot u_1"), _sym(r"\dot u_2"), _sym(r"\dot u_3")
DUS = _sym(r"\dot u_s")
US = _sym("u_s")
N_F, F_F = _sym("N"), _sym("F")

_DISPLAY = {
    S["fp"]: _sym("f'"),
    S["f2"]: _sym("f''"),
    S["f3"]: _sym("f'''"),
    S["s_dot"]: US,
    S["c_drag"]: _sym(r"c_{lin} + c_{quad} |\mathbf{v}|"),
}

m, r, k, g = S["m"], S["r"], S["k"], S["g"]
z, e, mu_k, sgn = S["z"], S["e"], S["mu_k"], S["sgn"]
u1, u2, u3 = S["u1"], S["u2"], S["u3"]
vb1, vb2, ab1, ab2 = S["vb1"], S["vb2"], S["ab1"], S["ab2"]
cz, sz = sm.cos(z), sm.sin(z)


def _impact(hypothesis: str) -> Stage:
    """Kane and Levinson's impact in the boundary's frame, for a sphere: the normal
    impulse from restitution, the tangential one from the hypothesis, and the jumps in
    the centre's velocity (impulse / m) and the spin (moment r R_t / (k m r^2))."""
    stick = hypothesis == "stick"
    rt = -k * m * W_T / (1 + k) if stick else -mu_k * sgn * R_N
    return Stage(
        title=f"impact_{hypothesis}",
        text=(
            "With w^- the contact point's velocity relative to the boundary before the "
            "impact, restitution on the normal component gives R_n for any ball: the "
            "normal impulse passes through the centre and does not turn the ball. "
            + (
                "No slip after the impact, w_t^+ = w_t^- + R_t/m + r R_t/(k m r^2) = 0, "
                "gives R_t; for a solid sphere (k = 2/5) R_t = -(2/7) m w_t^-. "
                if stick
                else "Kinetic friction opposes the slip throughout: R_t = -mu_k sgn R_n. "
            )
            + "The impulse changes the centre's velocity by R/m and the spin by its moment "
            "r R_t about the centre over k m r^2."
        ),
        unknowns=(U1P, U2P, U3P, R_T, R_N),
        intermediates=(
            (W_T, (u1 - vb1) * cz + (u2 - vb2) * sz + r * u3),
            (W_N, -(u1 - vb1) * sz + (u2 - vb2) * cz),
        ),
        forms=(
            Form("Rn", R_N, -m * W_N * (1 + e)),
            Form("Rt", R_T, rt),
            Form("u1p", U1P, u1 + (R_T * cz - R_N * sz) / m),
            Form("u2p", U2P, u2 + (R_T * sz + R_N * cz) / m),
            Form("u3p", U3P, u3 + R_T / (k * m * r)),
        ),
        test=f"test_impact_{hypothesis}_equals_textbook",
    )


# The contact intermediates in the derivation's plain symbols (contact.py's z, L, L_s,
# z_s, z_ss and the drag factor's placeholder c_drag).
_ELL = S["L"] - r * S["z_s"]
_CONTACT = (
    (US, S["s_dot"]),
    (ELL, _ELL),
    (ELL_S, S["L_s"] - r * S["z_ss"]),
    (A_T, ab1 * cz + ab2 * sz),
    (A_N, -ab1 * sz + ab2 * cz),
    (V_T, vb1 * cz + vb2 * sz + ELL * US),
    (V_N, -vb1 * sz + vb2 * cz),
    (C_D, S["c_drag"]),
    (G_T, S["g"] * sm.sin(S["z"]) + A_T),
    (A_REL, ELL * DUS + ELL_S * US**2),
)


def stages() -> tuple[Stage, ...]:
    """Every stage of the derivation in its textbook form, in the page's order."""
    speed = sm.sqrt(u1**2 + u2**2)
    c_lin, c_quad, c_magnus = S["c_lin"], S["c_quad"], S["c_magnus"]
    u4, un, wt, wn = _sym("u_4"), _sym("u_n"), _sym("w_t"), _sym("w_n")
    kinematics = Stage(
        title="kinematics",
        text=(
            "The centre's velocity along the contact frame, and the velocity of the ball's "
            "material contact point P = C - r c2 relative to the boundary: the spin adds "
            "omega x (-r c2) = r u3 c1."
        ),
        unknowns=(u4, un, wt, wn),
        intermediates=(),
        forms=(
            Form("u4", u4, u1 * cz + u2 * sz),
            Form("un", un, -u1 * sz + u2 * cz),
            Form("wt", wt, (u1 - vb1) * cz + (u2 - vb2) * sz + r * u3),
            Form("wn", wn, -(u1 - vb1) * sz + (u2 - vb2) * cz),
        ),
        test="test_kinematics_equals_textbook",
    )
    flight = Stage(
        title="flight",
        text=(
            "Newton's second law for the centre with gravity, Fowles drag -c_d v on the "
            "centre's lab velocity v = (u1, u2) and the Magnus force c_magnus (omega x v), "
            "and Euler's law for the spin: no load has a moment about the centre, so the "
            "spin is constant. Without the Magnus force c_magnus = 0 (flight_rhs_drag)."
        ),
        unknowns=(DU1, DU2, DU3),
        intermediates=((SPEED, speed), (C_D, c_lin + c_quad * SPEED)),
        forms=(
            Form("du1/dt", m * DU1, -C_D * u1 - c_magnus * u3 * u2),
            Form("du2/dt", m * DU2, -m * g - C_D * u2 + c_magnus * u3 * u1),
            Form("du3/dt", k * m * r**2 * DU3, sm.S.Zero),
        ),
        test="test_flight_equals_textbook",
    )
    t, q1, q2 = S["t"], S["q1"], S["q2"]
    state = tuple(_sym(n) for n in ("q_1(t)", "q_2(t)", "u_1(t)", "u_2(t)"))
    flight_exact = Stage(
        title="flight_exact",
        text="Without drag the acceleration is -g n2: the projectile of every textbook.",
        unknowns=state,
        intermediates=(),
        forms=(
            Form("q1", state[0], q1 + u1 * t),
            Form("q2", state[1], q2 + u2 * t - g * t**2 / 2),
            Form("u1", state[2], u1),
            Form("u2", state[3], u2 - g * t),
        ),
        test="test_flight_exact_equals_textbook",
    )
    fp, f2, f3 = S["fp"], S["f2"], S["f3"]
    length = sm.sqrt(1 + fp**2)
    zz, ll, zs, ls, zss = (_sym(n) for n in ("z", "L", "z_s", "L_s", "z_{ss}"))
    geometry = Stage(
        title="geometry",
        text=(
            "The wall's tangent angle z and the length L of dW/ds = (1, f'); the curvature "
            "kappa gives dz/ds = kappa L, the rate at which c1 turns per unit s, and the "
            "offset curve's length per unit s, ell = L - r z_s = L (1 - r kappa): the "
            "single-point contact needs r kappa < 1."
        ),
        unknowns=(zz, ll, zs, ls, zss),
        intermediates=((KAPPA, f2 / (1 + fp**2) ** sm.Rational(3, 2)),),
        forms=(
            Form("z", zz, sm.atan(fp)),
            Form("L", ll, length),
            Form("z_s", zs, KAPPA * length),
            Form("L_s", ls, fp * f2 / length),
            Form("z_ss", zss, f3 / (1 + fp**2) - 2 * fp * f2**2 / (1 + fp**2) ** 2),
        ),
        test="test_contact_geometry_equals_textbook",
    )
    spin = S["u3"]
    wts, u3s, sdot, energy = _sym("w_t"), _sym("u_3"), _sym(r"\dot s"), _sym("E_B")
    contact_kinematics = Stage(
        title="contact_kinematics",
        text=(
            "On the offset curve C = W(s) + r c2, dC/ds = (L - r z_s) c1 = ell c1, since "
            "dc2/ds = -z_s c1: the centre moves along c1 at ell u_s relative to the "
            "boundary. The slip adds the spin's r u3; rolling makes it zero. A lab velocity "
            "(u1, u2) of the centre gives ds/dt from its component along c1 relative to the "
            "boundary; the energy in the boundary's frame is E_B."
        ),
        unknowns=(wts, u3s, sdot, energy),
        intermediates=((US, S["s_dot"]), (ELL, _ELL), (HEIGHT, S["f0"] + r * cz)),
        forms=(
            Form("slip_velocity", wts, ELL * US + r * spin),
            Form("roll_spin", u3s, -ELL * US / r),
            Form("s_dot_of_velocity", ELL * sdot, (u1 - vb1) * cz + (u2 - vb2) * sz),
            Form(
                "contact_energy",
                energy,
                m * (ELL**2 * US**2 + k * r**2 * spin**2) / 2 + m * g * HEIGHT,
            ),
        ),
        test="test_contact_kinematics_equals_textbook",
    )
    # Sustained contact: Newton along c1 and c2 with the centre's acceleration
    # A_B + (ell du_s/dt + ell_s u_s^2) c1 + z_s ell u_s^2 c2, Euler for the spin
    # k m r^2 du3/dt = r F (the friction's moment about C).
    a_t, gt = A_REL, G_T
    normal = m * (g * cz + A_N + S["z_s"] * ELL * US**2) + C_D * V_N
    rolling = Stage(
        title="rolling",
        text=(
            "Rolling: the no-slip condition makes the spin follow, r du3/dt = -(ell du_s/dt "
            "+ ell_s u_s^2), so Euler's law k m r^2 du3/dt = r F gives F. Newton along c1 "
            "then has the inertia (1 + k) m, the textbook result for a ball rolling down "
            "an incline, here on a curved, moving path; Newton along c2 gives N, with the "
            "centripetal term z_s ell u_s^2. c_d is the drag factor c_lin + c_quad |v| on "
            "the centre's lab velocity, whose components along c1, c2 are v_t, v_n."
        ),
        unknowns=(DUS, DU3, F_F, N_F),
        intermediates=_CONTACT,
        forms=(
            Form("s_ddot", (1 + k) * m * a_t, -m * gt - C_D * V_T),
            Form("F", F_F, k * (m * gt + C_D * V_T) / (1 + k)),
            Form("N", N_F, normal),
        ),
        test="test_rolling_equals_textbook",
    )
    sliding = Stage(
        title="sliding",
        text=(
            "Sliding: the same normal balance gives N; kinetic friction F = -mu_k sgn N "
            "drives the spin alone (Euler) and brakes the centre (Newton along c1)."
        ),
        unknowns=(DUS, DU3, N_F, F_F),
        intermediates=_CONTACT,
        forms=(
            Form("N", N_F, normal),
            Form("F", F_F, -mu_k * sgn * N_F),
            Form("s_ddot", m * a_t, F_F - m * gt - C_D * V_T),
            Form("spin_dot", k * m * r * DU3, F_F),
        ),
        test="test_sliding_equals_textbook",
    )
    return (
        kinematics,
        flight,
        flight_exact,
        _impact("stick"),
        _impact("slip"),
        geometry,
        contact_kinematics,
        rolling,
        sliding,
    )


def stage(title: str) -> Stage:
    """The stage called *title* (``flight``, ``impact_stick``, ``rolling``, ...)."""
    for st in stages():
        if st.title == title:
            return st
    raise KeyError(title)


# --- exact comparison ------------------------------------------------------------------

_TAU = sm.Symbol("tau", positive=True)


def is_zero(expr) -> bool:
    """Is *expr*, rational in sin z, cos z and the other symbols, identically zero?

    Exact and fast: the Weierstrass substitution tan(z/2) = tau makes sin z and cos z
    rational in tau, and the difference of two equal rational functions cancels to 0.
    (This holds for all z but z = pi, which continuity then covers.) Any square root left
    (the drag speed, sqrt(1 + f'^2)) is replaced by one symbol per distinct canonical
    radicand, so equal roots written differently still match, and the numerator is
    reduced by each root's square. True only when the difference is proven zero; with
    roots nested in roots a False may be a zero this reduction cannot see (a test then
    fails, it never passes wrongly).
    """
    expr = sm.expand_trig(canonical(expr))
    zs = S["z"]
    expr = expr.xreplace(
        {
            sm.sin(zs): 2 * _TAU / (1 + _TAU**2),
            sm.cos(zs): (1 - _TAU**2) / (1 + _TAU**2),
            sm.tan(zs): 2 * _TAU / (1 - _TAU**2),
        }
    )
    if expr.has(zs):
        raise ValueError(f"z left after the substitution: {expr}")
    roots: dict[sm.Basic, sm.Symbol] = {}
    while True:  # innermost roots first: a radicand may hold another root
        inner = [
            atom
            for atom in expr.atoms(sm.Pow)
            if atom.exp.is_Rational and atom.exp.q == 2 and not _has_root(atom.base)
        ]
        if not inner:
            break
        for atom in sorted(inner, key=sm.default_sort_key):
            radicand = sm.factor(sm.cancel(_reduce(atom.base, roots)))
            root = roots.setdefault(radicand, sm.Dummy("root"))
            expr = expr.xreplace({atom: root ** (2 * atom.exp)})
    numerator = sm.numer(sm.cancel(sm.together(expr)))  # nonzero denominator: drop it
    # a root's square is its radicand: reduce the numerator, a polynomial in the roots,
    # to degree one in each; it is zero iff every coefficient is (a root of a radicand that
    # is no perfect square is no rational function of the other symbols)
    for radicand, root in roots.items():
        numerator = sm.rem(sm.expand(numerator), root**2 - radicand, root)
    return sm.expand(numerator) == 0


def _reduce(expr, roots: dict) -> sm.Basic:
    """*expr* with each known root's square replaced by its radicand, in the numerator
    and the denominator, so that one radicand written two ways gets one root."""
    num, den = sm.fraction(sm.cancel(sm.together(expr)))
    for radicand, root in roots.items():
        num = sm.rem(sm.expand(num), root**2 - radicand, root)
        den = sm.rem(sm.expand(den), root**2 - radicand, root)
    return num / den


def _has_root(expr) -> bool:
    return any(a.exp.is_Rational and a.exp.q == 2 for a in expr.atoms(sm.Pow))


# --- the built-in curves -------------------------------------------------------------------


def curve_stages(name: str) -> tuple[Stage, ...]:
    """The textbook forms of each wall of the built-in curve *name* (one Stage per wall,
    left to right): f', f'', f''' at s by hand, and the nearest-point polynomial P(s),
    (s - px) + (f(s) - py) f'(s) = 0 with its denominators and roots cleared."""
    s, px, py = (sm.Symbol(n, real=True) for n in ("s", "px", "py"))
    fp, f2, f3, poly = _sym("f'"), _sym("f''"), _sym("f'''"), _sym("P")
    unknowns = (fp, f2, f3, poly)
    test = "test_builtin_curve_equals_textbook"
    if name == "parabola":
        a, c = sm.symbols("a c", real=True)
        walls = [
            ((), 2 * a * s, 2 * a, sm.S.Zero, 2 * a**2 * s**3 + (1 + 2 * a * (c - py)) * s - px)
        ]
        text = "f = a x^2 + c: the slope grows linearly, the curvature at the bottom is 2 a."
    elif name == "wedge":
        b, c = sm.symbols("b c", real=True)
        walls = [
            ((), side * b, sm.S.Zero, sm.S.Zero, (1 + b**2) * s + side * b * (c - py) - px)
            for side in (-1, 1)
        ]
        text = "f = b |x| + c: two straight walls of slope -b and b meeting in a convex kink."
    elif name == "hyperbola":
        alpha, beta, delta = sm.symbols("alpha beta delta", real=True)
        big_r = _sym("R")
        root = sm.sqrt(alpha * (1 + beta * s**2))
        # (s - px) + (R - delta - py) alpha beta s / R = 0, times R, with R isolated and
        # squared: ((1 + alpha beta) s - px)^2 (1 + beta s^2) = alpha beta^2 s^2 (delta + py)^2
        q = _sym("q")
        quartic = q**2 * (1 + beta * s**2) - alpha * beta**2 * s**2 * (delta + py) ** 2
        walls = [
            (
                ((big_r, root), (q, (1 + alpha * beta) * s - px)),
                alpha * beta * s / big_r,
                alpha**2 * beta / big_r**3,
                -3 * alpha**3 * beta**2 * s / big_r**5,
                quartic,
            )
        ]
        text = (
            "f = R - delta with R = sqrt(alpha (1 + beta x^2)): f' = alpha beta x / R, and "
            "each further derivative brings a factor 1/R^2."
        )
    else:
        raise KeyError(name)
    return tuple(
        Stage(
            title=f"{name}_{i}",
            text=text,
            unknowns=unknowns,
            intermediates=inter,
            forms=(
                Form("df", fp, dfx),
                Form("d2f", f2, d2fx),
                Form("d3f", f3, d3fx),
                Form("poly", poly, polyx),
            ),
            test=test,
        )
        for i, (inter, dfx, d2fx, d3fx, polyx) in enumerate(walls)
    )
