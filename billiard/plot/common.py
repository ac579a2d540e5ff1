"""What every figure shares: reading a run's CSV, units, colours, axes helpers and saving.

This is the one module of :mod:`billiard.plot` that imports the run-file reader
(:func:`billiard.analysis.camera.read_collisions`) and :class:`RunDataError`; the others import
them from here.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from billiard.analysis.camera import camera_filter
from billiard.runfile.record import LID_WALL, RunDataError
from billiard.runfile.tables import read_collisions

__all__ = ["RunDataError", "camera_filter", "read_collisions"]

MM = 1e3  # mm per m

DPI = 100
#: Matplotlib settings while a figure is drawn: Agg draws a line of more than this many
#: vertices in pieces (a trajectory over a long window has millions; in one piece Agg
#: refuses it), and a shorter line, as every figure of a usual run, in one.
DRAW_RC = {"agg.path.chunksize": 20_000}
#: Pixels per inch of the parts of an SVG or PDF figure embedded as images (print quality).
VECTOR_IMAGE_DPI = 300
SINGLE_SIZE = (6.0, 5.6)  # inches: 600 x 560 px at DPI
MODEL_COLOR = "tab:blue"
CAMERA_COLOR = "tab:orange"
LID_COLOR = "black"
REGIME_COLORS = {"stick": "tab:green", "slip": "tab:red", "elastic": "tab:purple"}
#: Camera markers are hollow rings this many times the size of the model's dots, drawn
#: beneath them: a camera impact shows as a ring around the model's dot, and a model dot
#: is never hidden.
CAMERA_RING = 2.4

Window = tuple[int | None, int | None]
Columns = Mapping[str, np.ndarray]


# --- columns -------------------------------------------------------------------------------


def column(columns: Columns, name: str) -> np.ndarray:
    """A numeric column as a float array.

    Raises:
        RunDataError: the column is missing.
    """
    if name not in columns:
        raise RunDataError(f"collisions data have no column {name!r}")
    return np.asarray(columns[name], dtype=float)


def lid_mask(columns: Columns) -> np.ndarray:
    """True for the impacts on the lid: column ``wall`` is -1 (``"lid"`` in columns
    made before it was an integer), or the contact tangent angle ``z`` is pi (the lid's;
    see the CSV columns in the README)."""
    lid = np.abs(column(columns, "z") - math.pi) < 1e-9
    if "wall" in columns:
        wall = np.asarray(columns["wall"])
        if wall.dtype.kind in "US":
            lid |= np.char.strip(wall.astype(str)) == "lid"
        elif wall.dtype.kind in "iu":
            lid |= wall == LID_WALL
    return lid


# --- axes helpers --------------------------------------------------------------------------


def marker_size(x: np.ndarray, y: np.ndarray, spans: tuple[float, float] | None = None) -> float:
    """Marker size (points) that keeps a cloud of points readable.

    It depends on how many distinct places the points occupy (cells of a 250 x 250 grid
    over ``spans``, the axes' data ranges, by default the data's own), not on how many
    points there are: 25,000 impacts on a period-one orbit still get visible markers.
    """
    good = np.isfinite(x) & np.isfinite(y)
    if not good.any():
        return 3.5
    x, y = x[good], y[good]
    sx, sy = spans if spans is not None else (float(np.ptp(x)), float(np.ptp(y)))
    sx = sx if sx > 0 else 1.0
    sy = sy if sy > 0 else 1.0
    ix = np.floor((x - x.min()) / sx * 250).astype(np.int64)
    iy = np.floor((y - y.min()) / sy * 250).astype(np.int64)
    cells = np.unique(ix * 1_000_003 + iy).size
    if cells <= 300:
        return 3.5
    if cells <= 3000:
        return 2.0
    return 1.0


def uniform_legend_markers(legend: Any, size: float = 4.0) -> None:
    """Draw every marker of a legend at one readable size."""
    for handle in getattr(legend, "legend_handles", []):
        if isinstance(handle, Line2D) and handle.get_marker() not in (None, "None", ""):
            handle.set_markersize(size)


def dots(ax: Axes, x: np.ndarray, y: np.ndarray, label: str, color: str, size: float) -> Line2D:
    """Filled dots, the model's data."""
    (line,) = ax.plot(
        x,
        y,
        linestyle="none",
        marker="o",
        markersize=size,
        markeredgewidth=0,
        color=color,
        label=label,
        zorder=2.5,
    )
    return line


def rings(ax: Axes, x: np.ndarray, y: np.ndarray, label: str, size: float) -> Line2D:
    """Hollow rings in the camera's colour, larger than the model's dots of ``size`` and
    beneath them, so that both stay visible where they coincide."""
    (line,) = ax.plot(
        x,
        y,
        linestyle="none",
        marker="o",
        markersize=max(size * CAMERA_RING, 3.5),
        markerfacecolor="none",
        markeredgecolor=CAMERA_COLOR,
        markeredgewidth=0.8,
        color=CAMERA_COLOR,
        label=label,
        zorder=2.0,
    )
    return line


def marker_handle(marker: str, color: Any, label: str) -> Line2D:
    """A legend entry for points drawn with ``marker`` (no line)."""
    return Line2D([], [], linestyle="none", marker=marker, markersize=4, color=color, label=label)


def camera_handle(frame_interval: float, label: str | None = None) -> Line2D:
    """A legend entry for the camera's rings."""
    return Line2D(
        [],
        [],
        linestyle="none",
        marker="o",
        markersize=6,
        markerfacecolor="none",
        markeredgecolor=CAMERA_COLOR,
        markeredgewidth=0.8,
        label=label or f"camera, frame {frame_interval * 1e3:.3g} ms",
    )


def square_range(values: Sequence[np.ndarray]) -> tuple[float, float]:
    """The range of a square view over ``values`` (the finite ones, padded by 4 %)."""
    finite = np.concatenate([v[np.isfinite(v)] for v in values]) if values else np.array([])
    if finite.size == 0:
        lo, hi = 0.0, 1.0
    else:
        lo, hi = float(finite.min()), float(finite.max())
        if hi - lo < 1e-12 * max(1.0, abs(hi)):
            pad = max(abs(hi) * 0.05, 1e-3)
        else:
            pad = 0.04 * (hi - lo)
        lo, hi = lo - pad, hi + pad
    return lo, hi


def square_limits(ax: Axes, values: Sequence[np.ndarray]) -> tuple[float, float]:
    """Set the same range (:func:`square_range`) on both axes, with equal aspect."""
    lo, hi = square_range(values)
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal", adjustable="box")
    return lo, hi


def diagonal(ax: Axes, lo: float, hi: float, label: str) -> None:
    ax.plot([lo, hi], [lo, hi], color="0.35", linewidth=0.8, linestyle="--", label=label, zorder=0)


# --- figures and files ---------------------------------------------------------------------


def new_figure(size: tuple[float, float] = SINGLE_SIZE, dpi: int = DPI) -> Figure:
    """A constrained-layout figure on an Agg canvas (never pyplot: nothing is kept in a
    global registry)."""
    fig = Figure(figsize=size, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def cannot_write(path: str | os.PathLike[str], exc: OSError) -> RunDataError:
    """The one-line error for a figure that cannot be written."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return RunDataError(f"{path}: cannot write the figure: {reason}")


def output_directory(out: str | os.PathLike[str]) -> Path:
    """Create ``out`` if missing and check that figures can be written into it.

    Raises:
        RunDataError: it cannot be created or is not writable (one line naming it).
    """
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise RunDataError(f"{out}: cannot create the figure directory: {reason}") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise RunDataError(f"{out}: cannot write the figures: permission denied")
    return out


def save(fig: Figure, path: str | os.PathLike[str], dpi: int = DPI) -> Path:
    """Save ``fig`` to ``path`` and clear it.

    The format follows the file's extension (``.png``, ``.svg``, ``.pdf``...); ``dpi`` is
    the pixels per inch of a raster file. A vector file (SVG, PDF) ignores it: what it
    holds as an image (a layer of many markers, see
    :func:`billiard.plot.density.rasterize_if_large`) is embedded at
    :data:`VECTOR_IMAGE_DPI`. SVG and PDF files are written without a creation date and
    with fixed element ids, so that the same figure gives the same bytes.

    Raises:
        RunDataError: the file cannot be written (one line naming it).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    metadata: dict[str, Any] | None = None
    if suffix == ".svg":
        metadata, dpi = {"Date": None}, VECTOR_IMAGE_DPI
    elif suffix == ".pdf":
        metadata, dpi = {"CreationDate": None}, VECTOR_IMAGE_DPI
    try:
        with rc_context({**DRAW_RC, "svg.hashsalt": "billiard"}):
            fig.savefig(path, dpi=dpi, metadata=metadata)
    except OSError as exc:
        raise cannot_write(path, exc) from None
    finally:
        fig.clear()
    return path
