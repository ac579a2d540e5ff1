"""A chunk's points on the ensemble kernel against the per-point path: the same
classes, periods, counts and last impacts, the same statistics to rounding; the points
the kernel does not take go to the per-point path."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.engine.ensemble import supports
from billiard.scene.scene import load_scene, with_values
from billiard.sweep import Sweep, parse_vary
from billiard.sweep.attractor import CLASSES
from billiard.sweep.batch import measure_batch
from billiard.sweep.columns import MODES, RUN_STATUSES
from billiard.sweep.measure import PointTask, measure_point

pytestmark = pytest.mark.skipif(supports(load_scene("wedge-6.6hz")) is not None, reason="numba")

EXACT = ("period", "drive_periods", "impacts", "total_impacts")
CLOSE = ("height_mean", "height_std", "tof_mean", "tof_std", "rest_height", "height_max")


def _compare(sweep: Sweep) -> int:
    settings = sweep.settings()
    indices = np.arange(sweep.size)
    columns, rest = measure_batch(sweep, indices, settings)
    assert columns is not None
    for row, index in enumerate(columns["index"].tolist()):
        values = sweep.point_values(index)
        record = measure_point(PointTask(index, values, with_values(sweep.scene, values), settings))
        assert record["status"] == "ok"
        assert CLASSES[columns["attractor"][row]] == record["attractor"], index
        assert RUN_STATUSES[columns["run_status"][row]] == record["run_status"]
        assert MODES[columns["final_mode"][row]] == record["final_mode"]
        for name in EXACT:
            assert columns[name][row] == (record[name] or 0), (index, name)
        for name in CLOSE:
            if record[name] is None:  # no impact measured (a ball that stayed down)
                assert np.isnan(columns[name][row]), name
                continue
            assert columns[name][row] == pytest.approx(record[name], rel=1e-12, abs=1e-15), name
        if columns["impacts"][row]:
            share = columns["elastic_impacts"][row] / columns["impacts"][row]
            assert share == record["elastic_share"]
            assert columns["lid_impacts"][row] / columns["impacts"][row] == record["lid_share"]
        tail = columns["last_height"][row]
        np.testing.assert_array_equal(tail[~np.isnan(tail)], record["last_height"])
        tail = columns["last_tof"][row]
        np.testing.assert_array_equal(tail[~np.isnan(tail)], record["last_tof"])
    return len(rest)


def test_a_basin_map_chunk_matches_the_per_point_path() -> None:
    """Wedge starts (lid impacts, aperiodic) and parabola starts (period 2)."""
    for name in ("wedge-6.6hz", "parabola-5.4hz"):
        sweep = Sweep(
            load_scene(name),
            (parse_vary("initial.q1=-0.02:0.02:3"), parse_vary("initial.q2=0.06:0.1:2")),
            impacts=150,
            transient=150,
            keep=7,
        )
        assert _compare(sweep) == 0


def test_a_frequency_sweep_from_rest_matches_the_per_point_path() -> None:
    """Balls at rest on the bottom (no initial position), one set-up per frequency,
    and a duration that ends some runs before their impacts (time_limit)."""
    sweep = Sweep(
        load_scene("parabola-5.4hz"),
        (parse_vary("drive.frequency=5.0:5.8:3"),),
        impacts=120,
        transient=100,
        keep=5,
        duration=15.0,
    )
    assert _compare(sweep) == 0


def test_contact_phases_points_match_the_per_point_path() -> None:
    """Under contact.model = "phases", batched: a basin map chunk of bouncing balls,
    and balls that end on the boundary, classed as the per-point path classes them:
    at rest on a still bottom, in contact for the contact span after a few impacts
    (rolling), rolling at a time limit without an impact."""
    for name in ("wedge-6.6hz", "parabola-5.4hz"):
        sweep = Sweep(
            with_values(load_scene(name), {"contact.model": "phases"}),
            (parse_vary("initial.q1=-0.02:0.02:3"), parse_vary("initial.q2=0.06:0.1:2")),
            impacts=100,
            transient=100,
            keep=7,
        )
        assert _compare(sweep) == 0
    gentle = with_values(
        load_scene("parabola-5.4hz"),
        {"contact.model": "phases", "run.contact_span": 1.0, "initial.q1": 0.0},
    )
    sweep = Sweep(
        gentle,
        (parse_vary("drive.amplitude=0.0,0.005"), parse_vary("initial.q2=0.03,0.05")),
        impacts=50,
        transient=2,
        keep=3,
    )
    assert _compare(sweep) == 0
    at_rest = with_values(gentle, {"initial.q1": None, "drive.amplitude": 0.005})
    sweep = Sweep(at_rest, (parse_vary("drive.frequency=5.0,5.4"),), impacts=5, duration=2.0)
    assert _compare(sweep) == 0
    classes = {
        CLASSES[c] for c in measure_batch(sweep, np.arange(2), sweep.settings())[0]["attractor"]
    }
    assert classes == {"rolling"}


def test_points_the_kernel_does_not_take_are_left_to_the_per_point_path() -> None:
    base = load_scene("parabola-5.4hz")
    axes = (parse_vary("drive.frequency=5.2,5.4"),)
    rk4 = Sweep(with_values(base, {"run.method": "rk4"}), axes, impacts=5, transient=0)
    columns, rest = measure_batch(rk4, np.arange(2), rk4.settings())
    assert columns is None and rest == [0, 1]
    lyapunov = Sweep(base, axes, impacts=5, transient=0, lyapunov=True)
    columns, rest = measure_batch(lyapunov, np.arange(2), lyapunov.settings())
    assert columns is None and rest == [0, 1]
    # a ball that escapes over a low escape height stops early: measured one by one
    escaping = Sweep(
        with_values(base, {"boundary.escape_height": 0.08, "boundary.ceiling": None}),
        (parse_vary("initial.q2=0.05,0.075"),),
        impacts=50,
        transient=0,
    )
    columns, rest = measure_batch(escaping, np.arange(2), escaping.settings())
    record = measure_point(
        PointTask(rest[0], escaping.point_values(rest[0]), with_values(
            escaping.scene, escaping.point_values(rest[0])), escaping.settings())
    )  # fmt: skip
    assert record["status"] == "failed" and "escaped" in record["reason"]


def test_a_parameter_map_is_one_set_up_and_matches_the_per_point_path(monkeypatch) -> None:
    """Drive, contact and ball keys varied together: one Simulation for the whole map
    (the other parameter sets are patched from it), the per-point path's results."""
    from billiard.engine import ensemble as EN
    from billiard.sweep import batch

    prepared: list = []
    real = EN.prepare
    monkeypatch.setattr(EN, "prepare", lambda scene: prepared.append(scene) or real(scene))
    monkeypatch.setattr(batch, "_SETUPS", type(batch._SETUPS)())
    sweep = Sweep(
        with_values(load_scene("parabola-5.4hz"), {"drive.direction": "vertical"}),
        (
            parse_vary("drive.frequency=5.0:5.8:3"),
            parse_vary("drive.amplitude=0.002,0.004"),
            parse_vary("contact.restitution=0.393,0.6"),
            parse_vary("ball.mass=1.3e-4,2e-4"),
        ),
        impacts=100,
        transient=80,
        keep=5,
    )
    assert _compare(sweep) == 0
    assert len(prepared) == 1


def test_starts_and_parameters_vary_together() -> None:
    """A basin map at two drive amplitudes of the wedge: placed starts, patched set-ups."""
    sweep = Sweep(
        load_scene("wedge-6.6hz"),
        (
            parse_vary("drive.amplitude=0.02,0.03"),
            parse_vary("initial.q1=-0.02:0.02:3"),
            parse_vary("initial.q2=0.07,0.09"),
        ),
        impacts=100,
        transient=100,
        keep=5,
    )
    assert _compare(sweep) == 0
