"""Sweep plots: labelled colour bars, a constant map drawn as one value, whole-number
periods in discrete colours, and titles that name the base scene's --set changes."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from billiard import load_scene
from billiard.sweep import Sweep, parse_vary
from billiard.sweep.plots import (
    bifurcation_figure,
    constant_value,
    heatmaps_figure,
    plot_sweep,
)
from billiard.sweep.units import variable_name

matplotlib.use("Agg")


def _sweep(changes=("contact.model=phases",), **settings) -> Sweep:
    scene = load_scene("parabola-5.4hz", overrides=list(changes))
    axes = (parse_vary("drive.frequency=5.0:5.4:3"), parse_vary("drive.amplitude=0.02,0.025"))
    return Sweep(scene, axes, impacts=300, transient=100, changes=tuple(changes), **settings)


def _data(sweep: Sweep, **fields) -> dict:
    """Result-file arrays of a sweep whose points are all ok (fields override)."""
    shape = sweep.shape
    data = {variable_name(a.key): np.asarray(a.values, dtype=float) for a in sweep.axes} | {
        "status": np.full(shape, "ok", dtype=object),
        "attractor": np.full(shape, "periodic", dtype=object),
        "period": np.full(shape, 2, dtype=np.int32),
        "height_mean": np.full(shape, 0.075),
        "lyapunov": np.full(shape, np.nan),
        "rest_height": np.full(shape, 0.00785),
        "last_height": np.full((*shape, 4), 0.075),
        "last_tof": np.full((*shape, 4), 0.0926),
    }
    return data | fields


def _colour_bars(fig) -> list:
    """The figure's colour bar axes (matplotlib marks them with ``_colorbar``)."""
    return [ax for ax in fig.axes if getattr(ax, "_colorbar", None) is not None]


def _cell_colours(fig, panel: int) -> set:
    """The distinct colours of a map's drawn cells (masked cells are not drawn)."""
    fig.canvas.draw()
    mesh = fig.axes[panel].collections[0]
    shown = ~np.ma.getmaskarray(mesh.get_array()).ravel()
    return {tuple(c) for c in mesh.to_rgba(mesh.get_array().ravel())[shown]}


def test_constant_value_detects_rounding_only():
    # the same orbit at two masses without air drag: equal to 6e-11 relative
    noisy = np.array([[0.0753465998259358, 0.0753465998305629], [np.nan, 0.0753465998259358]])
    assert constant_value(noisy) == pytest.approx(0.0753465998, rel=1e-9)
    assert constant_value(np.array([0.075, 0.0751])) is None
    # within a resolution: 2 nm apart, one value to a sweep that resolves 10 um
    near = np.array([0.07534659, 0.075346592])
    assert constant_value(near) is None
    assert constant_value(near, 1e-5) == pytest.approx(0.075346591)
    assert constant_value(np.zeros(4)) == 0.0
    assert constant_value(np.full(3, np.nan)) is None


def test_constant_height_map_is_one_colour_with_its_value_and_unit():
    sweep = _sweep()
    heights = 0.0753465998259358 + np.array([[0.0, 4.6e-12], [1e-13, 0.0], [2e-12, 3e-12]])
    fig = heatmaps_figure(sweep, _data(sweep, height_mean=heights))
    bars = _colour_bars(fig)
    assert len(bars) == 2  # period and height: every map has its colour bar
    height_bar = bars[1]._colorbar
    assert height_bar.ax.get_ylabel() == "mean impact height q2 (m)"
    ticks = [t.get_text() for t in height_bar.ax.get_yticklabels()]
    assert ticks == ["0.0753466"]
    notes = [t.get_text() for t in fig.axes[1].texts]
    assert notes == ["one value: 0.0753466\n(all within 1e-05 m, the sweep's tolerance)"]
    assert len(_cell_colours(fig, 1)) == 1  # one colour, no noise


def test_varying_height_map_keeps_a_continuous_labelled_bar():
    sweep = _sweep()
    heights = np.array([[0.03, 0.05], [0.06, 0.075], [0.08, 0.11]])
    fig = heatmaps_figure(sweep, _data(sweep, height_mean=heights))
    bar = _colour_bars(fig)[1]._colorbar
    assert bar.ax.get_ylabel() == "mean impact height q2 (m)"
    assert len(_cell_colours(fig, 1)) == 6


def test_period_map_has_discrete_colours_and_whole_number_ticks():
    sweep = _sweep()
    period = np.array([[2, 2], [3, 8], [0, 2]], dtype=np.int32)  # 0: no period, blank
    fig = heatmaps_figure(sweep, _data(sweep, period=period))
    bar = _colour_bars(fig)[0]._colorbar
    assert bar.ax.get_ylabel() == "period (impacts per repetition of the state)"
    assert list(bar.get_ticks()) == [2.0, 3.0, 8.0]
    assert bar.cmap.N == 7  # one colour per whole number from 2 to 8
    assert len(_cell_colours(fig, 0)) == 3  # 2, 3 and 8 (the blank cell is masked)


def test_period_map_without_any_period_says_so():
    sweep = _sweep()
    fig = heatmaps_figure(sweep, _data(sweep, period=np.zeros(sweep.shape, dtype=np.int32)))
    bar = _colour_bars(fig)[0]._colorbar
    assert list(bar.get_ticks()) == []
    assert [t.get_text() for t in fig.axes[0].texts] == ["no period found"]


def test_lyapunov_bar_is_labelled():
    sweep = _sweep()
    lyap = np.array([[0.1, -0.2], [0.05, 0.0], [0.3, -0.01]])
    fig = heatmaps_figure(sweep, _data(sweep, lyapunov=lyap))
    labels = [ax._colorbar.ax.get_ylabel() for ax in _colour_bars(fig)]
    assert labels[2] == "Lyapunov exponent (1/impact)"
    assert all(labels)


def test_titles_name_the_set_changes():
    sweep = _sweep(changes=("contact.model=phases", "drive.phase=0.5"))
    fig = heatmaps_figure(sweep, _data(sweep))
    title = " ".join(fig._suptitle.get_text().split())
    assert "parabola-5.4hz with contact.model=phases, drive.phase=0.5" in title
    one = Sweep(sweep.scene, (sweep.axes[0],), impacts=300, transient=100, changes=sweep.changes)
    data = _data(one)
    fig = bifurcation_figure(one, data)
    title = " ".join(fig.axes[0].get_title().split())
    assert "with contact.model=phases, drive.phase=0.5" in title


def test_bifurcation_draws_a_ball_without_impacts_at_its_resting_height(tmp_path):
    one = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=5.0:5.4:3"),))
    shape = one.shape
    heights = np.full((*shape, 4), np.nan)
    heights[2] = 0.075
    data = _data(
        one,
        attractor=np.array(["rolling", "resting", "periodic"], dtype=object),
        last_height=heights,
        last_tof=np.where(np.isnan(heights), np.nan, 0.0926),
    )
    fig = bifurcation_figure(one, data)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "rolling, no impacts: at the resting height" in labels
    assert "resting, no impacts: at the resting height" in labels
    assert "periodic (1)" in labels
    paths = plot_sweep(one, data, tmp_path)
    assert [p.name for p in paths] == ["bifurcation.png"] and paths[0].stat().st_size > 0
