"""Tests of the whitelist parser for curve expressions (billiard.derivation.expr)."""

from __future__ import annotations

import builtins
import math
import time

import pytest
import sympy
from billiard.derivation.expr import (
    FUNCTIONS,
    MAX_LENGTH,
    CurveExpression,
    CurveExpressionError,
    is_parameter_name,
    parse_curve,
)
from hypothesis import given, settings
from hypothesis import strategies as st

X = sympy.Symbol("x", real=True)

# ---------------------------------------------------------------------------------
# valid expressions

PAPER_CURVES = [
    # (text, parameters, x, expected f(x))
    ("26*x**2 + 0.0063", {}, 0.01, 26 * 0.01**2 + 0.0063),
    ("1.85*abs(x) + 0.0063", {}, -0.02, 1.85 * 0.02 + 0.0063),
    (
        "sqrt(40.3e-4*(1 + 800*x**2)) - 0.0445",
        {},
        0.03,
        math.sqrt(40.3e-4 * (1 + 800 * 0.03**2)) - 0.0445,
    ),
    ("a*x**2 + c", {"a": 26.0, "c": 0.0063}, 0.05, 26.0 * 0.05**2 + 0.0063),
]


@pytest.mark.parametrize(("text", "params", "x", "expected"), PAPER_CURVES)
def test_paper_curves_evaluate(text: str, params: dict, x: float, expected: float) -> None:
    curve = parse_curve(text)
    assert curve.text == text
    assert curve.parameters == tuple(sorted(params))
    assert curve.evaluate(x, **params) == pytest.approx(expected, rel=1e-15, abs=0.0)


@pytest.mark.parametrize(("text", "params", "x", "expected"), PAPER_CURVES)
def test_paper_curves_to_sympy(text: str, params: dict, x: float, expected: float) -> None:
    curve = parse_curve(text)
    symbols = {name: sympy.Symbol(name, real=True) for name in params}
    expression = curve.to_sympy(X, symbols)
    substitutions = {X: sympy.Rational(repr(x))}
    substitutions.update({symbols[name]: sympy.Rational(repr(v)) for name, v in params.items()})
    exact = float(expression.subs(substitutions).evalf(30))
    assert exact == pytest.approx(curve.evaluate(x, **params), rel=1e-14)
    assert exact == pytest.approx(expected, rel=1e-14)


def test_paper_parabola_is_exact_in_sympy() -> None:
    expression = parse_curve("26*x**2 + 0.0063").to_sympy(X)
    assert sympy.simplify(expression - (26 * X**2 + sympy.Rational(63, 10000))) == 0
    assert all(atom.is_Rational for atom in expression.atoms(sympy.Number))


def test_hyperbola_to_sympy_is_exact() -> None:
    expression = parse_curve("sqrt(40.3e-4*(1 + 800*x**2)) - 0.0445").to_sympy(X)
    expected = sympy.sqrt(sympy.Rational(403, 100000) * (1 + 800 * X**2)) - sympy.Rational(
        445, 10000
    )
    assert sympy.simplify(expression - expected) == 0


def test_default_symbols_and_numeric_parameters() -> None:
    curve = parse_curve("a*x**2 + c")
    expression = curve.to_sympy()
    names = sorted(str(symbol) for symbol in expression.free_symbols)
    assert names == ["a", "c", "x"]
    bound = curve.to_sympy(X, {"a": 26, "c": 0.5})
    assert bound.subs(X, 2) == 26 * 4 + sympy.Float(0.5)


def test_to_sympy_rejects_non_numeric_parameter_values() -> None:
    with pytest.raises(TypeError, match="parameter 'a'"):
        parse_curve("a*x").to_sympy(X, {"a": "1"})


@pytest.mark.parametrize(
    ("text", "x", "expected"),
    [
        ("x", 0.25, 0.25),
        ("-x**2", 3.0, -9.0),
        ("(-x)**2", 3.0, 9.0),
        ("2**-1", 0.0, 0.5),
        ("x**-2", 2.0, 0.25),
        ("x**0.5", 4.0, 2.0),
        ("8/2/2", 0.0, 2.0),
        ("(2**3)**2", 0.0, 64.0),
        ("1 - 2 - 3", 0.0, -4.0),
        ("1 - (2 - 3)", 0.0, 2.0),
        ("+x", 1.5, 1.5),
        ("pi*x", 2.0, 2 * math.pi),
        ("exp(log(x))", 2.5, 2.5),
        ("cosh(x)**2 - sinh(x)**2", 0.7, 1.0),
        ("sin(x)**2 + cos(x)**2", 1.3, 1.0),
        ("tan(x) - sin(x)/cos(x)", 0.4, 0.0),
        ("tanh(0)", 0.0, 0.0),
        ("abs(-3)", 0.0, 3.0),
        ("0x10 + 1_000", 0.0, 1016.0),
        ("1e-3*x", 2.0, 0.002),
        ("  x + 1  ", 1.0, 2.0),
    ],
)
def test_evaluate_values(text: str, x: float, expected: float) -> None:
    curve = parse_curve(text)
    assert curve.evaluate(x) == pytest.approx(expected, rel=1e-14, abs=1e-15)
    via_sympy = float(curve.to_sympy(X).subs(X, sympy.Float(x, 30)).evalf(30))
    assert via_sympy == pytest.approx(expected, rel=1e-14, abs=1e-15)


def test_tree_structure() -> None:
    curve = parse_curve("a*x**2 + sqrt(-x) - 0.5")
    assert curve.tree == (
        "sub",
        (
            "add",
            ("mul", ("param", "a"), ("pow", ("x",), ("num", "2"))),
            ("call", "sqrt", ("neg", ("x",))),
        ),
        ("num", "0.5"),
    )
    assert isinstance(curve, CurveExpression)


@pytest.mark.parametrize(
    ("first", "second"),
    [
        ("26*x**2 + 0.0063", "26 * x ** 2+0.0063"),
        ("1.50e-3*x", "0.0015*x"),
        ("(x)", "x"),
        ("+x", "x"),
        ("2.0*x", "2*x"),
        ("((a*x))", "a*x"),
    ],
)
def test_canonical_ignores_spelling(first: str, second: str) -> None:
    assert parse_curve(first).canonical() == parse_curve(second).canonical()


@pytest.mark.parametrize(
    ("text", "canonical"),
    [
        ("26*x**2+0.0063", "26*x**2 + 0.0063"),
        ("x - (y - z)", "x - (y - z)"),
        ("(x - y) - z", "x - y - z"),
        ("x/(a*b)", "x/(a*b)"),
        ("(-x)**2", "(-x)**2"),
        ("-(x**2)", "-x**2"),
        ("(x**2)**3", "(x**2)**3"),
        ("40.3e-4", "0.00403"),
        ("1e5", "100000"),
        ("1e-7", "1e-7"),
    ],
)
def test_canonical_text(text: str, canonical: str) -> None:
    curve = parse_curve(text)
    assert curve.canonical() == canonical
    assert parse_curve(curve.canonical()).tree == curve.tree


def test_canonical_distinguishes_different_curves() -> None:
    assert parse_curve("x - (y - z)").canonical() != parse_curve("x - y - z").canonical()


def test_evaluate_parameter_errors() -> None:
    curve = parse_curve("a*x + c")
    assert curve.evaluate(2.0, a=3.0, c=1.0) == 7.0
    with pytest.raises(ValueError, match="missing value for parameter"):
        curve.evaluate(1.0, a=1.0)
    with pytest.raises(ValueError, match="unknown parameter"):
        curve.evaluate(1.0, a=1.0, c=1.0, d=2.0)


@pytest.mark.parametrize(
    ("text", "x"),
    [("sqrt(x)", -1.0), ("log(x)", 0.0), ("1/x", 0.0), ("exp(x)", 1e4), ("x**0.5", -2.0)],
)
def test_evaluate_domain_errors_are_value_errors(text: str, x: float) -> None:
    curve = parse_curve(text)
    with pytest.raises(ValueError, match="curve expression"):
        curve.evaluate(x)


def test_parameter_name_rules() -> None:
    assert is_parameter_name("alpha_2")
    assert is_parameter_name("a" * 31)
    assert not is_parameter_name("a" * 32)
    for bad in ("x", "pi", "sqrt", "_a", "2a", "lambda", "a-b", "", "é"):
        assert not is_parameter_name(bad), bad
    assert set(FUNCTIONS) == {
        "abs",
        "sqrt",
        "exp",
        "log",
        "sin",
        "cos",
        "tan",
        "sinh",
        "cosh",
        "tanh",
    }


def test_limits_at_the_boundary_are_accepted() -> None:
    assert parse_curve("x**32").evaluate(1.0) == 1.0
    assert parse_curve("x**-32").evaluate(1.0) == 1.0
    assert parse_curve("(x**32)**32").evaluate(1.0) == 1.0
    nested = "(" * 20 + "x" + ")" * 20
    assert parse_curve(nested).tree == ("x",)
    long_sum = " + ".join(["x"] * 99)
    assert len(long_sum) <= MAX_LENGTH
    assert parse_curve(long_sum).evaluate(1.0) == 99.0


# ---------------------------------------------------------------------------------
# hostile input

HOSTILE = [
    # attribute access and dunder names
    "x.__class__",
    "().__class__",
    "x.__class__.__mro__",
    "x.__class__.__mro__[1].__subclasses__()",
    "().__class__.__bases__[0].__subclasses__()",
    "os.system",
    "os.system('ls')",
    "sys.modules",
    "x.real",
    "(1).__add__(2)",
    "1 .real",
    "a.b.c",
    "__import__",
    "__import__('os')",
    "__import__('os').system('echo hacked')",
    "__builtins__",
    "__builtins__['eval']",
    "__loader__",
    "__spec__",
    "__name__",
    "_",
    "_x",
    "x.__dict__",
    "sqrt.__globals__",
    "sqrt.__code__",
    "(lambda: 0).__globals__",
    # statements
    "import os",
    "from os import system",
    "x = 1",
    "x += 1",
    "del x",
    "pass",
    "assert x",
    "raise SystemExit",
    "global x",
    "def f(): pass",
    "class A: pass",
    "for i in x: pass",
    "while 1: pass",
    "with open('f') as f: pass",
    "try: x\nexcept: pass",
    "x\nimport os",
    "x\r\nimport os",
    "x; import os",
    "x;",
    "x ; y",
    "return x",
    "yield x",
    "await x",
    # lambdas, comprehensions, generators
    "lambda: 1",
    "lambda x: x",
    "(lambda: __import__('os'))()",
    "[x for x in ()]",
    "[x for x in range(10**9)]",
    "{x for x in ()}",
    "{x: x for x in ()}",
    "(x for x in ())",
    "sum(x for x in range(10))",
    # huge powers and numbers
    "9**9**9",
    "10**10**10",
    "x**100000",
    "x**33",
    "x**-33",
    "2**a",
    "x**x",
    "x**(1+1)",
    "x**sqrt(2)",
    "((x**32)**32)**32",
    "(((2**32)**32)**32)**32",
    "1" * 31,
    "1." + "0" * 30,
    "1e999",
    "1e999 - 1e999",
    "9" * 5000,
    # deep nesting and long input
    "(" * 5000 + "x" + ")" * 5000,
    "(" * 21 + "x" + ")" * 21,
    "[" * 30,
    "-" * 300 + "x",
    "sqrt(" * 30 + "x" + ")" * 30,
    "x" * 10**6,
    "x+" * 199 + "x",
    " " * 401,
    # Unicode look-alikes and control characters
    "\u0445",  # Cyrillic small ha
    "\u0445**2",
    "x + \uff11",  # fullwidth digit one
    "\uff58",  # fullwidth x
    "x\u00a0+ 1",  # no-break space
    "x\u200b",  # zero-width space
    "\u03c0*x",  # Greek pi
    "x \u2212 1",  # minus sign
    "x\x00",
    "\x00",
    "x\t+ 1",
    "x\n",
    "x\x1b[31m",
    "x\x7f",
    "s\u0456n(x)",  # Cyrillic i
    # strings, bytes, f-strings, other literals
    "'x'",
    '"x"',
    "b'x'",
    "f'{x}'",
    "f'{__import__(\"os\")}'",
    "'a' * 10**9",
    "u'x'",
    "r'x'",
    "1j",
    "x + 2j",
    "True",
    "False",
    "None",
    "...",
    # containers, subscripts, starred, walrus
    "(x, x)",
    "x,",
    "[x]",
    "{x}",
    "{}",
    "{'a': 1}",
    "x[0]",
    "x[0:1]",
    "*x",
    "sqrt(*x)",
    "sqrt(**x)",
    "(y := 1)",
    "(x := 2)",
    # comparisons, boolean ops, other operators
    "x < 1",
    "x == x",
    "x is None",
    "x in x",
    "x and x",
    "x or x",
    "not x",
    "x if x else 0",
    "x // 2",
    "x % 2",
    "x @ x",
    "x << 2",
    "x & 1",
    "x | 1",
    "x ^ 1",
    "~x",
    # calls outside the whitelist and call-shape errors
    "open('/etc/passwd')",
    "eval('1')",
    "exec('import os')",
    "getattr(x, 'y')",
    "setattr(x, 'y', 1)",
    "globals()",
    "locals()",
    "vars()",
    "compile('1', '', 'eval')",
    "input()",
    "print(x)",
    "breakpoint()",
    "help()",
    "exit()",
    "range(10)",
    "max(x, 1)",
    "pow(x, 2)",
    "a(x)",
    "x(1)",
    "pi(1)",
    "sqrt",
    "sqrt()",
    "sqrt(x, x)",
    "sqrt(x=1)",
    "sin(x, key=1)",
    "sqrt(x)(x)",
    "2(x)",
    "math.sqrt(x)",
    "sympy.sqrt(x)",
    "np.sin(x)",
    # malformed syntax
    "",
    "   ",
    "x +",
    "(x",
    "x)",
    "x x",
    "1 2",
    "x**",
    "sqrt(",
    "@",
    "$x",
    "x!",
    "`x`",
    "\\",
    "#",
    # names outside the parameter rules
    "a" * 32,
    "Ellipsis.__class__",
    "None.__class__",
]


def test_hostile_list_is_large() -> None:
    assert len(HOSTILE) >= 100
    assert len(set(HOSTILE)) == len(HOSTILE)


@pytest.mark.parametrize("text", HOSTILE, ids=lambda text: repr(text[:40]))
def test_hostile_input_is_refused(text: str) -> None:
    start = time.perf_counter()
    with pytest.raises(CurveExpressionError) as info:
        parse_curve(text)
    elapsed = time.perf_counter() - start
    message = str(info.value)
    assert isinstance(info.value, ValueError)
    assert message.startswith("curve expression:")
    assert len(message.splitlines()) == 1
    assert "\r" not in message and "\n" not in message
    assert elapsed < 0.5


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("x + x.__class__", ["attribute access '.__class__'", "column 6"]),
        ("__import__('os').system('ls')", ["'.system'"]),
        ("eval(x)", ["function 'eval' is not allowed", "allowed: abs, sqrt, exp"]),
        ("x**100000", ["exponent '100000'", "32"]),
        ("9**9**9", ["exponent", "must be a number"]),
        ("\u0445 + 1", ["U+0445", "CYRILLIC SMALL LETTER HA", "column 1"]),
        ("x + \uff11", ["U+FF11", "column 5"]),
        ("x\u00a0+ 1", ["U+00A0", "NO-BREAK SPACE"]),
        ("x\x00", ["U+0000", "column 2"]),
        ("x" * 10**6, ["1000000 characters"]),
        ("(" * 5000 + "x" + ")" * 5000, ["10001 characters"]),
        ("(" * 21 + "x" + ")" * 21, ["nested deeper than 20", "column 21"]),
        ("x+" * 199 + "x", ["too complex"]),
        ("sqrt(x=1)", ["keyword argument 'x='"]),
        ("sqrt(x, 1)", ["exactly one argument"]),
        ("'x'", ["string literal"]),
        ("b'x'", ["bytes literal"]),
        ("f'{x}'", ["f-string"]),
        ("x < 1", ["comparison"]),
        ("x and 1", ["boolean operator 'and'"]),
        ("x[0]", ["subscript"]),
        ("(y := 1)", ["assignment expression"]),
        ("lambda: 1", ["lambda"]),
        ("[x for x in ()]", ["comprehension"]),
        ("x // 2", ["operator '//'"]),
        ("_x", ["name '_x'"]),
        ("x; import os", ["invalid syntax"]),
        ("1" * 31, ["longer than 30"]),
        ("1e999", ["not finite"]),
        ("((x**32)**32)**32", ["nested powers"]),
        ("True", ["constant 'True'"]),
        ("", ["empty"]),
    ],
)
def test_messages_name_the_offending_part(text: str, fragments: list[str]) -> None:
    with pytest.raises(CurveExpressionError) as info:
        parse_curve(text)
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message


def test_non_string_is_refused() -> None:
    with pytest.raises(CurveExpressionError, match="expected a string, got int"):
        parse_curve(5)  # type: ignore[arg-type]


def test_canary_side_effects_never_happen(tmp_path, monkeypatch) -> None:
    canary = tmp_path / "canary.txt"

    def forbidden(*args, **kwargs):
        raise AssertionError("eval/exec must not be called")

    monkeypatch.setattr(builtins, "eval", forbidden)
    monkeypatch.setattr(builtins, "exec", forbidden)
    attacks = [
        f"__import__('pathlib').Path({str(canary)!r}).write_text('pwned')",
        f"open({str(canary)!r}, 'w').write('pwned')",
        "__import__('builtins').setattr(__import__('builtins'), 'BILLIARD_CANARY', 1)",
        "setattr(__import__('builtins'), 'BILLIARD_CANARY', 1)",
        f"exec(\"open({str(canary)!r}, 'w')\")",
    ]
    for attack in attacks:
        with pytest.raises(CurveExpressionError):
            parse_curve(attack)
    # valid expressions are handled without eval/exec too
    assert parse_curve("a*x**2 + c").evaluate(1.0, a=2.0, c=1.0) == 3.0
    assert not canary.exists()
    assert not hasattr(builtins, "BILLIARD_CANARY")


def test_to_sympy_does_not_parse_strings(monkeypatch) -> None:
    import sympy.parsing.sympy_parser as sympy_parser

    def forbidden(*args, **kwargs):
        raise AssertionError("string parsing must not be used")

    monkeypatch.setattr(sympy_parser, "parse_expr", forbidden)
    monkeypatch.setattr(sympy, "sympify", forbidden)
    monkeypatch.setattr(sympy, "parse_expr", forbidden, raising=False)
    expression = parse_curve("sqrt(40.3e-4*(1 + 800*x**2)) - 0.0445").to_sympy(X)
    assert float(expression.subs(X, 0)) == pytest.approx(math.sqrt(40.3e-4) - 0.0445)


# ---------------------------------------------------------------------------------
# fuzzing


@settings(max_examples=500, deadline=None)
@given(st.text())
def test_random_text_is_parsed_or_refused(text: str) -> None:
    try:
        curve = parse_curve(text)
    except CurveExpressionError as exc:
        assert str(exc).startswith("curve expression:")
        assert "\n" not in str(exc)
    else:
        assert isinstance(curve, CurveExpression)
        assert parse_curve(curve.canonical()).tree == curve.tree


PYTHONISH = st.lists(
    st.sampled_from(
        list("x+-*/()., 0123456789e_[]{}'\":;=<>!@%&|^~") + list(FUNCTIONS) + ["pi", "**", "a"]
    ),
    max_size=40,
).map("".join)


@settings(max_examples=1000, deadline=None)
@given(PYTHONISH)
def test_python_like_text_is_parsed_or_refused(text: str) -> None:
    try:
        curve = parse_curve(text)
    except CurveExpressionError as exc:
        assert str(exc).startswith("curve expression:")
        assert "\n" not in str(exc)
    else:
        assert parse_curve(curve.canonical()).tree == curve.tree
        try:
            value = curve.evaluate(0.3, **{name: 0.7 for name in curve.parameters})
        except ValueError:
            return
        assert math.isfinite(value)


def _expressions() -> st.SearchStrategy[str]:
    """Expression text over x, a parameter a and literals exactly representable in binary."""
    leaves = st.one_of(
        st.just("x"),
        st.just("a"),
        st.just("pi"),
        st.integers(min_value=0, max_value=32).map(lambda k: str(k / 8)),
    )

    def extend(children: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        return st.one_of(
            st.tuples(children, st.sampled_from(["+", "-", "*"]), children).map(
                lambda t: f"({t[0]} {t[1]} {t[2]})"
            ),
            st.tuples(children, st.sampled_from(["2", "3"])).map(lambda t: f"({t[0]})**{t[1]}"),
            st.tuples(st.sampled_from(["sin", "cos", "abs", "tanh"]), children).map(
                lambda t: f"{t[0]}({t[1]})"
            ),
            children.map(lambda c: f"-{c}"),
        )

    return st.recursive(leaves, extend, max_leaves=6)


def _magnitude(tree: tuple, x: float, a: float) -> float:
    """An upper bound of the size of every intermediate value, for a rounding tolerance."""
    tag = tree[0]
    if tag == "num":
        return abs(float(tree[1]))
    if tag == "x":
        return abs(x)
    if tag == "param":
        return abs(a)
    if tag == "pi":
        return math.pi
    if tag == "neg":
        return _magnitude(tree[1], x, a)
    if tag == "call":
        inner = _magnitude(tree[2], x, a)
        return inner if tree[1] == "abs" else max(1.0, inner)
    if tag == "pow":
        return _magnitude(tree[1], x, a) ** float(tree[2][1])
    left, right = _magnitude(tree[1], x, a), _magnitude(tree[2], x, a)
    return left * right if tag == "mul" else left + right


@settings(max_examples=300, deadline=None)
@given(_expressions(), st.floats(min_value=-2, max_value=2), st.floats(min_value=0.5, max_value=2))
def test_generated_expressions_agree_with_sympy(text: str, x: float, a: float) -> None:
    curve = parse_curve(text)
    params = {"a": a} if "a" in curve.parameters else {}
    value = curve.evaluate(x, **params)
    a_symbol = sympy.Symbol("a", real=True)
    expression = curve.to_sympy(X, {"a": a_symbol})
    exact = expression.subs({X: sympy.Rational(x), a_symbol: sympy.Rational(a)}).evalf(40)
    tolerance = 1e-12 * (1.0 + _magnitude(curve.tree, x, a))
    assert abs(float(exact) - value) <= tolerance
    assert parse_curve(curve.canonical()).tree == curve.tree
