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
        ctxs, setup.params, setup.walls, consts, nears=setup.nears,
        transient=transient, impacts=total - transient,
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
            ctxs, setup.params, setup.walls, consts, nears=setup.nears,
        transient=transient, impacts=impacts,
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


def test_the_kept_impacts_are_the_runs_last_measured_ones() -> None:
    """advance_setup(keep=K): each trajectory's last K measured heights and times of
    flight are the run's last K records, oldest first, NaN before the first measured
    one; through a ring that wrapped (width 8 < 23 measured) and one that did not (a
    run ended by its duration after fewer measured impacts than kept)."""
    scene = load_scene("wedge-6.6hz")
    setup = EN.prepare(scene)
    starts = ((0.01, 0.08, None), (-0.012, 0.06, None), (0.005, 0.07, 0.6))
    transient, impacts, keep, width = 7, 23, 6, 8
    rows = []
    for q1, q2, duration in starts:
        ctx, ok = EN.start(setup, [q1], [q2], duration=duration)
        assert ok.all()
        rows.append(ctx[0])
    consts = EN.constants(scene, 1e-5, 64, 256)
    stats, (heights, tofs) = EN.advance_setup(
        setup, np.array(rows), consts, transient=transient, impacts=impacts, width=width,
        keep=keep, threads=1,
    )  # fmt: skip
    assert heights.shape == tofs.shape == (len(starts), keep)
    short = 0
    for i, (q1, q2, duration) in enumerate(starts):
        point = with_values(scene, {"initial.q1": q1, "initial.q2": q2})
        cols = simulate(point, collisions=transient + impacts, duration=duration).columns
        h = np.asarray(cols["q2"][transient:], float)[-keep:]
        tof = np.asarray(cols["tof"][transient:], float)[-keep:]
        pad = np.full(keep - h.size, np.nan)
        short += 0 < h.size < keep
        assert stats[i, E.ST_MEASURED] == len(cols["q2"][transient:])
        np.testing.assert_array_equal(heights[i], np.concatenate([pad, h]))
        np.testing.assert_array_equal(tofs[i], np.concatenate([pad, tof]))
    assert short == 1  # the one ended by its duration measured fewer than K, not none


def test_a_duration_ends_trajectories_as_a_run_ends() -> None:
    """run.duration: the trajectory stops before the first impact after t + duration,
    at the run's impact count."""
    scene = load_scene("wedge-6.6hz")
    setup = EN.prepare(scene)
    ctxs, ok = EN.start(setup, [0.01], [0.08], duration=0.5)
    assert ok.all()
    consts = EN.constants(scene, 1e-5, 64, 256)
    stats, _ = EN.advance(
        ctxs,
        setup.params,
        setup.walls,
        consts,
        nears=setup.nears,
        transient=0,
        impacts=10**6,
        width=8,
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


# ---------------------------------------------------------------------- contact phases


def _phases(name: str, **changes) -> object:
    return with_values(load_scene(name), {"contact.model": "phases", **changes})


def _gentle(**changes) -> object:
    """The paper's parabola shaken gently under contact phases: a ball on the bottom
    rolls there and never flies (see tests/engine/test_run_ends.py)."""
    return _phases("parabola-5.4hz", **{"drive.amplitude": 0.005, **changes})


def _batched(scene, q1, q2, total, *, duration=None, threads=1):
    """(stats, rings, ctxs) of trajectories of ``scene`` from (q1, q2) (None: at rest on
    the bottom) to ``total`` impacts, every impact kept in the ring."""
    setup = EN.prepare(scene)
    if q1 is None:
        ctxs = EN.start_at_rest(setup, 1, duration=duration)
    else:
        ctxs, ok = EN.start(setup, q1, q2, t=scene.initial.t, duration=duration)
        assert ok.all()
    consts = EN.constants(scene, 1e-5, 64, 256)
    stats, rings = EN.advance(
        ctxs, setup.params, setup.walls, consts, nears=setup.nears,
        transient=0, impacts=total, width=total,
        threads=threads,
    )  # fmt: skip
    return stats, rings, ctxs


def _same_run(stats, ring, ctx, result) -> None:
    """A batched trajectory against the run: every impact and the final ball, bit for
    bit, the impacts counted, the motion state it ended in."""
    columns = result.columns
    n = len(columns["n"])
    assert stats[E.ST_TOTAL] == stats[E.ST_MEASURED] == n
    for name, col in RING:
        np.testing.assert_array_equal(ring[:n, col], np.asarray(columns[name], float))
    assert L.MOTION_NAMES[int(stats[E.ST_MODE])] == result.final_mode
    if n:
        assert ctx[L.MC_LAST_IMPACT] == columns["t"][-1]


@pytest.mark.parametrize("name", ["wedge-6.6hz", "parabola-5.4hz"])
def test_phases_trajectories_are_the_runs_bit_for_bit(name: str, monkeypatch) -> None:
    """Under contact.model = "phases" (landings, rolling, sliding, held phases) every
    impact of every trajectory, in rounds of 23 impacts on slices of 2 trajectories
    over 2 threads, equals the run's record; so do the counts and final modes."""
    monkeypatch.setattr(EN, "ROUND_IMPACTS", 23)
    monkeypatch.setattr(EN, "SLICE", 2)
    scene = _phases(name)
    setup = EN.prepare(scene)
    q1, q2 = _starts(4, 20)
    _, ok = EN.start(setup, q1, q2)
    q1, q2 = q1[ok][:5], q2[ok][:5]
    total = 120
    stats, rings, ctxs = _batched(scene, q1, q2, total, threads=2)
    for i in range(q1.size):
        point = with_values(scene, {"initial.q1": float(q1[i]), "initial.q2": float(q2[i])})
        result = simulate(point, collisions=total)
        assert result.status.name == "COMPLETE" and stats[i, E.ST_STATUS] == E.RUN_COMPLETE
        _same_run(stats[i], rings[i], ctxs[i], result)
        assert ctxs[i, L.EN_Q1] == result.columns["q1"][-1]


def test_a_phases_start_lying_on_the_bottom_starts_in_contact() -> None:
    """A start placed where the ball rests (on the wall, pressed) starts in contact
    (sliding: the shaken bottom moves under it), as a run's set-up starts it, and runs
    as the run does; so does one at rest on the bottom with a velocity (no initial
    position)."""
    scene = _phases("parabola-5.4hz")
    setup = EN.prepare(scene)
    q1, q2 = setup.at_rest[L.EN_Q1], setup.at_rest[L.EN_Q2]
    ctxs, ok = EN.start(setup, [q1], [q2])
    assert ok.all() and ctxs[0, L.MC_MODE] == setup.at_rest[L.MC_MODE] != L.M_FLIGHT
    np.testing.assert_array_equal(ctxs[0, L.MC_CONTACT : L.MC_CONTACT + 6],
                                  setup.at_rest[L.MC_CONTACT : L.MC_CONTACT + 6])  # fmt: skip
    stats, rings, ctxs = _batched(scene, [q1], [q2], 40)
    point = with_values(scene, {"initial.q1": float(q1), "initial.q2": float(q2)})
    _same_run(stats[0], rings[0], ctxs[0], simulate(point, collisions=40))
    kicked = with_values(scene, {"initial.v1": 0.3, "initial.omega": -5.0})
    setup = EN.prepare(kicked)
    ctxs = EN.start_at_rest(setup, 1, v1=0.3, omega=-5.0)
    consts = EN.constants(kicked, 1e-5, 64, 256)
    stats, rings = EN.advance(
        ctxs,
        setup.params,
        setup.walls,
        consts,
        nears=setup.nears,
        transient=0,
        impacts=40,
        width=40,
        threads=1,
    )
    _same_run(stats[0], rings[0], ctxs[0], simulate(kicked, collisions=40))


def test_phases_statuses_are_the_runs() -> None:
    """How a run under contact phases ends, batched as the run ends it: at rest on a
    still boundary, in contact for the contact span after some impacts, at a time
    limit while rolling, and at a time limit after the lid held the ball (a run that
    stopped as a collapse there before the lid could hold a ball)."""
    from tests.engine.test_run_ends import PRESSED_ON_THE_LID

    on_lid = [*PRESSED_ON_THE_LID, "run.duration=2"]
    cases = [
        (_gentle(**{"drive.amplitude": 0.0}), None, None, E.RUN_AT_REST, "AT_REST"),
        (_gentle(**{"run.contact_span": 1.0}), 0.0, 0.03, E.RUN_IN_CONTACT, "IN_CONTACT"),
        (_gentle(**{"run.duration": 3.0}), None, None, E.RUN_TIME_LIMIT, "TIME_LIMIT"),
        (load_scene("hyperbola-5.8hz", on_lid), "scene", None, E.RUN_TIME_LIMIT, "TIME_LIMIT"),
    ]  # fmt: skip
    for scene, q1, q2, status, name in cases:
        if q1 == "scene":
            q1, q2 = scene.initial.q1, scene.initial.q2
        if q1 is not None:
            scene = with_values(scene, {"initial.q1": q1, "initial.q2": q2})
        result = simulate(scene, collisions=100_000)
        assert result.status.name == name
        stats, rings, ctxs = _batched(
            scene, None if q1 is None else [q1], None if q2 is None else [q2], 100_000,
            duration=scene.run.duration,
        )  # fmt: skip
        assert stats[0, E.ST_STATUS] == status, name
        _same_run(stats[0], rings[0], ctxs[0], result)


def test_phases_start_is_the_vector_a_run_hands_the_state_machine(monkeypatch) -> None:
    """The state vector of a start, slot for slot, is the one a run's first call of
    the state machine gets (but the call's target and row counters): in flight, lying
    on the bottom, and at rest on the bottom with a velocity."""
    from billiard.kernels import machine
    from billiard.runfile.record import MemoryRecorder

    seen = []
    real = machine.run_machine

    def spy(ctx, *args):
        seen.append(np.array(ctx))
        return real(ctx, *args)

    monkeypatch.setattr(machine, "run_machine", spy)
    per_call = [L.EN_TARGET, L.MC_ROW, L.MC_CROW]

    def first_call(point) -> np.ndarray:
        seen.clear()
        Simulation(point).run(1, MemoryRecorder())
        vector = seen[0]
        vector[per_call] = 0.0
        return vector

    scene = _phases("wedge-6.6hz", **{"run.duration": 5.0, "initial.t": 0.1})
    setup = EN.prepare(scene)
    q1, q2 = _starts(5, 6)
    q1 = np.append(q1, setup.at_rest[L.EN_Q1])
    q2 = np.append(q2, setup.at_rest[L.EN_Q2])
    ctxs, ok = EN.start(setup, q1, q2, v1=0.2, t=0.1, duration=5.0)
    assert ok.sum() > 2 and ok[-1]
    for i in np.nonzero(ok)[0]:
        point = with_values(
            scene, {"initial.q1": float(q1[i]), "initial.q2": float(q2[i]), "initial.v1": 0.2}
        )
        ctxs[i, per_call] = 0.0
        np.testing.assert_array_equal(ctxs[i], first_call(point))
    kicked = with_values(scene, {"initial.v1": 0.3, "initial.omega": -5.0})
    ctx = EN.start_at_rest(EN.prepare(kicked), 1, v1=0.3, omega=-5.0, duration=5.0)[0]
    ctx[per_call] = 0.0
    np.testing.assert_array_equal(ctx, first_call(kicked))


def test_starts_set_up_in_slices_on_threads_are_the_starts_set_up_at_once(monkeypatch):
    from billiard.engine import ensemble as EN
    from billiard.scene.scene import load_scene

    setup = EN.prepare(load_scene("wedge-6.6hz"))
    q1, q2 = np.meshgrid(np.linspace(-0.04, 0.04, 9), np.linspace(0.02, 0.12, 7))
    whole, ok = EN.start(setup, q1.ravel(), q2.ravel(), v1=0.1)
    monkeypatch.setattr(EN, "START_SLICE", 5)
    monkeypatch.setattr(EN, "threads_default", lambda: 3)
    sliced, ok_sliced = EN.start(setup, q1.ravel(), q2.ravel(), v1=0.1)
    assert not ok.all() and ok.any()  # the grid reaches outside the wedge
    np.testing.assert_array_equal(ok_sliced, ok)
    np.testing.assert_array_equal(sliced, whole)
