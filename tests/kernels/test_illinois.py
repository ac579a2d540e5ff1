"""The Illinois root search (``billiard/kernels/illinois.py``), run as its callers run it
(``first_root`` in ``kernels/contact.py`` and ``kernels/vertex.py``: the caller's loop
evaluates the function, the module proposes the point and keeps the bracket), on
functions whose roots are known in closed form. The kernels are taken from the
interpreted twin: the same source, as plain functions."""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable

import pytest

from billiard.kernels import interpreted as twin

illinois = importlib.import_module(f"{twin.PACKAGE}.illinois")
secant_point, narrow = illinois.secant_point, illinois.narrow

TOL = 1e-12


def search(
    f: Callable[[float], float], a: float, b: float, halving: bool = True
) -> tuple[float, float, int]:
    """The callers' loop: f > 0 at a, f <= 0 at b; (a, b, evaluations) once b - a <= TOL
    or after 200 evaluations. ``halving=False`` forgets the side kept, which makes the
    search plain regula falsi."""
    fa, fb = f(a), f(b)
    side = 0
    evaluations = 0
    for _ in range(200):
        if b - a <= TOL:
            break
        m = secant_point(a, b, fa, fb)
        assert a < m < b
        fm = f(m)
        evaluations += 1
        a, b, fa, fb, side = narrow(a, b, fa, fb, m, fm, side if halving else 0)
        # the bracket keeps the sign change: positive at a, zero or below at b
        assert f(a) > 0.0 >= f(b)
        assert fa > 0.0 >= fb
    return a, b, evaluations


CASES = {
    "sqrt2": (lambda x: 2.0 - x * x, 0.0, 2.0, math.sqrt(2.0)),
    "cbrt2": (lambda x: 2.0 - x**3, 0.0, 2.0, math.cbrt(2.0)),
    "cos": (math.cos, 0.0, 3.0, math.pi / 2),
    "log": (lambda x: -math.log(x), 0.25, 3.0, 1.0),
    "tenth_power": (lambda x: 1.0 - x**10, 0.0, 1.5, 1.0),
}


@pytest.mark.parametrize("name", CASES)
def test_the_search_brackets_the_known_root(name):
    f, a0, b0, root = CASES[name]
    a, b, evaluations = search(f, a0, b0)
    assert b - a <= TOL
    # the exact root is inside the final bracket (up to its own rounding)
    assert a - 4 * math.ulp(root) <= root <= b + 4 * math.ulp(root)
    assert evaluations < 40


def test_halving_keeps_the_search_from_stalling_on_one_side():
    # 1 - x**10 is convex on [0, 1.5]: regula falsi keeps moving a and never b, and
    # after 200 evaluations the bracket is still as wide as at the start; the Illinois
    # halving moves b within a few steps
    f, a0, b0, root = CASES["tenth_power"]
    _, b_plain, n_plain = search(f, a0, b0, halving=False)
    assert n_plain == 200 and b_plain == b0
    a, b, n = search(f, a0, b0)
    assert b - a <= TOL and n < 20


def test_the_secant_point_of_a_line_is_its_root():
    # f(x) = 3 - 2 x on [0, 4]: the secant is the line itself, its zero 1.5
    def f(x: float) -> float:
        return 3.0 - 2.0 * x

    assert secant_point(0.0, 4.0, f(0.0), f(4.0)) == 1.5
    assert secant_point(1.0, 2.0, f(1.0), f(2.0)) == 1.5


@pytest.mark.parametrize(
    ("fa", "fb"),
    [
        (1.0, 1.0),  # a flat secant has no zero
        (2.0, 1.0),  # both positive: the zero is beyond b
        (-1.0, -2.0),  # both negative: before a
        (1.0, 0.0),  # the zero is b itself, not inside (a, b)
        (0.0, -1.0),  # the zero is a itself
    ],
)
def test_a_secant_zero_outside_the_open_bracket_gives_the_middle(fa, fb):
    assert secant_point(1.0, 3.0, fa, fb) == 2.0


def test_narrow_moves_the_end_whose_sign_the_point_has():
    # a positive value replaces a, a value of zero or below replaces b
    assert narrow(0.0, 1.0, 2.0, -2.0, 0.4, 0.5, 0) == (0.4, 1.0, 0.5, -2.0, -1)
    assert narrow(0.0, 1.0, 2.0, -2.0, 0.4, -0.5, 0) == (0.0, 0.4, 2.0, -0.5, 1)
    assert narrow(0.0, 1.0, 2.0, -2.0, 0.4, 0.0, 0) == (0.0, 0.4, 2.0, 0.0, 1)


def test_narrow_halves_the_value_at_the_end_kept_twice():
    a, b, fa, fb, side = 0.0, 1.0, 4.0, -8.0, 0
    # first move of a: b kept once, its value untouched
    a, b, fa, fb, side = narrow(a, b, fa, fb, 0.1, 3.0, side)
    assert (a, fa, b, fb, side) == (0.1, 3.0, 1.0, -8.0, -1)
    # a moves again: b is kept a second time in a row, its value halves, and again
    a, b, fa, fb, side = narrow(a, b, fa, fb, 0.2, 2.0, side)
    assert (a, fa, fb) == (0.2, 2.0, -4.0)
    a, b, fa, fb, side = narrow(a, b, fa, fb, 0.3, 1.0, side)
    assert (a, fa, fb) == (0.3, 1.0, -2.0)
    # b moves: a was not kept before, its value is untouched
    a, b, fa, fb, side = narrow(a, b, fa, fb, 0.9, -1.0, side)
    assert (a, fa, b, fb, side) == (0.3, 1.0, 0.9, -1.0, 1)
    # b moves again: now a's value halves
    a, b, fa, fb, side = narrow(a, b, fa, fb, 0.8, -0.5, side)
    assert (a, fa, b, fb, side) == (0.3, 0.5, 0.8, -0.5, 1)
