"""Figures in the layout of the paper's Figs. 2 and 3, several runs side by side (used by
:mod:`billiard.reproduce`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from ..scene import Scene
from .common import (
    LID_COLOR,
    MODEL_COLOR,
    Columns,
    RunDataError,
    camera_filter,
    camera_handle,
    lid_mask,
    new_figure,
    save,
)
from .inputs import checked_interval
from .maps import return_map, time_map
from .phase import PHASE_CAPTION, phase_plot
from .run import load_run
from .titles import short_label

__all__ = ["paper_figure", "paper_phase_figure"]

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
) -> Path:
    """Panels in rows, one column per run; one shared legend (and ``caption``) at the
    bottom. ``labels`` replace the panels' own x and y labels (shorter ones that fit a
    narrow panel). ``lid_legend``: the panels mark lid impacts (the return map)."""
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
        axes[0, j].set_title(f"{short_label(scene)}\n{count}", fontsize=9)
    handles = [
        Line2D(
            [],
            [],
            linestyle="none",
            marker="o",
            markersize=4,
            color=MODEL_COLOR,
            label="model: every impact",
        )
    ]
    if frame_interval is not None:
        handles.append(camera_handle(frame_interval))
    if any_lid and lid_legend:
        handles.append(
            Line2D(
                [],
                [],
                linestyle="none",
                marker="x",
                markersize=4,
                color=LID_COLOR,
                label="lid impacts",
            )
        )
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
            "$u_4/u_{4,max}$, $u_{4,max} = \\sqrt{2E/m}$ (m/s)",
            "$q_2/q_{2,max}$, $q_{2,max} = E/(m\\,g)$ (m)",
        ),
        caption=PHASE_CAPTION,
    )
