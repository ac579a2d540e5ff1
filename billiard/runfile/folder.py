"""Names of the files a run writes into its folder (no heavy imports: the command line
consults them before and after a run without loading the plotting stack)."""

from __future__ import annotations

__all__ = ["FIGURE_NAMES"]

#: Figures written by :func:`billiard.plot.plot_run`, in order.
FIGURE_NAMES: tuple[str, ...] = (
    "return_map.png",
    "time_map.png",
    "phase.png",
    "trajectory.png",
    "animation.gif",
)
