"""Regenerate, or check, every generated module and docs/derivation.md.

``regenerate()`` is what ``billiard derive`` runs; ``check()`` is ``billiard derive --check``;
``derive_user_curve()`` is ``billiard derive --name NAME --curve EXPR`` and the first use of
a curve expression in a scene.
"""

from __future__ import annotations

import functools
import importlib.machinery
import importlib.util
import os
import tempfile
from pathlib import Path

import sympy as sm

from . import codegen, curve, report, shape
from .ball import BallDerivation, derive_ball, plain
from .expr import PAPER_CURVES, curve_name_problem, parse_curve

GENERATED = Path(__file__).resolve().parent.parent / "generated"


def _sym(name: str) -> sm.Symbol:
    return sm.Symbol(name)


def ball_module(d: BallDerivation) -> str:
    S = _sym
    u1, u2, u3, q1, q2 = S("u1"), S("u2"), S("u3"), S("q1"), S("q2")
    m, r, k, g = S("m"), S("r"), S("k"), S("g")
    c_lin, c_quad, c_magnus = S("c_lin"), S("c_quad"), S("c_magnus")
    z, vb1, vb2, e, mu_k, sgn, t = (S(n) for n in ("z", "vb1", "vb2", "e", "mu_k", "sgn", "t"))

    def p(expr):
        # Drop the assumptions of the derivation's symbols so that printing is uniform.
        expr = plain(expr)
        return expr.xreplace({a: S(a.name) for a in expr.free_symbols})

    mm = p(d.mass_matrix)
    parts = [
        '"""Dynamics and impact maps of the rotating ball '
        "(Kane's method, Kane-Levinson impacts).\n\n"
        "Symbols and conventions: see docs/design.md and docs/derivation.md. SI units.\n"
        '"""\n\nimport math\n\n',
        codegen.function_source(
            "mass_matrix",
            [m, r, k],
            [tuple(mm.row(i)) for i in range(3)],
            "Kane's mass matrix for u = (u1, u2, u3), rows as tuples (kg, kg m^2).",
        ),
        codegen.function_source(
            "forcing_drag",
            [u1, u2, u3, m, g, c_lin, c_quad],
            list(p(d.forcing_drag)),
            "Kane's forcing vector with gravity and Fowles drag (N, N, N m).",
        ),
        codegen.function_source(
            "flight_rhs_drag",
            [u1, u2, m, g, c_lin, c_quad],
            list(p(d.rhs_drag))[:2],
            "Accelerations (du1/dt, du2/dt) in flight with gravity and drag (m/s^2).",
        ),
        codegen.function_source(
            "flight_rhs_magnus",
            [u1, u2, u3, m, g, c_lin, c_quad, c_magnus],
            list(p(d.rhs_magnus))[:2],
            "Accelerations (du1/dt, du2/dt) with gravity, drag and the Magnus force (m/s^2).",
        ),
        codegen.function_source(
            "flight_exact",
            [t, q1, q2, u1, u2, g],
            list(p(d.flight_exact)),
            "State (q1, q2, u1, u2) after a drag-free flight of duration t (m, m/s).",
        ),
        codegen.function_source(
            "contact_velocity",
            [u1, u2, u3, z, vb1, vb2, r],
            list(p(d.contact_velocity)),
            "Velocity (wt, wn) of the ball's contact point relative to the boundary, "
            "along c1 and c2 (m/s).",
        ),
        codegen.function_source(
            "frame_velocity",
            [u1, u2, z],
            list(p(d.frame_velocity)),
            "Velocity (u4, un) of the centre along c1 and c2 (m/s); u4 is the paper's u4.",
        ),
        codegen.function_source(
            "impact_stick",
            [u1, u2, u3, z, vb1, vb2, m, r, k, e],
            list(p(d.stick)),
            "No-slip impact: post-impact (u1, u2, u3) and impulse (Rt, Rn) in N s.",
        ),
        codegen.function_source(
            "impact_slip",
            [u1, u2, u3, z, vb1, vb2, m, r, k, e, mu_k, sgn],
            list(p(d.slip)),
            "Slipping impact: post-impact (u1, u2, u3) and impulse (Rt, Rn) in N s; "
            "sgn is the sign of wt before the impact.",
        ),
        codegen.function_source(
            "energy",
            [q2, u1, u2, u3, m, r, k, g],
            p(d.energy),
            "Mechanical energy (J): translation + rotation + gravity, zero at q2 = 0.",
        ),
    ]
    body = "\n\n".join(parts)
    header = codegen.generated_notice("derivation/ball.py (Kane's method)") + [
        "Functions: mass_matrix, forcing_drag, flight_rhs_drag, flight_rhs_magnus, "
        "flight_exact, contact_velocity, frame_velocity, impact_stick, impact_slip, energy",
    ]
    return codegen.module_text(header, body)


def curve_from_text(name: str, text: str, parameters: dict[str, str]) -> curve.CurveDerivation:
    parsed = parse_curve(text)
    missing = sorted(set(parsed.parameters) - set(parameters))
    if missing:
        raise curve.CurveDerivationError(
            f"curve parameter(s) without a value: {', '.join(missing)}"
        )
    unused = sorted(set(parameters) - set(parsed.parameters))
    if unused:
        raise curve.CurveDerivationError(
            f"curve parameter(s) not in the expression: {', '.join(unused)}"
        )
    psyms = [sm.Symbol(n, real=True) for n in sorted(parameters)]
    expr = parsed.to_sympy(x_symbol=curve.x, parameter_symbols={p.name: p for p in psyms})
    if expr.has(sm.zoo, sm.nan, sm.oo, -sm.oo):
        raise curve.CurveDerivationError(
            f"curve {text!r} divides by zero or is otherwise undefined (sympy reduces it to {expr})"
        )
    try:
        return curve.derive_curve(name, text, expr, parameters, psyms)
    except curve.CurveDerivationError:
        raise
    except (TypeError, ValueError, ArithmeticError, NotImplementedError) as exc:
        # sympy failing on a whitelisted expression: say so in one line, not a traceback
        raise curve.CurveDerivationError(
            f"curve {text!r} cannot be derived ({type(exc).__name__}: {exc})"
        ) from None


#: Version of the generated curve modules' layout; the runtime refuses other layouts.
CURVE_FORMAT = 2
#: Name of the parameter-array argument of every generated wall function (parameter
#: names start with a letter, so it cannot clash with one).
PARAMETER_ARRAY = "_p"


def curve_module(cd: curve.CurveDerivation) -> str:
    x, s, px, py = sm.Symbol("x"), sm.Symbol("s"), sm.Symbol("px"), sm.Symbol("py")

    def p(expr):
        expr = sm.sympify(expr)
        return expr.xreplace({a: sm.Symbol(a.name) for a in expr.free_symbols})

    names = sorted(cd.parameters)
    array = (PARAMETER_ARRAY, names)
    lines = [
        f'"""Boundary curve {cd.name!r}: f(x) = {cd.text} (x and f in metres).',
        "",
        "Every function takes the curve's parameters as its last argument, an array in the",
        "order of PARAMETER_NAMES. WALLS lists, per smooth wall, the functions",
        "(interval, f, df, d2f, near, dnear, poly); poly is None where the nearest-point",
        'condition is not a polynomial."""',
        "",
        "import math",
        "",
        f"FORMAT = {CURVE_FORMAT}",
        f"NAME = {cd.name!r}",
        f"EXPRESSION = {cd.text!r}",
        f"PARAMETER_NAMES = {tuple(names)!r}",
        "PARAMETERS = {"
        + ", ".join(f"{n!r}: {float(sm.Rational(v))!r}" for n, v in sorted(cd.parameters.items()))
        + "}",
        "",
    ]
    walls = []
    for i, w in enumerate(cd.walls):
        fx = {curve.s: curve.x}
        lo = "-math.inf" if w.lo == -sm.oo else f"float({codegen.pyexpr(p(w.lo))})"
        hi = "math.inf" if w.hi == sm.oo else f"float({codegen.pyexpr(p(w.hi))})"
        used = {a.name for b in (w.lo, w.hi) if b not in (-sm.oo, sm.oo) for a in p(b).free_symbols}
        reads = [f"    {n} = {PARAMETER_ARRAY}[{k}]" for k, n in enumerate(names) if n in used]
        lines += [
            "",
            f"def interval_{i}({PARAMETER_ARRAY}):",
            '    """(lo, hi): the interval of x on which this wall is the curve (m)."""',
            *reads,
            f"    return ({lo}, {hi})",
            "",
        ]
        lines.append(
            "\n"
            + codegen.function_source(
                f"f_{i}", [x], p(w.f.subs(fx)), "Height of the wall (m).", array=array
            )
        )
        lines.append(
            "\n"
            + codegen.function_source(f"df_{i}", [x], p(w.df.subs(fx)), "Slope f'(x).", array=array)
        )
        lines.append(
            "\n"
            + codegen.function_source(
                f"d2f_{i}", [x], p(w.d2f.subs(fx)), "Second derivative f''(x) (1/m).", array=array
            )
        )
        lines.append(
            "\n"
            + codegen.function_source(
                f"near_{i}",
                [s, px, py],
                p(w.near),
                "Nearest-point condition g(s) = (s - px) + (f(s) - py) f'(s) (m).",
                array=array,
            )
        )
        lines.append(
            "\n"
            + codegen.function_source(
                f"dnear_{i}", [s, px, py], p(w.dnear), "Derivative dg/ds.", array=array
            )
        )
        if w.poly is not None:
            lines.append(
                "\n"
                + codegen.function_source(
                    f"poly_{i}",
                    [px, py],
                    [p(c) for c in w.poly],
                    f"Coefficients (highest power first) of the degree-{len(w.poly) - 1} "
                    "polynomial whose real roots are the candidate nearest points.",
                    array=array,
                )
            )
        poly = f"poly_{i}" if w.poly is not None else "None"
        walls.append(f"    (interval_{i}, f_{i}, df_{i}, d2f_{i}, near_{i}, dnear_{i}, {poly}),")
    lines += ["", "WALLS = (\n" + "\n".join(walls) + "\n)", ""]
    bps = ", ".join(f"float({codegen.pyexpr(p(b))})" for b in cd.breakpoints)
    used = {a.name for b in cd.breakpoints for a in p(b).free_symbols}
    reads = [f"    {n} = {PARAMETER_ARRAY}[{k}]" for k, n in enumerate(names) if n in used]
    lines += [
        "",
        f"def breakpoints({PARAMETER_ARRAY}):",
        '    """x positions of the kinks (m)."""',
        *reads,
        f"    return ({bps}{',' if len(cd.breakpoints) == 1 else ''})",
        "",
    ]
    body = "\n".join(lines)
    header = codegen.generated_notice("derivation/curve.py") + [
        f"Curve {cd.name!r}: f(x) = {cd.text}",
        "Parameters: "
        + (", ".join(f"{n} = {v}" for n, v in sorted(cd.parameters.items())) or "none"),
        f"Walls: {len(cd.walls)}; nearest-point polynomial degree: "
        + ", ".join(str(len(w.poly) - 1) if w.poly else "none" for w in cd.walls),
    ]
    return codegen.module_text(header, body)


def repo_root() -> Path | None:
    root = GENERATED.parent
    return root if (root / "pyproject.toml").exists() and (root / "derivation").is_dir() else None


@functools.lru_cache(maxsize=1)
def _expected_texts() -> tuple[tuple[str, str], ...]:
    """(relative path, text) of every file the derivation writes. Cached: ~5 s of sympy."""
    d = derive_ball()
    files = [("generated/ball.py", ball_module(d))]
    curves = []
    for name, (text, params) in PAPER_CURVES.items():
        cd = curve_from_text(name, text, params)
        curves.append(cd)
        files.append((f"generated/curves/{name}.py", curve_module(cd)))
    files.append(("docs/derivation.md", report.derivation_markdown(d, curves)))
    return tuple(files)


def expected_files(generated_dir: Path = GENERATED) -> dict[Path, str]:
    """Every file the derivation writes, with its exact expected content.

    docs/derivation.md is included only in a source checkout (beside pyproject.toml).
    """
    out = {}
    for rel, text in _expected_texts():
        if rel.startswith("generated/"):
            out[generated_dir / rel.removeprefix("generated/")] = text
        elif generated_dir == GENERATED and repo_root() is not None:
            out[repo_root() / rel] = text
    return out


def regenerate() -> list[Path]:
    written = []
    for path, text in expected_files().items():
        if not path.exists() or path.read_text() != text:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            written.append(path)
    return written


def check(generated_dir: Path = GENERATED) -> list[str]:
    """Problems found comparing the committed files with a fresh regeneration."""
    problems = []
    expected = expected_files(generated_dir)
    for path, text in expected.items():
        if not path.exists():
            problems.append(f"{path}: missing")
        elif path.read_text() != text:
            current = path.read_text()
            why = (
                ""
                if path.suffix != ".py" or codegen.hash_matches(current)
                else " (its content hash does not match: edited by hand?)"
            )
            problems.append(f"{path}: differs from a fresh regeneration{why}")
    for path in sorted((generated_dir / "curves").glob("*.py")):
        if path.name != "__init__.py" and path not in expected:
            problems.append(f"{path}: not produced by the derivation (stale?)")
    return problems


def derive_user_curve(
    name: str,
    text: str,
    parameters: dict[str, float | str] | None,
    directory: Path,
    *,
    force: bool = False,
) -> Path:
    """Derive a user's curve into ``directory/<name>.py`` and return the path.

    The curve must be able to hold a ball (:mod:`billiard.derivation.shape`, with the
    parameters at their given values). The module is written to a temporary file in
    ``directory``, checked, and renamed into place: another process never sees a partial
    module. An existing module is replaced only with ``force``. Names starting with
    ``expr_`` are the cache of scene expressions (derived with ``force``).

    Raises:
        CurveDerivationError: a bad name, an existing curve, or a curve that cannot be
            derived or cannot hold a ball (one line).
        OSError: ``directory`` cannot be written.
    """
    problem = curve_name_problem(name)
    if problem is not None and not (force and name.startswith("expr_")):
        raise curve.CurveDerivationError(problem)
    path = directory / f"{name}.py"
    if path.exists() and not force:
        raise curve.CurveDerivationError(
            f"curve {name!r} already exists ({path}); add --force to replace it"
        )
    params = {k: _exact(v) for k, v in (parameters or {}).items()}
    cd = curve_from_text(name, text, params)
    try:
        source = curve_module(cd)
    except codegen.NonFiniteConstantError as exc:
        raise curve.CurveDerivationError(f"curve {text!r}: {exc}") from None
    directory.mkdir(parents=True, exist_ok=True)
    handle, temp_name = tempfile.mkstemp(prefix=f".{name}-", suffix=".py.tmp", dir=directory)
    temp = Path(temp_name)
    try:
        with os.fdopen(handle, "w") as out:
            out.write(source)
        os.chmod(temp, 0o666 & ~_umask())  # mkstemp makes it private; a module is not
        problem = shape.shape_problem(_load_walls(temp, name, params))
        if problem is not None:
            raise curve.CurveDerivationError(f"curve {text!r} cannot hold a ball: {problem}")
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _load_walls(path: Path, name: str, params: dict[str, str]) -> list[dict]:
    """The walls of a freshly written curve module, parameters at their given values."""
    module_name = f"billiard_curve_check.{name}"
    loader = importlib.machinery.SourceFileLoader(module_name, str(path))
    spec = importlib.util.spec_from_file_location(module_name, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    p = tuple(float(params[n]) for n in module.PARAMETER_NAMES)
    walls = []
    for interval, f, df, d2f, *_ in module.WALLS:
        lo, hi = interval(p)
        walls.append(
            {
                "lo": lo,
                "hi": hi,
                "f": lambda x, f=f: f(x, p),
                "df": lambda x, df=df: df(x, p),
                "d2f": lambda x, d2f=d2f: d2f(x, p),
            }
        )
    return walls


def _exact(value) -> str:
    text = repr(float(value)) if not isinstance(value, str) else value
    sm.Rational(text)  # validates
    return text
