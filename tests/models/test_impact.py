"""The Kane-Levinson impact law with a moving boundary."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from billiard.models.impact import Contact, KaneLevinsonImpact

M, R, K = 1.3028e-4, 1.55e-3, 0.4
E, MU_S, MU_K, V_E = 0.393, 0.61, 0.47, 0.01


def law(elastic_below=V_E, e=E):
    return KaneLevinsonImpact(M, R, K, e, MU_S, MU_K, elastic_below)


def ball(u1, u2, u3):
    return SimpleNamespace(u1=u1, u2=u2, u3=u3)


def contact_velocity(u1, u2, u3, contact):
    c, s = math.cos(contact.z), math.sin(contact.z)
    x1, x2 = u1 - contact.vb1, u2 - contact.vb2
    return c * x1 + s * x2 + R * u3, -s * x1 + c * x2


def random_impacts(n, seed=3, moving=True):
    """Approaching balls: random tangent angle, boundary velocity, slip and spin."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        z = rng.uniform(-1.2, 1.2)
        vb = rng.uniform(-0.3, 0.3, size=2) if moving else (0.0, 0.0)
        contact = Contact(z, float(vb[0]), float(vb[1]))
        c, s = math.cos(z), math.sin(z)
        wn = -rng.uniform(0.05, 2.0)  # approaching
        wt = rng.uniform(-2.0, 2.0)
        u3 = rng.uniform(-500, 500)
        vt = wt - R * u3  # tangential centre velocity relative to the boundary
        u1 = contact.vb1 + c * vt - s * wn
        u2 = contact.vb2 + s * vt + c * wn
        yield ball(u1, u2, u3), contact


def test_restitution_friction_and_momentum():
    stick = slip = 0
    for state, contact in random_impacts(300):
        wt, wn = contact_velocity(state.u1, state.u2, state.u3, contact)
        out = law().apply(state, contact)
        wt2, wn2 = contact_velocity(out.u1, out.u2, out.u3, contact)
        assert (out.wt, out.wn) == pytest.approx((wt, wn), abs=1e-12)
        assert wn2 == pytest.approx(-E * wn, rel=1e-9)  # Newton restitution
        assert out.Rn > 0.0
        # the impulse is the change of momentum, and its moment changes the spin
        c, s = math.cos(contact.z), math.sin(contact.z)
        assert out.Rt * c - out.Rn * s == pytest.approx(
            M * (out.u1 - state.u1), rel=1e-9, abs=1e-15
        )
        assert out.Rt / (K * M * R) == pytest.approx(out.u3 - state.u3, rel=1e-9, abs=1e-9)
        if out.regime == "stick":
            stick += 1
            assert abs(wt2) < 1e-9 and abs(out.Rt) <= MU_S * out.Rn * (1 + 1e-12)
        else:
            slip += 1
            assert out.regime == "slip"
            assert out.Rt == pytest.approx(-math.copysign(MU_K * out.Rn, wt), rel=1e-12)
    assert stick > 20 and slip > 20


def test_energy_never_grows_on_a_fixed_boundary():
    for state, contact in random_impacts(300, seed=5, moving=False):
        out = law().apply(state, contact)

        def energy(u1, u2, u3):
            return 0.5 * M * (u1 * u1 + u2 * u2) + 0.5 * K * M * R * R * u3 * u3

        assert energy(out.u1, out.u2, out.u3) <= energy(state.u1, state.u2, state.u3) * (1 + 1e-12)


def test_low_velocity_rule_is_elastic():
    contact = Contact(0.3, 0.1, 0.0)
    c, s = math.cos(0.3), math.sin(0.3)
    wn = -0.004
    state = ball(0.1 - s * wn, c * wn, 0.0)
    out = law().apply(state, contact)
    assert out.regime == "elastic" and not out.resting
    assert contact_velocity(out.u1, out.u2, out.u3, contact)[1] == pytest.approx(-wn, rel=1e-9)
    assert law(elastic_below=0.0).apply(state, contact).regime in ("stick", "slip")


def test_lying_ball_is_lifted_at_elastic_below():
    """A ball at rest on the bottom of a horizontally shaken container: zero normal
    velocity, pressed into the wall. It leaves at elastic_below, and friction acts."""
    contact = Contact(0.0, 0.15, 0.0, pressing=True)
    out = law().apply(ball(0.0, 0.0, 0.0), contact)
    assert out.resting and out.regime == "elastic"
    wt2, wn2 = contact_velocity(out.u1, out.u2, out.u3, contact)
    assert wn2 == pytest.approx(V_E, rel=1e-12)
    assert out.Rn == pytest.approx(M * out.u2, rel=1e-12)  # impulse on the true state
    assert out.u3 != 0.0  # friction spun the ball
    not_pressed = law().apply(ball(0.0, 0.0, 0.0), Contact(0.0, 0.15, 0.0, pressing=False))
    assert not not_pressed.resting and not_pressed.Rn == 0.0


def test_lid_contact():
    """The lid is the tangent angle pi: c2 points down into the container."""
    out = law().apply(ball(0.2, 1.0, 0.0), Contact(math.pi, 0.0, 0.0))
    assert out.u2 == pytest.approx(-E * 1.0, rel=1e-9)
    assert out.Rn > 0.0 and out.u1 < 0.2
