"""Period detection and attractor classes on synthetic impact sequences (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.sweep.attractor import classify, find_period
from billiard.sweep.basins import attractor_labels

F = 5.4  # Hz


def _columns(q1, q2, t):
    n = len(q2)
    zeros = np.zeros(n)
    return {"q1": np.asarray(q1), "q2": np.asarray(q2), "v1": zeros, "v2": zeros,
            "omega": zeros, "t": np.asarray(t)}  # fmt: skip


def _period(cols, tolerance=1e-5):
    return find_period(
        cols, frequency=F, phase=0.0, radius=1.55e-3, g=9.81, tolerance=tolerance, max_period=16
    )


def test_alternating_walls_is_period_two_though_heights_repeat_every_impact():
    n = 200
    t = np.arange(n) / (2 * F)  # one impact per half drive period
    q1 = np.where(np.arange(n) % 2 == 0, -0.05, 0.05)
    cols = _columns(q1, np.full(n, 0.075), t)
    assert _period(cols) == 2


def test_same_state_at_a_different_drive_phase_is_not_the_same_state():
    n = 200
    t = np.arange(n) * (1 / F) * 1.37  # same position every impact, drifting phase
    cols = _columns(np.zeros(n), np.full(n, 0.05), t)
    assert _period(cols) == 0
    cols = _columns(np.zeros(n), np.full(n, 0.05), np.arange(n) / F)
    assert _period(cols) == 1


def test_period_three_and_tolerance():
    n = 300
    pattern = np.array([0.02, 0.05, 0.09])
    q2 = np.tile(pattern, n // 3)
    t = np.arange(n) / F
    assert _period(_columns(np.zeros(n), q2, t)) == 3
    noisy = q2 + 1e-4 * np.sin(np.arange(n))  # 0.1 mm wobble: not periodic at 10 um
    assert _period(_columns(np.zeros(n), noisy, t)) == 0
    assert _period(_columns(np.zeros(n), noisy, t), tolerance=1e-3) == 3


def test_chaotic_sequence_has_no_period():
    rng = np.random.default_rng(1)
    n = 300
    cols = _columns(
        rng.uniform(-0.05, 0.05, n), rng.uniform(0.01, 0.1, n), np.cumsum(rng.uniform(0.01, 0.1, n))
    )
    assert _period(cols) == 0


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"failed": True}, "failed"),
        ({"rise": 0.004, "elastic_share": 0.8}, "resting"),
        ({"rise": 0.004, "elastic_share": 0.1, "period": 2}, "periodic"),  # low orbit, flying
        ({"rise": 0.05, "elastic_share": 0.8, "period": 0}, "aperiodic"),
        ({"rise": 0.05, "period": 0, "lyapunov": 0.1}, "chaotic"),
        ({"rise": 0.05, "period": 0, "lyapunov": 0.001}, "quasi-periodic"),
        ({"rise": 0.05, "period": 0, "lyapunov": math.nan}, "aperiodic"),
    ],
)
def test_classify(kwargs, expected):
    args = {"failed": False, "period": 0, "rise": 0.05, "elastic_share": 0.0,
            "rest_band": 0.01, "lyapunov": None, "chaos_threshold": 0.01} | kwargs  # fmt: skip
    assert classify(**args) == expected


def test_attractor_labels_tell_orbits_apart_by_height():
    def rec(attractor, period=0, height=None):
        return {"attractor": attractor, "period": period, "height_mean": height}

    records = [
        rec("periodic", 2, 0.0750),
        rec("resting"),
        rec("periodic", 2, 0.0352),
        rec("periodic", 2, 0.07505),
        rec("failed"),
    ]
    ids, labels = attractor_labels(records)
    assert labels == [
        "failed",
        "resting",
        "period 2, mean q2 0.0352 m",
        "period 2, mean q2 0.0750 m",
    ]
    assert ids == [3, 1, 2, 3, 0]
