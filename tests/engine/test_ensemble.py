"""The ensemble kernel against the single-run engine: the same start gives the same
state vector and the same impacts, bit for bit, whatever the threads, slices and rounds;
its measurements against the sweep's own (numpy) statistics and period test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.engine import ensemble as EN
from billiard.engine.ctx import state_vector
from billiard.engine.simulation import Simulation
from billiard.errors import GeometryError
from billiard.kernels import ensemble as E
from billiard.kernels import layout as L
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values
from billiard.sweep.attractor import find_period

pytestmark = pytest.mark.skipif(EN.supports(load_scene("wedge-6.6hz")) is not None, reason="numba")

RING = (("t", E.R_T), ("q1", E.R_Q1), ("q2", E.R_Q2), ("v1", E.R_V1), ("v2", E.R_V2))
RING += (("omega", E.R_OMEGA), ("tof", E.R_TOF))


def _starts(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(-0.035, 0.035, n), rng.uniform(0.03, 0.12, n)


@pytest.mark.parametrize("name", ["wedge-6.6hz", "parabola-5.4hz"])
def test_start_is_the_runs_state_vector(name: str) -> None:
    """Valid starts: the state vector of a run's set-up, slot for slot; invalid ones:
    those the set-up refuses."""
    scene = load_scene(name)
    setup = EN.prepare(scene)
    q1, q2 = _starts(1, 16)
    ctxs, ok = EN.start(setup, q1, q2, v1=0.1, v2=-0.2, omega=3.0, t=0.25, duration=7.0)
    refused = 0
    for i in range(q1.size):
        point = with_values(
            scene,
            {"initial.q1": float(q1[i]), "initial.q2": float(q2[i]), "initial.v1": 0.1}
            | {"initial.v2": -0.2, "initial.omega": 3.0, "initial.t": 0.25, "run.duration": 7.0},
        )
        try:
            sim = Simulation(point)
        except GeometryError:
            assert not ok[i], i
            refused += 1
            continue
        assert ok[i], i
        ref = np.array(state_vector(sim))
        same = (ref == ctxs[i]) | (np.isnan(ref) & np.isnan(ctxs[i]))
        assert same.all(), np.nonzero(~same)[0]
    assert 0 < refused < q1.size


@pytest.mark.parametrize("name", ["wedge-6.6hz", "hyperbola-5.8hz"])
def test_trajectories_are_the_runs_bit_for_bit(name: str, monkeypatch) -> None:
    """Every impact of every trajectory, made in rounds of 37 impacts on slices of 2
    trajectories over 2 threads, equals the run's record; so do the final states."""
    monkeypatch.setattr(EN, "ROUND_IMPACTS", 37)
    monkeypatch.setattr(EN, "SLICE", 2)
    scene = load_scene(name)
    setup = EN.prepare(scene)
    q1, q2 = _starts(2, 30)
    ctxs, ok = EN.start(setup, q1, q2)
    q1, q2, ctxs = q1[ok][:5], q2[ok][:5], ctxs[ok][:5]
    total, transient = 150, 20
    consts = EN.constants(scene, 1e-5, 64, 256)
    stats, rings = EN.advance(
        ctxs, setup.params, setup.walls, consts, transient=transient, impacts=total - transient,
        width=total, threads=2,
    )  # fmt: skip
    for i in range(q1.size):
        point = with_values(scene, {"initial.q1": float(q1[i]), "initial.q2": float(q2[i])})
        columns = simulate(point, collisions=total).columns
        assert stats[i, E.ST_STATUS] == E.RUN_COMPLETE
        assert stats[i, E.ST_TOTAL] == total and stats[i, E.ST_MEASURED] == total - transient
        for name_, col in RING:
            np.testing.assert_array_equal(
                rings[i, : total - transient, col], np.asarray(columns[name_][transient:], float)
            )
        assert ctxs[i, L.EN_Q1] == columns["q1"][-1] and ctxs[i, L.EN_U3] == columns["omega"][-1]


def test_measurements_match_the_sweeps_statistics() -> None:
    """Welford's running statistics against numpy's, the compiled period test against
    find_period (periodic parabola orbits, aperiodic wedge trajectories), the shares."""
    for name, period in (("parabola-5.4hz", 2), ("wedge-6.6hz", 0)):
        scene = load_scene(name)
        setup = EN.prepare(scene)
        q1, q2 = _starts(3, 20)
        ctxs, ok = EN.start(setup, q1, q2)
        q1, q2, ctxs = q1[ok][:3], q2[ok][:3], ctxs[ok][:3]
        transient, impacts = 300, 300
        consts = EN.constants(scene, 1e-5, 64, 256)
        stats, _ = EN.advance(
            ctxs, setup.params, setup.walls, consts, transient=transient, impacts=impacts,
            width=256,
        )  # fmt: skip
        for i in range(q1.size):
            point = with_values(scene, {"initial.q1": float(q1[i]), "initial.q2": float(q2[i])})
            cols = simulate(point, collisions=transient + impacts).columns
            post = {k: np.asarray(v[transient:]) for k, v in cols.items()}
            h, tof = post["q2"].astype(float), post["tof"].astype(float)
            assert stats[i, E.ST_H_MEAN] == pytest.approx(np.mean(h), rel=1e-13)
            assert math.sqrt(stats[i, E.ST_H_M2] / impacts) == pytest.approx(np.std(h), rel=1e-9)
            assert stats[i, E.ST_H_MAX] == np.max(h)
            assert stats[i, E.ST_TOF_MEAN] == pytest.approx(np.mean(tof), rel=1e-13)
            assert stats[i, E.ST_ELASTIC] == np.sum(post["regime"] == "elastic")
            assert stats[i, E.ST_LID] == np.sum(post["wall"] == -1)
            expected = find_period(
                post, frequency=scene.drive.frequency, phase=scene.drive.phase,
                radius=scene.ball.radius, g=scene.run.gravity, tolerance=1e-5, max_period=64,
            )  # fmt: skip
            assert stats[i, E.ST_PERIOD] == expected == period


def test_a_duration_ends_trajectories_as_a_run_ends() -> None:
    """run.duration: the trajectory stops before the first impact after t + duration,
    at the run's impact count."""
    scene = load_scene("wedge-6.6hz")
    setup = EN.prepare(scene)
    ctxs, ok = EN.start(setup, [0.01], [0.08], duration=0.5)
    assert ok.all()
    consts = EN.constants(scene, 1e-5, 64, 256)
    stats, _ = EN.advance(
        ctxs, setup.params, setup.walls, consts, transient=0, impacts=10**6, width=8
    )
    point = with_values(scene, {"initial.q1": 0.01, "initial.q2": 0.08})
    run = simulate(point, collisions=10**6, duration=0.5)
    assert stats[0, E.ST_STATUS] == E.RUN_TIME_LIMIT
    assert stats[0, E.ST_TOTAL] == len(run.columns["n"]) > 0


def test_a_start_at_rest_is_the_runs_state_vector() -> None:
    """A scene without initial.q1, q2 puts the ball on the bottom: the set-up's vector."""
    scene = load_scene("parabola-5.4hz")
    point = with_values(scene, {"initial.v1": 0.05, "initial.omega": -2.0, "run.duration": 3.0})
    setup = EN.prepare(point)
    ctxs = EN.start_at_rest(setup, 2, v1=0.05, v2=0.0, omega=-2.0, duration=3.0)
    ref = np.array(state_vector(Simulation(point)))
    for ctx in ctxs:
        same = (ref == ctx) | (np.isnan(ref) & np.isnan(ctx))
        assert same.all(), np.nonzero(~same)[0]
