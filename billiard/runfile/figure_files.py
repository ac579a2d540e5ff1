"""How a run's figures are written: the file formats, their resolution, and the names they
get in a run folder.

No heavy imports (no matplotlib): the command line checks ``--format`` and ``--dpi``
before a run starts, and removes a run's outdated figures of every format, without loading
the plotting stack.
"""

from __future__ import annotations

import math

from billiard.runfile.folder import FIGURE_NAMES
from billiard.runfile.record import RunDataError

__all__ = [
    "DEFAULT_DPI",
    "DEFAULT_FORMAT",
    "DPI_RANGE",
    "FIGURE_FORMATS",
    "all_figure_names",
    "check_dpi",
    "check_format",
    "figure_names",
]

#: The formats a run's still figures can be written in: a raster image (PNG) or a vector
#: file (SVG, PDF), as journals take them. The animation is always a GIF.
FIGURE_FORMATS: tuple[str, ...] = ("png", "svg", "pdf")
DEFAULT_FORMAT = "png"
#: Pixels per inch of a PNG figure. A run's figures are 6 inches wide, so 1200 px at the
#: default: sharp when printed at a journal's column width (3.5 in, about 340 dpi there).
#: Fonts and lines keep their size in points, so a figure looks the same at any dpi.
DEFAULT_DPI = 200
#: The dpi accepted (inclusive): below 20 text is unreadable, above 1200 a 6-inch figure
#: is over 7000 px wide (about 200 MB of pixels while it is drawn).
DPI_RANGE = (20, 1200)

_GIF = "animation.gif"


def check_format(value: str, what: str = "figure format") -> str:
    """A figure format of :data:`FIGURE_FORMATS`, lower-cased (``"PDF"`` is ``"pdf"``).

    Raises:
        RunDataError: (a ValueError) any other value; one line naming ``what``.
    """
    text = str(value).strip().lower().lstrip(".") if isinstance(value, str) else None
    if text not in FIGURE_FORMATS:
        raise RunDataError(f"{what} must be one of {', '.join(FIGURE_FORMATS)}, got {value!r}")
    return text


def check_dpi(value: float | str, what: str = "figure dpi") -> int:
    """A resolution in pixels per inch: a whole number in :data:`DPI_RANGE` (a string such
    as ``"300"`` is read as a number).

    Raises:
        RunDataError: (a ValueError) not a whole number in the range; one line naming
            ``what``.
    """
    try:
        number = float(value)  # a number, or text such as "300"
    except (TypeError, ValueError, OverflowError):
        number = math.nan
    lo, hi = DPI_RANGE
    if isinstance(value, bool) or not (math.isfinite(number) and number == int(number)):
        raise RunDataError(f"{what} must be a whole number of pixels per inch, got {value!r}")
    if not lo <= number <= hi:
        raise RunDataError(f"{what} must be between {lo} and {hi} pixels per inch, got {value!r}")
    return int(number)


def figure_names(fmt: str = DEFAULT_FORMAT) -> tuple[str, ...]:
    """The files :func:`billiard.plot.plot_run` writes, in order, for figures in format
    ``fmt``: :data:`~billiard.runfile.folder.FIGURE_NAMES` with that extension (the
    animation stays ``animation.gif``)."""
    fmt = check_format(fmt)
    return tuple(
        name if name == _GIF else f"{name.rsplit('.', 1)[0]}.{fmt}" for name in FIGURE_NAMES
    )


def all_figure_names() -> tuple[str, ...]:
    """Every name a run's figures may have, in any format (for removing outdated ones)."""
    names: list[str] = []
    for fmt in FIGURE_FORMATS:
        names += [n for n in figure_names(fmt) if n not in names]
    return tuple(names)
