"""Plots and the camera filter, on a real short run."""

from __future__ import annotations

import math

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from billiard.camera import RunDataError, camera_filter, read_collisions
from billiard.cli import main
from billiard.plot import (
    load_run,
    paper_figure,
    paper_phase_figure,
    phase_coordinates,
    plot_run,
    return_map,
)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    code = main(["run", "parabola-5.4hz", "--collisions", "300", "--out", str(out),
                 "--no-plot"])
    assert code == 0
    return out


def test_plot_run_writes_readable_images(run_dir, tmp_path):
    paths = plot_run(run_dir, tmp_path, window=(250, 300))
    names = sorted(p.name for p in paths)
    assert names == ["animation.gif", "phase.png", "return_map.png", "time_map.png",
                     "trajectory.png"]
    for path in paths:
        if path.suffix == ".png":
            image = mpimg.imread(path)
            height, width = image.shape[:2]
            assert 400 <= width <= 2000 and 300 <= height <= 2000
            assert image.std() > 0.01  # not a blank canvas
        else:
            with Image.open(path) as gif:
                assert gif.n_frames > 10
            assert path.stat().st_size < 2_000_000


def test_paper_figures(run_dir, tmp_path):
    for draw in (paper_figure, paper_phase_figure):
        path = draw([run_dir, run_dir], tmp_path / f"{draw.__name__}.png", frame_interval=1 / 30)
        assert mpimg.imread(path).shape[1] > 600


def test_return_map_plots_consecutive_heights(run_dir):
    columns, _ = load_run(run_dir)
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    return_map(columns, ax)
    q2 = columns["q2"]
    datasets = [line.get_data() for line in ax.get_lines()]
    scale = [1.0, 1e3]  # the axes may be in metres or millimetres
    assert any(
        len(x) == len(q2) - 1 and np.allclose(np.asarray(x) / s, q2[:-1])
        and np.allclose(np.asarray(y) / s, q2[1:])
        for x, y in datasets for s in scale
    )


def test_camera_filter_keeps_what_a_camera_sees():
    t = np.array([0.0, 0.001, 0.1, 0.1005, 0.3])
    cols = {"t": t, "tof": np.array([0.0, 0.001, 0.099, 0.0005, 0.1995]),
            "n": np.arange(1, 6)}
    kept = camera_filter(cols, 1 / 30)
    assert list(kept["n"]) == [1, 3, 5]
    assert kept["tof"][1:] == pytest.approx([0.1, 0.2])
    with pytest.raises(ValueError):
        camera_filter(cols, 0.0)


def test_phase_normalization_on_constructed_rows():
    m, g = 1.3028e-4, 9.81
    scene = {"ball": {"mass": m}, "run": {"gravity": g}}
    h, v = 0.05, 0.7
    cols = {"q2": np.array([h, h]), "u4": np.array([0.0, v]),
            "energy": np.array([m * g * h, m * g * h + 0.5 * m * v * v])}
    x, y = phase_coordinates(cols, scene)
    assert (x[0], y[0]) == pytest.approx((0.0, 1.0))
    energy = m * g * h + 0.5 * m * v * v
    assert x[1] == pytest.approx(v / math.sqrt(2 * energy / m))
    assert y[1] == pytest.approx(m * g * h / energy)
    assert x[1] ** 2 + y[1] == pytest.approx(1.0)  # all energy in q2 and u4


def test_bad_run_directory_is_a_one_line_error(tmp_path):
    with pytest.raises(RunDataError) as info:
        read_collisions(tmp_path / "collisions.csv")
    assert "\n" not in str(info.value)
    (tmp_path / "collisions.csv").write_text("n,t,q2\n")
    with pytest.raises(RunDataError):
        plot_run(tmp_path)
