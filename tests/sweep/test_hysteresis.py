"""Up/down sweeps: a continued trajectory is the uninterrupted one, the drive angle is
carried through a change of frequency, and the parabola shows its bistability."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from billiard.engine import ensemble as EN
from billiard.kernels import ensemble as E
from billiard.kernels import layout as L
from billiard.scene.scene import load_scene, with_values
from billiard.sweep.hysteresis import (
    continue_states,
    drive_phases,
    hysteresis_figure,
    run_hysteresis,
    start_grid,
    write_csv,
)

BALL = [L.EN_T, L.EN_THETA, L.EN_Q1, L.EN_Q2, L.EN_U1, L.EN_U2, L.EN_U3]


@pytest.fixture(scope="module")
def parabola():
    return load_scene("parabola-5.4hz")


def _rows(ctx, setup, count):
    out = np.empty(count * L.NCOL)
    done = E.run_rows(ctx, setup.params, setup.walls, out, count)
    return out.reshape(count, L.NCOL)[:done]


def test_a_continued_trajectory_is_the_uninterrupted_one(parabola):
    """Continued at the same parameters, the next impacts are the same, bit for bit:
    the continuation carries every slot the next flight reads."""
    setup = EN.prepare(parabola)
    ctxs, ok = EN.start(setup, np.array([0.012]), np.array([0.05]))
    assert ok.all()
    _rows(ctxs[0], setup, 7)
    again, ok = continue_states(setup, ctxs.copy())
    assert ok.all() and again[0, L.EN_IMPACTS] == 0.0
    straight = _rows(ctxs[0].copy(), setup, 7 + 30)  # impacts 8 .. 37
    continued = _rows(again[0].copy(), setup, 30)
    assert straight.shape == continued.shape == (30, L.NCOL)
    assert np.array_equal(straight[:, 1:], continued[:, 1:])  # all but the impact number


def test_the_drive_angle_is_carried_through_a_change_of_frequency(parabola):
    low = EN.prepare(parabola)
    high = EN.prepare(with_values(parabola, {"drive.frequency": 6.0}))
    ctxs, _ = EN.start(low, np.array([0.0, 0.01]), np.array([0.04, 0.06]))
    for ctx in ctxs:
        _rows(ctx, low, 11)
    before = ctxs.copy()
    after, ok = continue_states(high, ctxs)
    assert ok.all()
    assert np.array_equal(after[:, BALL], before[:, BALL])  # theta kept, not recomputed
    assert np.all(after[:, L.OMEGA] == 2.0 * math.pi * 6.0)
    # from the switch on the kernel turns the drive at the new frequency from the kept
    # angle: omega_new t + (the phase drive_phases gives) is the angle at every impact
    phases = drive_phases(after, 6.0)
    for i, ctx in enumerate(after):
        rows = _rows(ctx, high, 20)
        angle = 2.0 * math.pi * 6.0 * rows[-1, 1] + phases[i]
        assert abs(math.remainder(angle - ctx[L.EN_THETA], 2.0 * math.pi)) < 1e-9
    # and at the scene's own frequency the phase is the scene's
    assert np.allclose(drive_phases(before, 5.4), parabola.drive.phase % (2 * math.pi))


def test_the_starts(parabola):
    setup = EN.prepare(parabola)
    q1, q2 = start_grid(parabola, setup, 1)
    assert (q1[0], q2[0]) == (setup.template[L.EN_Q1], setup.template[L.EN_Q2])
    assert q2[0] == setup.rest_height
    q1, q2 = start_grid(parabola, setup, 12)
    assert q1.size == 12 and len(set(zip(q1, q2, strict=True))) == 12
    _, ok = EN.start(setup, q1, q2)
    assert ok.all()
    assert q2.min() > setup.rest_height and q2.max() - q2.min() > 0.03  # spread up
    assert q1.min() < -0.005 and q1.max() > 0.005  # and across
    with pytest.raises(ValueError, match="starts must be >= 1"):
        start_grid(parabola, setup, 0)


def test_the_parabola_is_bistable_near_4_8_hz(parabola, tmp_path):
    """Coming up from 4.7 Hz the ball stays on the low period-one orbit at 4.8 Hz;
    coming down from 4.9 Hz it stays on a higher orbit (period 7): two attractors at
    one frequency, told apart only by the history."""
    result = run_hysteresis(
        parabola, "drive.frequency", [4.9, 4.7, 4.8], impacts=100, transient=200
    )
    assert list(result.values) == [4.7, 4.8, 4.9]
    assert result.columns["height_mean"].shape == (2, 3, 1)
    up, down = result.columns["height_mean"][:, 1, 0]
    assert result.columns["period"][0, 1, 0] == 2
    assert abs(up - 0.0227) < 1e-3
    assert down - up > 5e-3
    assert result.columns["attractor"][1, 1, 0] == "periodic"
    assert result.columns["period"][1, 1, 0] not in (0, 2)
    # at 4.7 Hz both ways meet the same orbit again
    assert abs(np.diff(result.columns["height_mean"][:, 0, 0])[0]) < 1e-4
    path = write_csv(result, tmp_path / "h.csv")
    with open(path) as f:
        rows = list(csv.DictReader(f))
    assert [(r["direction"], float(r["value"])) for r in rows] == [
        ("up", 4.7), ("up", 4.8), ("up", 4.9), ("down", 4.9), ("down", 4.8), ("down", 4.7),
    ]  # fmt: skip
    assert float(rows[4]["height_mean_m"]) == down
    figure = hysteresis_figure(result, tmp_path / "h.png")
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_orbit_of_the_calibrated_frequency(parabola):
    """parabola-5.4hz's drive amplitude puts its period-one orbit at 0.075 m at 5.4 Hz
    (the scene's calibration), whichever way the frequency comes from."""
    result = run_hysteresis(
        parabola, "drive.frequency", [5.3, 5.4, 5.5], starts=4, impacts=100, transient=300
    )
    heights = result.columns["height_mean"][:, 1, :]
    assert heights.shape == (2, 4)
    assert np.all(np.abs(heights - 0.075) < 5e-4)
    assert np.all(result.columns["period"][:, 1, :] == 2)


@pytest.mark.parametrize(
    ("key", "values", "match"),
    [
        ("drive.frequency", [5.0], "at least 2 values"),
        ("initial.q1", [0.0, 0.01], "ball's start"),
        ("drive.phase", [0.0, 1.0], "the phase has no effect"),
        ("drive.frequency", [5.0, "6"], "not a number"),
        ("drive.frequency", [5.0, math.nan], "not a finite number"),
    ],
)
def test_bad_sweeps_are_refused(parabola, key, values, match):
    with pytest.raises(ValueError, match=match):
        run_hysteresis(parabola, key, values)


def test_a_scene_the_ensemble_kernel_does_not_take(parabola):
    phases = with_values(parabola, {"contact.model": "phases"})
    with pytest.raises(ValueError, match="contact.model = 'phases'"):
        run_hysteresis(phases, "drive.frequency", [5.0, 5.1])


def test_the_result_does_not_depend_on_the_chunks(parabola, monkeypatch):
    """Between values only the carried slots are kept, chunk by chunk: chunks of 3
    trajectories give what one chunk gives, value for value."""
    import billiard.sweep.hysteresis as H

    args = (parabola, "drive.frequency", [4.7, 4.8, 4.9])
    kwargs = {"starts": 7, "impacts": 40, "transient": 60}
    whole = run_hysteresis(*args, **kwargs)
    monkeypatch.setattr(H, "CHUNK", 3)
    chunked = run_hysteresis(*args, **kwargs)
    for name, column in whole.columns.items():
        assert np.array_equal(column, chunked.columns[name], equal_nan=column.dtype != object)


def test_the_public_name_takes_a_scene_name():
    import billiard

    assert billiard.run_hysteresis is run_hysteresis
    result = billiard.run_hysteresis(
        "parabola-5.4hz", "drive.frequency", [5.3, 5.4], impacts=30, transient=50
    )
    assert result.scene.name == "parabola-5.4hz" and result.values.tolist() == [5.3, 5.4]
