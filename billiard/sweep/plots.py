"""Plots of a sweep (matplotlib, SI units on every axis and colour bar).

* one numeric axis: ``bifurcation.png``, the last K impact heights and times of flight
  against the swept key (and the Lyapunov exponent when computed);
* two numeric axes (the first one horizontal): ``heatmaps.png``, period (a category:
  one colour per period found, named in a legend), mean impact height and (when
  computed) the Lyapunov exponent; and when a swept key is a starting state
  (``initial.*``), ``basins.png``, each start coloured by the attractor it reaches (one
  colour per attractor, named in a legend), with the container's wall at the start time
  when the keys are the starting position (``initial.q1`` and ``initial.q2``).

A map whose values agree to rounding (relative spread at most 1e-9), or for heights
within the sweep's ``tolerance`` (10 µm by default: states closer than that are the same
state to the sweep), is drawn in one colour with its one value on the colour bar, not as
noise stretched over the colour scale. Every colour bar names its quantity and unit;
titles name the base scene and its ``--set`` changes.

The plots are drawn from the result file's arrays (:func:`~billiard.sweep.read_result`),
not from the points' records. Other sweeps (three or more axes, or text-valued keys) get
no plots; the result file holds everything.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.colors import LogNorm

from billiard.analysis.bins import bin_counts
from billiard.sweep.attractor import CONTACT_CLASSES
from billiard.sweep.basins import attractor_labels
from billiard.sweep.categories import (
    CLASS_COLOURS,
    category_legend,
    category_map,
    distinct_colours,
)
from billiard.sweep.container import POSITION_KEYS, lid_height, wall_outline
from billiard.sweep.definition import Sweep
from billiard.sweep.units import axis_label, key_unit, variable_name

__all__ = ["plot_sweep"]

_CLASS_COLOURS = {
    "periodic": "tab:blue",
    "resting": "tab:gray",
    "chaotic": "tab:red",
    "quasi-periodic": "tab:purple",
    "aperiodic": "tab:orange",
    "rolling": "tab:green",
    "sliding": "tab:olive",
    "held": "tab:brown",
}
#: Classes of a ball that stays on the boundary: without impacts they are drawn at the
#: point's resting height.
_DOWN = ("resting", *CONTACT_CLASSES.values())
#: Relative spread under which a map's values are one value (rounding, not physics).
_ROUNDING = 1e-9
#: a bifurcation diagram of more impacts than this is drawn as counts per bin (as
#: billiard.plot.density draws a run's large clouds)
DENSITY_ABOVE = 50_000


def plot_sweep(sweep: Sweep, data: Mapping[str, Any], directory: Path) -> list[Path]:
    """Draw the plots that suit the sweep's axes into ``directory``; returns their paths.

    Args:
        sweep: the sweep.
        data: its result file's arrays, as :func:`~billiard.sweep.read_result` gives them.
        directory: where the PNG files go.
    """
    numeric = [a for a in sweep.axes if a.numeric]
    if len(numeric) != len(sweep.axes) or len(sweep.axes) > 2:
        return []
    import matplotlib

    matplotlib.use("Agg")
    paths = []
    if len(sweep.axes) == 1:
        paths.append(bifurcation(sweep, data, directory / "bifurcation.png"))
    else:
        paths.append(heatmaps(sweep, data, directory / "heatmaps.png"))
        if any(a.key.startswith("initial.") for a in sweep.axes):
            paths.append(basins(sweep, data, directory / "basins.png"))
    return paths


def _title(sweep: Sweep, width: int = 110) -> str:
    """The base scene, its --set changes and the measurement, wrapped to ``width``."""
    name = sweep.scene.name
    if sweep.changes:
        name += " with " + ", ".join(sweep.changes)
    text = f"{name}: {sweep.transient} impacts of transient, {sweep.impacts} measured per point"
    return "\n".join(textwrap.wrap(text, width))


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def bifurcation(sweep: Sweep, data: Mapping[str, Any], path: Path) -> Path:
    """Last K impact heights and times of flight against the one swept key."""
    return _save(bifurcation_figure(sweep, data), path)


def bifurcation_figure(sweep: Sweep, data: Mapping[str, Any]) -> Any:
    import matplotlib.pyplot as plt

    axis = sweep.axes[0]
    x = np.asarray(data[variable_name(axis.key)], dtype=float)
    attractor, status = np.asarray(data["attractor"]), np.asarray(data["status"])
    heights, tofs = np.asarray(data["last_height"]), np.asarray(data["last_tof"])
    lyap = np.asarray(data["lyapunov"], dtype=float)
    with_lyap = bool(np.isfinite(lyap).any())
    rows = 3 if with_lyap else 2
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(7.5, 2.4 * rows + 0.9), dpi=110)
    points = int(np.isfinite(heights).sum())
    dense = points > DENSITY_ABOVE
    if dense:
        # a million points as dots cover one another: counts per bin, one column of bins
        # per swept value (up to 600), the classes' counts in the title
        _bifurcation_density(axes[:2], x, heights, tofs, axis.key)
    for name, colour in ({} if dense else _CLASS_COLOURS).items():
        mask = attractor == name
        if not mask.any():
            continue
        xs = np.repeat(x[mask], heights.shape[1])
        hs, ts = heights[mask].ravel(), tofs[mask].ravel()
        keep = np.isfinite(hs)
        label = f"{name} ({int(mask.sum())})"
        axes[0].scatter(xs[keep], hs[keep], s=1.5, color=colour, label=label, linewidths=0)
        axes[1].scatter(xs[keep], ts[keep], s=1.5, color=colour, linewidths=0)
        if name in _DOWN:  # no impacts at all: the ball lies, rolls or is held
            still = mask & ~np.isfinite(heights).any(axis=1)
            if still.any():
                axes[0].scatter(
                    x[still],
                    np.asarray(data["rest_height"], dtype=float)[still],
                    marker="^",
                    s=8,
                    color=colour,
                    label=f"{name}, no impacts: at the resting height",
                )
    bad = status != "ok"
    if bad.any():
        axes[0].scatter(
            x[bad],
            np.zeros(int(bad.sum())),
            marker="x",
            color="black",
            label=f"failed or invalid ({int(bad.sum())})",
        )
    axes[0].set_ylabel("impact height q2 (m)")
    axes[1].set_ylabel("time of flight (s)")
    if not dense and np.isfinite(tofs).any() and np.nanmin(tofs) > 0.0:
        axes[1].set_yscale("log")
    if with_lyap:
        axes[2].plot(x, lyap, "o-", ms=3, color="black")
        axes[2].axhline(0.0, color="grey", lw=0.8)
        axes[2].set_ylabel("Lyapunov exponent\n(1/impact)")
    axes[-1].set_xlabel(axis_label(axis.key))
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(loc="best", fontsize=7, markerscale=4)
    title = f"{_title(sweep, 80)}; last {sweep.keep} impacts"
    if dense:
        names, counts = np.unique(attractor[status == "ok"], return_counts=True)
        classes = ", ".join(f"{n} {c:,}" for n, c in zip(names, counts, strict=True))
        title += f" of each point ({points:,} impacts; points: {classes})"
    axes[0].set_title(textwrap.fill(title, 100), fontsize=9)
    return fig


def _bifurcation_density(
    axes: Any, x: np.ndarray, heights: np.ndarray, tofs: np.ndarray, key: str
) -> None:
    """The last impacts' heights and times of flight against the swept value as density
    images (impacts per bin, logarithmic colour scale)."""
    values = np.unique(x[np.isfinite(x)])
    lo, hi = float(values[0]), float(values[-1])
    if hi == lo:
        lo, hi = lo - 0.5, hi + 0.5
    else:  # each value in the middle of its column of bins
        step = (hi - lo) / max(len(values) - 1, 1)
        lo, hi = lo - step / 2, hi + step / 2
    columns = min(len(values), 600)
    xs = np.repeat(x, heights.shape[-1])
    unit = key_unit(key)
    for ax, ys, what in ((axes[0], heights, "m"), (axes[1], tofs, "s")):
        ys = ys.ravel()
        finite = ys[np.isfinite(ys)]
        if not finite.size:
            continue
        y0, y1 = float(finite.min()), float(finite.max())
        if y1 == y0:
            y0, y1 = y0 - 1e-3 * max(abs(y0), 1e-3), y1 + 1e-3 * max(abs(y1), 1e-3)
        counts = bin_counts(xs, ys, (lo, hi), (y0, y1), (columns, 300)).astype(float)
        counts[counts == 0] = np.nan  # empty bins transparent
        image = ax.imshow(
            counts, origin="lower", extent=(lo, hi, y0, y1), aspect="auto",
            interpolation="none", cmap="viridis",
            norm=LogNorm(vmin=1.0, vmax=max(2.0, float(np.nanmax(counts)))),
        )  # fmt: skip
        bins = f"{(hi - lo) / columns:.2g} {unit} x {(y1 - y0) / 300:.2g} {what}"
        ax.figure.colorbar(image, ax=ax, label=f"impacts per bin\n{bins}", pad=0.02)
        ax.set_xlim(lo, hi)
        ax.set_ylim(y0, y1)


def _edges(values: Any) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if len(v) == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _grid(data: Mapping[str, Any], name: str) -> np.ndarray:
    """A variable over the two swept keys as floats, NaN where not measured."""
    values = np.asarray(data[name], dtype=float).copy()
    values[np.asarray(data["status"]) != "ok"] = np.nan
    return values


def constant_value(field: np.ndarray, resolution: float = 0.0) -> float | None:
    """The one value of a map whose finite values agree to rounding (relative spread at
    most 1e-9) or within ``resolution`` (in the field's unit), else None."""
    finite = field[np.isfinite(field)]
    if finite.size == 0:
        return None
    low, high = float(finite.min()), float(finite.max())
    scale = max(abs(low), abs(high))
    if high - low <= max(_ROUNDING * scale, resolution):
        return float(np.mean(finite)) if scale > 0.0 else 0.0
    return None


def _panel(
    fig: Any,
    ax: Any,
    xe: Any,
    ye: Any,
    field: np.ndarray,
    cmap: str,
    label: str,
    resolution: tuple[float, str] | None = None,
) -> Any:
    """A continuous map with a labelled colour bar; one colour and one value when the
    map is constant to rounding or within ``resolution`` (value, and its text)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.ticker import ScalarFormatter

    masked = np.ma.masked_invalid(field).T
    value = constant_value(field, resolution[0] if resolution else 0.0)
    if value is None:
        mesh = ax.pcolormesh(xe, ye, masked, cmap=cmap)
        bar = fig.colorbar(mesh, ax=ax)
        bar.formatter = ScalarFormatter(useOffset=False)  # values, not an offset to add
        bar.update_ticks()
        bar.set_label(label, fontsize=8)
        return bar
    import matplotlib.pyplot as plt

    half = max(abs(value), 1.0) * 1e-6
    norm = BoundaryNorm([value - half, value + half], 1)
    mesh = ax.pcolormesh(xe, ye, masked, cmap=ListedColormap([plt.get_cmap(cmap)(0.6)]), norm=norm)
    bar = fig.colorbar(mesh, ax=ax, ticks=[value])
    bar.ax.set_yticklabels([f"{value:.6g}"])
    bar.set_label(label, fontsize=8)
    within = f"all within {resolution[1]}" if resolution else "equal to rounding"
    ax.text(
        0.5,
        0.5,
        f"one value: {value:.6g}\n({within})",
        transform=ax.transAxes,
        ha="center",
        va="center",
        fontsize=8,
        bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"},
    )
    return bar


#: periods named in a period map's legend: beyond, the most common ``PERIODS_SHOWN - 1``
#: are named and the others drawn together in :data:`OTHER_PERIODS`
PERIODS_SHOWN = 12
#: the colour of the periods a map's legend does not name (light grey: tab10 has a
#: mid grey)
OTHER_PERIODS = (0.85, 0.85, 0.85)


def _period_panel(ax: Any, xe: Any, ye: Any, period: np.ndarray) -> Any:
    """Periods are categories: one distinct colour per period found, named in a legend
    (a colour scale would suggest that period 3 lies between 2 and 4 as a height does)."""
    # NaN: none (the file's _FillValue); 0 too, the "none" of files written before it
    found, counts = np.unique(period[np.isfinite(period) & (period > 0)], return_counts=True)
    found = found.astype(int)
    shown = found
    if len(found) > PERIODS_SHOWN:
        # a large map finds dozens of periods, most in a few cells: their legend filled
        # the figure and their colours could not be told apart; the most common are
        # named, the rest share one grey
        shown = np.sort(found[np.argsort(-counts, kind="stable")[: PERIODS_SHOWN - 1]])
    ids = np.full(period.shape, -1)
    for k, value in enumerate(shown):
        ids[period == value] = k
    labels = [f"period {value}" for value in shown]
    colours = distinct_colours(len(shown), taken=[OTHER_PERIODS])
    others = found[~np.isin(found, shown)]
    if others.size:
        ids[np.isfinite(period) & (period > 0) & (ids < 0)] = len(shown)
        labels.append(f"{others.size} other periods, {others.min()} to {others.max()}")
        colours.append(OTHER_PERIODS)
    handles = category_map(ax, xe, ye, ids, labels, colours)
    legend = category_legend(ax, handles, "impacts per repetition\nof the state")
    if legend is None:
        ax.text(0.5, 0.5, "no period found", transform=ax.transAxes, ha="center", fontsize=8)
    return legend


def heatmaps(sweep: Sweep, data: Mapping[str, Any], path: Path) -> Path:
    """Period, mean impact height and Lyapunov exponent over two swept keys."""
    return _save(heatmaps_figure(sweep, data), path)


def heatmaps_figure(sweep: Sweep, data: Mapping[str, Any]) -> Any:
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    xa, ya = sweep.axes  # first key horizontal, second vertical
    xe, ye = _edges(data[variable_name(xa.key)]), _edges(data[variable_name(ya.key)])
    period = _grid(data, "period")  # NaN: no period (the file's _FillValue)
    lyap = _grid(data, "lyapunov")
    panels = 3 if np.isfinite(lyap).any() else 2
    fig, axes = plt.subplots(1, panels, figsize=(4.8 * panels, 4.3), dpi=100)
    axes = np.atleast_1d(axes)
    _period_panel(axes[0], xe, ye, period)
    axes[0].set_title("period (blank: none, failed or invalid)", fontsize=9)
    # heights closer than the sweep's state tolerance are one orbit's to the sweep
    resolution = (sweep.tolerance, f"{sweep.tolerance:g} m, the sweep's tolerance")
    heights = _grid(data, "height_mean")
    _panel(fig, axes[1], xe, ye, heights, "magma", "mean impact height q2 (m)", resolution)
    axes[1].set_title("mean impact height q2 (blank: no impacts, failed)", fontsize=9)
    if panels == 3:
        value = constant_value(lyap)
        if value is None:
            span = float(np.nanmax(np.abs(lyap))) or 1.0
            mesh = axes[2].pcolormesh(
                xe,
                ye,
                np.ma.masked_invalid(lyap).T,
                cmap="coolwarm",
                norm=TwoSlopeNorm(0.0, -span, span),
            )
            bar = fig.colorbar(mesh, ax=axes[2])
            bar.set_label("Lyapunov exponent (1/impact)", fontsize=8)
        else:
            _panel(fig, axes[2], xe, ye, lyap, "coolwarm", "Lyapunov exponent (1/impact)")
        axes[2].set_title("largest Lyapunov exponent", fontsize=9)
    from matplotlib.ticker import MaxNLocator

    for ax in axes:
        ax.xaxis.set_major_locator(MaxNLocator(nbins=4))
        ax.set_xlabel(axis_label(xa.key))
        ax.set_ylabel(axis_label(ya.key))
    fig.suptitle(_title(sweep, 40 * panels), fontsize=9)
    return fig


def basins(sweep: Sweep, data: Mapping[str, Any], path: Path) -> Path:
    """Each start coloured by the attractor it reaches."""
    return _save(basins_figure(sweep, data), path)


def basins_figure(sweep: Sweep, data: Mapping[str, Any]) -> Any:
    """Each start coloured by the attractor it reaches, one distinct colour per attractor
    (periodic orbits told apart by period and mean height) named in a legend; over
    starting positions (initial.q1 and initial.q2) with the container's wall and lid at
    the start time, at equal scales."""
    import matplotlib.pyplot as plt

    flat = {name: np.asarray(data[name]).ravel() for name in ("attractor", "period", "height_mean")}
    records = [
        {"attractor": str(a), "period": p, "height_mean": h}
        for a, p, h in zip(flat["attractor"], flat["period"], flat["height_mean"], strict=True)
    ]
    ids, labels = attractor_labels(records)
    special = [CLASS_COLOURS[label] for label in labels if label in CLASS_COLOURS]
    others = iter(distinct_colours(len(labels) - len(special), taken=special))
    colours = [CLASS_COLOURS[label] if label in CLASS_COLOURS else next(others) for label in labels]
    xa, ya = sweep.axes  # first key horizontal, second vertical
    xe, ye = _edges(data[variable_name(xa.key)]), _edges(data[variable_name(ya.key)])
    grid = np.array(ids).reshape(sweep.shape)
    fig, ax = plt.subplots(figsize=(7.5, 5.0), dpi=100)
    handles = category_map(ax, xe, ye, grid, labels, colours, unit="start")
    if {xa.key, ya.key} == set(POSITION_KEYS):
        handles += _container(ax, sweep, xe, ye, transposed=xa.key == "initial.q2")
    category_legend(ax, handles)
    ax.set_xlabel(axis_label(xa.key))
    ax.set_ylabel(axis_label(ya.key))
    ax.set_title(f"attractor reached from each start\n{_title(sweep, 70)}", fontsize=9)
    return fig


def _container(ax: Any, sweep: Sweep, xe: np.ndarray, ye: np.ndarray, transposed: bool) -> list:
    """Draw the wall (and the lid, if in view) over a map of starting positions, at equal
    scales, the view kept to the map's cells; ``transposed``: q2 is horizontal. Returns
    the lines, for the legend."""
    q1_edges, q2_edges = (ye, xe) if transposed else (xe, ye)
    lo, hi = float(np.min(q1_edges)), float(np.max(q1_edges))
    try:
        x, y = wall_outline(sweep.scene, lo, hi)
    except ValueError:  # a curve that cannot be loaded here: the map without it
        return []
    line = (y, x) if transposed else (x, y)
    (wall,) = ax.plot(*line, color="black", lw=1.2, label="container wall at the start")
    lines = [wall]
    lid = lid_height(sweep.scene)
    if lid is not None and np.min(q2_edges) <= lid <= np.max(q2_edges):
        draw = ax.axvline if transposed else ax.axhline
        lines.append(draw(lid, color="black", lw=1.2, ls="--", label="lid"))
    ax.set_xlim(float(np.min(xe)), float(np.max(xe)))
    ax.set_ylim(float(np.min(ye)), float(np.max(ye)))
    ax.set_aspect("equal", adjustable="box")
    return lines
