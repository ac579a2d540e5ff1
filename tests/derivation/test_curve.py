"""The boundary as a chain of pieces (derivation/curve.py): Piecewise curves, the exact
classification of each join, the refusals (a jump in height, a ridge), and the chain that
``billiard derive`` prints."""

from __future__ import annotations

import pytest
import sympy as sm
from billiard.derivation import build
from billiard.derivation.curve import CurveDerivationError, chain_lines
from billiard.derivation.expr import CurveExpressionError, parse_curve


def _derive(text: str, parameters: dict[str, str] | None = None):
    return build.curve_from_text("chain", text, parameters or {})


@pytest.mark.parametrize(
    ("text", "parameters", "joins"),
    [
        ("Piecewise((10*x**2, x < 0), (30*x**2, True))", {}, ["C1"]),
        ("20*x**2 + 10*x*abs(x)", {}, ["C1"]),  # the same curve, through abs
        ("Piecewise((x**2, x < 0), (x**2 + x**3, True))", {}, ["C2"]),  # f''' jumps only
        ("Piecewise((-2*x, x < 0), (3*x, True))", {}, ["kink"]),  # a valley
        ("b*abs(x) + c", {"b": "1.85", "c": "0.0063"}, ["kink"]),  # the wedge
        # a parabola continued at x = a (a symbolic bound) by a steeper line: a valley,
        # and by its tangent line: C1
        ("Piecewise((x**2, x < a), (2*a*x - a**2 + (x - a), True))", {"a": "0.1"}, ["kink"]),
        ("Piecewise((x**2, x < a), (2*a*x - a**2, True))", {"a": "0.1"}, ["C1"]),
        # three pieces: a flat bottom between two parabolas, C1 at both joins
        (
            "Piecewise(((x + 1)**2, x < -1), (0, x <= 1), ((x - 1)**2, True))",
            {},
            ["C1", "C1"],
        ),
        ("26*x**2 + 0.0063", {}, []),
    ],
)
def test_joins_are_classified_exactly(text, parameters, joins):
    cd = _derive(text, parameters)
    assert cd.joins == joins
    assert len(cd.walls) == len(joins) + 1 == len(cd.breakpoints) + 1
    # the pieces meet: equal heights at every join, exactly (at the defaults)
    defaults = {p: sm.Rational(parameters[p.name]) for p in cd.parameter_symbols}
    s = sm.Symbol("s", real=True)
    for b, left, right in zip(cd.breakpoints, cd.walls, cd.walls[1:], strict=False):
        at = b.subs(defaults)
        assert sm.simplify((right.f - left.f).subs(defaults).subs(s, at)) == 0


def test_the_symbolic_bound_is_proven_for_every_parameter_value():
    cd = _derive("Piecewise((x**2, x < a), (2*a*x - a**2, True))", {"a": "0.1"})
    assert cd.joins_exact == [True]
    # equal slopes at the defaults only: 2 b on the left, b + 1 on the right of x = 1
    cd = _derive("Piecewise((b*x**2, x < 1), (b*x + 2*x**3 - 3*x**2 + x, True))", {"b": "1"})
    assert cd.joins == ["C1"] and cd.joins_exact == [False]


def test_the_piecewise_pieces_are_the_walls_formulas():
    cd = _derive("Piecewise((10*x**2, x < 0), (30*x**2, True))")
    s = sm.Symbol("s", real=True)
    assert [w.f for w in cd.walls] == [10 * s**2, 30 * s**2]
    assert [(w.lo, w.hi) for w in cd.walls] == [(-sm.oo, 0), (0, sm.oo)]


@pytest.mark.parametrize(
    ("text", "parameters", "message"),
    [
        (
            "Piecewise((x**2, x < 0), (x**2 + 0.001, True))",
            {},
            "the height jumps by 0.001 m at the join x = 0 m (from 0 m to 0.001 m)",
        ),
        (
            "Piecewise((x**2, x < a), (x**2 + a, True))",
            {"a": "0.25"},
            "the height jumps by 0.25 m at the join x = 0.25 m",
        ),
        ("Piecewise((x**2, x < 0), (-x, True))", {}, "concave kink at x = 0 m"),
    ],
)
def test_a_broken_chain_is_refused_in_one_line(text, parameters, message):
    with pytest.raises(CurveDerivationError) as caught:
        _derive(text, parameters)
    assert message in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("Piecewise((x, y < 0), (2*x, True))", "must compare x itself"),
        ("Piecewise((x, x*x < 0), (2*x, True))", "must compare x itself"),
        ("Piecewise((x, x < x), (2*x, True))", "must compare x itself"),
        ("Piecewise((x, x == 0), (1, True))", "only <, <=, >, >= are allowed"),
        ("Piecewise((x, x < 0) (2*x, True))", "must be a pair (expression, condition)"),
        ("Piecewise((x, x < 0), (2*x, x > 0))", "the last piece of Piecewise must have"),
        ("Piecewise((x, True), (x, x < 0))", "the last piece of Piecewise must have"),
        ("Piecewise((x, True), (x, True))", "pieces after it are never used"),
        ("1 + Piecewise((x, True))", "Piecewise must be the whole expression"),
        ("Piecewise((x, x < 0 and x > 1), (x, True))", "must compare x with numbers"),
        ("Piecewise()", "Piecewise takes 1 to 16 pieces"),
        ("Piecewise((x, x < 0), (x, True), key=1)", "no keyword arguments"),
        ("Piecewise((x, x < 0), (2*x, True)", "invalid syntax"),
        ("Piecewise((x, x < __import__('os')), (x, True))", "function '__import__' is not"),
    ],
)
def test_piecewise_forms_that_are_refused(text, fragment):
    with pytest.raises(CurveExpressionError) as caught:
        parse_curve(text)
    message = str(caught.value)
    assert message.startswith("curve expression: ") and "\n" not in message
    assert fragment in message, message


@pytest.mark.parametrize(
    "text",
    [
        "Piecewise((10*x**2, x < 0), (30*x**2, True))",
        "Piecewise((x, 0 <= x < a), (a*x, x >= a), (-x, True))",
        "Piecewise((x**2, -1 > x), (1, True))",
    ],
)
def test_piecewise_forms_that_are_accepted(text):
    parsed = parse_curve(text)
    assert parse_curve(parsed.canonical()).tree == parsed.tree
    assert parsed.tree[0] == "piecewise"


def test_piecewise_evaluates_the_first_piece_that_holds():
    parsed = parse_curve("Piecewise((x, 0 <= x < a), (a*x, x >= a), (-x, True))")
    assert parsed.evaluate(0.5, a=1.0) == 0.5
    assert parsed.evaluate(2.0, a=1.0) == 2.0
    assert parsed.evaluate(-3.0, a=1.0) == 3.0
    x = sm.Symbol("x", real=True)
    expr = parsed.to_sympy(x_symbol=x)
    assert [float(expr.subs({x: v, sm.Symbol("a", real=True): 1})) for v in (0.5, 2, -3)] == [
        0.5,
        2.0,
        3.0,
    ]


def test_the_chain_in_words():
    lines = chain_lines(_derive("Piecewise((x**2, x < a), (2*a*x - a**2, True))", {"a": "0.1"}))
    assert lines == [
        "chain: 2 piece(s), 1 join(s)",
        "  piece 0: x < a = 0.1 m: f = x**2",
        "  join at x = a = 0.1 m: C1, smooth: height and slope continuous, f'' jumps",
        "  piece 1: x > a = 0.1 m: f = -a**2 + 2*a*x",
    ]
    assert chain_lines(_derive("26*x**2"))[1:] == ["  piece 0: all x: f = 26*x**2"]


def test_the_generated_module_lists_the_joins():
    source = build.curve_module(_derive("b*abs(x) + c", {"b": "1.85", "c": "0.0063"}))
    namespace: dict = {}
    exec(compile(source, "wedge", "exec"), namespace)  # the generated text, as loaded
    assert namespace["JOINS"] == ("kink",)
    assert namespace["FORMAT"] == build.CURVE_FORMAT == 7


@pytest.mark.parametrize(
    ("curve", "fragment"),
    [
        (
            "Piecewise((x**2, x < 0), (x**2 + 0.001, True))",
            "the height jumps by 0.001 m at the join x = 0 m",
        ),
        ("Piecewise((x**2, y < 0), (x**2, True))", "must compare x itself"),
        ("Piecewise((x**2, x < 0), (x**2, True)", "invalid syntax"),
    ],
)
def test_derive_refuses_a_broken_piecewise_in_one_line(curve, fragment, tmp_path, capsys):
    from billiard.cli import main

    code = main(["derive", "--dir", str(tmp_path / "curves"), "--name", "pw", "--curve", curve])
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("billiard: error:"), lines
    assert fragment in lines[0]
    assert "Traceback" not in captured.err + captured.out
    assert not list(tmp_path.rglob("*.py"))


def test_derive_prints_the_chain_of_a_piecewise_curve(tmp_path, capsys):
    from billiard.cli import main

    curve = "Piecewise(((x + 1)**2, x < -1), (0, x <= 1), ((x - 1)**2, True))"
    args = ["derive", "--dir", str(tmp_path / "curves"), "--name", "flat", "--curve", curve]
    assert main(args) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:6] == [
        "chain: 3 piece(s), 2 join(s)",
        "  piece 0: x < -1 m: f = (x + 1)**2",
        "  join at x = -1 m: C1, smooth: height and slope continuous, f'' jumps",
        "  piece 1: -1 m < x < 1 m: f = 0",
        "  join at x = 1 m: C1, smooth: height and slope continuous, f'' jumps",
        "  piece 2: x > 1 m: f = (x - 1)**2",
    ], out
