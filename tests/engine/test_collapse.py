"""Inelastic collapse: impacts whose flight times shrink to nothing (a geometric series
converging to the moment the ball comes to rest) stop the run with the documented
message, within a few hundred impacts; the paper scenes never trip it."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.run.simulate import COLLAPSE_COUNT, COLLAPSE_SPAN, Status, simulate
from billiard.scene.scene import load_scene, scene_from_toml

TABLE = """
name = "table-vertical"
[boundary]
curve = "0"
ceiling = 0.2
[drive]
amplitude = 0.003976
frequency = 10.0
direction = "vertical"
[contact]
model = "impacts"  # contact phases sum the series and land (tests/validation/test_chatter.py)
restitution = 0.393
elastic_below = 0.0
[air]
drag = "none"
[initial]
q1 = 0.0
q2 = 0.012
"""


def test_tiny_flights_accumulating_stop_the_run(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    result = simulate(scene_from_toml(TABLE), collisions=2000)
    assert result.status == Status.COLLAPSE
    n = len(result)
    assert result.stop_reason.startswith(
        f"inelastic collapse: {COLLAPSE_COUNT} impacts within {COLLAPSE_SPAN:g} s of "
        f"simulated time, at impact {n} (t = "
    )
    tof = result.columns["tof"]
    # it stopped within a few hundred impacts of the flights falling below the span,
    # none of them zero: a geometric series, not a pile-up at one instant
    first_tiny = int(np.argmax(tof < COLLAPSE_SPAN))
    assert n - first_tiny <= COLLAPSE_COUNT + 1 and n < 300
    assert np.all(tof > 0.0)
    ratios = tof[first_tiny - 8 : first_tiny] / tof[first_tiny - 9 : first_tiny - 1]
    assert np.all((ratios > 0.1) & (ratios < 0.5))  # about e^2 = 0.154 ... 0.4


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["parabola-5.4hz", "wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz"]
)
def test_the_paper_scenes_never_collapse(name):
    result = simulate(load_scene(name), collisions=25_000)
    assert result.stop_reason is None and len(result) == 25_000
    t = result.columns["t"]
    assert np.all(np.diff(t) >= COLLAPSE_SPAN)  # not even two impacts within the span


@pytest.mark.parametrize(
    "name", ["parabola-5.4hz", "wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz"]
)
def test_the_paper_scenes_keep_far_from_the_criterion(name):
    result = simulate(load_scene(name), collisions=2_000)
    assert result.stop_reason is None
    assert np.diff(result.columns["t"]).min() > COLLAPSE_SPAN
