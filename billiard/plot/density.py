"""Large point clouds drawn as a density image: impacts counted per bin of a 2-D grid.

A return map, time map or phase plot of a long run holds up to millions of points. Drawn
as dots they cover one another (the figure shows where points are, not how many), a
vector file (SVG, PDF) grows by tens of bytes per point, and drawing takes seconds. Above
:data:`DENSITY_THRESHOLD` points the cloud is drawn instead as an image of the number of
points in each bin of a :data:`DENSITY_BINS` x :data:`DENSITY_BINS` grid over the axes'
view, with a logarithmic colour scale (a period-one orbit's bin and a chaotic sea's
sparse bins show in one figure) and a colour bar labelled "impacts per bin" with the bin's
size in the axes' units. Empty bins are left transparent, so the grid shows through.

Counting is one :func:`numpy.bincount` over the bin indices (a few milliseconds per
million points); the image has one pixel per bin, drawn without smoothing, so a vector
file embeds the counts as they are.
"""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.collections import QuadMesh
from matplotlib.colors import LogNorm
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D

from billiard.analysis.bins import bin_counts
from billiard.plot.titles import fmt

__all__ = [
    "COUNT_LABEL",
    "DENSITY_BINS",
    "DENSITY_CMAP",
    "DENSITY_THRESHOLD",
    "bin_counts",
    "density_handle",
    "density_image",
    "rasterize_if_large",
    "use_density",
]

#: Above this many points a cloud is drawn as a density image (with ``density=None``).
#: The paper scenes' default runs (25,000 impacts) stay dots, as in the paper's figures;
#: up to this count Agg draws the dots in a few hundredths of a second.
DENSITY_THRESHOLD = 50_000
#: Bins along each axis of the density image: 200 over a 4.5-inch axes is a bin of about
#: 4.5 px at 200 dpi, so a single occupied bin (a period-one orbit) stays visible.
DENSITY_BINS = 200
#: A perceptually uniform colour map, readable in grey scale.
DENSITY_CMAP = "viridis"
#: The colour bar's label (the bin's size follows it).
COUNT_LABEL = "impacts per bin"


def use_density(count: int, density: bool | None = None) -> bool:
    """Whether a cloud of ``count`` points is drawn as a density image: ``density`` when it
    is True or False, else whether ``count`` exceeds :data:`DENSITY_THRESHOLD`."""
    return count > DENSITY_THRESHOLD if density is None else bool(density)


def _bin_text(
    x_range: tuple[float, float], y_range: tuple[float, float], bins: tuple[int, int],
    unit: str, log: bool,
) -> str:  # fmt: skip
    if log:
        wx = np.log10(x_range[1] / x_range[0]) / bins[0]
        wy = np.log10(y_range[1] / y_range[0]) / bins[1]
        return f"bins {fmt(wx)} x {fmt(wy)} decades wide"
    wx = (x_range[1] - x_range[0]) / bins[0]
    wy = (y_range[1] - y_range[0]) / bins[1]
    suffix = f" {unit}" if unit else ""
    return f"bins of {fmt(wx)}{suffix} x {fmt(wy)}{suffix}"


def density_image(
    ax: Axes,
    x: np.ndarray,
    y: np.ndarray,
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    *,
    unit: str = "",
    bins: tuple[int, int] = (DENSITY_BINS, DENSITY_BINS),
    log: bool = False,
    weight: float | None = None,
    label: str = COUNT_LABEL,
    cmap: str = DENSITY_CMAP,
    colorbar: bool = True,
) -> AxesImage | QuadMesh:
    """Draw the density image of the points ``(x, y)`` over the view ``x_range`` by
    ``y_range`` (in the axes' data units, ``unit``), with its colour bar.

    The counts (see :func:`bin_counts`; each point counts ``weight`` if given) are
    coloured with ``cmap`` on a logarithmic scale from the smallest non-zero count to the
    largest; empty bins are transparent. Unless ``colorbar`` is False, the colour bar
    beside the axes is labelled ``label`` and the bin's size (in ``unit``, or in decades
    with ``log``). The axes' aspect is left "auto": set limits and aspect after this call.

    Returns:
        The image: an :class:`~matplotlib.image.AxesImage` (a
        :class:`~matplotlib.collections.QuadMesh` with ``log``, for log-scaled axes) whose
        ``get_array()`` holds the counts.
    """
    counts = bin_counts(x, y, x_range, y_range, bins, log=log, weight=weight)
    low = float(weight) if weight is not None else 1.0  # one point's count
    norm = LogNorm(vmin=low, vmax=max(2.0 * low, float(counts.max())))
    image: AxesImage | QuadMesh
    if log:
        xe = np.logspace(np.log10(x_range[0]), np.log10(x_range[1]), counts.shape[1] + 1)
        ye = np.logspace(np.log10(y_range[0]), np.log10(y_range[1]), counts.shape[0] + 1)
        image = ax.pcolormesh(xe, ye, counts, norm=norm, cmap=cmap, rasterized=True, zorder=1.5)
    else:
        image = ax.imshow(
            counts,
            origin="lower",
            extent=(x_range[0], x_range[1], y_range[0], y_range[1]),
            aspect="auto",
            interpolation="none",
            norm=norm,
            cmap=cmap,
            zorder=1.5,
        )
    figure = ax.get_figure()
    if not colorbar or figure is None:
        return image
    figure.colorbar(
        image,
        ax=ax,
        label=f"{label}\n({_bin_text(x_range, y_range, bins, unit, log)})",
        shrink=0.85,
        pad=0.02,
    )
    return image


def density_handle(ax: Axes, label: str) -> Line2D:
    """An empty line in ``ax`` whose legend entry (a square in the colour map's middle
    colour) stands for the density image: an image has no legend entry of its own."""
    from matplotlib import colormaps

    (handle,) = ax.plot(
        [],
        [],
        linestyle="none",
        marker="s",
        markersize=6,
        markeredgewidth=0,
        color=colormaps[DENSITY_CMAP](0.55),
        label=label,
    )
    return handle


def rasterize_if_large(artist: Artist, count: int) -> None:
    """Embed a layer of more than :data:`DENSITY_THRESHOLD` markers as an image in a vector
    file (at the figure's dpi): as vectors it would take tens of bytes per marker."""
    if count > DENSITY_THRESHOLD:
        artist.set_rasterized(True)
