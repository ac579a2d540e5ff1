"""Tests of whole-run plotting: plot_run, the paper figures, and ``billiard plot`` (the
command line in billiard.cli), with its errors."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import matplotlib
import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib._pylab_helpers import Gcf
from PIL import Image

from billiard import plot
from billiard.cli import main
from billiard.plot import density as density_module
from billiard.plot import run as plot_run_module
from billiard.plot.common import new_figure, save
from billiard.runfile.figure_files import DEFAULT_DPI, figure_names
from billiard.runfile.record import RunDataError, write_collisions
from billiard.scene.scene import SceneError
from tests.plot_support import (
    bouncing_ball,
    check_gif,
    check_png,
    engine_run,
    make_run,
    scene_toml,
    static_columns,
    static_toml,
)

matplotlib.use("Agg")


@pytest.fixture(scope="module", autouse=True)
def private_curve_cache(tmp_path_factory):
    """Curve expressions are derived once, into a private BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard-home")))
        yield


@pytest.fixture(scope="module")
def bounce_columns() -> dict[str, np.ndarray]:
    return bouncing_ball(160, amplitude=1e-3, frequency=25.0, e=0.5)


@pytest.fixture
def bounce_run(tmp_path: Path, bounce_columns) -> Path:
    return make_run(tmp_path / "bounce", bounce_columns, scene_toml())


@pytest.fixture
def static_run(tmp_path: Path) -> Path:
    """A horizontally driven scene with zero amplitude (a still boundary), its curve given
    as an expression: the ball bounces on the vertex at the constant height c + r."""
    return make_run(tmp_path / "still", static_columns(), static_toml())


# --- whole runs ----------------------------------------------------------------------------


def test_plot_run_writes_every_figure(bounce_run):
    managers = Gcf.get_num_fig_managers()
    written = plot.plot_run(bounce_run)
    assert [p.name for p in written] == list(plot.FIGURE_NAMES)
    assert all(p.parent == bounce_run for p in written)
    for path in written[:-1]:
        check_png(path, dpi=DEFAULT_DPI)
        assert mpimg.imread(path).shape[1] == 6 * DEFAULT_DPI  # 6 inches wide
    check_gif(written[-1])
    assert Gcf.get_num_fig_managers() == managers  # no pyplot figure left behind


def test_every_axis_is_labelled_with_its_unit(bounce_run, monkeypatch):
    labels: dict[str, list[tuple[str, str]]] = {}
    texts: dict[str, list[str]] = {}
    save = plot_run_module.save

    def capture(fig, path, **options):
        labels[Path(path).name] = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
        texts[Path(path).name] = [
            t.get_text() for legend in fig.legends for t in [legend.get_title(), *legend.texts]
        ]
        return save(fig, path, **options)

    monkeypatch.setattr(plot_run_module, "save", capture)
    plot.plot_run(bounce_run, frame_interval=0.02, gif=False)
    units = {
        "return_map.png": ("(mm)", "(mm)"),
        "time_map.png": ("(s)", "(s)"),
        "phase.png": ("(m/s)", "(m)"),
        "trajectory.png": ("(mm)", "(mm)"),
    }
    assert set(labels) == set(units)
    for name, (x_unit, y_unit) in units.items():
        ((xlabel, ylabel),) = labels[name]
        assert x_unit in xlabel and y_unit in ylabel, name
    # the phase figure says what E0, h0, m and g are, with units
    caption = " ".join(texts["phase.png"])
    assert "$E_0$ (J): kinetic energy of translation (spin left out)" in caption
    assert "$h_0$ (m): the ball's centre at rest at the bottom" in caption
    assert "m (kg)" in caption and "g (m/s$^2$)" in caption
    assert any("camera, frame 20 ms" in t for t in texts["return_map.png"])


def test_plot_run_camera_window_out_dir_no_gif(static_run, tmp_path):
    out = tmp_path / "figures"
    written = plot.plot_run(static_run, out, frame_interval=1 / 30, window=(3, 30), gif=False)
    assert [p.name for p in written] == list(plot.FIGURE_NAMES[:-1])
    assert all(p.parent == out for p in written)
    for path in written:
        check_png(path, dpi=DEFAULT_DPI)
    assert not (static_run / "return_map.png").exists()


def test_animation_of_a_still_boundary(static_run, tmp_path):
    columns, scene = plot.load_run(static_run)
    path = plot.animate(columns, scene, tmp_path / "a.gif", window=(1, 10), max_frames=40)
    check_gif(path)
    with Image.open(path) as gif:
        assert gif.n_frames == 40


def test_paper_figures(bounce_run, static_run, tmp_path):
    path = plot.paper_figure(
        [bounce_run, static_run, bounce_run], tmp_path / "fig2.png", frame_interval=1 / 30
    )
    check_png(path, min_width=900)
    path = plot.paper_phase_figure([bounce_run, static_run], tmp_path / "fig3.png")
    check_png(path, min_width=600)


# --- formats, resolution, titles ----------------------------------------------------------

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF-"}


def check_format_of(path: Path, fmt: str) -> None:
    head = path.read_bytes()[:400]
    if fmt == "svg":
        assert head.startswith(b"<?xml") and b"<svg" in head
    else:
        assert head.startswith(MAGIC[fmt])


@pytest.mark.parametrize(
    "fmt", ["png", *(pytest.param(f, marks=pytest.mark.slow) for f in ("svg", "pdf"))]
)
def test_each_format_writes_files_of_that_format(bounce_run, tmp_path, fmt):
    written = plot.plot_run(bounce_run, tmp_path, format=fmt, dpi=30, gif=False)
    assert [p.name for p in written] == list(figure_names(fmt)[:4])
    assert [p.suffix for p in written] == [f".{fmt}"] * 4
    for path in written:
        check_format_of(path, fmt)


def test_vector_figures_are_reproducible(tmp_path):
    for suffix in ("svg", "pdf"):
        files = []
        for name in ("a", "b"):
            fig = new_figure()
            ax = fig.add_subplot()
            ax.plot([0, 1], [1, 0], label="line")
            ax.legend()
            files.append(save(fig, tmp_path / f"{name}.{suffix}", dpi=123).read_bytes())
        assert files[0] == files[1], suffix


def capture_figures(monkeypatch) -> dict[str, dict]:
    """What plot_run's figures hold when saved: size, titles and images, by file name."""
    seen: dict[str, dict] = {}
    save_figure = plot_run_module.save

    def capture(fig, path, **options):
        seen[Path(path).name] = {
            "inches": tuple(fig.get_size_inches()),
            "suptitle": fig.get_suptitle(),
            "axes titles": [t for ax in fig.axes for t in (ax.get_title(), ax.get_title("left"))],
            "images": [im for ax in fig.axes for im in ax.get_images()],
            "lines": [line for ax in fig.axes for line in ax.get_lines()],
        }
        return save_figure(fig, path, **options)

    monkeypatch.setattr(plot_run_module, "save", capture)
    return seen


@pytest.mark.slow  # also in test_figure_options, test_density
def test_dpi_sets_the_png_size_and_titles_are_drawn(bounce_run, tmp_path, monkeypatch):
    seen = capture_figures(monkeypatch)
    written = plot.plot_run(bounce_run, tmp_path, dpi=40, gif=False)
    for path in written:
        width, height = seen[path.name]["inches"]
        with Image.open(path) as image:
            assert image.size[0] == 6 * 40 == round(width * 40)  # 6 inches wide
            assert abs(image.size[1] - height * 40) <= 1
            assert image.info["dpi"] == pytest.approx((40, 40), abs=0.05)
        assert seen[path.name]["suptitle"].startswith("bounce, 160 impacts")
    assert any("impacts" in t for t in seen["trajectory.png"]["axes titles"])


@pytest.mark.slow  # also in test_figure_options, test_density
def test_no_title_removes_the_titles(bounce_run, tmp_path, monkeypatch):
    seen = capture_figures(monkeypatch)
    written = plot.plot_run(bounce_run, tmp_path, title=False, dpi=20, gif=False)
    assert [p.name for p in written] == list(figure_names()[:4])
    for path in written:
        assert seen[path.name]["suptitle"] == "", path.name
        assert not any(seen[path.name]["axes titles"]), path.name


@pytest.mark.parametrize(("options", "problem"), [
    ({"format": "gif"}, "figure format must be one of png, svg, pdf, got 'gif'"),
    ({"dpi": 0}, "figure dpi must be between 20 and 1200 pixels per inch, got 0"),
    ({"dpi": "high"}, "figure dpi must be a whole number of pixels per inch, got 'high'"),
])  # fmt: skip
def test_bad_format_or_dpi_is_refused_before_drawing(bounce_run, tmp_path, options, problem):
    with pytest.raises(RunDataError) as info:
        plot.plot_run(bounce_run, tmp_path / "out", **options)
    assert str(info.value) == problem
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # also in test_figure_options, test_density
def test_large_clouds_are_density_images_small_ones_points(bounce_run, tmp_path, monkeypatch):
    # 159 pairs in the maps are above a threshold of 158; 113 normalized phase points
    # (those with E0 > 0) are below it
    monkeypatch.setattr(density_module, "DENSITY_THRESHOLD", 158)
    seen = capture_figures(monkeypatch)
    plot.plot_run(bounce_run, tmp_path, dpi=20, gif=False, window=(None, None))
    for name in ("return_map.png", "time_map.png"):
        (image,) = seen[name]["images"]
        assert np.asarray(image.get_array()).sum() == 159, name
    x, y = plot.phase_coordinates(*plot.load_run(bounce_run))
    assert seen["phase.png"]["images"] == []
    dots = [line for line in seen["phase.png"]["lines"] if line.get_marker() == "o"]
    np.testing.assert_array_equal(dots[0].get_xdata(), x)
    np.testing.assert_array_equal(dots[0].get_ydata(), y)
    assert len(seen["trajectory.png"]["images"]) == 1  # 160 impacts: the path's density


# --- billiard plot -------------------------------------------------------------------------


@pytest.mark.slow  # also in test_figure_options, test_density
def test_command_line(bounce_run, tmp_path, capsys):
    out = tmp_path / "o"
    args = ["plot", str(bounce_run), "--out", str(out), "--frame-interval", "1/30"]
    assert main([*args, "--window", "2:12", "--no-gif"]) == 0
    printed = capsys.readouterr().out
    assert printed.count("wrote ") == 4 and str(out / "trajectory.png") in printed
    assert main(["plot", str(bounce_run), "--window", "150:", "--no-gif"]) == 0
    assert capsys.readouterr().out.count("wrote ") == 4
    assert (bounce_run / "trajectory.png").exists()


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (["--frame-interval", "-1"], "frame interval '-1' must be a positive number of seconds"),
        (["--frame-interval", "1/0"], "frame interval '1/0' must be a positive number of seconds"),
        (["--frame-interval", "0"], "must be a positive number of seconds"),
        (["--window", "5"], "window '5': expected N0:N1"),
        (["--window", "a:b"], "must be whole impact numbers"),
        (["--window", "500:600"], "window 500:600 holds no impacts"),
    ],
)
def test_command_line_bad_arguments(bounce_run, capsys, extra, problem):
    assert main(["plot", str(bounce_run), "--no-gif", *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1
    assert problem in err
    assert not (bounce_run / "return_map.png").exists()


def test_command_line_missing_run(tmp_path, capsys):
    assert main(["plot", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing: not a directory" in err


def test_output_directory_under_a_regular_file(bounce_run, tmp_path, capsys):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory\n")
    out = blocker / "figures"
    with pytest.raises(RunDataError, match="^[^\n]*a-file/figures: cannot create"):
        plot.plot_run(bounce_run, out, gif=False)
    assert main(["plot", str(bounce_run), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1
    assert str(out) in err


def test_read_only_run_directory(bounce_run, capsys):
    mode = bounce_run.stat().st_mode
    bounce_run.chmod(0o555)
    try:
        if os.access(bounce_run, os.W_OK):
            pytest.skip("the directory stays writable (running as root)")
        assert main(["plot", str(bounce_run), "--no-gif"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"{bounce_run}: cannot write" in err
    finally:
        bounce_run.chmod(stat.S_IMODE(mode))


def test_figure_that_cannot_be_written(bounce_run, capsys):
    # a directory where a figure should go: saving it fails after the checks
    (bounce_run / "phase.png").mkdir()
    assert main(["plot", str(bounce_run), "--no-gif"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{bounce_run / 'phase.png'}: cannot write the figure" in err


# --- bad input -----------------------------------------------------------------------------

HEADER = "n,t,q1,q2,v1,v2,omega,u4,un,tof,regime,z,energy,wall,Rt,Rn"
ROW = "1,0.1,0,0.008,0,0.1,0,0,0.1,0.1,stick,0,1e-5,0,0,0"


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        (None, "file not found"),
        ("", "empty file"),
        (HEADER + "\n", "no impacts to plot"),
        ("n,t,q1\n1,0,0\n", "missing column(s) q2"),
        (HEADER + "\n" + ROW + "\n1,0.2,0\n", "line 3: expected 16 fields, got 3"),
        (HEADER + "\n" + ROW.replace("0.008", "high") + "\n", "column q2: 'high'"),
        (HEADER + "\n" + ROW + "\n" + ROW.replace("1,0.1", "2,0.05", 1) + "\n", "decrease"),
    ],
)
def test_bad_collisions_file(tmp_path, text, problem):
    run = tmp_path / "run"
    run.mkdir()
    (run / "scene.toml").write_text(scene_toml())
    csv_path = run / "collisions.csv"
    if text is not None:
        csv_path.write_text(text)
    with pytest.raises(RunDataError) as info:
        plot.plot_run(run)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(csv_path))
    assert problem in message


@pytest.mark.parametrize(
    ("toml", "error", "problem"),
    [
        (None, RunDataError, "scene.toml: file not found"),
        ("name = [unclosed\n", SceneError, "scene.toml: invalid TOML"),
        (scene_toml().replace("mass = ", "mass = -"), SceneError, "'ball.mass'"),
        (scene_toml() + "[wind]\nspeed = 3\n", SceneError, "wind"),
        (scene_toml().replace('drag = "none"', 'drag = "stokes"'), SceneError, "air.drag"),
    ],
)
def test_bad_scene_file(tmp_path, bounce_columns, capsys, toml, error, problem):
    run = tmp_path / "run"
    run.mkdir()
    write_collisions(run / "collisions.csv", bounce_columns)
    if toml is not None:
        (run / "scene.toml").write_text(toml)
    with pytest.raises(error, match="^[^\n]*$") as info:
        plot.plot_run(run)
    assert problem in str(info.value) and str(run / "scene.toml") in str(info.value)
    assert main(["plot", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1 and problem in err


def test_bad_window_and_interval(bounce_run):
    with pytest.raises(RunDataError, match="window 500:600 holds no impacts"):
        plot.plot_run(bounce_run, window=(500, 600))
    with pytest.raises(RunDataError, match="frame interval"):
        plot.plot_run(bounce_run, frame_interval=0.0)
    with pytest.raises(RunDataError, match="not a directory"):
        plot.plot_run(bounce_run / "nothing")


def test_unknown_curve_is_reported(tmp_path, bounce_columns):
    run = make_run(
        tmp_path / "run",
        bounce_columns,
        scene_toml()
        .replace('curve = "parabola"', 'curve = "no_such_curve"')
        .replace("[boundary.parameters]\na = 26.0\nc = 0.0063\n", ""),
    )
    with pytest.raises(RunDataError, match="no_such_curve") as info:
        plot.plot_run(run, gif=False)
    assert "\n" not in str(info.value)


# --- a real run of the engine --------------------------------------------------------------


@pytest.fixture(scope="module")
def real_run(tmp_path_factory) -> Path:
    return engine_run(tmp_path_factory.mktemp("engine"))


def test_engine_run_plots(real_run, tmp_path):
    columns, scene = plot.load_run(real_run)
    assert columns["t"].size == 300
    written = plot.plot_run(real_run, tmp_path, frame_interval=1 / 30, window=(250, 300))
    assert [p.name for p in written] == list(plot.FIGURE_NAMES)
    for path in written[:-1]:
        check_png(path, dpi=DEFAULT_DPI)
    check_gif(written[-1])
    x, y = plot.phase_coordinates(columns, scene)
    # The run starts at rest at the bottom, the default reference's zero: heights from 0.
    assert np.all((np.abs(x) <= 1) & (y >= -1e-9) & (y <= 1))
    assert np.all(x**2 + y <= 1 + 1e-9)  # q2 >= h0: the point lies under the energy bound


def test_engine_run_billiard_plot_command(real_run, capsys):
    assert main(["plot", str(real_run), "--window", "280:300", "--no-gif"]) == 0
    assert capsys.readouterr().out.count("wrote ") == 4
    assert (real_run / "trajectory.png").exists()
