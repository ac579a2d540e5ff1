"""``billiard view DIR``: the interactive view of a run, one self-contained HTML page."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["add_parser", "cmd_view"]


def cmd_view(args: argparse.Namespace) -> int:
    from billiard.plot import parse_window
    from billiard.plot.interactive import write_view

    window = None if args.window is None else parse_window(args.window)
    path = write_view(Path(args.dir), Path(args.out) if args.out else None, window=window)
    print(f"wrote {path}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "view",
        help="write a run's interactive view (one HTML page)",
        description="Write DIR/view.html: one self-contained page (no server, no network) "
        "to scrub through the run: the ball in the moving boundary, the return map, the "
        "phase plot and the height over time, linked to the selected impact.",
    )
    p.add_argument("dir", help="run directory (what `billiard run` writes)")
    p.add_argument("--out", metavar="FILE", help="where to write the page (default: DIR/view.html)")
    p.add_argument(
        "--window",
        metavar="N0:N1",
        help="impacts N0 <= n < N1 on the page (either may be left out; default: the whole "
        "run, at most its last 20,000 impacts)",
    )
    p.set_defaults(func=cmd_view)
