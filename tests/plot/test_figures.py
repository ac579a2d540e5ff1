"""Tests of the figures of billiard.plot drawn into axes: what each one draws and labels."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.colors import to_rgba

from billiard import plot
from billiard.analysis.camera import camera_filter
from billiard.plot.flights import positions_at
from billiard.runfile.record import LID_WALL
from tests.plot_support import (
    C_CURVE,
    MASS,
    RADIUS,
    G,
    K,
    bouncing_ball,
    engine_run,
    make_run,
    scene_of,
    scene_toml,
    single_axes,
)

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def bounce_columns() -> dict[str, np.ndarray]:
    return bouncing_ball(160, amplitude=1e-3, frequency=25.0, e=0.5)


@pytest.fixture(scope="module")
def bounce_scene():
    return scene_of(scene_toml())


@pytest.fixture(scope="module")
def drag_run(tmp_path_factory) -> Path:
    return engine_run(tmp_path_factory.mktemp("drag"))


def test_fixture_is_consistent(bounce_columns):
    c = bounce_columns
    expected = 0.0063 + RADIUS + 1e-3 * np.sin(2 * np.pi * 25.0 * c["t"])
    np.testing.assert_allclose(c["q2"], expected, atol=1e-12)
    np.testing.assert_allclose(np.diff(c["t"]), c["tof"][1:], atol=1e-12)
    assert np.ptp(c["q2"]) > 1e-3  # the heights do vary
    # Each flight ends where the next impact is: drag-free parabola from the last impact.
    end = c["q2"][:-1] + c["v2"][:-1] * c["tof"][1:] - 0.5 * G * c["tof"][1:] ** 2
    np.testing.assert_allclose(end, c["q2"][1:], atol=1e-9)


# --- maps ----------------------------------------------------------------------------------


def test_return_map_plots_consecutive_heights(bounce_columns):
    fig, ax = single_axes()
    (line,) = plot.return_map(bounce_columns, ax)
    q2 = bounce_columns["q2"]
    np.testing.assert_allclose(line.get_xdata(), q2[:-1] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), q2[1:] * 1e3)
    assert "mm" in ax.get_xlabel() and "mm" in ax.get_ylabel()


def with_lid_impacts(columns: dict[str, np.ndarray], rows: list[int], height: float):
    """A copy of ``columns`` in which ``rows`` are lid impacts at centre height ``height``."""
    out = {name: np.array(values, copy=True) for name, values in columns.items()}
    out["wall"] = np.zeros(out["n"].size, dtype=np.int64)
    for row in rows:
        out["wall"][row] = LID_WALL
        out["z"][row] = math.pi
        out["q2"][row] = height
    return out


def test_return_map_marks_lid_impacts(bounce_columns):
    lid_rows = [20, 21, 60]
    height = 0.15 - RADIUS
    columns = with_lid_impacts(bounce_columns, lid_rows, height)
    fig, ax = single_axes()
    lines = plot.return_map(columns, ax)
    assert len(lines) == 2
    model, lid = lines
    # the pairs (n, n+1) that hold a lid impact: 19-20, 20-21, 21-22, 59-60, 60-61
    pairs = [19, 20, 21, 59, 60]
    q2 = columns["q2"] * 1e3
    np.testing.assert_allclose(lid.get_xdata(), q2[pairs])
    np.testing.assert_allclose(lid.get_ydata(), q2[np.array(pairs) + 1])
    assert model.get_xdata().size == q2.size - 1 - len(pairs)
    assert not np.any(np.isclose(model.get_ydata(), height * 1e3))
    assert lid.get_marker() != model.get_marker()
    assert "lid impacts (3" in lid.get_label()
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert any(text.startswith("lid impacts") for text in legend)


def test_lid_impacts_found_by_tangent_angle_without_wall_column(bounce_columns):
    columns = with_lid_impacts(bounce_columns, [30], 0.1)
    del columns["wall"]
    fig, ax = single_axes()
    assert len(plot.return_map(columns, ax)) == 2


def assert_camera_rings_beneath(model, camera):
    """The camera's markers are hollow, larger than the model's and beneath them."""
    assert camera.get_markerfacecolor() == "none" or to_rgba(camera.get_markerfacecolor())[3] < 1
    assert camera.get_markersize() > model.get_markersize()
    assert camera.get_zorder() < model.get_zorder()


def test_return_map_and_time_map_with_camera(bounce_columns):
    interval = 0.02
    seen = camera_filter(bounce_columns, interval)
    assert 2 < seen["t"].size < bounce_columns["t"].size
    fig, ax = single_axes()
    model, camera = plot.return_map(bounce_columns, ax, frame_interval=interval)
    np.testing.assert_allclose(camera.get_xdata(), seen["q2"][:-1] * 1e3)
    assert "33" not in camera.get_label() and "20 ms" in camera.get_label()
    assert_camera_rings_beneath(model, camera)
    fig, ax = single_axes()
    model, camera = plot.time_map(bounce_columns, ax, frame_interval=interval)
    tof = bounce_columns["tof"]
    np.testing.assert_allclose(model.get_xdata(), tof[:-1])
    np.testing.assert_allclose(model.get_ydata(), tof[1:])
    np.testing.assert_allclose(camera.get_ydata(), seen["tof"][1:])
    assert_camera_rings_beneath(model, camera)
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert any(text.startswith("camera, frame 20 ms") for text in legend)
    assert "(s)" in ax.get_xlabel()


# --- phase plot ----------------------------------------------------------------------------


def test_phase_normalization_known_rows():
    # The default reference: potential zero at the resting ball's centre h0 = c + r (the
    # bounce scene's parabola has a smooth bottom), the spin's energy left out.
    h, v, omega = 0.05, 0.4, 30.0
    scene = scene_of(scene_toml())
    h0 = C_CURVE + RADIUS
    spin = 0.5 * K * MASS * RADIUS**2 * omega**2
    columns = {
        "q2": np.array([h0 + h, h0, h0 + h, h0]),
        "u4": np.array([0.0, -v, v, 0.0]),
        "omega": np.array([0.0, 0.0, omega, 0.0]),
        "energy": np.array(
            [
                MASS * G * (h0 + h),
                MASS * G * h0 + 0.5 * MASS * v**2,
                MASS * G * (h0 + h) + 0.5 * MASS * v**2 + spin,
                MASS * G * h0,
            ]
        ),
    }
    x, y = plot.phase_coordinates(columns, scene)
    # At rest at height h above h0: all energy potential.
    assert x[0] == pytest.approx(0.0) and y[0] == pytest.approx(1.0)
    # At h0 moving along the tangent: all energy kinetic.
    assert x[1] == pytest.approx(-1.0) and y[1] == pytest.approx(0.0, abs=1e-12)
    e0 = MASS * G * h + 0.5 * MASS * v**2  # the spin is left out
    assert y[2] == pytest.approx(h / (e0 / (MASS * G)))
    assert x[2] == pytest.approx(v / math.sqrt(2 * e0 / MASS))
    assert x[2] ** 2 + y[2] == pytest.approx(1.0)  # no normal velocity in this row
    assert math.isnan(x[3]) and math.isnan(y[3])  # at rest at h0: E0 = 0, no point
    # With the spin counted it holds some of the energy.
    xs, ys = plot.phase_coordinates(columns, scene, "lowest-centre+spin")
    assert xs[2] ** 2 + ys[2] < 1
    assert ys[2] == pytest.approx(h / ((e0 + spin) / (MASS * G)))
    # The lab origin (the definition before the default changed): E as it is.
    xl, yl = plot.phase_coordinates(columns, scene, "lab-origin+spin")
    energy = columns["energy"][2]
    assert yl[2] == pytest.approx((h0 + h) / (energy / (MASS * G)))
    assert xl[2] == pytest.approx(v / math.sqrt(2 * energy / MASS))


def test_phase_coordinates_of_an_unknown_reference_or_curve_are_one_line_errors(bounce_columns):
    scene = scene_of(scene_toml())
    with pytest.raises(plot.RunDataError, match="no-such-zero"):
        plot.phase_coordinates(bounce_columns, scene, "no-such-zero")
    without_spin = {k: v for k, v in bounce_columns.items() if k != "omega"}
    with pytest.raises(plot.RunDataError, match="omega"):
        plot.phase_coordinates(without_spin, scene)
    # the lab origin with the spin counted needs neither the curve nor the spin
    x, y = plot.phase_coordinates(without_spin, scene, "lab-origin+spin")
    assert np.all(np.isfinite(y))


def test_phase_plot_data_and_range(bounce_columns, bounce_scene):
    # The vertically shaken table puts impacts below the resting centre at D = 0, where
    # the default reference has no point; the lab origin has one for every impact.
    fig, ax = single_axes()
    (line,) = plot.phase_plot(bounce_columns, bounce_scene, ax, reference="lab-origin+spin")
    x, y = plot.phase_coordinates(bounce_columns, bounce_scene, "lab-origin+spin")
    np.testing.assert_allclose(line.get_xdata(), x)
    np.testing.assert_allclose(line.get_ydata(), y)
    np.testing.assert_allclose(line.get_xdata(), 0.0)  # vertical bounces: u4 = 0
    assert ax.get_xlim() == (-1.0, 1.0) and ax.get_ylim() == (0.0, 1.0)


def test_phase_plot_states_the_normalizations_with_units(bounce_columns, bounce_scene):
    fig, ax = single_axes()
    model, camera = plot.phase_plot(bounce_columns, bounce_scene, ax, frame_interval=0.02)
    xlabel, ylabel = ax.get_xlabel(), ax.get_ylabel()
    assert "u_{4,max} = \\sqrt{2E_0/m}" in xlabel and "(m/s)" in xlabel
    assert "q_{2,max} = E_0/(m\\,g)" in ylabel and "(q_2 - h_0)" in ylabel and "(m)" in ylabel
    caption = plot.phase.PHASE_CAPTION
    assert "$E_0$ (J)" in caption and "spin left out" in caption
    assert "centre at rest at the bottom" in caption and "'lowest-centre'" in caption
    assert "lab frame" in plot.phase.phase_caption("lab-origin+spin")
    assert_camera_rings_beneath(model, camera)


# --- trajectory and flights ----------------------------------------------------------------


def arc_pieces(line) -> list[np.ndarray]:
    x = line.get_xdata()
    y = line.get_ydata()
    pieces = np.split(np.column_stack([x, y]), np.flatnonzero(np.isnan(x)))
    return [p[~np.isnan(p[:, 0])] for p in pieces if np.isfinite(p).any()]


def test_trajectory_arcs_join_the_impacts(bounce_columns, bounce_scene):
    fig, ax = single_axes()
    drawn = plot.trajectory(bounce_columns, bounce_scene, ax, window=(11, 21))
    rows = drawn["rows"]
    np.testing.assert_array_equal(bounce_columns["n"][rows], np.arange(11, 21))
    pieces = arc_pieces(drawn["arcs"])
    assert len(pieces) == 9
    q2 = bounce_columns["q2"][rows] * 1e3
    for k, piece in enumerate(pieces):
        assert piece[0, 1] == pytest.approx(q2[k], abs=1e-9)
        assert piece[-1, 1] == pytest.approx(q2[k + 1], abs=1e-6)
    assert ax.get_aspect() == 1.0
    assert "mm" in ax.get_xlabel() and "mm" in ax.get_ylabel()
    assert "no drag" in drawn["arcs"].get_label()


def test_trajectory_with_air_drag_draws_the_drag_flight(drag_run):
    columns, scene = plot.load_run(drag_run)
    assert scene.air.drag == "fowles"
    fig, ax = single_axes()
    drawn = plot.trajectory(columns, scene, ax, window=(260, 300))
    rows = drawn["rows"]
    pieces = arc_pieces(drawn["arcs"])
    assert len(pieces) == rows.size - 1
    ends = np.array([piece[-1] for piece in pieces]) / 1e3  # m
    nxt = rows[1:]
    impacts = np.column_stack([columns["q1"][nxt], columns["q2"][nxt]])
    misses = np.hypot(*(ends - impacts).T)
    assert misses.max() < 1e-6
    # the drag-free parabola from the same states misses the next impact by more
    tof = columns["tof"][nxt]
    parabola = np.column_stack(
        [
            columns["q1"][rows[:-1]] + columns["v1"][rows[:-1]] * tof,
            columns["q2"][rows[:-1]] + columns["v2"][rows[:-1]] * tof - 0.5 * G * tof**2,
        ]
    )
    parabola_misses = np.hypot(*(parabola - impacts).T)
    long = tof > 0.05
    assert long.any() and np.all(parabola_misses[long] > 1e-5)
    assert "drag" in drawn["arcs"].get_label() and "no drag" not in drawn["arcs"].get_label()


def test_animation_follows_the_drag_flight(drag_run):
    columns, scene = plot.load_run(drag_run)
    rows = np.arange(270, 290)
    # frames at the impact times: the ball is at each impact, reached by the flight
    # from the previous one (an impact time is on the previous flight's end)
    times = columns["t"][rows[1:]] - 1e-12
    x, y, starts = positions_at(columns, rows, times, scene)
    np.testing.assert_array_equal(starts, rows[:-1])
    np.testing.assert_allclose(x, columns["q1"][rows[1:]], atol=1e-6)
    np.testing.assert_allclose(y, columns["q2"][rows[1:]], atol=1e-6)


def test_flight_positions_parabola_without_drag(bounce_columns, bounce_scene):
    tau = np.array([0.0, 0.01, 0.02])
    x, y = plot.flight_positions(bounce_columns, 5, tau, bounce_scene)
    c = bounce_columns
    np.testing.assert_allclose(y, c["q2"][5] + c["v2"][5] * tau - 0.5 * G * tau**2)
    np.testing.assert_allclose(x, c["q1"][5] + c["v1"][5] * tau)


def test_default_window_and_parse_window(bounce_columns, bounce_scene):
    n0, n1 = plot.default_window(bounce_columns, bounce_scene)
    n = bounce_columns["n"]
    assert n1 == n[-1] + 1 and n0 < n1 - 1
    t = bounce_columns["t"]
    assert t[n == n0][0] >= t[-1] - 4 / 25.0 - 1e-12
    assert plot.parse_window("5:20") == (5, 20)
    assert plot.parse_window(":20") == (None, 20)
    assert plot.parse_window("7:") == (7, None)
    for bad in ("5", "a:b", "1.5:3"):
        with pytest.raises(plot.RunDataError):
            plot.parse_window(bad)


def test_parse_frame_interval():
    assert plot.parse_frame_interval("1/30") == pytest.approx(1 / 30)
    assert plot.parse_frame_interval("0.0333") == 0.0333
    for bad in ("0", "-1", "1/0", "nan", "inf", "fast"):
        with pytest.raises(plot.RunDataError, match="frame interval"):
            plot.parse_frame_interval(bad)


def test_scene_title_names_the_parameters(tmp_path, bounce_columns):
    run = make_run(tmp_path / "bounce", bounce_columns, scene_toml())
    title = plot.scene_title(plot.read_scene(run / "scene.toml"), 160)
    for text in ("bounce", "160 impacts", "parabola", "25 Hz", "A = 1 mm", "e = 0.5", "0.61"):
        assert text in title
    assert "0.47" in title and "a=26" in title
