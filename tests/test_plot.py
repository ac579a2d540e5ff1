"""Tests of billiard.camera and billiard.plot on small synthetic runs.

The main fixture is a physically consistent run: a ball bouncing vertically at the vertex
x = 0 of the parabola f(x) = 26 x^2 + 0.0063 (m) while the boundary is shaken vertically,
D(t) = A sin(2 pi f t). At the vertex the contact is the bottom point (tangent angle 0, the
radius of curvature 1/(2a) = 19 mm exceeds the ball's radius), so the centre's height at
impact n is known: q2,n = c + r + D(t_n).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib
import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib._pylab_helpers import Gcf
from matplotlib.figure import Figure
from PIL import Image
from scipy.optimize import brentq

from billiard import plot
from billiard.camera import camera_filter
from billiard.record import (
    REQUIRED_COLUMNS,
    RunDataError,
    read_collisions,
    write_collisions,
)

matplotlib.use("Agg")

A_CURVE, C_CURVE = 26.0, 0.0063  # parabola a (1/m), c (m)
RADIUS, MASS, K = 1.55e-3, 1.3028e-4, 0.4
G = 9.81
COLUMN_NAMES = list(REQUIRED_COLUMNS) + ["wall", "Rt", "Rn"]


def scene_toml(
    *,
    curve: str = "parabola",
    amplitude: float = 1e-3,
    frequency: float = 25.0,
    direction: str = "vertical",
    restitution: float = 0.5,
    name: str = "bounce",
) -> str:
    params = "[boundary.parameters]\na = 26.0\nc = 0.0063\n" if curve == "parabola" else ""
    return f"""name = "{name}"
description = "synthetic run for the plotting tests"

[boundary]
curve = "{curve}"
ceiling = 0.15
escape_height = 1.0

{params}
[drive]
amplitude = {amplitude}
frequency = {frequency}
direction = "{direction}"
phase = 0.0

[ball]
radius = {RADIUS}
mass = {MASS}
inertia_factor = {K}

[contact]
restitution = {restitution}
mu_static = 0.61
mu_kinetic = 0.47
elastic_below = 0.01

[air]
drag = "none"

[run]
gravity = {G}
"""


def bouncing_ball(
    impacts: int,
    *,
    amplitude: float,
    frequency: float,
    e: float,
    elastic_below: float = 0.01,
    drop: float = 0.004,
) -> dict[str, np.ndarray]:
    """Impacts of a ball dropped from rest, `drop` m above contact, onto the vertex of the
    vertically shaken parabola (drag off, no spin: the tangential velocity stays 0)."""
    w = 2 * math.pi * frequency
    rest = C_CURVE + RADIUS

    def plate(t):
        return rest + amplitude * np.sin(w * t)

    t, q2, v2 = 0.0, rest + drop, 0.0
    t_prev = 0.0
    rows = []
    step = 2e-5
    for n in range(1, impacts + 1):
        tau = np.arange(1, 200_001) * step
        gap = q2 + v2 * tau - 0.5 * G * tau**2 - plate(t + tau)
        first_open = int(np.argmax(gap > 0))
        j = first_open + int(np.argmax(gap[first_open:] < 0))
        assert gap[j] < 0, "no impact found"

        def h(s, t=t, q2=q2, v2=v2):
            return q2 + v2 * s - 0.5 * G * s * s - plate(t + s)

        s = brentq(h, tau[j - 1], tau[j], xtol=1e-15)
        t += s
        v2 -= G * s
        q2 = float(plate(t))
        vb = amplitude * w * math.cos(w * t)
        relative = v2 - vb
        elastic = abs(relative) < elastic_below
        v2 = vb - (1.0 if elastic else e) * relative
        energy = 0.5 * MASS * v2**2 + MASS * G * q2
        rows.append(
            (
                n,
                t,
                0.0,
                q2,
                0.0,
                v2,
                0.0,
                0.0,
                v2,
                t - t_prev,
                "elastic" if elastic else "stick",
                0.0,
                energy,
                0,
                0.0,
                MASS * (v2 - (relative + vb)),
            )
        )
        t_prev = t
    return {name: np.array([row[i] for row in rows]) for i, name in enumerate(COLUMN_NAMES)}


def make_run(directory: Path, columns: dict[str, np.ndarray], toml: str) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    write_collisions(directory / "collisions.csv", columns)
    (directory / "scene.toml").write_text(toml)
    return directory


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
    columns = bouncing_ball(40, amplitude=0.0, frequency=5.4, e=0.8, drop=0.02)
    toml = scene_toml(
        curve="26*x**2 + 0.0063",
        amplitude=0.0,
        frequency=5.4,
        direction="horizontal",
        restitution=0.8,
        name="still",
    )
    return make_run(tmp_path / "still", columns, toml)


def single_axes() -> tuple[Figure, object]:
    fig = Figure()
    return fig, fig.add_subplot()


# --- the fixture itself ------------------------------------------------------------------


def test_fixture_is_consistent(bounce_columns):
    c = bounce_columns
    expected = C_CURVE + RADIUS + 1e-3 * np.sin(2 * np.pi * 25.0 * c["t"])
    np.testing.assert_allclose(c["q2"], expected, atol=1e-12)
    np.testing.assert_allclose(np.diff(c["t"]), c["tof"][1:], atol=1e-12)
    assert np.ptp(c["q2"]) > 1e-3  # the heights do vary
    # Each flight ends where the next impact is: drag-free parabola from the last impact.
    end = c["q2"][:-1] + c["v2"][:-1] * c["tof"][1:] - 0.5 * G * c["tof"][1:] ** 2
    np.testing.assert_allclose(end, c["q2"][1:], atol=1e-9)


# --- camera ------------------------------------------------------------------------------


def hand_columns(times):
    t = np.asarray(times, dtype=float)
    tof = np.diff(t, prepend=-0.05)
    return {
        "n": np.arange(1.0, t.size + 1),
        "t": t,
        "q2": 0.01 + t,
        "tof": tof,
        "regime": np.array(["stick"] * t.size),
    }


def test_camera_filter_keeps_first_and_drops_rapid_impacts():
    kept = camera_filter(hand_columns([0, 0.001, 0.1, 0.1005, 0.3]), 1 / 30)
    np.testing.assert_array_equal(kept["t"], [0.0, 0.1, 0.3])
    np.testing.assert_array_equal(kept["n"], [1, 3, 5])
    np.testing.assert_allclose(kept["q2"], [0.01, 0.11, 0.31])
    # tof: time since the previous kept impact; the first keeps its own tof.
    np.testing.assert_allclose(kept["tof"], [0.05, 0.1, 0.2])
    assert list(kept["regime"]) == ["stick"] * 3


def test_camera_filter_measures_from_the_last_kept_impact():
    # A burst every 10 ms seen with a 25 ms frame: every third impact is kept, measured
    # from the previous *kept* one (not from the previous impact).
    kept = camera_filter(hand_columns(np.arange(10) * 0.01), 0.025)
    np.testing.assert_allclose(kept["t"], [0.0, 0.03, 0.06, 0.09])
    np.testing.assert_allclose(kept["tof"][1:], [0.03, 0.03, 0.03])


def test_camera_filter_is_strict_at_one_frame():
    kept = camera_filter(hand_columns([0.0, 0.5, 1.0, 1.75]), 0.5)
    np.testing.assert_array_equal(kept["t"], [0.0, 1.0, 1.75])


def test_camera_filter_edge_cases():
    empty = camera_filter(hand_columns([]), 0.1)
    assert all(v.size == 0 for v in empty.values())
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError):
            camera_filter(hand_columns([0, 1]), bad)
    with pytest.raises(ValueError):
        camera_filter(hand_columns([0.2, 0.1]), 0.01)
    # Without rapid impacts, everything is kept and tof is unchanged.
    columns = hand_columns([0, 0.2, 0.4])
    kept = camera_filter(columns, 1 / 30)
    np.testing.assert_allclose(kept["tof"], columns["tof"])


def test_read_collisions_round_trip(tmp_path, bounce_columns):
    path = write_collisions(tmp_path / "c.csv", bounce_columns)
    back = read_collisions(path)
    assert list(back) == COLUMN_NAMES
    assert back["regime"].dtype.kind == "U"
    assert set(back["regime"]) <= {"stick", "elastic"}
    for name in COLUMN_NAMES:
        if name not in ("regime", "wall"):
            assert back[name].dtype == (np.int64 if name == "n" else float)
            np.testing.assert_array_equal(back[name], bounce_columns[name])


# --- figure data ---------------------------------------------------------------------------


def test_return_map_plots_consecutive_heights(bounce_columns):
    fig, ax = single_axes()
    (line,) = plot.return_map(bounce_columns, ax)
    q2 = bounce_columns["q2"]
    np.testing.assert_allclose(line.get_xdata(), q2[:-1] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), q2[1:] * 1e3)
    assert "mm" in ax.get_xlabel() and "mm" in ax.get_ylabel()


def test_return_map_and_time_map_with_camera(bounce_columns):
    interval = 0.02
    seen = camera_filter(bounce_columns, interval)
    assert 2 < seen["t"].size < bounce_columns["t"].size
    fig, ax = single_axes()
    model, camera = plot.return_map(bounce_columns, ax, frame_interval=interval)
    np.testing.assert_allclose(camera.get_xdata(), seen["q2"][:-1] * 1e3)
    assert "33" not in camera.get_label() and "20 ms" in camera.get_label()
    fig, ax = single_axes()
    model, camera = plot.time_map(bounce_columns, ax, frame_interval=interval)
    tof = bounce_columns["tof"]
    np.testing.assert_allclose(model.get_xdata(), tof[:-1])
    np.testing.assert_allclose(model.get_ydata(), tof[1:])
    np.testing.assert_allclose(camera.get_ydata(), seen["tof"][1:])
    assert "(s)" in ax.get_xlabel()


def test_phase_normalization_known_rows():
    h, v, omega = 0.05, 0.4, 30.0
    scene = {"ball": {"mass": MASS, "radius": RADIUS}, "run": {"gravity": G}}
    spin = 0.5 * K * MASS * RADIUS**2 * omega**2
    columns = {
        "q2": np.array([h, 0.0, h, h]),
        "u4": np.array([0.0, -v, v, 0.0]),
        "energy": np.array(
            [MASS * G * h, 0.5 * MASS * v**2, MASS * G * h + 0.5 * MASS * v**2 + spin, 0.0]
        ),
    }
    x, y = plot.phase_coordinates(columns, scene)
    # At rest at height h: all energy potential.
    assert x[0] == pytest.approx(0.0) and y[0] == pytest.approx(1.0)
    # At q2 = 0 moving along the tangent: all energy kinetic.
    assert x[1] == pytest.approx(-1.0) and y[1] == pytest.approx(0.0)
    energy = columns["energy"][2]
    assert y[2] == pytest.approx(h / (energy / (MASS * G)))
    assert x[2] == pytest.approx(v / math.sqrt(2 * energy / MASS))
    assert x[2] ** 2 + y[2] < 1  # spin holds some of the energy
    assert math.isnan(x[3]) and math.isnan(y[3])  # zero energy cannot be normalized


def test_phase_plot_data_and_range(bounce_columns, bounce_run):
    scene = plot.read_scene(bounce_run / "scene.toml")
    fig, ax = single_axes()
    (line,) = plot.phase_plot(bounce_columns, scene, ax)
    x, y = plot.phase_coordinates(bounce_columns, scene)
    np.testing.assert_allclose(line.get_xdata(), x)
    np.testing.assert_allclose(line.get_ydata(), y)
    np.testing.assert_allclose(line.get_xdata(), 0.0)  # vertical bounces: u4 = 0
    assert ax.get_xlim() == (-1.0, 1.0) and ax.get_ylim() == (0.0, 1.0)


def test_trajectory_arcs_join_the_impacts(bounce_columns, bounce_run):
    scene = plot.read_scene(bounce_run / "scene.toml")
    fig, ax = single_axes()
    drawn = plot.trajectory(bounce_columns, scene, ax, window=(11, 21))
    rows = drawn["rows"]
    np.testing.assert_array_equal(bounce_columns["n"][rows], np.arange(11, 21))
    x = drawn["arcs"].get_xdata()
    y = drawn["arcs"].get_ydata()
    pieces = np.split(np.column_stack([x, y]), np.flatnonzero(np.isnan(x)))
    pieces = [p[~np.isnan(p[:, 0])] for p in pieces if np.isfinite(p).any()]
    assert len(pieces) == 9
    q2 = bounce_columns["q2"][rows] * 1e3
    for k, piece in enumerate(pieces):
        assert piece[0, 1] == pytest.approx(q2[k], abs=1e-9)
        assert piece[-1, 1] == pytest.approx(q2[k + 1], abs=1e-6)
    assert ax.get_aspect() == 1.0
    assert "mm" in ax.get_xlabel()


def test_default_window_and_parse_window(bounce_columns):
    scene = {"drive": {"frequency": 25.0}}
    n0, n1 = plot.default_window(bounce_columns, scene)
    n = bounce_columns["n"]
    assert n1 == n[-1] + 1 and n0 < n1 - 1
    t = bounce_columns["t"]
    assert t[n == n0][0] >= t[-1] - 4 / 25.0 - 1e-12
    assert plot.parse_window("5:20") == (5, 20)
    assert plot.parse_window(":20") == (None, 20)
    assert plot.parse_window("7:") == (7, None)
    for bad in ("5", "a:b", "1.5:3"):
        with pytest.raises(ValueError):
            plot.parse_window(bad)


def test_scene_title_names_the_parameters(bounce_run):
    title = plot.scene_title(plot.read_scene(bounce_run / "scene.toml"), 160)
    for text in (
        "bounce",
        "160 impacts",
        "parabola",
        "25 Hz",
        "A = 1 mm",
        "e = 0.5",
        "0.61",
        "0.47",
    ):
        assert text in title


# --- whole runs ----------------------------------------------------------------------------


def check_png(path: Path, min_width: int = 500) -> None:
    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    height, width = image.shape[:2]
    assert width >= min_width and 250 <= height <= 1000
    assert image[..., :3].std() > 0.02  # not blank


def check_gif(path: Path) -> None:
    assert path.stat().st_size <= 2_000_000
    with Image.open(path) as gif:
        assert gif.format == "GIF"
        assert 2 <= gif.n_frames <= 150
        assert 200 <= gif.size[0] <= 800


def test_plot_run_writes_every_figure(bounce_run):
    managers = Gcf.get_num_fig_managers()
    written = plot.plot_run(bounce_run)
    assert [p.name for p in written] == list(plot.FIGURE_NAMES)
    assert all(p.parent == bounce_run for p in written)
    for path in written[:-1]:
        check_png(path)
        assert mpimg.imread(path).shape[1] == 600
    check_gif(written[-1])
    assert Gcf.get_num_fig_managers() == managers  # no pyplot figure left behind


def test_plot_run_camera_window_out_dir_no_gif(static_run, tmp_path):
    out = tmp_path / "figures"
    written = plot.plot_run(static_run, out, frame_interval=1 / 30, window=(3, 30), gif=False)
    assert [p.name for p in written] == list(plot.FIGURE_NAMES[:-1])
    assert all(p.parent == out for p in written)
    for path in written:
        check_png(path)
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


def test_command_line(bounce_run, tmp_path, capsys):
    parser = argparse.ArgumentParser()
    plot.add_plot_arguments(parser)
    args = parser.parse_args(
        [
            str(bounce_run),
            "--out",
            str(tmp_path / "o"),
            "--frame-interval",
            "1/30",
            "--window",
            "2:12",
            "--no-gif",
        ]
    )
    assert args.frame_interval == pytest.approx(1 / 30) and args.window == (2, 12)
    assert plot.run_plot_command(args) == 0
    assert capsys.readouterr().out.count("wrote ") == 4
    args = parser.parse_args([str(tmp_path / "missing")])
    assert plot.run_plot_command(args) == 2
    assert "missing" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        parser.parse_args([str(bounce_run), "--frame-interval", "-1"])


# --- bad input ---------------------------------------------------------------------------

HEADER = ",".join(COLUMN_NAMES)
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
    with pytest.raises(ValueError) as info:
        plot.plot_run(run)
    message = str(info.value)
    assert isinstance(info.value, RunDataError)
    assert "\n" not in message
    assert message.startswith(str(csv_path))
    assert problem in message


@pytest.mark.parametrize(
    ("toml", "problem"),
    [
        (None, "scene.toml: file not found"),
        ("name = [unclosed\n", "scene.toml: not valid TOML"),
    ],
)
def test_bad_scene_file(tmp_path, bounce_columns, toml, problem):
    run = tmp_path / "run"
    run.mkdir()
    write_collisions(run / "collisions.csv", bounce_columns)
    if toml is not None:
        (run / "scene.toml").write_text(toml)
    with pytest.raises(RunDataError, match="^[^\n]*$") as info:
        plot.plot_run(run)
    assert problem in str(info.value)


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
def engine_run(tmp_path_factory) -> Path:
    from billiard.cli import main

    out = tmp_path_factory.mktemp("engine")
    assert (
        main(["run", "parabola-5.4hz", "--collisions", "300", "--out", str(out), "--no-plot"]) == 0
    )
    return out


def test_engine_run_plots(engine_run, tmp_path):
    columns, scene = plot.load_run(engine_run)
    assert columns["t"].size == 300
    written = plot.plot_run(engine_run, tmp_path, frame_interval=1 / 30, window=(250, 300))
    assert [p.name for p in written] == list(plot.FIGURE_NAMES)
    for path in written[:-1]:
        check_png(path)
    check_gif(written[-1])
    fig, ax = single_axes()
    (line,) = plot.return_map(columns, ax)
    np.testing.assert_allclose(line.get_xdata(), columns["q2"][:-1] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), columns["q2"][1:] * 1e3)
    x, y = plot.phase_coordinates(columns, scene)
    assert np.all((np.abs(x) <= 1) & (y > 0) & (y <= 1))
    assert np.all(x**2 + y <= 1 + 1e-9)  # q2 > 0: the point lies under the energy bound


def test_engine_run_billiard_plot_command(engine_run, tmp_path, capsys):
    from billiard.cli import main

    assert main(["plot", str(engine_run), "--window", "280:300", "--no-gif"]) == 0
    assert capsys.readouterr().out.count("wrote ") == 4
    assert (engine_run / "trajectory.png").exists()


def test_read_collisions_skips_a_row_cut_short_by_a_kill(tmp_path):
    from billiard.record import read_collisions

    header = "n,t,q1,q2,v1,v2,omega,u4,un,tof,regime,z,energy"
    row = "{n},{t},0.0,0.01,0.1,0.2,0.0,0.1,0.2,0.1,stick,0.0,1e-5"
    complete = "\n".join([header, row.format(n=1, t=0.1), row.format(n=2, t=0.2)]) + "\n"
    (tmp_path / "collisions.csv").write_text(complete + "3,0.3,0.0,0.0")
    cols = read_collisions(tmp_path / "collisions.csv")
    assert list(cols["n"]) == [1.0, 2.0]
    (tmp_path / "collisions.csv").write_text(complete)
    assert list(read_collisions(tmp_path / "collisions.csv")["t"]) == [0.1, 0.2]
