"""billiard derive: regenerate, check, or derive a user's curve."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from billiard.cli.common import UserError


def cmd_derive(args: argparse.Namespace) -> int:
    from billiard.derivation import build
    from billiard.derivation.curve import CurveDerivationError
    from billiard.derivation.expr import CurveExpressionError

    if args.report is not None and not (args.curve and args.name):
        raise UserError("derive: --report DIR goes with --name and --curve")
    if args.curve is not None or args.name is not None:
        if not (args.curve and args.name):
            raise UserError("derive: --name and --curve go together")
        params = dict(_key_value(p, "--param") for p in args.param)
        from billiard.geometry.curves import user_curve_dir

        directory = Path(args.dir) if args.dir else user_curve_dir()
        if args.dir:
            if directory.exists() and not directory.is_dir():
                raise UserError(f"derive --dir {directory}: not a directory")
            if not directory.exists() and not directory.parent.is_dir():
                raise UserError(
                    f"derive --dir {directory}: its parent directory {directory.parent} "
                    "does not exist"
                )
        if not (args.timeout > 0):  # also NaN
            raise UserError(
                f"derive: --timeout must be a number of seconds > 0, got {args.timeout}"
            )
        report = _report_dir(args)
        started = time.perf_counter()
        derived: list = []
        try:
            path = build.derive_user_curve(
                args.name,
                args.curve,
                params,
                directory,
                force=args.force,
                timeout=args.timeout,
                derived=derived,
            )
        except (CurveExpressionError, CurveDerivationError) as exc:
            # a refusal is one line on stderr and nothing on stdout: the chain derived so
            # far goes to the report, when one is asked for
            if report is not None and derived:
                _write_report(derived[0], args, report, refusal=str(exc))
            raise UserError(str(exc)) from None
        except OSError as exc:
            where = "" if args.dir else " (the user curve directory: $BILLIARD_HOME/curves)"
            raise UserError(
                f"derive: cannot write the curve to {directory}{where}: {exc.strerror or exc}"
            ) from None
        _print_chain(derived[0])
        print(
            f"curve {args.name!r}: f(x) = {args.curve} -> {path} "
            f"({time.perf_counter() - started:.1f} s); a scene can now use "
            f'curve = "{args.name}"'
        )
        if report is not None and not _write_report(derived[0], args, report):
            print("derive --report: a check failed: the generated code does not agree with it")
            return 1
        return 0
    root = build.repo_root()
    where = (
        f"{build.GENERATED} (source checkout {root})"
        if root is not None
        else f"{build.GENERATED}: the installed package, not a source checkout"
    )
    if args.check:
        print(f"derive --check: checking {where}")
        try:
            problems = build.check()
        except build.SympyVersionError as exc:
            raise UserError(f"derive --check: {exc}") from None
        for line in problems:
            print(line)
        if problems:
            print(f"derive --check: {len(problems)} file(s) differ; run `billiard derive`")
            return 1
        print("derive --check: generated/ is current")
        return 0
    print(f"derive: regenerating {where}")
    if root is None:
        print(
            "derive: changes made here are lost when the package is reinstalled; "
            "docs/derivation.md is written only in a source checkout"
        )
    mismatch = build.sympy_mismatch()
    if mismatch is not None:
        # allowed (a deliberate upgrade of sympy regenerates this way), but every module's
        # header changes and the pin of the test extra must follow
        print(f"derive: note: {mismatch}; regenerating with it changes every module")
    started = time.perf_counter()
    written = build.regenerate()
    for path in written:
        print(f"wrote {path}")
    print(f"derive: {len(written)} file(s) changed ({time.perf_counter() - started:.1f} s)")
    return 0


def _print_chain(cd) -> None:
    """The derived curve's chain: its pieces, their intervals and the joins' classes."""
    from billiard.derivation.curve import chain_lines

    for line in chain_lines(cd):
        print(line)


def _report_dir(args: argparse.Namespace) -> Path | None:
    """``--report DIR``, checked before the derivation starts (None without it)."""
    if args.report is None:
        return None
    if not (0 < args.radius < float("inf")):
        raise UserError(f"derive: --radius must be a length > 0 in metres, got {args.radius}")
    folder = Path(args.report)
    if folder.exists() and not folder.is_dir():
        raise UserError(f"derive --report {folder}: not a directory")
    if not folder.exists() and not folder.parent.is_dir():
        raise UserError(
            f"derive --report {folder}: its parent directory {folder.parent} does not exist"
        )
    return folder


def _write_report(cd, args: argparse.Namespace, folder: Path, refusal: str | None = None) -> bool:
    """Write the report; True when all its checks passed."""
    from billiard.derivation.curve_report import HTML, MARKDOWN, report_curve

    started = time.perf_counter()
    try:
        report = report_curve(cd, args.radius, folder, refusal)
    except OSError as exc:
        raise UserError(
            f"derive --report: cannot write the report to {folder}: {exc.strerror or exc}"
        ) from None
    failed = [c.name for c in report.checks if not c.passed]
    verdict = (
        f"all {len(report.checks)} checks passed"
        if not failed
        else f"{len(failed)} of {len(report.checks)} checks FAILED: {'; '.join(failed)}"
    )
    what = "the refused curve's report" if refusal else "report"
    print(
        f"derive: wrote {what} {folder / MARKDOWN} and {folder / HTML} "
        f"({time.perf_counter() - started:.1f} s; {verdict})"
    )
    return report.passed


class _DeriveParser(argparse.ArgumentParser):
    """``billiard derive``'s parser: an argument starting with a single '-' that is not
    one of its options is a value, so ``--curve -x**2 + ...`` needs no ``=``."""

    def _parse_optional(self, arg_string):
        if (
            arg_string.startswith("-")
            and not arg_string.startswith("--")
            and len(arg_string) > 1
            and arg_string not in self._option_string_actions
        ):
            return None
        return super()._parse_optional(arg_string)


def _key_value(text: str, flag: str) -> tuple[str, float]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise UserError(f"{flag} {text!r}: expected NAME=VALUE")
    try:
        return key.strip(), float(value)
    except ValueError:
        raise UserError(f"{flag} {text!r}: value is not a number") from None


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "derive",
        help="regenerate the generated code from the derivation",
        description="Regenerate generated/ and docs/derivation.md, check them, "
        "or derive a user's curve.",
    )
    p.add_argument(
        "--check",
        action="store_true",
        help="verify that generated/ equals a fresh regeneration (exit 1 if not)",
    )
    p.__class__ = _DeriveParser  # accept --curve -x**2 ... (same layout: a subclass)
    p.add_argument(
        "--name", help="name of a user curve to derive (with --curve): letters, digits, _ and -"
    )
    p.add_argument(
        "--curve",
        help="curve expression in x, metres, e.g. '30*x**4 + 0.0063'; it must hold a ball "
        "(real, finite, convex and rising on both sides of its bottom)",
    )
    p.add_argument("--force", action="store_true", help="replace a user curve of the same name")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="value of a named parameter of --curve (repeatable)",
    )
    p.add_argument(
        "--dir",
        help="where to write a user curve (default: the user curve directory, "
        "$BILLIARD_HOME/curves, see `billiard.geometry.curves.user_curve_dir`)",
    )
    from billiard.derivation.expr import DERIVE_TIMEOUT

    p.add_argument(
        "--timeout",
        type=float,
        default=DERIVE_TIMEOUT,
        metavar="SECONDS",
        help="longest time the derivation of --curve may take (s; inf: no limit); an "
        "expression sympy cannot simplify is refused after it",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="with --name and --curve: write report.md and report.html (offline) into DIR: "
        "the curve's pieces and joins, its offset curve and where it is valid, the "
        "equations in readable form and the checks passed; also for a refused curve",
    )
    from billiard.scene.spec import BallSpec

    p.add_argument(
        "--radius",
        type=float,
        default=BallSpec.radius,
        metavar="METRES",
        help="ball radius (m) the report checks the curvature against "
        f"(default {BallSpec.radius:g}, the default scene's ball)",
    )
    p.set_defaults(func=cmd_derive)
