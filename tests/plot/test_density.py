"""Tests of density rendering: large point clouds drawn as counts per bin, small ones as
points (billiard.plot.density, and its use by the maps, the phase plot, the trajectory
and the animation)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from matplotlib.collections import QuadMesh
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D

from billiard import plot
from billiard.plot import density as density_module
from billiard.plot.density import (
    COUNT_LABEL,
    DENSITY_BINS,
    DENSITY_THRESHOLD,
    bin_counts,
    rasterize_if_large,
    use_density,
)
from tests.plot_support import bouncing_ball, scene_of, scene_toml, single_axes

# the module, not the function billiard.plot exports under the same name
trajectory_module = importlib.import_module("billiard.plot.trajectory")


def cloud(impacts: int, seed: int = 1) -> dict[str, np.ndarray]:
    """The columns the maps read, for ``impacts`` random impacts (heights 10 to 200 mm,
    times of flight 1 to 200 ms; none on the lid)."""
    rng = np.random.default_rng(seed)
    tof = rng.uniform(1e-3, 0.2, impacts)
    return {
        "n": np.arange(1, impacts + 1),
        "t": np.cumsum(tof),
        "q2": rng.uniform(0.01, 0.2, impacts),
        "tof": tof,
        "z": np.zeros(impacts),
    }


def colorbar_labels(ax) -> list[str]:
    figure = ax.get_figure()
    return [other.get_ylabel() for other in figure.axes if other is not ax]


def legend_texts(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().texts]


# --- counting --------------------------------------------------------------------------------


def test_bin_counts_match_numpy_histogram2d():
    rng = np.random.default_rng(7)
    x = rng.normal(0.5, 0.3, 20_000)
    y = rng.normal(0.2, 0.5, 20_000)
    # points on the edges, outside the ranges and not finite
    x[:6] = [0.0, 1.0, 1.0, -0.5, np.nan, 0.3]
    y[:6] = [-1.0, 1.0, -1.0, 0.0, 0.1, np.inf]
    x_range, y_range, bins = (0.0, 1.0), (-1.0, 1.0), (40, 25)
    counts = bin_counts(x, y, x_range, y_range, bins)
    finite = np.isfinite(x) & np.isfinite(y)
    expected, _, _ = np.histogram2d(x[finite], y[finite], bins=bins, range=[x_range, y_range])
    assert counts.shape == (25, 40)
    np.testing.assert_array_equal(counts, expected.T)
    assert counts[-1, -1] >= 1 and counts[0, -1] >= 1  # the upper edge is the last bin


def test_bin_counts_log_bins_and_weights():
    x = np.array([1e-3, 1e-2, 1e-1, 1.0, 0.0, -1.0])
    y = np.array([1e-3, 1e-3, 1.0, 1.0, 1.0, 1.0])
    counts = bin_counts(x, y, (1e-3, 1.0), (1e-3, 1.0), (3, 3), log=True)
    # three decades, one bin each: 1e-3 -> bin 0, 1e-2 -> bin 1, 1e-1 and 1 -> bin 2;
    # x <= 0 cannot be placed on log axes
    expected = np.zeros((3, 3), dtype=int)
    expected[0, 0] = expected[0, 1] = 1
    expected[2, 2] = 2
    np.testing.assert_array_equal(counts, expected)
    weighted = bin_counts(x, y, (1e-3, 1.0), (1e-3, 1.0), (3, 3), log=True, weight=0.25)
    np.testing.assert_allclose(weighted, 0.25 * expected)


def test_use_density_threshold():
    assert not use_density(DENSITY_THRESHOLD)
    assert use_density(DENSITY_THRESHOLD + 1)
    assert use_density(3, True) and not use_density(10**7, False)


def test_rasterize_if_large():
    fig, ax = single_axes()
    (small,) = ax.plot([0, 1], [0, 1])
    (large,) = ax.plot([0, 1], [0, 1])
    rasterize_if_large(small, DENSITY_THRESHOLD)
    rasterize_if_large(large, DENSITY_THRESHOLD + 1)
    assert not small.get_rasterized() and large.get_rasterized()


# --- the maps --------------------------------------------------------------------------------


def test_return_map_above_the_threshold_is_a_density_image():
    columns = cloud(DENSITY_THRESHOLD + 2)  # one pair more than the threshold
    fig, ax = single_axes()
    (image,) = plot.return_map(columns, ax)
    assert isinstance(image, AxesImage)
    counts = np.asarray(image.get_array())
    assert counts.shape == (DENSITY_BINS, DENSITY_BINS)
    assert counts.sum() == DENSITY_THRESHOLD + 1  # every pair, once
    # the image covers the axes' square view, and its counts are those of the pairs there
    lo, hi = ax.get_xlim()
    assert ax.get_ylim() == (lo, hi)
    np.testing.assert_allclose(image.get_extent(), [lo, hi, lo, hi])
    q2 = columns["q2"] * 1e3
    np.testing.assert_array_equal(counts, bin_counts(q2[:-1], q2[1:], (lo, hi), (lo, hi)))
    (label,) = colorbar_labels(ax)
    assert label.startswith(COUNT_LABEL) and "mm" in label
    assert f"model: all {DENSITY_THRESHOLD + 2} impacts (density)" in legend_texts(ax)
    assert "(mm)" in ax.get_xlabel() and "(mm)" in ax.get_ylabel()


def test_return_map_at_the_threshold_holds_the_points():
    columns = cloud(DENSITY_THRESHOLD + 1)  # as many pairs as the threshold
    fig, ax = single_axes()
    (line,) = plot.return_map(columns, ax)
    assert isinstance(line, Line2D)
    np.testing.assert_allclose(line.get_xdata(), columns["q2"][:-1] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), columns["q2"][1:] * 1e3)
    assert not ax.images and colorbar_labels(ax) == []


def test_density_can_be_forced_either_way():
    columns = cloud(500)
    fig, ax = single_axes()
    (image,) = plot.return_map(columns, ax, density=True)
    assert isinstance(image, AxesImage) and np.asarray(image.get_array()).sum() == 499
    big = cloud(DENSITY_THRESHOLD + 10)
    fig, ax = single_axes()
    (line,) = plot.time_map(big, ax, density=False)
    assert isinstance(line, Line2D) and line.get_xdata().size == DENSITY_THRESHOLD + 9


def test_time_map_density_in_seconds_and_on_log_axes():
    columns = cloud(3000)
    fig, ax = single_axes()
    (image,) = plot.time_map(columns, ax, density=True)
    assert isinstance(image, AxesImage)
    assert np.asarray(image.get_array()).sum() == 2999
    (label,) = colorbar_labels(ax)
    assert label.startswith(COUNT_LABEL) and " s " in label
    assert "(s)" in ax.get_xlabel() and "(s)" in ax.get_ylabel()
    fig, ax = single_axes()
    (mesh,) = plot.time_map(columns, ax, density=True, log=True)
    assert isinstance(mesh, QuadMesh) and ax.get_xscale() == "log"
    assert np.asarray(mesh.get_array()).sum() == 2999
    assert "decades" in colorbar_labels(ax)[0]


# --- the phase plot ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def bounce():
    return bouncing_ball(160, amplitude=1e-3, frequency=25.0, e=0.5), scene_of(scene_toml())


def test_phase_plot_above_the_threshold_is_a_density_image(bounce, monkeypatch):
    columns, scene = bounce
    x, y = plot.phase_coordinates(columns, scene)
    finite = int((np.isfinite(x) & np.isfinite(y)).sum())
    assert finite > 100
    monkeypatch.setattr(density_module, "DENSITY_THRESHOLD", 100)
    fig, ax = single_axes()
    (image,) = plot.phase_plot(columns, scene, ax)
    assert isinstance(image, AxesImage)
    assert np.asarray(image.get_array()).sum() == finite
    np.testing.assert_allclose(image.get_extent(), [*ax.get_xlim(), *ax.get_ylim()])
    (label,) = colorbar_labels(ax)
    assert label.startswith(COUNT_LABEL)
    monkeypatch.setattr(density_module, "DENSITY_THRESHOLD", 160)
    fig, ax = single_axes()
    (line,) = plot.phase_plot(columns, scene, ax)
    assert isinstance(line, Line2D)
    np.testing.assert_allclose(line.get_xdata(), x)


# --- the trajectory and the animation of a long window ----------------------------------


def test_trajectory_of_a_long_window_is_the_flight_time_per_bin(bounce, monkeypatch, tmp_path):
    columns, scene = bounce
    monkeypatch.setattr(density_module, "DENSITY_THRESHOLD", 100)
    monkeypatch.setattr(trajectory_module, "PATH_SAMPLES", 5000)
    fig, ax = single_axes()
    drawn = plot.trajectory(columns, scene, ax, (1, 161))
    image = drawn["arcs"]
    assert isinstance(image, AxesImage) and drawn["impacts"] == []
    # samples evenly spaced in time, each counting the time step: the image holds the
    # window's whole duration (every sample is inside the view)
    t = columns["t"]
    step = (t[-1] - t[0]) / 4999
    np.testing.assert_allclose(np.asarray(image.get_array()).sum(), 5000 * step, rtol=1e-12)
    assert colorbar_labels(ax)[0].startswith(trajectory_module.FLIGHT_TIME_LABEL)
    # a short window keeps its arcs as a line
    fig, ax = single_axes()
    drawn = plot.trajectory(columns, scene, ax, (100, 161))
    assert isinstance(drawn["arcs"], Line2D) and drawn["impacts"]
    # the animation of the long window draws the path's density behind the ball
    path = plot.animate(columns, scene, tmp_path / "a.gif", window=(1, 161), max_frames=5)
    assert path.stat().st_size > 0
