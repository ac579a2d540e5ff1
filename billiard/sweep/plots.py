"""Plots of a sweep (matplotlib, SI units on every axis).

* one numeric axis: ``bifurcation.png``, the last K impact heights and times of flight
  against the swept key (and the Lyapunov exponent when computed);
* two numeric axes (the first one horizontal): ``heatmaps.png``, period, mean impact
  height and (when computed) the Lyapunov exponent; and when a swept key is a starting
  state (``initial.*``), ``basins.png``, each start coloured by the attractor it reaches.

Other sweeps (three or more axes, or text-valued keys) get no plots; the result file
holds everything.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from billiard.sweep.basins import attractor_labels
from billiard.sweep.definition import Sweep
from billiard.sweep.units import axis_label

__all__ = ["plot_sweep"]

_CLASS_COLOURS = {
    "periodic": "tab:blue",
    "resting": "tab:gray",
    "chaotic": "tab:red",
    "quasi-periodic": "tab:purple",
    "aperiodic": "tab:orange",
}


def plot_sweep(sweep: Sweep, records: Sequence[dict[str, Any]], directory: Path) -> list[Path]:
    """Draw the plots that suit the sweep's axes into ``directory``; returns their paths."""
    numeric = [a for a in sweep.axes if a.numeric]
    if len(numeric) != len(sweep.axes) or len(sweep.axes) > 2:
        return []
    import matplotlib

    matplotlib.use("Agg")
    paths = []
    if len(sweep.axes) == 1:
        paths.append(bifurcation(sweep, records, directory / "bifurcation.png"))
    else:
        paths.append(heatmaps(sweep, records, directory / "heatmaps.png"))
        if any(a.key.startswith("initial.") for a in sweep.axes):
            paths.append(basins(sweep, records, directory / "basins.png"))
    return paths


def _title(sweep: Sweep) -> str:
    return (
        f"{sweep.scene.name}: {sweep.transient} impacts of transient, "
        f"{sweep.impacts} measured per point"
    )


def bifurcation(sweep: Sweep, records: Sequence[dict[str, Any]], path: Path) -> Path:
    """Last K impact heights and times of flight against the one swept key."""
    import matplotlib.pyplot as plt

    axis = sweep.axes[0]
    lyap = [r["lyapunov"] for r in records]
    with_lyap = any(v is not None for v in lyap)
    rows = 3 if with_lyap else 2
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(7.5, 2.4 * rows + 0.8), dpi=110)
    seen: set[str] = set()
    for record in records:
        x = record["values"][axis.key]
        colour = _CLASS_COLOURS.get(record["attractor"])
        if colour is None:  # failed or invalid
            continue
        label = record["attractor"] if record["attractor"] not in seen else None
        seen.add(record["attractor"])
        heights, tofs = record["last_height"], record["last_tof"]
        xs = np.full(len(heights), float(x))
        axes[0].scatter(xs, heights, s=1.5, color=colour, label=label, linewidths=0)
        axes[1].scatter(xs, tofs, s=1.5, color=colour, linewidths=0)
    bad = [r for r in records if r["status"] != "ok"]
    if bad:
        axes[0].scatter(
            [r["values"][axis.key] for r in bad],
            np.zeros(len(bad)),
            marker="x",
            color="black",
            label=f"failed or invalid ({len(bad)})",
        )
    axes[0].set_ylabel("impact height q2 (m)")
    axes[1].set_ylabel("time of flight (s)")
    axes[1].set_yscale("log")
    if with_lyap:
        xs = [r["values"][axis.key] for r in records]
        ys = [np.nan if v is None else v for v in lyap]
        axes[2].plot(xs, ys, "o-", ms=3, color="black")
        axes[2].axhline(0.0, color="grey", lw=0.8)
        axes[2].set_ylabel("Lyapunov exponent\n(1/impact)")
    axes[-1].set_xlabel(axis_label(axis.key))
    axes[0].legend(loc="best", fontsize=7, markerscale=4)
    axes[0].set_title(f"{_title(sweep)}; last {sweep.keep} impacts", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _edges(values: Sequence[float]) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if len(v) == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _grid(sweep: Sweep, records: Sequence[dict[str, Any]], name: str) -> np.ndarray:
    data = np.array(
        [np.nan if r[name] is None or r["status"] != "ok" else float(r[name]) for r in records]
    )
    return data.reshape(sweep.shape)


def heatmaps(sweep: Sweep, records: Sequence[dict[str, Any]], path: Path) -> Path:
    """Period, mean impact height and Lyapunov exponent over two swept keys."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    xa, ya = sweep.axes  # first key horizontal, second vertical
    xe, ye = _edges(xa.values), _edges(ya.values)
    period = _grid(sweep, records, "period")
    period[period == 0] = np.nan
    panels = [
        (
            "period (impacts per repetition;\nblank: none, failed or invalid)",
            period,
            "viridis",
            None,
        ),
        ("mean impact height q2 (m)", _grid(sweep, records, "height_mean"), "magma", None),
    ]
    lyap = _grid(sweep, records, "lyapunov")
    if np.isfinite(lyap).any():
        span = float(np.nanmax(np.abs(lyap))) or 1.0
        norm = TwoSlopeNorm(0.0, -span, span)
        panels.append(("Lyapunov exponent (1/impact)", lyap, "coolwarm", norm))
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 4.0), dpi=100)
    for ax, (title, data, cmap, norm) in zip(np.atleast_1d(axes), panels, strict=True):
        mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(data).T, cmap=cmap, norm=norm)
        fig.colorbar(mesh, ax=ax)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(axis_label(xa.key))
        ax.set_ylabel(axis_label(ya.key))
    fig.suptitle(_title(sweep), fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def basins(sweep: Sweep, records: Sequence[dict[str, Any]], path: Path) -> Path:
    """Each start coloured by the attractor it reaches."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    ids, labels = attractor_labels(records)
    palette = plt.get_cmap("tab10").colors
    special = {"failed": "black", "invalid": "white", "resting": "0.6", "chaotic": "tab:red"}
    colours = []
    k = 0
    for label in labels:
        if label in special:
            colours.append(special[label])
        else:
            colours.append(palette[k % len(palette)])
            k += 1
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(len(labels) + 1) - 0.5, len(labels))
    xa, ya = sweep.axes  # first key horizontal, second vertical
    grid = np.array(ids).reshape(sweep.shape)
    fig, ax = plt.subplots(figsize=(7.5, 5.0), dpi=100)
    ax.pcolormesh(_edges(xa.values), _edges(ya.values), grid.T, cmap=cmap, norm=norm)
    counts = np.bincount(grid.ravel(), minlength=len(labels))
    handles = [
        Patch(facecolor=c, edgecolor="black", label=f"{lab} ({n} starts)")
        for c, lab, n in zip(colours, labels, counts, strict=True)
    ]
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_xlabel(axis_label(xa.key))
    ax.set_ylabel(axis_label(ya.key))
    ax.set_title(f"attractor reached from each start\n{_title(sweep)}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path
