"""Kane's equations (derivation/ball.py, derivation/contact.py) against a second,
independent derivation (derivation/lagrange.py): Lagrange's equations for the flight and
the contact phases, and the impulse balance written directly for the impacts.

Every comparison is exact. Flight and impacts: the difference cancels to zero. Contact:
Kane's solved (s_ddot, spin_dot, F, N) is put into Lagrange's equations (the multipliers
eliminated) and every equation is shown to vanish by ``lagrange.vanishes``, an exact test
for expressions with square roots; Lagrange's system being nonsingular (its determinant is
nonzero at one point), the two solutions are then the same. That is much cheaper than
comparing the two solved forms (2 s against 15 s for the generic wall).
"""

from __future__ import annotations

import functools
import random

import pytest
import sympy as sm
from billiard.derivation import ball as kb
from billiard.derivation import contact as kc
from billiard.derivation import curve as cv
from billiard.derivation import lagrange
from billiard.derivation.build import curve_from_text
from billiard.derivation.expr import PAPER_CURVES


@functools.cache
def kane_ball() -> kb.BallDerivation:
    return kb.derive_ball()  # ~7 s of sympy, shared by the flight and impact tests


@functools.cache
def kane_contact() -> kc.ContactDerivation:
    return kc.derive_contact()


def random_polynomial() -> str:
    """A quintic with a fixed seed: f''' is not constant, unlike on the paper's curves."""
    rng = random.Random(36)
    terms = [f"{rng.randint(-40, 40)}/{rng.randint(1, 9)}*x**{i}" for i in range(6)]
    return " + ".join(terms)


def walls(name: str) -> list[cv.Wall]:
    if name == "polynomial":
        return curve_from_text("poly", random_polynomial(), {}).walls
    text, params = PAPER_CURVES[name]
    return curve_from_text(name, text, params).walls


def kane_on(wall: cv.Wall | None) -> tuple[sm.Matrix, sm.Matrix]:
    """Kane's rolling (s_ddot, spin_dot, F, N) and sliding (s_ddot, spin_dot, N) on a wall
    (None: the generic wall f0, fp, f2, f3), in the abscissa lagrange.S."""
    d = kane_contact()
    roll, slide = d.roll.subs(d.geometry), d.slide[:3, :].subs(d.geometry)
    if wall is not None:
        curve = {kc.fp: wall.df, kc.f2: wall.d2f, kc.f3: wall.d3f}
        roll = roll.subs(curve).subs(cv.s, lagrange.S)
        slide = slide.subs(curve).subs(cv.s, lagrange.S)
    return roll, slide


def lagrange_on(wall: cv.Wall | None) -> lagrange.ContactEquations:
    if wall is None:
        return lagrange.contact_equations()
    return lagrange.contact_equations(lambda q: wall.f.subs(cv.s, q))


def nonsingular(eqs: list[sm.Basic], unknowns: list[sm.Basic]) -> bool:
    """The system's determinant is not identically zero: nonzero at one rational point."""
    A, _ = sm.linear_eq_to_matrix(eqs, unknowns)
    point = {
        sym: sm.Rational(3 + i, 7 + 2 * i) for i, sym in enumerate(sorted(A.free_symbols, key=str))
    }
    return A.subs(point).det() != 0


def assert_kane_equals_lagrange(wall: cv.Wall | None) -> None:
    lg = lagrange_on(wall)
    roll, slide = kane_on(wall)
    for mode, values in (("roll", roll), ("slide", slide)):
        residuals = lg.residuals(mode, values)
        bad = [i for i, res in enumerate(residuals) if not lagrange.vanishes(res)]
        assert not bad, f"{mode}: Kane's solution violates Lagrange's equations {bad}"
    assert all(lagrange.vanishes(row) for row in lg.identities)
    roll_eqs = [e.xreplace(lg.roll_multipliers) for e in lg.roll_equations]
    slide_eqs = [e.xreplace(lg.slide_multipliers) for e in lg.slide_equations]
    assert nonsingular(roll_eqs, [kc.S_DDOT, kc.SPIN_DOT, kc.F_force, kc.N_force])
    assert nonsingular(slide_eqs, [kc.S_DDOT, kc.SPIN_DOT, kc.N_force])
    # The no-slip spin and the drag's speed, too.
    d = kane_contact()
    spin = d.roll_spin.subs(d.geometry)
    factor = d.drag_factor.subs(d.geometry)
    if wall is not None:
        curve = {kc.fp: wall.df, kc.f2: wall.d2f, kc.f3: wall.d3f}
        spin = spin.subs(curve).subs(cv.s, lagrange.S)
        factor = factor.subs(curve).subs(cv.s, lagrange.S)
    assert lagrange.vanishes(lg.roll_spin - spin)
    # The drag's |v|: compare |v|^2, the roots' arguments.
    speed2 = [((fac - kb.c_lin) / kb.c_quad) ** 2 for fac in (lg.drag_factor, factor)]
    assert lagrange.vanishes(speed2[0] - speed2[1])


# --- flight -------------------------------------------------------------------------------


def test_flight_kane_equals_lagrange():
    d = kane_ball()
    for magnus, kane in ((True, d.rhs_magnus), (False, d.rhs_drag)):
        diff = lagrange.flight_rhs(magnus) - kb.plain(kane)
        assert diff.applyfunc(sm.cancel) == sm.zeros(3, 1), (magnus, diff)


def test_flight_comparison_fails_on_a_wrong_potential(monkeypatch):
    """Gravity's potential with the wrong sign is seen (the check can fail)."""
    d = kane_ball()
    monkeypatch.setattr(lagrange, "g", -kb.g)
    diff = lagrange.flight_rhs(False) - kb.plain(d.rhs_drag)
    assert diff.applyfunc(sm.cancel)[1] == 2 * kb.g


# --- sustained contact ----------------------------------------------------------------------


def test_contact_kane_equals_lagrange_on_a_generic_wall():
    """f, f', f'', f''' symbols: the identity for every curve at once."""
    assert_kane_equals_lagrange(None)


@pytest.mark.parametrize("name", ["parabola", "wedge"])
def test_contact_kane_equals_lagrange_on_a_paper_curve(name):
    """The Lagrangian built from the curve's own expression (both walls of the wedge)."""
    for wall in walls(name):
        assert_kane_equals_lagrange(wall)


@pytest.mark.slow  # 75-120 s: the hyperbola's nested square roots
def test_contact_kane_equals_lagrange_on_the_hyperbola():
    (wall,) = walls("hyperbola")
    assert_kane_equals_lagrange(wall)


@pytest.mark.slow  # 80 s: a degree-8 radicand
def test_contact_kane_equals_lagrange_on_a_random_polynomial():
    (wall,) = walls("polynomial")
    assert wall.d3f.has(cv.s)  # f''' varies: the chain through f''' is exercised
    assert_kane_equals_lagrange(wall)


@pytest.mark.parametrize(
    "plant",
    ["potential", "radius"],
)
def test_contact_comparison_fails_on_a_planted_error(monkeypatch, plant):
    """A wrong sign of gravity's potential or of the ball's offset from the wall, planted
    in the Lagrangian, breaks the equality (the check can fail)."""
    if plant == "potential":
        monkeypatch.setattr(lagrange, "g", -kb.g)
    else:
        monkeypatch.setattr(lagrange, "r", -kb.r)
    (wall, _) = walls("wedge")
    lg = lagrange_on(wall)
    roll, slide = kane_on(wall)
    for mode, values in (("roll", roll), ("slide", slide)):
        assert not all(lagrange.vanishes(res) for res in lg.residuals(mode, values)), mode


# --- impacts ----------------------------------------------------------------------------------


def rational_angle(expr: sm.Basic) -> sm.Basic:
    """cos z, sin z through tan(z/2) = tau: the impact equations become rational in tau,
    so that ``cancel`` decides exactly whether a difference vanishes."""
    tau = sm.Symbol("tau", real=True)
    return expr.subs(
        {sm.cos(kb.z): (1 - tau**2) / (1 + tau**2), sm.sin(kb.z): 2 * tau / (1 + tau**2)}
    )


@pytest.mark.parametrize("law", ["stick", "slip"])
def test_impact_equations_equal_the_impulse_balance(law):
    kane = getattr(kane_ball(), law)
    direct = getattr(lagrange.impulse_balance(), law)
    diff = rational_angle(kane - direct).applyfunc(sm.cancel)
    assert diff == sm.zeros(5, 1), diff


@pytest.mark.parametrize("law", ["stick", "slip"])
def test_impacts_conserve_angular_momentum_about_the_contact_point(law):
    """The impulse acts at the contact point: Kane's post-impact speeds keep the angular
    momentum about it."""
    balance = lagrange.impulse_balance()
    post = getattr(kane_ball(), law)
    before = balance.contact_momentum(lagrange.U1, lagrange.U2, lagrange.U3)
    after = balance.contact_momentum(post[0], post[1], post[2])
    assert sm.cancel(rational_angle(after - before)) == 0


def test_impact_comparison_fails_on_a_wrong_lever_arm(monkeypatch):
    monkeypatch.setattr(lagrange, "r", -kb.r)  # the impulse applied at C + r c2
    direct = lagrange.impulse_balance().stick
    diff = rational_angle(kane_ball().stick - direct).applyfunc(sm.cancel)
    assert diff != sm.zeros(5, 1)


def test_vanishes_is_exact():
    x, y = sm.symbols("x y", real=True)
    root = sm.sqrt(1 + x**2)
    assert lagrange.vanishes(root**3 / (1 + x**2) - root)
    assert lagrange.vanishes(sm.sqrt(y + root) ** 2 - y - root)
    assert not lagrange.vanishes(root - x)
    assert not lagrange.vanishes(1 / root - 1 / (1 + x**2))
