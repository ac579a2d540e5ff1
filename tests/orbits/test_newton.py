"""find_orbit: Newton's method on the engine's return map, against the bouncing ball's
closed forms (tests/orbits/table.py), and on the parabola's period-one orbit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.orbits.newton import NEWTON_TOL, find_orbit
from billiard.orbits.returnmap import OrbitError
from billiard.scene.scene import load_scene
from tests.orbits import table


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


VERTICAL = ("t", "v2")  # the ball bounces straight up: v1 = omega = 0 stays so


@pytest.mark.parametrize("stable", [True, False], ids=["stable", "unstable"])
@pytest.mark.parametrize("gamma,e", [(1.3, 0.5), (2.0, 0.7), (1.6, 0.5)])
def test_the_bouncing_balls_period_one_orbits(gamma, e, stable):
    t, v = table.orbit(gamma, e, 1, stable)
    scene = table.scene(gamma, e)
    # a guess 1e-3 off in phase and speed: Newton must find the closed form's orbit
    orbit = find_orbit(
        scene, 1, guess=(t + 1e-3 * table.T, 0.0, 0.0, v * 1.001, 0.0), free=VERTICAL
    )
    assert orbit.periods == 1 and orbit.residual <= NEWTON_TOL
    # the orbit: its phase and take-off speed from Gamma cos(theta) = pi (1 - e)/(1 + e);
    # 1e-12 s and 1e-12 m/s are the rounding of the closed form's acos and of the map
    assert orbit.x[0] == pytest.approx(t, abs=1e-12)
    assert orbit.x[3] == pytest.approx(v, abs=1e-12)
    expected = table.multipliers(gamma, e, 1, stable)
    got = orbit.multipliers
    # the multipliers: the eigenvalues of the 2-D map's Jacobian derived in table.py
    assert np.sort_complex(got) == pytest.approx(np.sort_complex(expected), abs=1e-9)
    # det = e^2 for every period-one orbit of the exact map
    assert np.prod(got).real == pytest.approx(e * e, rel=1e-9)
    unstable_expected = not np.all(np.abs(expected) < 1)
    assert orbit.stable is not unstable_expected
    assert orbit.stable is (stable and gamma < table.period_doubling(e))


def test_the_parabolas_period_one_orbit_is_stable_at_5_4_hz():
    """The paper's orbit: two impacts a drive period, one on each side, about 0.075 m up
    (the drive amplitude was calibrated to put it there)."""
    scene = load_scene("parabola-5.4hz")
    orbit = find_orbit(scene, 2)
    assert orbit.residual <= NEWTON_TOL
    assert orbit.periods == 1
    assert orbit.lab[1] == pytest.approx(0.075, abs=1e-4)
    assert orbit.stable and np.max(np.abs(orbit.multipliers)) < 0.9
    # mirror symmetric: the second impact is the first reflected (s, v1, omega change sign)
    second = orbit.records[0]
    assert second.s == pytest.approx(-orbit.x[1], rel=1e-9)
    assert second.v2 == pytest.approx(orbit.x[3], rel=1e-9)
    assert second.t - orbit.x[0] == pytest.approx(1 / 5.4 / 2, rel=1e-9)


def test_a_guess_without_an_orbit_near_it_is_refused_in_one_line():
    scene = table.scene(1.3, 0.5)
    with pytest.raises(OrbitError, match="free coordinates must be some of"):
        find_orbit(scene, 1, guess=(0.0, 0.0, 0.0, 0.2, 0.0), free=("x",))
    with pytest.raises(OrbitError, match="less than half a drive period"):
        find_orbit(scene, 1, guess=(0.0, 0.0, 0.0, 0.01, 0.0), free=VERTICAL)
    with pytest.raises(OrbitError, match="five finite numbers"):
        find_orbit(scene, 1, guess=(0.0, math.nan, 0.0, 0.2, 0.0))


def test_the_public_api_has_find_orbit_and_continue_orbit():
    import billiard
    from billiard.orbits.continuation import continue_orbit

    assert billiard.find_orbit is find_orbit
    assert billiard.continue_orbit is continue_orbit
