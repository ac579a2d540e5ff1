"""The paper's calibration: a period-one orbit on the parabola at 0.075 m."""

from __future__ import annotations

import json
import math

import pytest

from billiard.analysis.calibrate import CalibrationError, calibrate, find_period_one
from billiard.cli import main
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values


@pytest.fixture(scope="module")
def parabola_calibration():
    scene = load_scene("parabola-5.4hz")
    return scene, calibrate(scene, "drive.amplitude", 0.075, low=0.02, high=0.03, points=3)


def test_calibrated_amplitude_is_the_scenes_default(parabola_calibration):
    scene, cal = parabola_calibration
    # The built-in scenes carry the calibrated amplitude rounded to 4 significant digits.
    assert cal.value == pytest.approx(scene.drive.amplitude, rel=2e-4)
    assert cal.orbit.height == pytest.approx(0.075, abs=1e-5)
    # Period one: the ball crosses from wall to wall in half a drive period.
    assert cal.orbit.time_of_flight == pytest.approx(0.5 / scene.drive.frequency, rel=1e-6)
    # The normalized point under the default reference (lowest-centre: potential zero at
    # the resting ball's centre c + r, spin left out), from its definition on the orbit's
    # own numbers.
    o = cal.orbit
    m, g = scene.ball.mass, scene.run.gravity
    r, k = scene.ball.radius, scene.ball.inertia_factor
    h0 = 0.0063 + r  # c + r: the bottom is smooth (radius of curvature 19 mm > r)
    e0 = o.energy - m * g * h0 - 0.5 * k * m * r**2 * o.omega**2
    assert o.reference == "lowest-centre"
    assert o.q2_normalized == pytest.approx((o.height - h0) * m * g / e0, rel=1e-9)
    assert abs(o.u4_normalized) == pytest.approx(abs(o.u4) / math.sqrt(2 * e0 / m), rel=1e-9)
    assert 0 < o.q2_normalized < 1 and abs(o.u4_normalized) < 0.2
    # The paper's point, (0.376, +-0.0372), to its own digits in height and within 1 %
    # in tangential velocity.
    assert round(o.q2_normalized, 3) == 0.376
    assert abs(o.u4_normalized) == pytest.approx(0.0372, rel=0.01)


def test_low_energy_state_is_not_a_period_one_orbit():
    scene = with_values(load_scene("parabola-5.4hz"), {"drive.amplitude": 0.01})
    result = simulate(scene, collisions=1500)
    assert find_period_one(result.columns, scene.ball.mass, scene.run.gravity) is None


def test_calibration_without_an_orbit_in_range_fails_in_one_line():
    scene = load_scene("parabola-5.4hz")
    with pytest.raises(CalibrationError) as info:
        calibrate(scene, "drive.amplitude", 0.075, low=0.005, high=0.008, points=2, impacts=300)
    assert "\n" not in str(info.value) and "no period-one orbit" in str(info.value)
    with pytest.raises(CalibrationError):
        calibrate(scene, "drive.colour", 0.075)


def test_calibrate_command_prints_json(capsys):
    code = main(
        [
            "calibrate",
            "parabola-5.4hz",
            "--parameter",
            "drive.amplitude",
            "--target-height",
            "0.075",
            "--low",
            "0.024",
            "--high",
            "0.027",
            "--json",
        ]
    )
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert data["parameter"] == "drive.amplitude"
    assert data["value"] == pytest.approx(0.02543, rel=2e-4)
    assert data["orbit_height"] == pytest.approx(0.075, abs=1e-5)


def test_restitution_round_trip():
    """At the calibrated amplitude, fitting e the paper's way gives back the paper's e."""
    scene = load_scene("parabola-5.4hz")
    cal = calibrate(scene, "contact.restitution", 0.075, low=0.3, high=0.5, points=3)
    assert cal.value == pytest.approx(0.393, abs=5e-4)
