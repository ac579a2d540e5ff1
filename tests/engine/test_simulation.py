"""The run loop: records, determinism, stop conditions, and the rk4 baseline."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.errors import GeometryError
from billiard.run.simulate import simulate
from billiard.runfile.record import COLUMNS, LID_WALL
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene, replace, with_values
from billiard.scene.spec import InitialSpec

CONTRACT = ("n", "t", "q1", "q2", "v1", "v2", "omega", "u4", "un", "tof", "regime", "z", "energy")


def dropped(name="parabola-5.4hz", **changes):
    """A ball dropped off-centre into a strongly driven container (real flights)."""
    scene = load_scene(name, overrides=["drive.amplitude=0.02"])
    values = {"initial.q1": 0.004, "initial.q2": 0.05}
    values.update(changes)
    return with_values(scene, values)


def test_columns_contract_and_types():
    result = simulate(load_scene("wedge-6.6hz"), collisions=300)
    c = result.columns
    assert tuple(c)[: len(CONTRACT)] == CONTRACT
    assert tuple(c) == COLUMNS
    assert len(result) == 300 and all(len(v) == 300 for v in c.values())
    assert c["n"].tolist() == list(range(1, 301))
    assert set(c["regime"]) <= {"stick", "slip", "elastic"}
    assert c["wall"].dtype == np.int64 and set(c["wall"].tolist()) <= {0, 1, LID_WALL}
    assert np.all(np.diff(c["t"]) >= 0.0) and np.all(c["tof"] >= 0.0)
    assert np.allclose(np.cumsum(c["tof"]), c["t"], rtol=0, atol=1e-12)
    assert sum(result.counts[k] for k in ("stick", "slip", "elastic")) == 300
    assert result.stop_reason is None
    assert "300 impacts" in result.summary()


def test_recorded_quantities_are_consistent():
    scene = dropped()
    c = simulate(scene, collisions=50).columns
    m, r, k, g = 1.3028e-4, 1.55e-3, 0.4, 9.81
    energy = (
        m * g * c["q2"]
        + 0.5 * m * (c["v1"] ** 2 + c["v2"] ** 2)
        + 0.5 * k * m * r * r * c["omega"] ** 2
    )
    assert np.allclose(c["energy"], energy, rtol=1e-12)
    u4 = np.cos(c["z"]) * c["v1"] + np.sin(c["z"]) * c["v2"]
    un = np.cos(c["z"]) * c["v2"] - np.sin(c["z"]) * c["v1"]
    assert np.allclose(c["u4"], u4, atol=1e-14) and np.allclose(c["un"], un, atol=1e-14)
    # the contact point lies on the curve, under the ball, with the recorded tangent
    walls = c["wall"] != LID_WALL
    assert np.allclose(np.tan(c["z"][walls]), 52.0 * c["s"][walls], rtol=1e-9, atol=1e-12)
    # the rotation angle integrates the spin over each flight
    q3 = np.concatenate([[0.0], np.cumsum(c["omega"][:-1] * c["tof"][1:])])
    assert np.allclose(c["q3"], q3, rtol=1e-9, atol=1e-12)


def test_run_is_deterministic_to_the_byte(tmp_path):
    scene = load_scene("hyperbola-5.8hz", overrides=["drive.amplitude=0.02"])
    simulate(scene, collisions=1500, out_dir=tmp_path / "a")
    simulate(scene, collisions=1500, out_dir=tmp_path / "b")
    a = (tmp_path / "a" / "collisions.csv").read_bytes()
    b = (tmp_path / "b" / "collisions.csv").read_bytes()
    assert a == b and len(a) > 100_000


def test_streamed_csv_round_trips_and_matches_memory(tmp_path):
    scene = load_scene("parabola-5.4hz")
    disk = simulate(scene, collisions=400, out_dir=tmp_path)
    memory = simulate(scene, collisions=400)
    assert disk.path == tmp_path / "collisions.csv"
    assert len(disk) == 400
    back = read_collisions(tmp_path / "collisions.csv")
    for name in COLUMNS:
        assert np.array_equal(back[name], memory.columns[name]), name
        assert np.array_equal(disk.columns[name], memory.columns[name]), name
    memory.to_csv(tmp_path / "copy.csv")
    assert (tmp_path / "copy.csv").read_bytes() == (tmp_path / "collisions.csv").read_bytes()


def test_resolved_scene_reproduces_the_run():
    scene = load_scene("wedge-6.6hz")
    first = simulate(scene, collisions=200)
    assert first.scene.initial.q1 == 0.0 and first.scene.initial.q2 > 0.0
    again = simulate(first.scene)
    assert again.scene == first.scene
    for name in COLUMNS:
        assert np.array_equal(first.columns[name], again.columns[name]), name


def test_progress_is_reported():
    calls = []
    simulate(
        load_scene("parabola-5.4hz"), collisions=250, progress=lambda d, t: calls.append((d, t))
    )
    assert calls[-1] == (250, 250)
    assert all(t == 250 for _, t in calls) and [d for d, _ in calls] == sorted(d for d, _ in calls)


def test_escape_stops_the_run_and_keeps_rows():
    scene = dropped(**{"boundary.ceiling": None, "boundary.escape_height": 0.2, "air.drag": "none"})
    scene = replace(scene, initial=InitialSpec(q1=0.0, q2=0.05, v2=2.5))
    result = simulate(scene, collisions=100)
    assert len(result) == 0
    assert result.stop_reason.startswith("ball escaped above escape_height = 0.2 m at t = ")
    assert result.stop_reason.endswith("after impact 0")
    # the escape time is that of the free flight reaching the level
    t = float(result.stop_reason.split(" at t = ")[1].split(" s")[0])
    assert t == pytest.approx((2.5 - math.sqrt(2.5**2 - 2 * 9.81 * 0.15)) / 9.81, rel=1e-6)


def test_unresolvable_collapse_stops_the_run():
    """Without the low-velocity rule a ball resting on the shaken bottom cannot be lifted
    by any impact: the run stops with a one-line reason, keeping the rows."""
    scene = load_scene("parabola-5.4hz", overrides=["contact.elastic_below=0"])
    result = simulate(scene, collisions=5000)
    assert result.stop_reason is not None
    assert result.stop_reason.startswith("inelastic collapse:")
    assert "at impact 201" in result.stop_reason
    assert len(result) == 201


def test_low_velocity_rule_lifts_a_resting_ball():
    result = simulate(load_scene("parabola-5.4hz"), collisions=200)
    c = result.columns
    assert c["tof"][0] == 0.0 and c["regime"][0] == "elastic"
    assert result.counts["resting"] >= 1
    assert c["un"][0] == pytest.approx(0.01, rel=1e-9)  # leaves at elastic_below
    assert np.all(c["tof"][1:] > 1e-4)


def test_geometry_errors():
    with pytest.raises(
        GeometryError,
        match=r"ball radius 0\.02 m exceeds the boundary's radius "
        r"of curvature 0\.0192 m at x = 0: single-point contact fails",
    ):
        simulate(load_scene("parabola-5.4hz", overrides=["ball.radius=0.02"]), collisions=1)
    scene = replace(load_scene("parabola-5.4hz"), initial=InitialSpec(q1=0.01, q2=0.005))
    with pytest.raises(
        GeometryError,
        match=r"q1 = 0\.01 m, q2 = 0\.005 m puts the ball .* m "
        r"into the wall",
    ):
        simulate(scene, collisions=1)
    base = load_scene("parabola-5.4hz")
    lid = base.boundary.ceiling - 0.5 * base.ball.radius  # centre closer to the lid than r
    scene = replace(base, initial=InitialSpec(q1=0.0, q2=lid))
    with pytest.raises(GeometryError, match="into the lid"):
        simulate(scene, collisions=1)


def test_rk4_agrees_with_event_on_first_impacts():
    scene = dropped(**{"air.drag": "none"})
    event = simulate(scene, collisions=8, method="event").columns
    rk4 = simulate(scene, collisions=8, method="rk4").columns
    assert list(rk4["wall"]) == list(event["wall"])
    assert np.abs(rk4["t"] - event["t"]).max() < 1e-11
    assert np.abs(rk4["q2"] - event["q2"]).max() < 1e-11


def test_rk4_impact_time_error_shrinks_like_h4():
    """With a strong (amplified) drag the flight is truly nonlinear; the rk4 impact time
    converges to the error-controlled event solution at fourth order."""
    scene = dropped(**{"air.c_quad": 2e-3, "air.c_lin": 1e-4, "run.rtol": 1e-13})
    reference = simulate(scene, collisions=1, method="event").columns["t"][0]
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        t = simulate(with_values(scene, {"run.step": h}), collisions=1, method="rk4").columns["t"][
            0
        ]
        errors.append(abs(t - reference))
    ratios = [errors[i] / errors[i + 1] for i in range(2)]
    assert all(10.0 < ratio < 25.0 for ratio in ratios), (errors, ratios)
    assert errors[-1] < 1e-10


@pytest.mark.parametrize("name", ["parabola-5.4hz", "wedge-6.6hz"])
def test_run_from_written_scene_toml_reproduces_the_csv(tmp_path, name):
    """`billiard run DIR/scene.toml` repeats `billiard run NAME` byte for byte."""
    from billiard.cli import main

    first, second = tmp_path / "first", tmp_path / "second"
    assert main(["run", name, "--collisions", "300", "--out", str(first), "--no-plot"]) == 0
    assert main(["run", str(first / "scene.toml"), "--out", str(second), "--no-plot"]) == 0
    a = (first / "collisions.csv").read_bytes()
    assert a.count(b"\n") == 301
    assert a == (second / "collisions.csv").read_bytes()


def test_duration_stops_at_the_last_impact_before_it():
    scene = load_scene("wedge-6.6hz")
    limited = simulate(scene, collisions=100_000, duration=0.5)
    free = simulate(scene, collisions=len(limited) + 1)
    t_limited, t_free = limited.columns["t"], free.columns["t"]
    assert limited.stop_reason is None
    assert limited.final_time == 0.5
    assert t_limited[-1] <= 0.5 < t_free[-1]
    # the time limit changes nothing before it: the rows are a prefix of the free run
    np.testing.assert_array_equal(t_limited, t_free[:-1])


def test_duration_from_the_command_line(tmp_path, capsys):
    from billiard.cli import main

    assert main(["run", "wedge-6.6hz", "--duration", "-1", "--out", str(tmp_path / "a")]) == 2
    assert "run.duration" in capsys.readouterr().err
    out = tmp_path / "b"
    assert main(["run", "wedge-6.6hz", "--duration", "0.2", "--no-plot", "--out", str(out)]) == 0
    rows = (out / "collisions.csv").read_text().splitlines()[1:]
    assert rows and float(rows[-1].split(",")[1]) <= 0.2


def test_one_run_file_format_read_back_with_the_same_dtypes(tmp_path):
    """The CSV reader and the in-memory result agree on every column's dtype and value."""
    import billiard

    scene = load_scene("wedge-6.6hz")
    memory = simulate(scene, collisions=300).columns
    streamed = simulate(scene, collisions=300, out_dir=tmp_path).columns
    read = billiard.read_collisions(tmp_path / "collisions.csv")
    assert list(memory) == list(read) == list(COLUMNS)
    for name in COLUMNS:
        assert memory[name].dtype == read[name].dtype == streamed[name].dtype, name
        np.testing.assert_array_equal(memory[name], read[name])
    assert read["n"].dtype == np.int64 and read["wall"].dtype == np.int64
