"""Names of the files a run writes into its folder (no heavy imports: the command line
consults them before and after a run without loading the plotting stack)."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = [
    "CHECKPOINT_JSON",
    "COLLISIONS_CSV",
    "COLLISIONS_NPY",
    "FIGURE_NAMES",
    "VIEW_NAME",
    "data_file",
    "side_file",
]

#: The file of a run's impacts: CSV text, or typed binary rows (billiard.runfile.npyfile).
COLLISIONS_CSV = "collisions.csv"
COLLISIONS_NPY = "collisions.npy"
#: The checkpoint of a run: where its rows end, their checksums, the engine state.
CHECKPOINT_JSON = "checkpoint.json"

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


def data_file(folder: str | os.PathLike[str]) -> Path:
    """The file of the impacts of the run in ``folder``: ``collisions.npy`` where there is
    one (a binary run; ``billiard export DIR --csv`` may have written a CSV copy beside
    it), else ``collisions.csv`` (which may not exist)."""
    folder = Path(folder)
    binary = folder / COLLISIONS_NPY
    return binary if binary.is_file() else folder / COLLISIONS_CSV


def side_file(folder: str | os.PathLike[str], name: str) -> Path | None:
    """The file of the side table ``name`` (``contacts``, ``trajectory``) of the run in
    ``folder``, binary (``NAME.npy``) or CSV (``NAME.csv``) as its impacts are; None when
    the run has none."""
    folder = Path(folder)
    binary = data_file(folder).suffix == ".npy"
    path = folder / f"{name}.{'npy' if binary else 'csv'}"
    return path if path.is_file() else None
