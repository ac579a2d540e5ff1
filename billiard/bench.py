"""``billiard bench``: speed against accuracy, where methods fail, the model ladder,
throughput; writes ``performance.md`` and its figures.

The measurements live in the ``bench/`` folder of a source checkout (they are not part
of the installed package); this module is the command's entry point.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

_SECTIONS = ("workprecision", "failures", "ladder", "throughput", "profile")


def _bench_package():
    root = Path(__file__).resolve().parent.parent
    if not (root / "bench" / "run.py").exists():
        raise SystemExit(
            "billiard bench: needs a source checkout (the bench/ folder beside billiard/)"
        )
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    import bench.run

    return bench.run


def _sections(text: str) -> tuple[str, ...]:
    chosen = tuple(s.strip() for s in text.split(",") if s.strip())
    unknown = [s for s in chosen if s not in _SECTIONS]
    if unknown or not chosen:
        raise argparse.ArgumentTypeError(
            f"unknown section {', '.join(unknown) or text!r}: choose from {', '.join(_SECTIONS)}"
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
        help=f"comma-separated sections to measure again ({', '.join(_SECTIONS)});"
        " the others are taken from the saved results",
    )
    parser.add_argument(
        "--render",
        action="store_true",
        help="measure nothing: redraw the figures and rewrite the page from the saved results",
    )
    parser.add_argument(
        "--out",
        metavar="DIR",
        help="where performance.md and figures/performance/ go (default docs, "
        "or runs/bench-quick with --quick)",
    )


def run_bench(args: argparse.Namespace) -> int:
    run = _bench_package()
    from bench.common import Config

    cfg = Config.quick_mode() if args.quick else Config.full()
    out = Path(args.out) if args.out else Path("runs/bench-quick" if args.quick else "docs")
    only = () if args.render else (args.only or _SECTIONS)
    path = run.main(cfg, out, only)
    print(f"wrote {path} and {out / 'figures' / 'performance'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="billiard bench", description=__doc__)
    add_bench_arguments(parser)
    return run_bench(parser.parse_args(argv))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
