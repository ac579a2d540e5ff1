"""Command line: ``billiard derive | scenes | run | export | calibrate | plot | lyapunov |
bench | reproduce | sweep | hysteresis | uncertainty | orbits | view``, one module per command or
group (this package).

Errors a user can cause (a bad scene, a bad curve expression, a stop condition) print one
line and exit with status 2; no traceback.
"""

from __future__ import annotations

import argparse
import atexit
import gc
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from billiard.cli import analyses, derive, export, orbits, run, study, sweep, view
from billiard.cli.common import UserError, long_name_error

__all__ = ["UserError", "build_parser", "main", "shows_default", "version_text"]


def _user_errors() -> tuple[type[BaseException], ...]:
    """Exception classes that mean bad input or a documented stop, not a bug.

    Only modules already imported are consulted: one never imported cannot have raised,
    and importing them all would load sympy and scipy on every command (half a second).
    """
    errors: list[type[BaseException]] = [UserError]
    for module, names in (
        ("billiard.derivation.expr", ["CurveExpressionError"]),
        ("billiard.geometry.curves", ["CurveNotFoundError"]),
        ("billiard.scene.scene", ["SceneError"]),
        ("billiard.errors", ["GeometryError", "SimulationError"]),
        ("billiard.derivation.curve", ["CurveDerivationError"]),
        ("billiard.analysis.calibrate", ["CalibrationError"]),
        ("billiard.analysis.lyapunov", ["LyapunovError"]),
        ("billiard.orbits.returnmap", ["OrbitError"]),
        ("billiard.reproduce.paper", ["ReproduceError"]),
        ("billiard.runfile.record", ["RunDataError"]),
        ("billiard.runfile.checkpoint", ["CheckpointError"]),
    ):
        mod = sys.modules.get(module)
        if mod is not None:
            errors += [getattr(mod, n) for n in names if hasattr(mod, n)]
    return tuple(errors)


_DISTRIBUTION = "realworld-billiard"


def version_text() -> str:
    """``billiard --version``: the distribution's name and version, and the folder of the
    package that runs (a source checkout's ``billiard/`` can shadow an installed copy).

    The version comes from the installed distribution's metadata, or, where none is
    installed (a checkout run with ``python -m billiard.cli``), from ``billiard.__version__``.
    """
    import importlib.metadata
    from pathlib import Path

    import billiard

    folder = Path(billiard.__file__).resolve().parent
    try:
        version = importlib.metadata.version(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return f"{_DISTRIBUTION} {billiard.__version__} (not installed; package at {folder})"
    return f"{_DISTRIBUTION} {version} (package at {folder})"


class _Version(argparse.Action):
    """``--version``: the text is made only when asked (reading the distribution's
    metadata on every command would slow every start)."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: object) -> None:
        super().__init__(
            option_strings,
            dest,
            nargs=0,
            default=argparse.SUPPRESS,
            help="print the package's name and version, then exit",
        )

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        print(version_text())
        parser.exit()


class _DefaultsFormatter(argparse.HelpFormatter):
    """Help that shows every option's default: an option whose help does not mention its
    default gets "(default: VALUE)" appended. Flags (on or off), the help option and
    repeatable options that start empty have nothing to show."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if shows_default(action) and "default" not in text.lower():
            text += " (default: %(default)s)"
        return text


def shows_default(action: argparse.Action) -> bool:
    """Whether ``--help`` must show ``action``'s default: an option (not a positional)
    taking a value, whose default is neither None, suppressed nor an empty list."""
    if not action.option_strings or action.nargs == 0:
        return False  # a positional, or a flag (store_true, --help, --version)
    default = action.default
    return default is not None and default is not argparse.SUPPRESS and default != []


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="billiard",
        description="Driven gravitational billiard with a spinning, rubbing ball (SI units).",
        formatter_class=_DefaultsFormatter,
    )
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    derive.add_parser(sub)
    study.add_scenes_parser(sub)
    run.add_parser(sub)
    export.add_parser(sub)
    study.add_parsers(sub)  # calibrate, plot, lyapunov, bench, reproduce
    sweep._add_sweep_parser(sub)
    analyses.add_parsers(sub)  # hysteresis, uncertainty
    orbits.add_parser(sub)
    view.add_parser(sub)
    for command in sub.choices.values():
        command.formatter_class = _DefaultsFormatter
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    if argv is None:
        # The command's own process. The objects its imports made (numba's and LLVM's
        # types and compiled libraries among them) live until the interpreter exits:
        # frozen now, the collector never walks them again during the command; frozen
        # again at the exit, they and what the command made are left to the operating
        # system instead of being freed one by one in the interpreter's last collections
        # (a tenth to a quarter of a second; atexit handlers still run, and every file
        # the command writes is closed before it returns).
        gc.freeze()
        atexit.register(gc.freeze)
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_notices(warnings.showwarning)
            return args.func(args)
    except Exception as exc:
        # a path given with a name too long for the file system fails wherever the
        # command first touches it: bad input, reported as such
        error = long_name_error(exc) if isinstance(exc, OSError) else exc
        if error is None or not isinstance(error, _user_errors()):
            raise
        message = " ".join(str(error).split())
        print(f"billiard: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"billiard: interrupted; {_interrupted(args)}", file=sys.stderr)
        return 130


def _one_line_notices(shown: Callable[..., None]) -> Callable[..., None]:
    """``warnings.showwarning`` that shows billiard's own warnings (files read
    unverified) as one line on stderr, like the other notices, and passes any other
    warning to ``shown``."""

    def show(message: Warning | str, category: type[Warning], *args: Any, **kwargs: Any) -> None:
        from billiard.errors import UnverifiedDataWarning

        if issubclass(category, UnverifiedDataWarning):
            print(f"billiard: {message}", file=sys.stderr)
        else:
            shown(message, category, *args, **kwargs)

    return show


def _interrupted(args: argparse.Namespace) -> str:
    """What is true of the files after Ctrl-C in a command (``billiard run`` reports its
    own interruptions while it writes rows; this is any other moment)."""
    command = args.command
    if command == "run":
        # before the run (loading, compiling) or after it (a signal just after its last
        # impact, or while plotting): a run's files hold whole rows either way
        return (
            "no row was lost: a run that started keeps whole rows and its checkpoint "
            "(`billiard run --resume DIR` finishes it, `billiard plot DIR` draws its figures)"
        )
    if command in ("calibrate", "lyapunov", "scenes", "orbits"):
        return "nothing was written"
    if command == "plot":
        where = args.out or args.dir
        return f"the figures in {where} may be missing or partly drawn; draw them again"
    if command == "derive":
        return "`billiard derive --check` names any generated file left out of date"
    if command == "reproduce":
        return "the report was not finished; runs and figures so far may be partly written"
    return "files being written may be incomplete"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
