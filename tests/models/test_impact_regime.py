"""The impact's regime is decided by the friction cone, not by rounding: a purely normal
impact (no tangential relative velocity, no spin) sticks for every angle and speed, even
with mu_s = 0; an impact genuinely outside the cone slips."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.engine.state import BallState
from billiard.models.impact import Contact, KaneLevinsonImpact

BALL = (1.3028e-4, 1.55e-3, 0.4)


def law(mu_s: float, elastic_below: float = 0.0) -> KaneLevinsonImpact:
    return KaneLevinsonImpact(*BALL, 0.393, mu_s, 0.77 * mu_s, elastic_below)


def changed(state: BallState, **speeds: float) -> BallState:
    values = {
        name: getattr(state, name) for name in ("t", "theta", "q1", "q2", "u1", "u2", "u3", "q3")
    }
    return BallState(**{**values, **speeds})


def normal_impact(z: float, speed: float, wall_normal: float, wall_tangential: float):
    """A ball approaching a wall of tangent angle z at ``speed`` along its normal, the
    wall moving with the given normal and tangential speeds: the contact point's
    relative velocity is purely normal."""
    c1 = (math.cos(z), math.sin(z))
    c2 = (-math.sin(z), math.cos(z))
    vb1 = wall_normal * c2[0] + wall_tangential * c1[0]
    vb2 = wall_normal * c2[1] + wall_tangential * c1[1]
    u1, u2 = vb1 - speed * c2[0], vb2 - speed * c2[1]
    return BallState(0.0, 0.0, 0.0, 0.0, u1, u2, 0.0, 0.0), Contact(z, vb1, vb2, False)


@pytest.mark.parametrize("mu_s", [0.0, 1e-9, 0.61])
def test_a_normal_impact_sticks_for_every_angle_and_speed(mu_s):
    impact = law(mu_s)
    regimes = []
    for z in np.linspace(-1.5, 1.5, 121):
        for speed in (1e-4, 3e-3, 0.05, 0.4, 1.3, 4.0):
            for wall_normal in (0.0, -0.3, 0.9):
                for wall_tangential in (0.0, 0.25, -1.1):
                    state, contact = normal_impact(z, speed, wall_normal, wall_tangential)
                    result = impact.apply(state, contact)
                    assert abs(result.wt) < 1e-15 * (1 + abs(wall_tangential))
                    regimes.append(result.regime)
    assert set(regimes) == {"stick"}, regimes.count("slip")


def test_a_genuinely_slipping_impact_slips():
    impact = law(0.61)
    for z in np.linspace(-1.2, 1.2, 25):
        c1 = (math.cos(z), math.sin(z))
        state, contact = normal_impact(z, 0.5, 0.0, 0.0)
        state = changed(state, u1=state.u1 + 3.0 * c1[0], u2=state.u2 + 3.0 * c1[1])
        assert impact.apply(state, contact).regime == "slip"
    # with mu_s = 0 any tangential relative velocity at all slips
    frictionless = law(0.0)
    state, contact = normal_impact(0.3, 0.5, 0.0, 0.0)
    assert frictionless.apply(changed(state, u3=1e-6), contact).regime == "slip"


def test_the_cone_edge_is_still_resolved():
    """Just inside the cone (by 1e-9 of its width) sticks, just outside slips: the
    tolerance is rounding-sized, not a change of the law."""
    impact = law(0.2)
    state, contact = normal_impact(0.4, 1.0, 0.0, 0.0)
    # the tangential slip speed at which the no-slip impulse is exactly at the cone edge
    # is linear in the slip speed: find it from one evaluation
    probe = impact.apply(changed(state, u3=100.0), contact)
    rn = probe.Rn
    scale = 0.2 * rn / abs(probe.Rt)
    inside = impact.apply(changed(state, u3=100.0 * scale * (1 - 1e-9)), contact)
    outside = impact.apply(changed(state, u3=100.0 * scale * (1 + 1e-9)), contact)
    assert (inside.regime, outside.regime) == ("stick", "slip")
