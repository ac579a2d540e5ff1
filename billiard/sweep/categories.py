"""Maps of categories (attractors, periods): one distinct colour per category present,
named in a legend, never a continuous colour scale (whose neighbouring shades would
suggest an order and a distance that classes do not have).

Classes with a meaning of their own keep one colour in every figure (a failed point is
black, an invalid one white, a chaotic one red, ...); the others take, in order,
colours from matplotlib's qualitative palettes that differ from those and from each
other, then evenly spaced hues: every category of a map has a colour of its own however
many there are.
"""

from __future__ import annotations

from collections.abc import Sequence
from colorsys import hsv_to_rgb
from typing import Any

import numpy as np

__all__ = ["CLASS_COLOURS", "category_legend", "category_map", "distinct_colours"]

#: Classes drawn in the same colour in every figure.
CLASS_COLOURS = {
    "failed": "black",
    "invalid": "white",
    "resting": "0.6",
    "chaotic": "tab:red",
    "rolling": "tab:green",
    "sliding": "tab:olive",
    "held": "tab:brown",
}

#: Qualitative palettes, taken in this order.
_PALETTES = ("tab10", "tab20", "tab20b", "tab20c", "Set1", "Set2", "Set3", "Dark2", "Accent")


def _key(rgb: tuple[float, ...]) -> tuple[float, ...]:
    """A colour as compared: to 6 decimals (one colour named two ways is one colour)."""
    return tuple(round(c, 6) for c in rgb)


def distinct_colours(count: int, taken: Sequence[Any] = ()) -> list[tuple[float, float, float]]:
    """``count`` RGB colours, different from each other and from the ``taken`` ones."""
    import matplotlib
    from matplotlib.colors import to_rgb

    used = {_key(to_rgb(c)) for c in taken}
    out: list[tuple[float, float, float]] = []

    def offer(rgb: tuple[float, float, float]) -> None:
        if _key(rgb) not in used:
            used.add(_key(rgb))
            out.append(rgb)

    for name in _PALETTES:
        for colour in matplotlib.colormaps[name].colors:
            if len(out) == count:
                return out
            offer(to_rgb(colour))
    k = 0
    while len(out) < count:  # beyond the palettes (about 100): hues a golden angle apart
        offer(hsv_to_rgb((k * 0.618033988749895) % 1.0, 0.75, 0.85 - 0.3 * (k % 2)))
        k += 1
    return out


def category_map(
    ax: Any,
    x_edges: np.ndarray,
    y_edges: np.ndarray,
    ids: np.ndarray,
    labels: Sequence[str],
    colours: Sequence[Any],
    unit: str = "point",
) -> list[Any]:
    """Draw ``ids`` (one category number per cell, x first; -1 for a blank cell) in one
    colour per category.

    Args:
        ax: the axes.
        x_edges, y_edges: the cells' edges (m or the swept keys' units).
        ids: category numbers, shape (len(x_edges) - 1, len(y_edges) - 1).
        labels, colours: one per category number.
        unit: what a cell is (singular), for the counts in the legend.

    Returns:
        The legend's entries (matplotlib patches), one per category that has a cell,
        naming it and its number of cells: give them to :func:`category_legend`.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    ids = np.asarray(ids)
    n = len(labels)
    if n:
        cmap = ListedColormap(list(colours))
        norm = BoundaryNorm(np.arange(n + 1) - 0.5, n)
        ax.pcolormesh(x_edges, y_edges, np.ma.masked_less(ids, 0).T, cmap=cmap, norm=norm)
    counts = np.bincount(ids[ids >= 0].ravel(), minlength=n).tolist()
    return [
        Patch(facecolor=c, edgecolor="black", label=f"{label} ({count} {unit}{'s' * (count > 1)})")
        for c, label, count in zip(colours, labels, counts, strict=True)
        if count
    ]


def category_legend(ax: Any, handles: Sequence[Any], title: str | None = None) -> Any:
    """The legend of a category map, beside the axes (None without entries)."""
    if not handles:
        return None
    legend = ax.legend(
        handles=list(handles),
        fontsize=7,
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        ncols=1 + len(handles) // 20,
        title=title,
    )
    if title:
        legend.get_title().set_fontsize(7)
    return legend
