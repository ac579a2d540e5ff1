"""Safe parsing of user-supplied boundary curve expressions, and the rules for curve names.

Pure Python: sympy is imported only inside :meth:`CurveExpression.to_sympy`, so the
runtime (``billiard.scene.scene``, ``billiard.geometry.curves``) imports this module without loading
sympy.

A scene may describe its boundary by an expression in ``x`` (metres) such as
``"26*x**2 + 0.0063"``. Such text is data, not code: it is never handed to
:func:`eval`, :func:`exec`, ``sympy.sympify`` or ``sympy.parse_expr``. Instead it
goes through cheap textual pre-checks, is parsed by :func:`ast.parse` into a
Python syntax tree, and that tree is walked against a strict whitelist. The
accepted tree is copied into a small immutable tree of tuples that the rest of
the package works with:

=====================================  ===========================================
node                                   meaning
=====================================  ===========================================
``("num", "0.0063")``                  a non-negative numeric literal (exact decimal
                                       text, normalised)
``("x",)``                             the horizontal coordinate x (m)
``("pi",)``                            the constant pi
``("param", "a")``                     a named parameter of the curve
``("neg", a)``                         unary minus
``("add", a, b)``, ``("sub", a, b)``   a + b, a - b
``("mul", a, b)``, ``("div", a, b)``   a * b, a / b
``("pow", a, p)``                      a ** p, where p is ``("num", ...)`` or
                                       ``("neg", ("num", ...))``
``("call", "sqrt", a)``                one of the functions in :data:`FUNCTIONS`
``("piecewise", ((a, c), ...))``       ``Piecewise((a, c), ...)``: the first piece
                                       whose condition c holds; c is ``("true",)``
                                       or ``("cmp", left, ((op, right), ...))``, a
                                       (chained) comparison with ``<``, ``<=``,
                                       ``>``, ``>=`` of x with numbers and
                                       parameters, x appearing once, bare
=====================================  ===========================================

``Piecewise`` must be the whole expression (a curve made of pieces, each valid on an
interval of x); the derivation checks that the pieces meet (no jump in height).

The expression gives the height y (m) of the boundary in its own frame as a function
of x (m); parameters carry whatever units make the expression a length.
"""

from __future__ import annotations

import ast
import keyword
import math
import re
import unicodedata
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from decimal import Context, Decimal, InvalidOperation
from typing import Any

__all__ = [
    "BUILTIN_CURVES",
    "DERIVE_TIMEOUT",
    "FUNCTIONS",
    "MAX_DEPTH",
    "MAX_EXPONENT",
    "MAX_LENGTH",
    "MAX_LITERAL_LENGTH",
    "MAX_NESTED_EXPONENT",
    "MAX_NODES",
    "MAX_CURVE_NAME",
    "PAPER_CURVES",
    "CurveExpression",
    "CurveExpressionError",
    "curve_name_problem",
    "is_curve_name",
    "is_parameter_name",
    "parse_curve",
]

#: Longest accepted expression text, in characters.
MAX_LENGTH = 400
#: Deepest accepted nesting of brackets.
MAX_DEPTH = 20
#: Largest number of expression nodes in the syntax tree.
MAX_NODES = 200
#: Longest accepted numeric literal, in characters.
MAX_LITERAL_LENGTH = 30
#: Largest accepted absolute value of an exponent of ``**``.
MAX_EXPONENT = 32
#: Largest accepted product of the absolute exponents of powers nested in one another,
#: as in ``(x**32)**32``; keeps exact symbolic evaluation of numeric powers cheap.
MAX_NESTED_EXPONENT = 1024
#: Seconds the derivation of an accepted expression (sympy) may take by default
#: (``billiard derive --timeout SECONDS``): the paper's curves and the usual polynomials,
#: radicals and abs() pieces take under a second; an expression sympy cannot simplify
#: can take minutes and gigabytes.
DERIVE_TIMEOUT = 60.0
#: The functions that may be called, each with exactly one positional argument: the name
#: in an expression -> (the :mod:`math` function, the name of the sympy function). The one
#: table of allowed functions; everything else is derived from it.
_FUNCTION_TABLE: dict[str, tuple[Callable[[float], float], str]] = {
    "abs": (abs, "Abs"),
    "sqrt": (math.sqrt, "sqrt"),
    "exp": (math.exp, "exp"),
    "log": (math.log, "log"),
    "sin": (math.sin, "sin"),
    "cos": (math.cos, "cos"),
    "tan": (math.tan, "tan"),
    "sinh": (math.sinh, "sinh"),
    "cosh": (math.cosh, "cosh"),
    "tanh": (math.tanh, "tanh"),
}
#: Functions that may be called, each with exactly one positional argument.
FUNCTIONS: tuple[str, ...] = tuple(_FUNCTION_TABLE)

#: The paper's boundaries (Hartl, Miller and Mazzoleni, eqs. 1-3), in metres:
#: a = 0.26 /cm, b = 1.85, c = 0.63 cm, alpha = 40.3 cm^2, beta = 0.08 /cm^2,
#: delta = 4.45 cm. Name -> (expression, parameter defaults as exact decimal text).
#: Their generated modules ship with the package (``billiard.generated.curves``).
PAPER_CURVES: dict[str, tuple[str, dict[str, str]]] = {
    "parabola": ("a*x**2 + c", {"a": "26", "c": "0.0063"}),
    "wedge": ("b*abs(x) + c", {"b": "1.85", "c": "0.0063"}),
    "hyperbola": (
        "sqrt(alpha*(1 + beta*x**2)) - delta",
        {"alpha": "0.00403", "beta": "800", "delta": "0.0445"},
    ),
}
#: Names of the built-in curves: a user curve may not take one of them.
BUILTIN_CURVES: tuple[str, ...] = tuple(PAPER_CURVES)

#: The comparison operators allowed in a ``Piecewise`` condition: AST type -> text.
_COMPARISONS: dict[type[ast.cmpop], str] = {
    ast.Lt: "<",
    ast.LtE: "<=",
    ast.Gt: ">",
    ast.GtE: ">=",
}
#: Most pieces in one ``Piecewise``.
MAX_PIECES = 16

#: Longest name of a user curve (it names a file).
MAX_CURVE_NAME = 40
_CURVE_NAME_RE = re.compile(r"[A-Za-z][A-Za-z0-9_-]*")

_PARAMETER_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,30}")
_RESERVED_NAMES = frozenset({"x", "pi"})
_BINARY_OPERATORS: dict[type[ast.operator], tuple[str, str]] = {
    ast.Add: ("add", "+"),
    ast.Sub: ("sub", "-"),
    ast.Mult: ("mul", "*"),
    ast.Div: ("div", "/"),
    ast.Pow: ("pow", "**"),
}
_OPERATOR_SYMBOLS: dict[type[ast.AST], str] = {
    ast.FloorDiv: "//",
    ast.Mod: "%",
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitXor: "^",
    ast.BitAnd: "&",
    ast.Invert: "~",
    ast.Not: "not",
    ast.And: "and",
    ast.Or: "or",
}
_NODE_DESCRIPTIONS: dict[type[ast.AST], str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscript",
    ast.Slice: "slice",
    ast.Lambda: "lambda",
    ast.ListComp: "list comprehension",
    ast.SetComp: "set comprehension",
    ast.DictComp: "dict comprehension",
    ast.GeneratorExp: "generator expression",
    ast.Compare: "comparison",
    ast.BoolOp: "boolean operator",
    ast.NamedExpr: "assignment expression",
    ast.JoinedStr: "f-string",
    ast.FormattedValue: "f-string",
    ast.Starred: "starred expression",
    ast.Tuple: "tuple",
    ast.List: "list",
    ast.Set: "set",
    ast.Dict: "dict",
    ast.IfExp: "conditional expression",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
}

# Precedence levels used to print the canonical text with minimal parentheses.
_LEVEL_SUM, _LEVEL_PRODUCT, _LEVEL_UNARY, _LEVEL_POWER, _LEVEL_ATOM = 1, 2, 3, 4, 5


class CurveExpressionError(ValueError):
    """A curve expression was refused; the message is one line starting with
    ``"curve expression:"`` and names the offending part."""


def is_parameter_name(name: str) -> bool:
    """Return True if *name* may name a curve parameter.

    Parameter names are ASCII identifiers of 1 to 31 characters that start with a
    letter, are not Python keywords, and are neither ``x``, ``pi`` nor the name of
    a function in :data:`FUNCTIONS`.
    """
    return (
        isinstance(name, str)
        and _PARAMETER_RE.fullmatch(name) is not None
        and name not in _RESERVED_NAMES
        and name not in FUNCTIONS
        and not keyword.iskeyword(name)
    )


def is_curve_name(text: str) -> bool:
    """Return True if a scene's ``boundary.curve`` text names a curve rather than being an
    expression in x: the one rule, used by scenes, the curve loader and the derivation.

    A name is an ASCII letter followed by letters, digits, ``_`` or ``-`` (``my-bowl`` is
    a name, not ``my - bowl``: an expression made of names and ``-`` alone is linear in x
    and could never hold a ball), and is neither ``x`` nor ``pi``.
    """
    return (
        isinstance(text, str)
        and _CURVE_NAME_RE.fullmatch(text) is not None
        and text not in _RESERVED_NAMES
    )


def curve_name_problem(name: str) -> str | None:
    """Why *name* cannot name a new user curve (one line), or None if it can."""
    if not is_curve_name(name):
        return (
            f"curve name {name!r} must start with a letter and use only letters, digits, "
            "'_' and '-' (and be neither x nor pi)"
        )
    if len(name) > MAX_CURVE_NAME:
        return f"curve name {name!r} is longer than {MAX_CURVE_NAME} characters"
    if name in BUILTIN_CURVES:
        return (
            f"curve name {name!r} is a built-in curve ({', '.join(BUILTIN_CURVES)}); "
            "choose another name"
        )
    if name.startswith("expr_"):
        return f"curve name {name!r}: names starting with 'expr_' are kept for cached expressions"
    return None


def _fail(message: str) -> CurveExpressionError:
    one_line = " ".join(message.splitlines())
    return CurveExpressionError(f"curve expression: {one_line}")


def _describe_char(ch: str) -> str:
    code = f"U+{ord(ch):04X}"
    name = unicodedata.name(ch, "")
    shown = f"'{ch}' " if ch.isprintable() and not ch.isspace() else ""
    return f"character {shown}({code}{' ' + name if name else ''})"


def _precheck(text: str) -> None:
    """Checks done on the raw text before any parsing."""
    if len(text) > MAX_LENGTH:
        raise _fail(f"text is {len(text)} characters long; at most {MAX_LENGTH} are allowed")
    for position, ch in enumerate(text):
        if not " " <= ch <= "~":
            raise _fail(
                f"{_describe_char(ch)} at column {position + 1} is not allowed; "
                "only printable ASCII characters are accepted"
            )
    if not text.strip():
        raise _fail("the expression is empty")
    depth = 0
    for position, ch in enumerate(text):
        if ch in "([{":
            depth += 1
            if depth > MAX_DEPTH:
                raise _fail(
                    f"brackets are nested deeper than {MAX_DEPTH} levels (at column {position + 1})"
                )
        elif ch in ")]}":
            depth -= 1


def _canonical_number(literal: str, value: int | float) -> str:
    """Exact, normalised decimal text of a numeric literal."""
    if isinstance(value, int):
        return str(value)
    try:
        exact = Decimal(literal.replace("_", ""))
    except InvalidOperation:  # pragma: no cover - Python float literals are valid decimals
        exact = Decimal(value)
    exact = exact.normalize(Context(prec=2 * MAX_LITERAL_LENGTH))
    if exact == exact.to_integral_value() and abs(exact) < 10**MAX_LITERAL_LENGTH:
        return str(int(exact))
    return str(exact).replace("E+", "e").replace("E", "e")


class _Validator:
    """Walks a Python syntax tree and builds the whitelisted tuple tree."""

    def __init__(self, source: str, offset: int) -> None:
        self.source = source
        self.offset = offset  # columns removed by stripping leading blanks
        self.parameters: set[str] = set()

    # -- helpers ---------------------------------------------------------------
    def _column(self, node: ast.AST) -> int:
        return getattr(node, "col_offset", 0) + self.offset + 1

    def _snippet(self, node: ast.AST, limit: int = 40) -> str:
        segment = ast.get_source_segment(self.source, node) or type(node).__name__
        if len(segment) > limit:
            segment = segment[: limit - 3] + "..."
        return segment

    def _refuse(self, node: ast.AST) -> CurveExpressionError:
        while isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute):
            node = node.value  # report the first attribute access in the text
        column = self._column(node)
        if isinstance(node, ast.Attribute):
            dot = self.source.find(".", node.value.end_col_offset or 0, node.end_col_offset)
            if dot >= 0:
                column = dot + self.offset + 1
            return _fail(f"attribute access '.{node.attr}' is not allowed (at column {column})")
        if isinstance(node, ast.Constant):
            value = node.value
            if isinstance(value, str):
                what = "string literal"
            elif isinstance(value, bytes):
                what = "bytes literal"
            elif isinstance(value, bool) or value is None or value is Ellipsis:
                what = "constant"
            elif isinstance(value, complex):
                what = "complex literal"
            else:
                what = "constant"
            return _fail(f"{what} '{self._snippet(node)}' is not allowed (at column {column})")
        if isinstance(node, ast.BoolOp):
            symbol = _OPERATOR_SYMBOLS.get(type(node.op), "?")
            return _fail(f"boolean operator '{symbol}' is not allowed (at column {column})")
        description = _NODE_DESCRIPTIONS.get(type(node), type(node).__name__.lower())
        return _fail(f"{description} '{self._snippet(node)}' is not allowed (at column {column})")

    # -- the walk ----------------------------------------------------------------
    def visit(self, node: ast.AST) -> tuple:
        if isinstance(node, ast.Constant):
            return self._number(node)
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.BinOp):
            return self._binop(node)
        if isinstance(node, ast.UnaryOp):
            return self._unary(node)
        if isinstance(node, ast.Call):
            return self._call(node)
        raise self._refuse(node)

    def _number(self, node: ast.Constant) -> tuple:
        value = node.value
        if type(value) not in (int, float):
            raise self._refuse(node)
        literal = ast.get_source_segment(self.source, node) or repr(value)
        if len(literal) > MAX_LITERAL_LENGTH:
            raise _fail(
                f"number '{self._snippet(node)}' is longer than {MAX_LITERAL_LENGTH} "
                f"characters (at column {self._column(node)})"
            )
        if isinstance(value, float) and not math.isfinite(value):
            raise _fail(
                f"number '{literal}' is not finite as a float (at column {self._column(node)})"
            )
        return ("num", _canonical_number(literal, value))

    def _name(self, node: ast.Name) -> tuple:
        name = node.id
        column = self._column(node)
        if name == "x":
            return ("x",)
        if name == "pi":
            return ("pi",)
        if name in FUNCTIONS:
            raise _fail(
                f"function '{name}' must be called with one argument, as in '{name}(x)' "
                f"(at column {column})"
            )
        if name.startswith("_"):
            raise _fail(
                f"name '{name}' is not allowed; names may not start with '_' (at column {column})"
            )
        if keyword.iskeyword(name):
            raise _fail(f"name '{name}' is a Python keyword (at column {column})")
        if _PARAMETER_RE.fullmatch(name) is None:
            raise _fail(
                f"name '{self._snippet(node)}' is not a valid parameter name (ASCII letter "
                f"first, then up to 30 letters, digits or '_') (at column {column})"
            )
        self.parameters.add(name)
        return ("param", name)

    def _binop(self, node: ast.BinOp) -> tuple:
        kind = _BINARY_OPERATORS.get(type(node.op))
        if kind is None:
            symbol = _OPERATOR_SYMBOLS.get(type(node.op), type(node.op).__name__)
            raise _fail(
                f"operator '{symbol}' is not allowed; allowed: + - * / ** "
                f"(at column {self._column(node)})"
            )
        tag = kind[0]
        left = self.visit(node.left)
        if tag == "pow":
            return ("pow", left, self._exponent(node))
        return (tag, left, self.visit(node.right))

    def _exponent(self, node: ast.BinOp) -> tuple:
        exponent = node.right
        sign = ""
        if isinstance(exponent, ast.UnaryOp) and isinstance(exponent.op, (ast.USub, ast.UAdd)):
            sign = "-" if isinstance(exponent.op, ast.USub) else ""
            exponent = exponent.operand
        if not (isinstance(exponent, ast.Constant) and type(exponent.value) in (int, float)):
            raise _fail(
                f"the exponent in '{self._snippet(node)}' must be a number, not "
                f"'{self._snippet(node.right)}' (at column {self._column(node.right)})"
            )
        number = self._number(exponent)
        if abs(Decimal(number[1])) > MAX_EXPONENT:
            raise _fail(
                f"exponent '{self._snippet(node.right)}' is too large; "
                f"|p| <= {MAX_EXPONENT} is required (at column {self._column(node.right)})"
            )
        return ("neg", number) if sign else number

    def _unary(self, node: ast.UnaryOp) -> tuple:
        if isinstance(node.op, ast.USub):
            return ("neg", self.visit(node.operand))
        if isinstance(node.op, ast.UAdd):
            return self.visit(node.operand)
        symbol = _OPERATOR_SYMBOLS.get(type(node.op), type(node.op).__name__)
        raise _fail(f"operator '{symbol}' is not allowed (at column {self._column(node)})")

    def _call(self, node: ast.Call) -> tuple:
        func = node.func
        column = self._column(node)
        if not isinstance(func, ast.Name):
            self.visit(func)  # raises a specific message for a refused construct
            raise _fail(
                f"call of '{self._snippet(func)}' is not allowed; only the functions "
                f"{', '.join(FUNCTIONS)} may be called (at column {column})"
            )
        name = func.id
        if name == "Piecewise":
            raise _fail(
                f"Piecewise must be the whole expression, not part of it (at column {column})"
            )
        if name not in FUNCTIONS:
            raise _fail(
                f"function '{name}' is not allowed; allowed: {', '.join(FUNCTIONS)} "
                f"(at column {column})"
            )
        for kw in node.keywords:
            label = f"{kw.arg}=" if kw.arg is not None else "**"
            raise _fail(
                f"keyword argument '{label}' in the call of '{name}' is not allowed "
                f"(at column {self._column(kw)})"
            )
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                raise _fail(
                    f"starred argument '{self._snippet(arg)}' in the call of '{name}' is not "
                    f"allowed (at column {self._column(arg)})"
                )
        if len(node.args) != 1:
            raise _fail(
                f"function '{name}' takes exactly one argument, got {len(node.args)} "
                f"(at column {column})"
            )
        return ("call", name, self.visit(node.args[0]))

    # -- Piecewise (the whole expression only) ------------------------------------
    def top(self, node: ast.AST) -> tuple:
        """The whole expression: ``Piecewise((expr, condition), ...)`` or any other."""
        if not (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id == "Piecewise"
        ):
            return self.visit(node)
        column = self._column(node)
        if node.keywords:
            raise _fail(f"Piecewise takes no keyword arguments (at column {column})")
        if not 1 <= len(node.args) <= MAX_PIECES:
            raise _fail(
                f"Piecewise takes 1 to {MAX_PIECES} pieces (expr, condition), got "
                f"{len(node.args)} (at column {column})"
            )
        pieces = []
        for k, arg in enumerate(node.args):
            if not (isinstance(arg, ast.Tuple) and len(arg.elts) == 2):
                raise _fail(
                    f"piece {k + 1} of Piecewise must be a pair (expression, condition), not "
                    f"'{self._snippet(arg)}' (at column {self._column(arg)})"
                )
            value, condition = arg.elts
            pieces.append((self.visit(value), self._condition(condition, k)))
        if pieces[-1][1] != ("true",):
            raise _fail(
                "the last piece of Piecewise must have the condition True, so that a piece "
                f"holds at every x (at column {self._column(node.args[-1])})"
            )
        for k, (_, condition) in enumerate(pieces[:-1]):
            if condition == ("true",):
                raise _fail(
                    f"piece {k + 1} of Piecewise has the condition True, so the pieces after "
                    f"it are never used (at column {column})"
                )
        return ("piecewise", tuple(pieces))

    def _condition(self, node: ast.AST, k: int) -> tuple:
        column = self._column(node)
        if isinstance(node, ast.Constant) and node.value is True:
            return ("true",)
        if not isinstance(node, ast.Compare):
            raise _fail(
                f"the condition of piece {k + 1} of Piecewise must compare x with numbers or "
                f"parameters (as in 'x < 0' or '0 <= x < a') or be True, not "
                f"'{self._snippet(node)}' (at column {column})"
            )
        operands = [node.left, *node.comparators]
        ops = []
        for op in node.ops:
            symbol = _COMPARISONS.get(type(op))
            if symbol is None:
                raise _fail(
                    f"comparison '{self._snippet(node)}' in piece {k + 1} of Piecewise: only "
                    f"<, <=, >, >= are allowed (at column {column})"
                )
            ops.append(symbol)
        trees = [self.visit(operand) for operand in operands]
        bare = [i for i, tree in enumerate(trees) if tree == ("x",)]
        if len(bare) != 1 or any(_has_x(tree) for tree in trees if tree != ("x",)):
            raise _fail(
                f"the condition '{self._snippet(node)}' of piece {k + 1} of Piecewise must "
                f"compare x itself, once, with numbers or parameters (at column {column})"
            )
        return ("cmp", trees[0], tuple(zip(ops, trees[1:], strict=True)))


def _has_x(tree: tuple) -> bool:
    """Does the (non-Piecewise) tree use x?"""
    if tree[0] == "x":
        return True
    return any(isinstance(child, tuple) and _has_x(child) for child in tree[1:])


def _subtrees(tree: tuple) -> list[tuple]:
    """The expressions inside a Piecewise tree (values and compared operands), or the tree."""
    if tree[0] != "piecewise":
        return [tree]
    found = []
    for value, condition in tree[1]:
        found.append(value)
        if condition[0] == "cmp":
            found += [condition[1], *(operand for _, operand in condition[2])]
    return found


def _holds(condition: tuple, x: float, params: Mapping[str, float]) -> bool:
    """Does a Piecewise condition hold at x?"""
    if condition[0] == "true":
        return True
    left = _evaluate(condition[1], x, params)
    for op, operand in condition[2]:
        right = _evaluate(operand, x, params)
        if not _COMPARE[op](left, right):
            return False
        left = right
    return True


_COMPARE: dict[str, Callable[[float, float], bool]] = {
    "<": lambda a, b: a < b,
    "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b,
}


def _nested_exponent(tree: tuple) -> Decimal:
    """Largest product of |exponents| along a chain of powers nested in each other."""
    tag = tree[0]
    if tag == "piecewise":
        return max(_nested_exponent(sub) for sub in _subtrees(tree))
    if tag in ("num", "x", "pi", "param"):
        return Decimal(1)
    if tag == "pow":
        exponent = tree[2][1] if tree[2][0] == "neg" else tree[2]
        return max(Decimal(1), abs(Decimal(exponent[1]))) * _nested_exponent(tree[1])
    children = [child for child in tree[1:] if isinstance(child, tuple)]
    return max(_nested_exponent(child) for child in children)


def parse_curve(text: str) -> CurveExpression:
    """Parse and validate a curve expression y = f(x), x and y in metres.

    Raises :class:`CurveExpressionError` (a :class:`ValueError`) with a one-line
    message naming the offending part for anything outside the whitelist
    described in this module's documentation.
    """
    if not isinstance(text, str):
        raise _fail(f"expected a string, got {type(text).__name__}")
    _precheck(text)
    stripped = text.lstrip(" ")
    offset = len(text) - len(stripped)
    try:
        syntax_tree = ast.parse(stripped, mode="eval")
    except SyntaxError as exc:
        column = (exc.offset or 1) + offset
        detail = "" if exc.msg == "invalid syntax" else f": {exc.msg}"
        raise _fail(f"invalid syntax{detail} (at column {column})") from None
    except (RecursionError, MemoryError, ValueError) as exc:
        raise _fail(f"cannot be parsed ({type(exc).__name__})") from None
    nodes = sum(1 for node in ast.walk(syntax_tree) if isinstance(node, ast.expr))
    if nodes > MAX_NODES:
        raise _fail(f"too complex: {nodes} nodes, at most {MAX_NODES} are allowed")
    validator = _Validator(stripped, offset)
    tree = validator.top(syntax_tree.body)
    nested = _nested_exponent(tree)
    if nested > MAX_NESTED_EXPONENT:
        raise _fail(
            f"nested powers are too large: combined exponent {nested} exceeds {MAX_NESTED_EXPONENT}"
        )
    return CurveExpression(text=text, tree=tree, parameters=tuple(sorted(validator.parameters)))


_MATH_FUNCTIONS: dict[str, Callable[[float], float]] = {
    name: pair[0] for name, pair in _FUNCTION_TABLE.items()
}


def _evaluate(tree: tuple, x: float, params: Mapping[str, float]) -> float:
    tag = tree[0]
    if tag == "piecewise":
        for value, condition in tree[1]:
            if _holds(condition, x, params):
                return _evaluate(value, x, params)
        raise ValueError("no piece of the Piecewise holds there")
    if tag == "num":
        return float(tree[1])
    if tag == "x":
        return x
    if tag == "pi":
        return math.pi
    if tag == "param":
        return params[tree[1]]
    if tag == "neg":
        return -_evaluate(tree[1], x, params)
    if tag == "call":
        return float(_MATH_FUNCTIONS[tree[1]](_evaluate(tree[2], x, params)))
    left = _evaluate(tree[1], x, params)
    right = _evaluate(tree[2], x, params)
    if tag == "add":
        return left + right
    if tag == "sub":
        return left - right
    if tag == "mul":
        return left * right
    if tag == "div":
        return left / right
    if tag == "pow":
        return math.pow(left, right)
    raise AssertionError(f"unknown node {tag!r}")  # pragma: no cover


def _text(tree: tuple) -> tuple[str, int]:
    """Canonical text of *tree* and its precedence level."""
    tag = tree[0]
    if tag == "piecewise":
        return "Piecewise(" + ", ".join(
            f"({_text(value)[0]}, {_condition_text(condition)})" for value, condition in tree[1]
        ) + ")", _LEVEL_ATOM
    if tag == "num":
        return tree[1], _LEVEL_ATOM
    if tag in ("x", "pi"):
        return tag, _LEVEL_ATOM
    if tag == "param":
        return tree[1], _LEVEL_ATOM
    if tag == "call":
        return f"{tree[1]}({_text(tree[2])[0]})", _LEVEL_ATOM
    if tag == "neg":
        return "-" + _wrap(tree[1], _LEVEL_POWER), _LEVEL_UNARY
    if tag == "pow":
        return f"{_wrap(tree[1], _LEVEL_ATOM)}**{_text(tree[2])[0]}", _LEVEL_POWER
    if tag in ("add", "sub"):
        symbol = " + " if tag == "add" else " - "
        text = _wrap(tree[1], _LEVEL_SUM) + symbol + _wrap(tree[2], _LEVEL_SUM + 1)
        return text, _LEVEL_SUM
    symbol = "*" if tag == "mul" else "/"
    return _wrap(tree[1], _LEVEL_PRODUCT) + symbol + _wrap(tree[2], _LEVEL_UNARY), _LEVEL_PRODUCT


def _condition_text(condition: tuple) -> str:
    if condition[0] == "true":
        return "True"
    return " ".join(
        [_text(condition[1])[0], *(f"{op} {_text(operand)[0]}" for op, operand in condition[2])]
    )


def _wrap(tree: tuple, minimum: int) -> str:
    text, level = _text(tree)
    return text if level >= minimum else f"({text})"


@dataclass(frozen=True)
class CurveExpression:
    """A validated curve expression y = f(x) (x and y in metres).

    Build instances with :func:`parse_curve`; the constructor does not validate.

    Attributes:
        text: the original text.
        tree: the validated immutable tree (see the module documentation).
        parameters: sorted names of the parameters the expression uses.
    """

    text: str
    tree: tuple
    parameters: tuple[str, ...]

    def canonical(self) -> str:
        """Normalised text of the expression, independent of whitespace, redundant
        parentheses, unary plus and the spelling of numbers (``1.50e-3`` and
        ``0.0015`` give the same text). It parses back to the same tree, so it
        serves as a cache key."""
        return _text(self.tree)[0]

    def evaluate(self, x: float, **params: float) -> float:
        """Evaluate f(x) in floating point with :mod:`math` (no sympy).

        Args:
            x: horizontal coordinate (m).
            **params: a value for every name in :attr:`parameters`, and no others.

        Returns:
            The height f(x) (m).

        Raises:
            ValueError: a parameter value is missing or unexpected, or the expression
                cannot be evaluated at *x* (domain error, division by zero, overflow,
                or a non-finite result).
        """
        missing = [name for name in self.parameters if name not in params]
        extra = sorted(set(params) - set(self.parameters))
        if missing or extra:
            parts = []
            if missing:
                parts.append(f"missing value for parameter(s) {', '.join(missing)}")
            if extra:
                parts.append(f"unknown parameter(s) {', '.join(extra)}")
            raise ValueError(f"curve expression {self.canonical()!r}: {'; '.join(parts)}")
        values = {name: float(value) for name, value in params.items()}
        try:
            result = _evaluate(self.tree, float(x), values)
        except (ArithmeticError, ValueError) as exc:
            raise ValueError(
                f"curve expression {self.canonical()!r} cannot be evaluated at x = {x!r}: {exc}"
            ) from None
        if not math.isfinite(result):
            raise ValueError(
                f"curve expression {self.canonical()!r} is not finite at x = {x!r}: {result!r}"
            )
        return result

    def to_sympy(
        self, x_symbol: Any = None, parameter_symbols: Mapping[str, Any] | None = None
    ) -> Any:
        """Build the expression with sympy constructors (no string parsing).

        Numeric literals become exact sympy rationals of their decimal text.

        Args:
            x_symbol: the sympy object standing for x; by default ``Symbol("x", real=True)``.
            parameter_symbols: optional map from parameter name to a sympy expression or an
                int/float value; parameters not in it become ``Symbol(name, real=True)``.

        Returns:
            A sympy expression for f(x).
        """
        import sympy

        x_sym = sympy.Symbol("x", real=True) if x_symbol is None else x_symbol
        given = dict(parameter_symbols or {})
        symbols: dict[str, Any] = {}
        for name in self.parameters:
            value = given.get(name)
            if value is None:
                symbols[name] = sympy.Symbol(name, real=True)
            elif isinstance(value, bool):
                raise TypeError(f"parameter {name!r}: expected a sympy expression or a number")
            elif isinstance(value, int):
                symbols[name] = sympy.Integer(value)
            elif isinstance(value, float):
                symbols[name] = sympy.Float(value)
            elif isinstance(value, sympy.Basic):
                symbols[name] = value
            else:
                raise TypeError(f"parameter {name!r}: expected a sympy expression or a number")

        functions = {name: getattr(sympy, pair[1]) for name, pair in _FUNCTION_TABLE.items()}

        relations = {"<": sympy.Lt, "<=": sympy.Le, ">": sympy.Gt, ">=": sympy.Ge}

        def condition(cond: tuple) -> Any:
            if cond[0] == "true":
                return sympy.true
            left = build(cond[1])
            parts = []
            for op, operand in cond[2]:
                right = build(operand)
                parts.append(relations[op](left, right, evaluate=False))
                left = right
            return sympy.And(*parts, evaluate=False) if len(parts) > 1 else parts[0]

        def build(tree: tuple) -> Any:
            tag = tree[0]
            if tag == "num":
                numerator, denominator = Decimal(tree[1]).as_integer_ratio()
                if denominator == 1:
                    return sympy.Integer(numerator)
                return sympy.Rational(numerator, denominator)
            if tag == "x":
                return x_sym
            if tag == "pi":
                return sympy.pi
            if tag == "param":
                return symbols[tree[1]]
            if tag == "neg":
                return sympy.Mul(sympy.Integer(-1), build(tree[1]))
            if tag == "call":
                return functions[tree[1]](build(tree[2]))
            if tag == "piecewise":
                return sympy.Piecewise(
                    *((build(value), condition(cond)) for value, cond in tree[1])
                )
            left, right = build(tree[1]), build(tree[2])
            if tag == "add":
                return sympy.Add(left, right)
            if tag == "sub":
                return sympy.Add(left, sympy.Mul(sympy.Integer(-1), right))
            if tag == "mul":
                return sympy.Mul(left, right)
            if tag == "div":
                return sympy.Mul(left, sympy.Pow(right, sympy.Integer(-1)))
            if tag == "pow":
                return sympy.Pow(left, right)
            raise AssertionError(f"unknown node {tag!r}")  # pragma: no cover

        return build(self.tree)
