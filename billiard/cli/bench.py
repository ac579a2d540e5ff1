"""``billiard bench``: speed against accuracy, where methods fail, the model ladder,
throughput; writes ``performance.md``, its appendix of full tables
(``performance-tables.md``) and its figures.

The measurements live in the ``bench/`` folder of a source checkout (they are not part
of the installed package); this module is the command's entry point. They measure the
checkout's code: where the ``billiard`` that runs is another copy (``pip install .``, a
wheel), the command starts again as ``python -m billiard.cli bench ...`` with the
checkout's root first on ``PYTHONPATH``, so that it and every process it starts import
the checkout's ``billiard``.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path
from types import ModuleType

from billiard.cli.common import UserError

#: The sections of the performance page, in order (bench/run.py measures them; they are
#: checked here, before the checkout's bench package is imported).
SECTIONS = (
    "workprecision",
    "failures",
    "ladder",
    "throughput",
    "profile",
    "contact",
    "io",
    "sweep",
    "ensemble",
)
_PROJECT = "realworld-billiard"
#: Set in the environment of the command started again in a checkout (see
#: :func:`rerun_in_checkout`): a second start would be a loop.
_RERUN = "BILLIARD_BENCH_CHECKOUT"


class BenchError(UserError):
    """``billiard bench`` cannot run here (no source checkout): the command line prints
    it in one line and exits with status 2."""


def _is_checkout(root: Path) -> bool:
    """True if ``root`` holds this project's pyproject.toml beside ``bench/run.py``."""
    try:
        with open(root / "pyproject.toml", "rb") as handle:
            name = tomllib.load(handle).get("project", {}).get("name")
    except (OSError, tomllib.TOMLDecodeError):
        return False
    return name == _PROJECT and (root / "bench" / "run.py").is_file()


def find_checkout(start: Path | None = None) -> Path | None:
    """The source checkout to measure: the first directory, from ``start`` (default the
    current directory) upward, that is a checkout of this project; else the checkout the
    package is installed from (an editable install); else None."""
    here = (start or Path.cwd()).resolve()
    for root in (here, *here.parents):
        if _is_checkout(root):
            return root
    beside = Path(__file__).resolve().parents[2]
    return beside if _is_checkout(beside) else None


def _bench_package(root: Path | None = None) -> ModuleType:
    """Import ``bench.run`` from the checkout's ``bench/`` folder (no ``sys.path`` edits)."""
    root = root or find_checkout()
    if root is None:
        raise BenchError(
            "bench needs a source checkout of realworld-billiard (its bench/ folder is not "
            "installed): run `billiard bench` inside the cloned repository"
        )
    folder = root / "bench"
    loaded = sys.modules.get("bench")
    if loaded is None or [str(folder)] != list(getattr(loaded, "__path__", [])):
        spec = importlib.util.spec_from_file_location(
            "bench", folder / "__init__.py", submodule_search_locations=[str(folder)]
        )
        if spec is None or spec.loader is None:  # pragma: no cover - a .py file always loads
            raise BenchError(f"cannot load the bench package in {folder}")
        package = importlib.util.module_from_spec(spec)
        for name in [m for m in sys.modules if m == "bench" or m.startswith("bench.")]:
            del sys.modules[name]  # another checkout's bench: do not mix the two
        sys.modules["bench"] = package
        spec.loader.exec_module(package)
    return importlib.import_module("bench.run")


def _sections(text: str) -> tuple[str, ...]:
    chosen = tuple(s.strip() for s in text.split(",") if s.strip())
    unknown = [s for s in chosen if s not in SECTIONS]
    if unknown or not chosen:
        raise argparse.ArgumentTypeError(
            f"unknown section {', '.join(unknown) or text!r}: choose from {', '.join(SECTIONS)}"
        )
    return chosen


def add_bench_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--quick",
        action="store_true",
        help="small sizes, under 2 minutes (default output runs/bench-quick)",
    )
    parser.add_argument(
        "--only",
        type=_sections,
        metavar="SECTIONS",
        help=f"comma-separated sections to measure again ({', '.join(SECTIONS)});"
        " the others are taken from the saved results (default: all)",
    )
    parser.add_argument(
        "--render",
        action="store_true",
        help="measure nothing: redraw the figures and rewrite the pages from the saved results",
    )
    parser.add_argument(
        "--baseline",
        metavar="REF",
        help="with the throughput section: measure start-up and time per impact of the git "
        "commit REF too (checked out in a temporary worktree), alternately with this "
        "checkout's: before and after, side by side",
    )
    parser.add_argument(
        "--out",
        metavar="DIR",
        help="where performance.md, performance-tables.md and figures/performance/ go "
        "(default docs, or runs/bench-quick with --quick)",
    )


def runs_checkout(root: Path) -> bool:
    """Whether the ``billiard`` package that runs is ``root``'s ``billiard/`` folder."""
    import billiard

    return Path(billiard.__file__).resolve().parent == (root / "billiard").resolve()


def bench_argv(args: argparse.Namespace) -> list[str]:
    """The command-line arguments of ``billiard bench`` that give ``args`` again."""
    argv = ["--quick"] if args.quick else []
    if args.only:
        argv += ["--only", ",".join(args.only)]
    if args.render:
        argv.append("--render")
    if args.baseline is not None:
        argv += ["--baseline", args.baseline]
    if args.out:
        argv += ["--out", args.out]
    return argv


def checkout_command(root: Path, args: argparse.Namespace) -> tuple[list[str], dict[str, str]]:
    """The command and environment that run ``billiard bench`` on ``root``'s code: the
    checkout's root first on ``PYTHONPATH`` (inherited by every process the measurements
    start, whatever their working directory)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), env.get("PYTHONPATH", "")) if p)
    env[_RERUN] = str(root)
    return [sys.executable, "-m", "billiard.cli", "bench", *bench_argv(args)], env


def rerun_in_checkout(root: Path, args: argparse.Namespace) -> int:
    """Run ``billiard bench`` again on ``root``'s code (this process runs another copy of
    the package, e.g. one installed with ``pip install .``). On POSIX the process is
    replaced (signals, Ctrl-C and the exit status are the new command's); elsewhere it
    waits for it."""
    import billiard

    if os.environ.get(_RERUN):
        raise BenchError(
            f"bench: the checkout {root} does not run its own billiard package even with "
            f"PYTHONPATH={os.environ.get('PYTHONPATH', '')} (it runs {billiard.__file__})"
        )
    command, env = checkout_command(root, args)
    print(
        f"billiard: bench measures the source checkout {root}: starting it again on the "
        f"checkout's code (the package running is {Path(billiard.__file__).parent})",
        file=sys.stderr,
        flush=True,
    )
    sys.stdout.flush()
    if os.name == "posix":
        os.execve(command[0], command, env)
    return subprocess.run(command, env=env).returncode  # pragma: no cover - not POSIX


def _saved_results(out: Path) -> Path:
    return out / "figures" / "performance" / "results.json"


def resolve_baseline(root: Path, ref: str, only: tuple[str, ...]) -> dict[str, str]:
    """The commit ``--baseline REF`` names (see ``bench.baseline.resolve``), checked before
    anything is measured: REF must be a commit of the checkout's repository, git must
    run, and the throughput section, which compares the two, must be measured."""
    if not only:
        raise BenchError("bench --baseline measures; --render measures nothing: use one of them")
    if "throughput" not in only:
        raise BenchError(
            "bench --baseline compares the throughput section: measure it "
            "(`--only throughput`, or no --only)"
        )
    baseline = importlib.import_module("bench.baseline")
    try:
        return baseline.resolve(root, ref)
    except baseline.TreeError as exc:
        raise BenchError(f"bench --baseline: {exc}") from None


def run_bench(args: argparse.Namespace) -> int:
    root = find_checkout()
    if root is not None and not runs_checkout(root):
        return rerun_in_checkout(root, args)
    run = _bench_package(root)
    Config = importlib.import_module("bench.common").Config

    cfg = Config.quick_mode() if args.quick else Config.full()
    out = Path(args.out) if args.out else Path("runs/bench-quick" if args.quick else "docs")
    only = () if args.render else (args.only or SECTIONS)
    if not only and not _saved_results(out).is_file():
        raise BenchError(
            f"bench --render: no saved results in {_saved_results(out)}; measure first "
            f"(`billiard bench{' --quick' if args.quick else ''}"
            f"{f' --out {shlex.quote(args.out)}' if args.out else ''}`)"
        )
    baseline = None
    if args.baseline is not None:
        assert root is not None  # else _bench_package raised
        baseline = resolve_baseline(root, args.baseline, only)
    tree_error = importlib.import_module("bench.baseline").TreeError
    try:
        path = run.main(cfg, out, only, baseline)
    except tree_error as exc:  # the commit's worktree or one of its processes failed
        raise BenchError(f"bench --baseline: {exc}") from None
    print(f"wrote {path} and {out / 'figures' / 'performance'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="billiard bench", description=__doc__)
    add_bench_arguments(parser)
    try:
        return run_bench(parser.parse_args(argv))
    except BenchError as exc:
        print(f"billiard bench: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
