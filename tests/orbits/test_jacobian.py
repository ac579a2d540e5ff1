"""The return map and its exact Jacobian (flight variational equations, saltation of
each impact) against central finite differences of the engine's own map."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.orbits.jacobian import map_jacobian
from billiard.orbits.returnmap import OrbitError, ReturnMap
from billiard.scene.scene import load_scene, with_values

#: Typical sizes of (t, s, v1, v2, omega) on the parabola's orbit (s, m, m/s, m/s, rad/s):
#: the Jacobian is compared made dimensionless by them, column by column.
SCALE = np.array([0.1, 0.05, 1.0, 1.0, 100.0])
#: Central differences' steps, 1e-7 of each scale: their truncation error (h^2 ~ 1e-14)
#: and their rounding error (1e-16 / 1e-7 = 1e-9) both lie far below the 1e-6 asked.
STEP = 1e-7 * SCALE


def _engine_orbit_state(scene, impacts=400):
    """The state after ``impacts`` impacts of the scene's run (near its orbit)."""
    rm = ReturnMap(scene)
    record = rm.run_scene(impacts)[-1]
    # t reduced to the first drive period: its rounding then stays ~1e-17 s
    t = record.t % rm.period
    return np.array([t, record.s, record.v1, record.v2, record.omega]), int(record.wall)


def _finite_differences(rm, x, wall):
    jac = np.empty((5, 5))
    for j in range(5):
        up, down = x.copy(), x.copy()
        up[j] += STEP[j]
        down[j] -= STEP[j]
        jac[:, j] = (rm(up, wall)[0].x - rm(down, wall)[0].x) / (2 * STEP[j])
    return jac


@pytest.mark.parametrize(
    "changes",
    [
        pytest.param({"run.rtol": 1e-13}, id="fowles-drag"),
        pytest.param({"air.drag": "none"}, id="no-air"),
        pytest.param(
            {"air.drag": "none", "contact.mu_static": 0.1, "contact.mu_kinetic": 0.08},
            id="slipping",
        ),
    ],
)
@pytest.mark.parametrize("impacts", [1, 2])
def test_the_jacobian_matches_central_differences_of_the_engines_map(changes, impacts):
    # under drag the engine's adaptive steps change discretely with the start: its tighter
    # tolerance (1e-13) keeps that noise below the differences' 1e-9
    scene = with_values(load_scene("parabola-5.4hz"), changes)
    x, wall = _engine_orbit_state(scene)
    if "contact.mu_static" in changes:
        x[4] = 2000.0  # a fast spin: the next impact meets a slip of about r omega = 3 m/s
    rm = ReturnMap(scene, impacts)
    landing, records = rm(x, wall)
    exact = map_jacobian(rm, x, wall, records) * SCALE / SCALE[:, None]
    numeric = _finite_differences(rm, x, wall) * SCALE / SCALE[:, None]
    error = np.linalg.norm(exact - numeric, axis=0) / np.linalg.norm(exact, axis=0)
    assert np.all(error < 1e-6), error
    if "contact.mu_static" in changes:
        assert records[0].regime == "slip"  # the slipping law's derivative


def test_the_map_is_the_engines_run():
    """P from a recorded impact lands on the run's next record (the same engine)."""
    scene = load_scene("parabola-5.4hz")
    rm = ReturnMap(scene, 1)
    records = rm.run_scene(50)
    for before, after in zip(records[-5:-1], records[-4:], strict=True):
        x = np.array([before.t, before.s, before.v1, before.v2, before.omega])
        landing, _ = rm(x, int(before.wall))
        expected = np.array([after.t, after.s, after.v1, after.v2, after.omega])
        # the start is rebuilt from (t, s): its centre differs from the run's by rounding
        assert landing.x == pytest.approx(expected, rel=1e-11, abs=1e-13)
        assert landing.wall == after.wall


def test_a_scene_under_contact_phases_is_refused():
    scene = with_values(load_scene("parabola-5.4hz"), {"contact.model": "phases"})
    with pytest.raises(OrbitError, match='need contact.model = "impacts"'):
        ReturnMap(scene)
