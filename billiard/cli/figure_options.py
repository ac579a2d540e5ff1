"""The options ``billiard plot`` and ``billiard run`` share for the figures they write:
``--format``, ``--dpi`` and ``--no-title``."""

from __future__ import annotations

import argparse
from typing import Any

from billiard.runfile.figure_files import (
    DEFAULT_DPI,
    DEFAULT_FORMAT,
    DPI_RANGE,
    FIGURE_FORMATS,
    check_dpi,
    check_format,
)

__all__ = ["add_figure_arguments", "figure_options"]


def add_figure_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--format``, ``--dpi`` and ``--no-title``.

    Their values are taken as text and checked by :func:`figure_options`, so that a bad
    value is one line (argparse's own checks print the usage first).
    """
    parser.add_argument(
        "--format",
        default=DEFAULT_FORMAT,
        metavar="FMT",
        help=f"file format of the still figures: {', '.join(FIGURE_FORMATS)} (SVG and PDF "
        "are vector files for print; the animation is always a GIF)",
    )
    lo, hi = DPI_RANGE
    parser.add_argument(
        "--dpi",
        default=DEFAULT_DPI,
        metavar="N",
        help=f"pixels per inch of PNG figures, {lo} to {hi}; they are 6 inches wide, "
        f"so {6 * DEFAULT_DPI} px at the default {DEFAULT_DPI}. Ignored by SVG and PDF "
        "(vector files), and by the GIF",
    )
    parser.add_argument(
        "--no-title",
        action="store_true",
        help="leave out the titles above the figures (the scene and its parameters), for a "
        "figure captioned in a paper",
    )


def figure_options(args: argparse.Namespace, command: str) -> dict[str, Any]:
    """The checked ``format``, ``dpi`` and ``title`` keyword arguments of
    :func:`billiard.plot.plot_run`, from the options of ``billiard COMMAND``.

    Raises:
        RunDataError: a format or dpi out of bounds; one line naming the option.
    """
    return {
        "format": check_format(args.format, f"{command}: --format"),
        "dpi": check_dpi(args.dpi, f"{command}: --dpi"),
        "title": not args.no_title,
    }
