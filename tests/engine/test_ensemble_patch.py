"""Set-ups patched from another parameter set's (a parameter map's points) equal the
set-ups made from a Simulation of their own, slot for slot."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.engine import ensemble as EN
from billiard.scene.scene import load_scene, with_values

#: a value of each patched key, away from its scene's value
CHANGES = {
    "drive.amplitude": 0.0213,
    "drive.frequency": 6.1,
    "drive.phase": 0.7,
    "contact.restitution": 0.51,
    "contact.mu_static": 0.7,
    "contact.mu_kinetic": 0.3,
    "contact.elastic_below": 0.02,
    "contact.law": "point-particle",
    "contact.beta0": 0.3,
    "contact.e_ref": 0.45,
    "contact.v_ref": 0.5,
    "contact.exponent": 0.1,
    "contact.viscous": 0.05,
    "contact.energy_scale": 1e-5,
    "contact.angle_slope": 0.1,
    "air.c_lin": 3e-7,
    "air.c_quad": 2e-6,
    "air.magnus": 1e-9,
    "ball.mass": 2e-4,
    "ball.inertia_factor": 0.35,
}


def test_every_patch_key_is_changed_here():
    assert set(CHANGES) == EN.PATCH_KEYS


@pytest.mark.parametrize(
    ("name", "direction"),
    [
        ("parabola-5.4hz", "horizontal"),
        ("parabola-5.4hz", "vertical"),
        ("wedge-6.6hz", "horizontal"),
        ("hyperbola-4.5hz", "horizontal"),
    ],
)
@pytest.mark.parametrize("key", sorted(CHANGES))
def test_a_patched_setup_is_the_prepared_one(name, direction, key):
    scene = load_scene(name)
    scene = with_values(scene, {"contact.model": "impacts", "drive.direction": direction})
    base = EN.prepare(scene)
    changed = with_values(scene, {key: CHANGES[key]})
    own = EN.prepare(changed)
    patched = EN.patch(base, changed)
    np.testing.assert_array_equal(patched.template, own.template)
    np.testing.assert_array_equal(patched.at_rest, own.at_rest)
    assert patched.rest_height == own.rest_height
    assert (patched.lid_level, patched.escape_level) == (own.lid_level, own.escape_level)
