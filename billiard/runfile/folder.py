"""Names of the files a run writes into its folder (no heavy imports: the command line
consults them before and after a run without loading the plotting stack)."""

from __future__ import annotations

__all__ = ["FIGURE_NAMES", "VIEW_NAME"]

#: Figures written by :func:`billiard.plot.plot_run`, in order.
FIGURE_NAMES: tuple[str, ...] = (
    "return_map.png",
    "time_map.png",
    "phase.png",
    "trajectory.png",
    "animation.gif",
)

#: The interactive view written by ``billiard view DIR`` (:mod:`billiard.plot.interactive`);
#: like the figures, it is removed when the run's data change without it being written again.
VIEW_NAME = "view.html"
