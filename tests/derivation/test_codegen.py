"""Generated code prints no power as ``**``, so that interpreted and compiled code agree:
integer powers up to the 8th (and their reciprocals) as products, any other power as
``math.pow``.

CPython evaluates a float ``x**n`` through libm's ``pow``, which is not always correctly
rounded; compiled code turns a constant integer power into multiplications. Only a
printed product, or an explicit ``math.pow`` (libm's ``pow`` in both), gives both the
same bits. A quartic user curve (``3e4*x**4``) once ran 12 impacts before the two
engines parted.
"""

from __future__ import annotations

import ast
import importlib.util
import math
import random
from pathlib import Path

import pytest
import sympy as sm

from derivation.codegen import pyexpr

ROOT = Path(__file__).resolve().parents[2]


def _as_function(source: str, folder: Path):
    """The printed expression as a function f(x, y, a) of a module written to ``folder``,
    imported the way the generated modules are."""
    path = folder / "printed.py"
    path.write_text(f"import math\n\n\ndef f(x, y, a):\n    return {source}\n")
    spec = importlib.util.spec_from_file_location("printed", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.f


@pytest.mark.parametrize(
    ("expr", "reference"),
    [
        ("x**2", lambda x, y, a: x * x),
        ("a/x**2", lambda x, y, a: a / (x * x)),
        ("(x + y)**2", lambda x, y, a: (x + y) * (x + y)),
        ("-x**2 + a", lambda x, y, a: -(x * x) + a),
        ("2*x**2*y", lambda x, y, a: 2 * (x * x) * y),
        ("a/x**3", lambda x, y, a: a / (x * x * x)),
        ("x**3*y", lambda x, y, a: (x * x * x) * y),
        ("3e4*x**4 + a", lambda x, y, a: 3e4 * (x * x * x * x) + a),
        ("y*x**8", lambda x, y, a: y * (x * x * x * x * x * x * x * x)),
        ("x**(-4)", lambda x, y, a: 1.0 / (x * x * x * x)),
        ("x**12", lambda x, y, a: math.pow(x, 12)),
        ("abs(x)**(3/2)", lambda x, y, a: math.pow(abs(x), 1.5)),
        ("abs(x)**abs(a)", lambda x, y, a: math.pow(abs(x), abs(a))),
    ],
)
def test_squares_print_as_products_with_the_same_bits(expr, reference, tmp_path):
    x, y, a = sm.symbols("x y a")
    source = pyexpr(sm.sympify(expr, locals={"x": x, "y": y, "a": a}))
    assert "**" not in source
    f = _as_function(source, tmp_path)
    rng = random.Random(7)
    for _ in range(2000):
        v = {"x": rng.uniform(-3, 3), "y": rng.uniform(-3, 3), "a": rng.uniform(-3, 3)}
        assert f(**v) == reference(**v)


def test_the_committed_modules_hold_no_power_operator():
    powers = []
    for path in sorted((ROOT / "generated").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
                powers.append(f"{path.name}:{node.lineno}")
    assert not powers
    assert len(list((ROOT / "generated").rglob("*.py"))) >= 5
