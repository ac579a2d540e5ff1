"""Regenerate, or check, every generated module and docs/derivation.md.

``regenerate()`` is what ``billiard derive`` runs; ``check()`` is ``billiard derive --check``;
``derive_user_curve()`` is ``billiard derive --name NAME --curve EXPR`` and the first use of
a curve expression in a scene.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.machinery
import importlib.util
import math
import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

import sympy as sm

from . import codegen, curve, report, shape
from .ball import BallDerivation, derive_ball, plain
from .contact import ContactDerivation, derive_contact
from .expr import DERIVE_TIMEOUT, PAPER_CURVES, curve_name_problem, parse_curve
from .orbit import orbit_module

GENERATED = Path(__file__).resolve().parent.parent / "generated"


def _sym(name: str) -> sm.Symbol:
    return sm.Symbol(name)


def ball_module(d: BallDerivation) -> str:
    S = _sym
    u1, u2, u3, q1, q2 = S("u1"), S("u2"), S("u3"), S("q1"), S("q2")
    m, r, k, g = S("m"), S("r"), S("k"), S("g")
    c_lin, c_quad, c_magnus = S("c_lin"), S("c_quad"), S("c_magnus")
    z, vb1, vb2, e, mu_k, sgn, t = (S(n) for n in ("z", "vb1", "vb2", "e", "mu_k", "sgn", "t"))
    beta0 = S("beta0")

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
            "impact_walton",
            [u1, u2, u3, z, vb1, vb2, m, r, k, e, beta0],
            list(p(d.walton)),
            "Walton's sticking impact, wt+ = -beta0 wt-: post-impact (u1, u2, u3) and "
            "impulse (Rt, Rn) in N s.",
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
        "flight_exact, contact_velocity, frame_velocity, impact_stick, impact_slip, "
        "impact_walton, energy",
    ]
    return codegen.module_text(header, body)


#: Units of the contact functions' arguments, for their docstrings.
_CONTACT_UNITS = {
    "s": "s the contact point's abscissa in the boundary's frame (m)",
    "s_dot": "s_dot = ds/dt (m/s)",
    "u3": "u3 the spin about n3 (rad/s, counter-clockwise positive)",
    "f0": "f0 = f(s) (m)",
    "fp": "fp = f'(s)",
    "f2": "f2 = f''(s) (1/m)",
    "f3": "f3 = f'''(s) (1/m^2)",
    "d1": "d1, d2 the boundary's displacement in N (m)",
    "vb1": "vb1, vb2 the boundary's velocity in N (m/s)",
    "ab1": "ab1, ab2 the boundary's acceleration in N (m/s^2)",
    "u1": "u1, u2 a lab velocity of the centre (m/s)",
    "m": "m the mass (kg)",
    "r": "r the radius (m)",
    "k": "k the inertia factor (I = k m r^2)",
    "g": "g gravity (m/s^2)",
    "c_lin": "c_lin (N s/m) and c_quad (N s^2/m^2) Fowles drag on the centre's lab velocity",
    "mu_k": "mu_k kinetic friction",
    "sgn": "sgn = +1 or -1 the sign of the slip (slip_velocity)",
}


def _contact_doc(summary: str, args: list[str]) -> str:
    units = "; ".join(_CONTACT_UNITS[a] for a in args if a in _CONTACT_UNITS)
    return f"{summary}\n\n    Arguments: {units}.\n    "


def contact_module(cd: ContactDerivation) -> str:
    S = _sym
    names = "s s_dot u3 f0 fp f2 f3 d1 d2 vb1 vb2 ab1 ab2 u1 u2 m r k g c_lin c_quad mu_k sgn"
    sym = {n: S(n) for n in names.split()}

    def by_name(expr):
        return expr.xreplace({a: S(a.name) for a in expr.free_symbols})

    geometry = {S(a.name): by_name(v) for a, v in cd.geometry.items()}
    drag_factor = by_name(cd.drag_factor)

    def p(expr):
        """Plain symbols by name; the drag factor; the geometry in f', f'', f'''."""
        expr = by_name(sm.sympify(expr)).xreplace({S("c_drag"): drag_factor})
        return expr.xreplace(geometry)

    def fn(name, args, outputs, summary):
        args = args.split()
        return codegen.function_source(
            name, [sym[a] for a in args], outputs, _contact_doc(summary, args)
        )

    roll, slide = cd.roll, cd.slide
    rhs_args = "s_dot fp f2 f3 ab1 ab2 vb1 vb2 m r k g c_lin c_quad"
    parts = [
        '"""Sustained contact of the ball with one wall of the moving boundary: rolling and '
        "sliding\n(Kane's method, contact forces from auxiliary speeds).\n\n"
        "The wall enters only through f'(s), f''(s), f'''(s) at the contact abscissa s, so\n"
        "these functions serve every curve. Contact force on the ball at the contact point:\n"
        "F c1 + N c2. Symbols and conventions: see docs/design.md and docs/derivation.md.\n"
        'SI units.\n"""\n\nimport math\n\n',
        fn(
            "roll_rhs",
            rhs_args,
            [p(roll[0]), p(roll[3]), p(roll[2])],
            "Rolling without slip: (s_ddot, N, F), s_ddot = d2s/dt2 (m/s^2) and the contact "
            "force's components N along c2 and F along c1 (N). The spin follows the no-slip "
            "condition: u3 = roll_spin(s_dot, fp, f2, r).",
        ),
        fn(
            "roll_spin",
            "s_dot fp f2 r",
            p(cd.roll_spin),
            "Spin u3 (rad/s) of the ball rolling without slip at ds/dt = s_dot.",
        ),
        fn(
            "slide_rhs",
            rhs_args + " mu_k sgn",
            [p(e) for e in slide],
            "Sliding: (s_ddot, spin_dot, N, F), s_ddot = d2s/dt2 (m/s^2), spin_dot = du3/dt "
            "(rad/s^2), N along c2 and F = -mu_k N sgn along c1 (N). The spin itself does "
            "not enter.",
        ),
        fn(
            "slip_velocity",
            "s_dot u3 fp f2 r",
            p(cd.slip),
            "Slip w_t (m/s): the velocity of the ball's material contact point relative to "
            "the wall, along c1.",
        ),
        fn(
            "centre_state",
            "s s_dot f0 fp f2 d1 d2 vb1 vb2 r",
            [p(e) for e in cd.centre],
            "Lab state (q1, q2, u1, u2) of the centre on the offset curve (m, m/s).",
        ),
        fn(
            "s_dot_of_velocity",
            "u1 u2 fp f2 vb1 vb2 r",
            p(cd.s_dot),
            "ds/dt (m/s) of a centre on the offset curve with the lab velocity (u1, u2); "
            "the velocity's normal component relative to the wall is ignored.",
        ),
        fn(
            "contact_energy",
            "s_dot u3 f0 fp f2 m r k g",
            p(cd.energy),
            "Energy in the boundary's frame (J): the kinetic energy relative to the "
            "boundary plus m g times the centre's height in the boundary's frame.",
        ),
    ]
    body = "\n\n".join(parts)
    header = codegen.generated_notice("derivation/contact.py (Kane's method)") + [
        "Functions: roll_rhs, roll_spin, slide_rhs, slip_velocity, centre_state, "
        "s_dot_of_velocity, contact_energy",
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
    except (
        TypeError, ValueError, ArithmeticError, NotImplementedError, RecursionError,
        SystemError, MemoryError,
    ) as exc:  # fmt: skip
        # sympy failing on a whitelisted expression: say so in one line, not a traceback
        # (an expression too large for it can end in a RecursionError or SystemError)
        raise curve.CurveDerivationError(
            f"curve {text!r} cannot be derived ({type(exc).__name__}: {exc})"
        ) from None


#: Version of the generated curve modules' layout; the runtime refuses other layouts.
CURVE_FORMAT = 6
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
        "(interval, f, df, d2f, near, dnear, poly, d3f); poly is None where the",
        'nearest-point condition is not a polynomial."""',
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
                f"d3f_{i}",
                [x],
                p(w.d3f.subs(fx)),
                "Third derivative f'''(x) (1/m^2).",
                array=array,
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
        walls.append(
            f"    (interval_{i}, f_{i}, df_{i}, d2f_{i}, near_{i}, dnear_{i}, {poly}, d3f_{i}),"
        )
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
def derivations() -> tuple[BallDerivation, ContactDerivation]:
    """The ball's and the contact's derivation, made once per process (~5 s of sympy):
    the writer of the files and the tests that check the textbook forms share them.
    Callers must not modify them."""
    return derive_ball(), derive_contact()


@functools.lru_cache(maxsize=1)
def _expected_texts() -> tuple[tuple[str, str], ...]:
    """(relative path, text) of every file the derivation writes. Cached: ~8 s of sympy."""
    d, contact = derivations()
    files = [
        ("generated/ball.py", ball_module(d)),
        ("generated/contact.py", contact_module(contact)),
        ("generated/orbit.py", orbit_module(d)),
    ]
    curves = []
    for name, (text, params) in PAPER_CURVES.items():
        cd = curve_from_text(name, text, params)
        curves.append(cd)
        files.append((f"generated/curves/{name}.py", curve_module(cd)))
    files.append(("docs/derivation.md", report.derivation_markdown(d, contact, curves)))
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


class SympyVersionError(RuntimeError):
    """The installed sympy is not the release that wrote ``generated/``: no regeneration
    by it can equal the committed files byte for byte. The message is one line naming the
    release needed."""


def generating_sympy(generated_dir: Path = GENERATED) -> str | None:
    """The sympy release that wrote ``generated_dir`` (the ``# sympy X`` line of its
    ``ball.py`` header, :func:`codegen.generated_notice`), or None when it names none."""
    try:
        with open(generated_dir / "ball.py", encoding="utf-8") as handle:
            header = [next(handle, "") for _ in range(8)]
    except OSError:
        return None
    for line in header:
        if line.startswith("# sympy "):
            return line.removeprefix("# sympy ").strip()
    return None


def sympy_mismatch(generated_dir: Path = GENERATED) -> str | None:
    """Why a byte-for-byte check of ``generated_dir`` cannot be made with the installed
    sympy (one line naming the release needed), or None when it can."""
    needed = generating_sympy(generated_dir)
    if needed is None or needed == sm.__version__:
        return None
    return (
        f"{generated_dir} was written by sympy {needed}, and only that release reproduces it "
        f"byte for byte; sympy {sm.__version__} is installed "
        f'(pip install "sympy=={needed}", or the test extra: pip install -e ".[test]")'
    )


def check(generated_dir: Path = GENERATED) -> list[str]:
    """Problems found comparing the committed files with a fresh regeneration.

    Raises:
        SympyVersionError: the installed sympy is not the release that wrote them.
    """
    mismatch = sympy_mismatch(generated_dir)
    if mismatch is not None:
        raise SympyVersionError(mismatch)
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


class _Deadline(BaseException):
    """Raised in the main thread when a derivation's time is up (a BaseException: the
    ``except Exception`` clauses inside sympy must not swallow it)."""


@contextlib.contextmanager
def _deadline(seconds: float | None) -> Iterator[None]:
    """Raise :class:`_Deadline` in the block after ``seconds`` of wall-clock time (None or
    inf: no limit). A timer signal (SIGALRM), so only in the main thread; elsewhere, and
    where the platform has none, the block runs unbounded."""
    usable = (
        seconds is not None
        and math.isfinite(seconds)
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
    )
    if not usable:
        yield
        return

    expired = [False]

    def expire(signum: int, frame: object) -> None:
        expired[0] = True
        raise _Deadline

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
    if expired[0]:
        # the signal came where Python drops an exception (a garbage collector's
        # callback, a __del__): the block went on to its end, past its time all the same
        raise _Deadline


def derive_user_curve(
    name: str,
    text: str,
    parameters: dict[str, float | str] | None,
    directory: Path,
    *,
    force: bool = False,
    timeout: float | None = DERIVE_TIMEOUT,
    derived: list[curve.CurveDerivation] | None = None,
) -> Path:
    """Derive a user's curve into ``directory/<name>.py`` and return the path.

    The curve must be able to hold a ball, and the maximum of its walls must be the curve
    (:mod:`billiard.derivation.shape`, with the parameters at their given values). The
    module is written to a temporary file in ``directory``, checked, and renamed into
    place: another process never sees a partial module. An existing module is replaced
    only with ``force``. Names starting with ``expr_`` are the cache of scene expressions
    (derived with ``force``). The derivation stops after ``timeout`` seconds (None: no
    limit; enforced in the main thread). ``derived``: a list that receives the curve's
    derivation as soon as sympy has it, before the checks that may refuse the curve (the
    report of ``billiard derive --report`` says why).

    Raises:
        CurveDerivationError: a bad name, an existing curve, a curve that cannot be
            derived or cannot hold a ball, or a derivation that took longer than
            ``timeout`` (one line).
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
    try:
        with _deadline(timeout):
            cd = curve_from_text(name, text, params)
            source = curve_module(cd)
        if derived is not None:
            derived.append(cd)
    except codegen.NonFiniteConstantError as exc:
        raise curve.CurveDerivationError(f"curve {text!r}: {exc}") from None
    except _Deadline:
        raise curve.CurveDerivationError(
            f"curve {text!r}: the derivation (sympy) did not finish within {timeout:g} s; "
            "write the expression more simply, or allow longer with `billiard derive "
            "--timeout SECONDS`"
        ) from None
    directory.mkdir(parents=True, exist_ok=True)
    handle, temp_name = tempfile.mkstemp(prefix=f".{name}-", suffix=".py.tmp", dir=directory)
    temp = Path(temp_name)
    try:
        with os.fdopen(handle, "w") as out:
            out.write(source)
        os.chmod(temp, 0o666 & ~_umask())  # mkstemp makes it private; a module is not
        walls = _load_walls(temp, name, params)
        problem = shape.shape_problem(walls)
        if problem is not None:
            raise curve.CurveDerivationError(f"curve {text!r} cannot hold a ball: {problem}")
        problem = shape.join_problem(walls)
        if problem is not None:
            raise curve.CurveDerivationError(f"curve {text!r}: {problem}")
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
