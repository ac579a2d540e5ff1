"""Figures in the layout of the paper's Figs. 2 and 3, several runs side by side (used by
:mod:`billiard.reproduce.paper`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from billiard.plot.common import (
    LID_COLOR,
    MODEL_COLOR,
    Columns,
    RunDataError,
    camera_filter,
    camera_handle,
    lid_mask,
    marker_handle,
    new_figure,
    save,
)
from billiard.plot.inputs import checked_interval
from billiard.plot.maps import return_map, time_map
from billiard.plot.phase import PHASE_CAPTION, phase_plot
from billiard.plot.run import load_run
from billiard.plot.titles import short_label
from billiard.scene.scene import Scene

__all__ = ["paper_figure", "paper_laws_figure", "paper_models_figure", "paper_phase_figure"]

Panel = Callable[[Columns, Scene, Axes], object]


def _paper_grid(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    panels: Sequence[Panel],
    title: str,
    frame_interval: float | None,
    guide: str,
    *,
    labels: tuple[str, str] | None = None,
    caption: str | None = None,
    lid_legend: bool = False,
    titles: Sequence[str] | None = None,
) -> Path:
    """Panels in rows, one column per run; one shared legend (and ``caption``) at the
    bottom. ``labels`` replace the panels' own x and y labels (shorter ones that fit a
    narrow panel). ``lid_legend``: the panels mark lid impacts (the return map).
    ``titles``: the columns' titles (default: each run's curve and drive frequency)."""
    if not run_dirs:
        raise RunDataError("no run directories given")
    runs = [load_run(d) for d in run_dirs]
    cols = len(runs)
    fig = new_figure((3.3 * cols + 0.4, 3.3 * len(panels) + 1.0 + (0.4 if caption else 0.0)))
    axes = fig.subplots(len(panels), cols, squeeze=False)
    any_lid = False
    for j, (columns, scene) in enumerate(runs):
        for i, draw in enumerate(panels):
            ax = axes[i, j]
            draw(columns, scene, ax)
            legend = ax.get_legend()
            if legend is not None:
                legend.remove()
            if labels is not None:
                ax.set_xlabel(labels[0])
                ax.set_ylabel(labels[1])
            ax.xaxis.label.set_fontsize(9)
            ax.yaxis.label.set_fontsize(9)
            ax.tick_params(labelsize=8)
        any_lid = any_lid or bool(lid_mask(columns).any())
        count = f"{columns['t'].size} impacts"
        if frame_interval is not None:
            count += f", camera {camera_filter(columns, frame_interval)['t'].size}"
        title_j = short_label(scene) if titles is None else titles[j]
        axes[0, j].set_title(f"{title_j}\n{count}", fontsize=9)
    handles = [marker_handle("o", MODEL_COLOR, "model: every impact")]
    if frame_interval is not None:
        handles.append(camera_handle(frame_interval))
    if any_lid and lid_legend:
        handles.append(marker_handle("x", LID_COLOR, "lid impacts"))
    handles.append(Line2D([], [], color="0.35", linewidth=0.8, linestyle="--", label=guide))
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncol=len(handles),
        fontsize=8,
        frameon=False,
        title=caption,
        title_fontsize=7,
    )
    fig.suptitle(title, fontsize=10)
    return save(fig, path)


def paper_figure(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    *,
    frame_interval: float | None = None,
) -> Path:
    """One figure in the layout of the paper's Fig. 2: one column per run, the return map
    of impact heights (q2,n vs q2,n+1, mm) on the top row and the map of times of flight
    (t_n vs t_n+1, s) on the bottom row; each column titled with its curve and drive
    frequency. With ``frame_interval`` (s), the camera-filtered data are drawn too.

    Returns:
        The path written (PNG, or any format matplotlib infers from the suffix).
    """
    interval = checked_interval(frame_interval)
    return _paper_grid(
        run_dirs,
        path,
        [
            lambda c, s, ax: return_map(c, ax, frame_interval=interval),
            lambda c, s, ax: time_map(c, ax, frame_interval=interval),
        ],
        "Impact heights (top) and times of flight (bottom)",
        interval,
        "diagonal $q_{2,n} = q_{2,n+1}$, $t_n = t_{n+1}$",
        lid_legend=True,
    )


def paper_phase_figure(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    *,
    frame_interval: float | None = None,
) -> Path:
    """One figure in the layout of the paper's Fig. 3: the phase plots (q2/q2max vs
    u4/u4max, see :func:`billiard.plot.phase_plot`) of the runs side by side, with the
    normalizations stated in the axis labels and E defined in a caption.

    Returns:
        The path written.
    """
    interval = checked_interval(frame_interval)
    return _paper_grid(
        run_dirs,
        path,
        [lambda c, s, ax: phase_plot(c, s, ax, frame_interval=interval)],
        "Normalized impact height vs normalized tangential velocity after each impact",
        interval,
        "all energy in $q_2$ and $u_4$",
        labels=(
            "$u_4/u_{4,max}$, $u_{4,max} = \\sqrt{2E_0/m}$ (m/s)",
            "$(q_2 - h_0)/q_{2,max}$, $q_{2,max} = E_0/(m\\,g)$ (m)",
        ),
        caption=PHASE_CAPTION,
    )


def paper_laws_figure(
    run_dirs: Sequence[str | os.PathLike[str]],
    titles: Sequence[str],
    path: str | os.PathLike[str],
    title: str,
) -> Path:
    """One scene under several impact laws, one column per law (titled ``titles``): the
    return map of impact heights (mm), the map of times of flight (s) and the phase
    plot (q2/q2max vs u4/u4max) in three rows.

    Returns:
        The path written.
    """
    return _paper_grid(
        run_dirs,
        path,
        [
            lambda c, s, ax: return_map(c, ax),
            lambda c, s, ax: time_map(c, ax),
            lambda c, s, ax: phase_plot(c, s, ax),
        ],
        title,
        None,
        "diagonals; phase: all energy in $q_2$ and $u_4$",
        lid_legend=True,
        titles=titles,
        caption=PHASE_CAPTION,
    )


_MODEL_ROWS = (
    ("return", "impacts"),
    ("return", "phases"),
    ("time", "impacts"),
    ("time", "phases"),
)
_DIAGONALS = ("$q_{2,n} = q_{2,n+1}$", "$t_n = t_{n+1}$")


def paper_models_figure(
    impacts_dirs: Sequence[str | os.PathLike[str]],
    phases_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    *,
    labels: tuple[str, str] = ('contact.model = "impacts"', 'contact.model = "phases"'),
) -> Path:
    """The paper's Fig. 2 under two contact models, one column per scene: the return map
    of impact heights (q2,n vs q2,n+1, mm) under the first model, then under the second,
    then the map of times of flight (t_n vs t_n+1, s, logarithmic axes: flights from
    microseconds to a tenth of a second) under each. The two panels of a map share their
    limits, so the models compare at a glance; each panel's title gives its scene, model
    and impact count.

    Args:
        impacts_dirs: run directories of the first model, one per scene.
        phases_dirs: run directories of the second model, the same scenes in the same
            order.
        path: the figure file.
        labels: the two models' names in the panel titles.

    Returns:
        The path written.

    Raises:
        RunDataError: no runs, or the two lists differ in length.
    """
    if not impacts_dirs or len(impacts_dirs) != len(phases_dirs):
        raise RunDataError(
            f"paper_models_figure: {len(impacts_dirs)} and {len(phases_dirs)} run "
            "directories; give the same scenes under both models"
        )
    runs = {"impacts": [load_run(d) for d in impacts_dirs]}
    runs["phases"] = [load_run(d) for d in phases_dirs]
    names = dict(zip(("impacts", "phases"), labels, strict=True))
    cols = len(impacts_dirs)
    fig = new_figure((3.4 * cols + 0.4, 3.4 * len(_MODEL_ROWS) + 1.0))
    axes = fig.subplots(len(_MODEL_ROWS), cols, squeeze=False)
    for j in range(cols):
        for i, (kind, model) in enumerate(_MODEL_ROWS):
            columns, scene = runs[model][j]
            ax = axes[i, j]
            if kind == "return":
                return_map(columns, ax)
            else:
                time_map(columns, ax, log=True)
            ax.get_legend().remove()
            ax.set_title(
                f"{short_label(scene)}: {names[model]}\n{columns['t'].size} impacts", fontsize=8
            )
            ax.xaxis.label.set_fontsize(8)
            ax.yaxis.label.set_fontsize(8)
            ax.tick_params(labelsize=7)
        for top in (0, 2):  # one set of limits for the two models' panels of a map
            pair = (axes[top, j], axes[top + 1, j])
            lo = min(min(ax.get_xlim()) for ax in pair)
            hi = max(max(ax.get_xlim()) for ax in pair)
            for ax in pair:
                ax.set_xlim(lo, hi)
                ax.set_ylim(lo, hi)
                for line in ax.get_lines():
                    if line.get_label() in _DIAGONALS:
                        line.set_data([lo, hi], [lo, hi])
    handles = [
        marker_handle("o", MODEL_COLOR, "every impact"),
        Line2D(
            [],
            [],
            color="0.35",
            linewidth=0.8,
            linestyle="--",
            label="diagonal $q_{2,n} = q_{2,n+1}$, $t_n = t_{n+1}$",
        ),
    ]
    if any(lid_mask(c).any() for model in runs.values() for c, _ in model):
        handles.insert(
            1,
            marker_handle("x", LID_COLOR, "pairs with a lid impact"),
        )
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncol=len(handles),
        fontsize=8,
        frameon=False,
    )
    fig.suptitle(
        f"Impact heights and times of flight: {labels[0]} (rows 1, 3) and {labels[1]} (rows 2, 4)",
        fontsize=10,
    )
    return save(fig, path)
