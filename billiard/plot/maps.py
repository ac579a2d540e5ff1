"""The paper's maps (Hartl, Miller and Mazzoleni, Fig. 2): the return map of impact
heights (q2,n vs q2,n+1, mm) and the map of times of flight (t_n vs t_n+1, s)."""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes

from billiard.plot.common import (
    LID_COLOR,
    MM,
    MODEL_COLOR,
    Columns,
    camera_filter,
    column,
    diagonal,
    dots,
    lid_mask,
    marker_size,
    rings,
    square_limits,
    square_range,
    uniform_legend_markers,
)
from billiard.plot.density import density_handle, density_image, rasterize_if_large, use_density
from billiard.plot.inputs import checked_interval
from billiard.plot.titles import camera_label

__all__ = ["return_map", "time_map"]

#: Marker size (points) of the camera's rings and the lid's crosses over a density image.
_OVER_DENSITY = 1.5


def return_map(
    columns: Columns,
    ax: Axes,
    *,
    frame_interval: float | None = None,
    density: bool | None = None,
) -> list[Artist]:
    """Return map of impact heights: q2,n (x) against q2,n+1 (y), both in mm.

    Each point is a pair of consecutive impacts (the centre's height q2 at impact n and at
    impact n + 1); the dashed line is the diagonal q2,n = q2,n+1, on which a period-one
    orbit sits. Points above it are impacts followed by a higher one. Pairs with an
    impact on the lid (its height is fixed, so they would line up at the lid's height
    without explanation) get their own marker and legend entry, "lid impacts".

    The model's pairs are dots, or, above :data:`billiard.plot.density.DENSITY_THRESHOLD`
    pairs, a density image of the pairs per bin with a colour bar (see
    :mod:`billiard.plot.density`); the lid's pairs and the camera's stay markers.

    Args:
        columns: a run's columns (``q2`` in m and ``z`` in rad; ``wall`` if present; ``t``
            in s with ``frame_interval``).
        ax: the axes to draw in.
        frame_interval: if given (s), also draw, as hollow rings beneath the model's dots,
            the return map of the impacts a camera with this frame interval would have
            recorded (see :func:`billiard.analysis.camera.camera_filter`).
        density: True for a density image, False for dots, None (default) to choose by
            the number of pairs.

    Returns:
        The data artists: the model's pairs without a lid impact (a line of dots with x
        data ``q2,n`` and y data ``q2,n+1`` in mm, or the density image whose
        ``get_array()`` holds the pairs per bin), then the camera's if ``frame_interval``
        is given, then the pairs with a lid impact if there are any.
    """
    interval = checked_interval(frame_interval)
    q2 = column(columns, "q2") * MM
    lid = lid_mask(columns)
    with_lid = lid[:-1] | lid[1:]
    x, y = q2[:-1], q2[1:]
    shown = [q2]
    seen = None
    if interval is not None:
        seen = column(camera_filter(columns, interval), "q2") * MM
        shown.append(seen)
    label = f"model: all {q2.size} impacts"
    mx, my = x[~with_lid], y[~with_lid]
    view = square_range(shown) if use_density(mx.size, density) else None
    lines, size = _pairs(ax, mx, my, view, "mm", label, density, (x, y), seen, interval)
    if with_lid.any():
        height = float(np.median(q2[lid]))
        (lid_line,) = ax.plot(
            x[with_lid],
            y[with_lid],
            linestyle="none",
            marker="x",
            markersize=max(size * 1.5, 3.0),
            markeredgewidth=0.7,
            color=LID_COLOR,
            label=f"lid impacts ({int(lid.sum())}; centre at $q_2$ = {height:.4g} mm)",
            zorder=2.6,
        )
        rasterize_if_large(lid_line, int(with_lid.sum()))
        lines.append(lid_line)
    lo, hi = square_limits(ax, shown)
    diagonal(ax, lo, hi, "$q_{2,n} = q_{2,n+1}$")
    ax.set_xlabel("impact height $q_{2,n}$ (mm)")
    ax.set_ylabel("next impact height $q_{2,n+1}$ (mm)")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    uniform_legend_markers(ax.legend(loc="upper left", fontsize=8))
    return lines


def time_map(
    columns: Columns,
    ax: Axes,
    *,
    frame_interval: float | None = None,
    log: bool = False,
    density: bool | None = None,
) -> list[Artist]:
    """Map of times of flight: t_n (x) against t_n+1 (y), in s.

    t_n is the time of flight before impact n (the ``tof`` column: time since the
    previous impact). The dashed line is the diagonal t_n = t_n+1. The model's pairs are
    dots, or a density image above :data:`billiard.plot.density.DENSITY_THRESHOLD` pairs
    (see :func:`return_map`).

    Args:
        columns: a run's columns (``tof`` in s, and ``t`` in s with ``frame_interval``).
        ax: the axes to draw in.
        frame_interval: if given (s), also draw, as hollow rings beneath the model's dots,
            the map of the camera-filtered impacts, whose times of flight are the times
            between recorded impacts.
        log: logarithmic axes (rapid-succession impacts have times of flight down to
            microseconds); a density image then has bins equally wide in log t.
        density: True for a density image, False for dots, None (default) to choose by
            the number of pairs.

    Returns:
        The data artists (``tof[:-1]``, ``tof[1:]``): the model's (dots, or the density
        image whose ``get_array()`` holds the pairs per bin), then the camera's.
    """
    interval = checked_interval(frame_interval)
    tof = column(columns, "tof")
    x, y = tof[:-1], tof[1:]
    shown = [tof]
    seen = None
    if interval is not None:
        seen = column(camera_filter(columns, interval), "tof")
        shown.append(seen)
    if log:
        positive = [s[s > 0] for s in shown]
        finite = np.concatenate(positive)
        lo = float(finite.min()) / 1.5 if finite.size else 1e-4
        hi = float(finite.max()) * 1.5 if finite.size else 1.0
    else:
        lo, hi = square_range(shown)
        lo = max(lo, -0.02 * hi)
    label = f"model: all {tof.size} impacts"
    lines, _ = _pairs(ax, x, y, (lo, hi), "s", label, density, (x, y), seen, interval, log)
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal", adjustable="box")
    diagonal(ax, lo, hi, "$t_n = t_{n+1}$")
    ax.set_xlabel("time of flight $t_n$ (s)")
    ax.set_ylabel("next time of flight $t_{n+1}$ (s)")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    uniform_legend_markers(ax.legend(loc="upper right", fontsize=8))
    return lines


def _pairs(
    ax: Axes,
    x: np.ndarray,
    y: np.ndarray,
    view: tuple[float, float] | None,
    unit: str,
    label: str,
    density: bool | None,
    sized: tuple[np.ndarray, np.ndarray],
    seen: np.ndarray | None,
    interval: float | None,
    log: bool = False,
) -> tuple[list[Artist], float]:
    """The model's pairs (x, y): a density image over ``view`` x ``view`` (in ``unit``)
    or dots sized for the pairs ``sized``; then the camera's pairs of ``seen`` as rings
    when a frame interval is given. Returns the artists drawn and the marker size."""
    lines: list[Artist]
    if use_density(x.size, density):
        lines = [density_image(ax, x, y, view, view, unit=unit, log=log)]
        density_handle(ax, f"{label} (density)")
        size = _OVER_DENSITY
    else:
        size = marker_size(*sized)
        lines = [dots(ax, x, y, label, MODEL_COLOR, size)]
    if seen is not None:
        lines.append(rings(ax, seen[:-1], seen[1:], camera_label(interval, seen.size), size))
        rasterize_if_large(lines[-1], seen.size)
    return lines, size
