"""The ladder of impact laws (docs/impact-laws.md) against the closed forms of their
references, for a sphere hitting a still plane (z = 0, the plane y = 0 below the ball):
Walton's three-parameter law as Foerster, Louge, Chang and Allia (1994) write it, the
speed-, energy- and angle-dependent restitutions against their formulas, the limits that
reduce each law to a simpler one, and no energy gain at an impact on a still boundary.

The closed forms are written here from the references, in the references' variables
(centre velocity v_t, v_n, spin omega, contact point velocity v_t + r omega), not taken
from the code."""

from __future__ import annotations

import math
import random

import pytest

from billiard.models.impact import IMPACT_LAWS, Contact, KaneLevinsonImpact
from billiard.scene.spec import LAW_PARAMETERS

M, R, K = 1.3028e-4, 1.55e-3, 0.4  # the paper's steel ball: kg, m, I / (m r^2)
STILL = Contact(0.0, 0.0, 0.0)


class Ball:
    def __init__(self, u1: float, u2: float, u3: float):
        self.u1, self.u2, self.u3 = u1, u2, u3


def law(name: str, e: float = 0.8, mu_s: float = 0.3, mu_k: float = 0.3, **params: float):
    """The law ``name`` for the paper's ball without the low-velocity rule."""
    return IMPACT_LAWS[name](M, R, K, e, mu_s, mu_k, 0.0, **params)


def incidence(angle: float, speed: float = 1.0, omega: float = 0.0) -> Ball:
    """A ball approaching the plane at ``angle`` (rad) from the normal."""
    return Ball(speed * math.sin(angle), -speed * math.cos(angle), omega)


def energy(b) -> float:
    return 0.5 * M * (b.u1**2 + b.u2**2) + 0.5 * K * M * R**2 * b.u3**2


ANGLES = [0.0, 0.1, 0.3, 0.6, 0.9, 1.2, 1.45]


# --- Walton's law ---------------------------------------------------------------------


def walton_closed_form(vt, vn, omega, e, mu, beta0):
    """Foerster et al. (1994), eqs. (1)-(6) for a sphere on a still plane: the contact
    point's tangential velocity c = vt + r omega; Walton's beta = min(beta0, -1 + mu
    (1 + e) (1 + 1/K) |vn| / |c|) so that c' = -beta c; the centre's tangential velocity
    changes by (c' - c) K / (1 + K), the spin by (c' - c) / (r (1 + K)); vn' = -e vn."""
    c = vt + R * omega
    beta = beta0
    if c != 0.0:
        beta = min(beta0, -1.0 + mu * (1.0 + e) * (1.0 + 1.0 / K) * abs(vn) / abs(c))
    dc = -(1.0 + beta) * c
    return vt + dc * K / (1.0 + K), -e * vn, omega + dc / (R * (1.0 + K)), beta == beta0


@pytest.mark.parametrize("beta0", [-0.5, 0.0, 0.35, 0.8])
@pytest.mark.parametrize("angle", ANGLES)
def test_walton_against_foerster(angle, beta0):
    e, mu = 0.9, 0.12
    walton = law("walton", e=e, mu_s=mu, mu_k=mu, beta0=beta0)
    ball = incidence(angle, 1.3, omega=40.0)
    got = walton.apply(ball, STILL)
    vt, vn, omega, sticks = walton_closed_form(ball.u1, ball.u2, ball.u3, e, mu, beta0)
    assert got.u1 == pytest.approx(vt, rel=1e-12, abs=1e-14)
    assert got.u2 == pytest.approx(vn, rel=1e-12)
    assert got.u3 == pytest.approx(omega, rel=1e-12, abs=1e-10)
    assert got.regime == ("stick" if sticks else "slip")
    # the impulse is the jump in momentum
    assert got.Rt == pytest.approx(M * (got.u1 - ball.u1), rel=1e-12, abs=1e-18)
    assert got.Rn == pytest.approx(M * (got.u2 - ball.u2), rel=1e-12)


def test_walton_takes_both_branches_over_the_angles():
    walton = law("walton", e=0.9, mu_s=0.12, mu_k=0.12, beta0=0.35)
    regimes = {walton.apply(incidence(a, 1.3), STILL).regime for a in ANGLES}
    assert regimes == {"stick", "slip"}


def test_walton_reverses_the_contact_point_tangential_velocity():
    # a grazing-free, sticking impact: the contact point leaves backwards at beta0 of
    # its speed (Kane and Levinson's law stops it)
    ball = incidence(0.2, 1.0)
    got = law("walton", mu_s=1.0, mu_k=1.0, beta0=0.5).apply(ball, STILL)
    assert got.u1 + R * got.u3 == pytest.approx(-0.5 * (ball.u1 + R * ball.u3), rel=1e-12)


@pytest.mark.parametrize("angle", ANGLES)
def test_walton_with_beta0_zero_is_kane_levinsons_sticking_impact(angle):
    ball = incidence(angle, 0.7, omega=-30.0)
    walton = law("walton", mu_s=0.3, mu_k=0.3, beta0=0.0).apply(ball, STILL)
    kane = law("kane-levinson", mu_s=0.3, mu_k=0.3).apply(ball, STILL)
    assert walton.regime == kane.regime
    for a, b in zip(
        (walton.u1, walton.u2, walton.u3, walton.Rt, walton.Rn),
        (kane.u1, kane.u2, kane.u3, kane.Rt, kane.Rn),
        strict=True,
    ):
        assert a == pytest.approx(b, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("angle", ANGLES)
def test_walton_with_beta0_minus_one_is_a_smooth_sphere(angle):
    ball = incidence(angle, 0.7, omega=25.0)
    got = law("walton", e=0.6, mu_s=5.0, mu_k=5.0, beta0=-1.0).apply(ball, STILL)
    assert got.u1 == pytest.approx(ball.u1, rel=1e-12, abs=1e-15)
    assert got.u3 == pytest.approx(ball.u3, rel=1e-12)
    assert got.u2 == pytest.approx(-0.6 * ball.u2, rel=1e-12)
    assert got.Rt == pytest.approx(0.0, abs=1e-18)


# --- restitution as a function of the impact ---------------------------------------


def rebound_ratio(model, ball) -> float:
    return -model.apply(ball, STILL).u2 / ball.u2


@pytest.mark.parametrize("speed", [0.01, 0.1, 0.5, 1.0, 3.0])
def test_power_law_restitution(speed):
    model = law("power-law", e_ref=0.5, v_ref=0.4, exponent=0.25)
    expected = min(1.0, 0.5 * (speed / 0.4) ** -0.25)
    assert rebound_ratio(model, incidence(0.0, speed)) == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("angle", ANGLES)
def test_power_law_with_exponent_zero_is_constant_e_bit_for_bit(angle):
    ball = incidence(angle, 0.9, omega=12.0)
    power = law("power-law", e_ref=0.45, v_ref=0.3, exponent=0.0).apply(ball, STILL)
    kane = law("kane-levinson", e=0.45).apply(ball, STILL)
    assert power == kane


#: Ramirez, Poeschel, Brilliantov and Schwager, Phys. Rev. E 60, 4465 (1999), eq. (32):
#: e = 1 - C1 A alpha^(2/5) v^(1/5) + C2 A^2 alpha^(4/5) v^(2/5), these coefficients
C1, C2 = 1.15344, 0.79826


@pytest.mark.parametrize("speed", [1e-4, 1e-3, 0.01, 0.1, 1.0])
def test_viscoelastic_rebound_ratio_against_its_series(speed):
    b = 0.2  # (s/m)^(1/5)
    model = law("viscoelastic", viscous=b)
    x = b * speed**0.2
    assert rebound_ratio(model, incidence(0.0, speed)) == pytest.approx(
        1.0 - C1 * x + C2 * x * x, rel=1e-13
    )


def test_viscoelastic_restitution_falls_with_speed_and_never_rises():
    model = law("viscoelastic", viscous=0.8)
    speeds = [10.0**p for p in range(-12, 3)]
    es = [model.restitution(0.0, -v) for v in speeds]
    assert es[0] > 0.98  # elastic in the limit of slow impacts
    assert all(a >= b for a, b in zip(es, es[1:], strict=False))
    # held at the series' minimum beyond it
    assert min(es) == pytest.approx(1.0 - C1**2 / (4.0 * C2), rel=1e-12)


@pytest.mark.parametrize("speed", [0.05, 0.3, 1.0, 2.0])
def test_energy_dependent_restitution(speed):
    scale = 2e-5  # J
    model = law("energy-dependent", e=0.4, energy_scale=scale)
    expected = 0.4 + 0.6 * math.exp(-0.5 * M * speed**2 / scale)
    assert rebound_ratio(model, incidence(0.0, speed)) == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("angle", ANGLES)
def test_angle_dependent_restitution(angle):
    # the ball not spinning: the contact point's tangent of incidence is tan(angle)
    model = law("angle-dependent", e=0.8, angle_slope=0.1)
    expected = min(1.0, 0.8 + 0.1 * math.tan(angle))
    assert rebound_ratio(model, incidence(angle, 1.0)) == pytest.approx(expected, rel=1e-12)


def test_angle_dependent_with_no_slope_is_kane_levinson_bit_for_bit():
    ball = incidence(0.7, 0.9, omega=12.0)
    angle = law("angle-dependent", e=0.45, angle_slope=0.0).apply(ball, STILL)
    assert angle == law("kane-levinson", e=0.45).apply(ball, STILL)


# --- the point particle --------------------------------------------------------------


@pytest.mark.parametrize("angle", ANGLES)
def test_point_particle_keeps_tangential_velocity_and_spin(angle):
    ball = incidence(angle, 1.1, omega=70.0)
    got = law("point-particle", e=0.393).apply(ball, STILL)
    assert (got.u1, got.u3, got.regime) == (ball.u1, ball.u3, "slip")
    assert got.u2 == pytest.approx(-0.393 * ball.u2, rel=1e-14)
    assert got.Rt == 0.0


@pytest.mark.parametrize("angle", ANGLES)
def test_frictionless_kane_levinson_of_a_small_ball_is_the_point_particle(angle):
    ball = incidence(angle, 1.1, omega=0.0)
    point = law("point-particle", e=0.5).apply(ball, STILL)
    tiny = IMPACT_LAWS["kane-levinson"](M, 1e-9, K, 0.5, 0.0, 0.0, 0.0).apply(ball, STILL)
    assert tiny.u1 == pytest.approx(point.u1, rel=1e-12, abs=1e-15)
    assert tiny.u2 == pytest.approx(point.u2, rel=1e-12)
    assert tiny.Rt == pytest.approx(0.0, abs=1e-18)


def test_point_particle_with_an_energy_scale_has_the_energy_dependent_e():
    ball = incidence(0.4, 0.6)
    point = law("point-particle", e=0.4, energy_scale=1e-5)
    energetic = law("energy-dependent", e=0.4, energy_scale=1e-5)
    assert point.restitution(0.1, -0.6) == energetic.restitution(0.1, -0.6) < 0.9
    assert rebound_ratio(point, ball) == pytest.approx(rebound_ratio(energetic, ball), rel=1e-13)


# --- every law -----------------------------------------------------------------------

PARAMETERS = {
    "kane-levinson": {},
    "walton": {"beta0": 0.6},
    "power-law": {"e_ref": 0.6, "v_ref": 0.5, "exponent": 0.3},
    "viscoelastic": {"viscous": 0.3},
    "energy-dependent": {"energy_scale": 1e-5},
    "angle-dependent": {"angle_slope": 0.5},
    "point-particle": {"energy_scale": 1e-5},
}


def test_every_law_is_registered_with_its_parameters():
    assert set(IMPACT_LAWS) == set(LAW_PARAMETERS) == set(PARAMETERS)
    for name, cls in IMPACT_LAWS.items():
        assert cls.name == name
        required, optional = LAW_PARAMETERS[name]
        assert set(required) <= set(PARAMETERS[name]) <= set(required + optional)
        if required:
            with pytest.raises(TypeError, match="needs"):
                law(name)


@pytest.mark.parametrize("name", PARAMETERS)
def test_no_law_gains_energy_at_an_impact_on_a_still_boundary(name):
    rng = random.Random(1234)
    model = law(name, e=rng.uniform(0.2, 0.95), mu_s=0.5, mu_k=0.3, **PARAMETERS[name])
    gains = []
    for _ in range(3000):
        z = rng.uniform(-math.pi, math.pi)
        ball = Ball(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2000, 2000))
        got = model.apply(ball, Contact(z, 0.0, 0.0))
        before, after = energy(ball), energy(got)
        gains.append((after - before) / before)
    assert max(gains) <= 1e-12


@pytest.mark.parametrize("name", PARAMETERS)
def test_every_law_restitutes_the_normal_velocity_relative_to_a_moving_boundary(name):
    model = law(name, **PARAMETERS[name])
    contact = Contact(0.3, 0.2, -0.4)
    got = model.apply(Ball(0.1, -1.0, 5.0), contact)
    e = model.restitution(got.wt, got.wn)
    c, s = math.cos(0.3), math.sin(0.3)
    wn_after = c * (got.u2 - contact.vb2) - s * (got.u1 - contact.vb1)
    assert 0.0 < e <= 1.0
    assert wn_after == pytest.approx(-e * got.wn, rel=1e-12)


def test_kane_levinson_is_unchanged_by_the_ladder():
    model = KaneLevinsonImpact(M, R, K, 0.393, 0.61, 0.47, 0.01)
    assert model.kind == 0.0 and model.name == "kane-levinson"
    assert model.restitution(0.3, -1.0) == 0.393
