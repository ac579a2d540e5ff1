"""Figures of a run: return map, times-of-flight map, phase plot, trajectory, animation.

Every function here reads the columns of a run's ``collisions.csv`` (see
:func:`billiard.analysis.camera.read_collisions`) and, where it needs them, the run's validated
:class:`billiard.scene.scene.Scene` (read from ``scene.toml`` by :func:`read_scene`). Lengths are
stored in metres and drawn in millimetres; times in seconds.

The figures follow Hartl, Miller and Mazzoleni, "Dynamic Modeling and Simulation of a Real
World Billiard": the return map of impact heights (q2,n vs q2,n+1), the map of times of
flight (t_n vs t_n+1), and the phase plot of the normalized impact height q2/q2max against
the normalized tangential velocity u4/u4max (their Figs. 2 and 3).

Drawing uses :class:`matplotlib.figure.Figure` with an Agg canvas and never pyplot, so no
figure is kept in a global registry; every figure made here is saved and dropped.

One module per figure:

| module | what it draws |
| --- | --- |
| ``common`` | shared helpers: the run-file reader, units, colours, axes, saving |
| ``inputs`` | checked user input: :func:`parse_frame_interval`, :func:`parse_window` |
| ``titles`` | figure titles and legend labels: :func:`scene_title` |
| ``outline`` | the boundary's outline y = f(x) and the drive's displacement D(t) |
| ``flights`` | flight arcs between impacts (exact parabola, or integrated with drag) |
| ``contacts`` | a phases run's path: flights, and rolling, sliding and held stretches |
| ``maps`` | :func:`return_map`, :func:`time_map` |
| ``phase`` | :func:`phase_plot`, :func:`phase_coordinates` |
| ``trajectory`` | :func:`trajectory`, :func:`default_window` |
| ``animation`` | :func:`animate` (GIF) |
| ``interactive`` | :func:`view`, :func:`write_view`: the interactive view, one HTML page |
| ``run`` | :func:`plot_run` (``billiard plot DIR``), :func:`load_run`, :func:`load_sides` |
| ``paper`` | :func:`paper_figure`, :func:`paper_phase_figure`, :func:`paper_models_figure`,
  :func:`paper_laws_figure` |
"""

from __future__ import annotations

from billiard.plot.animation import animate
from billiard.plot.common import RunDataError
from billiard.plot.flights import flight_positions
from billiard.plot.inputs import parse_frame_interval, parse_window
from billiard.plot.interactive import View, view, write_view
from billiard.plot.maps import return_map, time_map
from billiard.plot.outline import drive_offset
from billiard.plot.paper import (
    paper_figure,
    paper_laws_figure,
    paper_models_figure,
    paper_phase_figure,
)
from billiard.plot.phase import phase_coordinates, phase_plot
from billiard.plot.run import FIGURE_NAMES, load_run, load_sides, plot_run, read_scene
from billiard.plot.titles import scene_title
from billiard.plot.trajectory import default_window, trajectory

__all__ = [
    "FIGURE_NAMES",
    "RunDataError",
    "View",
    "animate",
    "default_window",
    "drive_offset",
    "flight_positions",
    "load_run",
    "load_sides",
    "paper_figure",
    "paper_laws_figure",
    "paper_models_figure",
    "paper_phase_figure",
    "parse_frame_interval",
    "parse_window",
    "phase_coordinates",
    "phase_plot",
    "plot_run",
    "read_scene",
    "return_map",
    "scene_title",
    "time_map",
    "trajectory",
    "view",
    "write_view",
]
