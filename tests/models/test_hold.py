"""The spin with which two walls hold a ball (``VertexHold.held_spin``), against the
closed form of the spin-down written here: the walls' kinetic friction stops a spin u3
in t* = k m r |u3| / (mu_k (N_a + N_b)) (Euler's law I du3/dt = -r mu_k (N_a + N_b) for
a sphere, I = k m r^2), N of the spinless hold."""

from __future__ import annotations

import math

from billiard import load_scene
from billiard.engine.simulation import Simulation

#: tangent angle of the wedge's walls (rad): y = 1.85 |x|
BETA = math.atan(1.85)


def _hold():
    scene = load_scene("wedge-6.6hz", ["contact.model=phases", "drive.amplitude=0.005"])
    return Simulation(scene).vertex_hold, scene


def test_a_spin_the_walls_hold_is_kept():
    hold, _ = _hold()
    # drive angle 0: both walls press a spinning ball
    assert hold.holds(-BETA, BETA, 0.0, -3.0)
    assert hold.held_spin(-BETA, BETA, 0.0, -3.0) == -3.0


def test_a_spin_that_friction_stops_at_once_is_held_as_none():
    hold, sc = _hold()
    theta = 1.5  # the shaken wedge's lateral push: a negative spin's friction lifts wall a
    assert hold.forces(-BETA, BETA, theta, -1.0)[0] < 0.0
    n_a, n_b = hold.forces(-BETA, BETA, theta, 0.0)
    assert n_a > 0.0 and n_b > 0.0
    ball, contact = sc.ball, sc.contact
    period = 1.0 / sc.drive.frequency
    # the largest spin stopped within 1e-6 of a drive period (CHATTER_TAIL)
    k, m, r = ball.inertia_factor, ball.mass, ball.radius
    largest = 1e-6 * period * contact.mu_kinetic * (n_a + n_b) / (k * m * r)
    assert hold.held_spin(-BETA, BETA, theta, -0.99 * largest) == 0.0
    assert math.isnan(hold.held_spin(-BETA, BETA, theta, -1.01 * largest))
