"""Print derived expressions as plain Python modules (scalar ``math`` code).

Output is reproducible byte for byte: functions and arguments come in a fixed order,
common subexpressions get fixed names (``_c0, _c1, ...`` in sympy's canonical order), and
the header carries no timestamp, only the source, the sympy version and a content hash.
"""

from __future__ import annotations

import sympy as sm
from sympy.printing.precedence import precedence
from sympy.printing.pycode import PythonCodePrinter

from .contenthash import HASH_PREFIX, content_hash, hash_matches, split_module

__all__ = [
    "HASH_PREFIX",
    "NonFiniteConstantError",
    "function_source",
    "generated_notice",
    "hash_matches",
    "module_text",
    "pyexpr",
    "split_module",
]


class NonFiniteConstantError(ValueError):
    """An expression holds a constant that is not a finite real number (``zoo`` from a
    division by zero, ``nan``, an infinity, ``I``): there is no code to print for it."""


def _refuse(what: str):
    def method(self, expr):
        raise NonFiniteConstantError(
            f"the derived expression contains {what}, which has no finite real value"
        )

    return method


#: Integer powers up to this one (and their reciprocals) print as products.
MAX_PRODUCT_POWER = 8


class _Printer(PythonCodePrinter):
    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})

    def _print_Pow(self, expr, rational=False):
        # No power prints as `**`: CPython computes a float `x**n` with libm's pow, while
        # compiled code turns a constant integer power into multiplications, and the two
        # differ in the last bit now and then. Small integer powers print as products
        # (faster, and the same operations in both); any other power as math.pow, which
        # is libm's pow in both. Products are parenthesized, since one must stay one
        # factor wherever it stands (a/(x*x), not a/x*x).
        exp = expr.exp
        if exp.is_Integer and 2 <= abs(int(exp)) <= MAX_PRODUCT_POWER:
            base = self.parenthesize(expr.base, precedence(expr))
            product = "(" + "*".join([base] * abs(int(exp))) + ")"
            return product if exp > 0 else f"(1.0/{product})"
        if exp in (sm.S.Half, -sm.S.Half, sm.S.NegativeOne):
            return super()._print_Pow(expr, rational=rational)  # sqrt, 1/sqrt, 1/x
        return f"math.pow({self._print(expr.base)}, {self._print(exp)})"

    def _print_Rational(self, expr):
        # Exact rational constants print as float literals: Python folds them anyway.
        return repr(float(expr))

    def _print_Half(self, expr):
        return "0.5"

    def _print_Float(self, expr):
        if not expr.is_finite:
            raise NonFiniteConstantError(
                f"the derived expression contains the constant {expr}, which is not finite"
            )
        return super()._print_Float(expr)

    # Printed as names (math.nan, math.inf, 1j) these would give code that computes
    # nonsense, or in pyexpr's number branch a bare undefined name: refuse them.
    _print_NaN = _refuse("nan (an undefined value, e.g. 0/0)")
    _print_ComplexInfinity = _refuse("zoo (a division by zero)")
    _print_Infinity = _refuse("an infinity")
    _print_NegativeInfinity = _refuse("an infinity")
    _print_ImaginaryUnit = _refuse("the imaginary unit I")


_printer = _Printer()


def pyexpr(expr: sm.Basic) -> str:
    """Python source of a sympy expression (``math`` functions, float literals).

    Raises NonFiniteConstantError for zoo, nan, infinities and complex constants: the
    output never names anything but ``math`` and the function's arguments.
    """
    if isinstance(expr, sm.Basic) and expr.is_Number:
        if not (expr.is_real and expr.is_finite):
            return _printer.doprint(expr)  # raises NonFiniteConstantError
        return repr(float(expr))  # a constant output is a float, like every other output
    return _printer.doprint(expr)


def function_source(
    name: str,
    args: list[sm.Symbol],
    outputs,
    doc: str,
    indent: str = "",
    array: tuple[str, list[str]] | None = None,
) -> str:
    """Source of ``def name(args): ... return outputs`` with common subexpressions.

    ``array = (ARG, names)`` adds a last argument ARG, an array of the values of the
    symbols ``names`` in that order; the function reads the ones it uses from it first
    (``a = ARG[0]``). Compiled code can take such an array where it cannot take a closure.
    """
    single = not isinstance(outputs, (list, tuple, sm.MatrixBase))
    exprs = [outputs] if single else list(outputs)
    replacements, reduced = sm.cse(exprs, symbols=sm.numbered_symbols("_c"), order="canonical")
    arg_names = [a.name for a in args]
    prelude = []
    if array is not None:
        arg_names.append(array[0])
        used = set().union(*(sm.sympify(e).free_symbols for e in exprs))
        used_names = {sym.name for sym in used}
        prelude = [
            f"{indent}    {n} = {array[0]}[{i}]" for i, n in enumerate(array[1]) if n in used_names
        ]
    lines = [f"{indent}def {name}({', '.join(arg_names)}):"]
    lines.append(f'{indent}    """{doc}"""')
    lines += prelude
    for sym, value in replacements:
        lines.append(f"{indent}    {sym.name} = {pyexpr(value)}")
    if single:
        lines.append(f"{indent}    return {pyexpr(reduced[0])}")
    elif len(reduced) == 1:
        lines.append(f"{indent}    return ({pyexpr(reduced[0])},)")
    else:
        body = ",\n".join(f"{indent}        {pyexpr(ex)}" for ex in reduced)
        lines.append(f"{indent}    return (\n{body},\n{indent}    )")
    return "\n".join(lines) + "\n"


def module_text(header_lines: list[str], body: str) -> str:
    """Assemble a module: header comments, a content hash of the body, then the body."""
    digest = content_hash(body)
    header = "".join(f"# {line}\n" if line else "#\n" for line in header_lines)
    return header + HASH_PREFIX + digest + "\n" + body


def generated_notice(source: str) -> list[str]:
    return [
        "Generated by `billiard derive`. Do not edit by hand: edit the derivation and regenerate.",
        f"Source: {source}",
        f"sympy {sm.__version__}",
    ]
