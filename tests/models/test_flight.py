"""Flight models: exact parabola, Dormand-Prince with error control, fixed-step RK4."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from billiard.models.flight import AdaptiveFlight, ExactFlight, RK4Flight, flight_model
from billiard.scene.scene import load_scene

M, G = 1.3028e-4, 9.81
C_LIN, C_QUAD = 4.805e-7, 2.1142e-6


def reference(y0, t, c_lin, c_quad, c_magnus=0.0, u3=0.0):
    def rhs(_, y):
        speed = math.hypot(y[2], y[3])
        k = (c_lin + c_quad * speed) / M
        return [
            y[2],
            y[3],
            -k * y[2] - c_magnus * u3 * y[3] / M,
            -G - k * y[3] + c_magnus * u3 * y[2] / M,
        ]

    sol = solve_ivp(rhs, (0.0, t), y0, method="DOP853", rtol=1e-13, atol=1e-15)
    return sol.y[:, -1]


def fly(model, y0, u3, t_end, step=0.02):
    model.begin(*y0, u3)
    tau = 0.0
    while tau < t_end:
        tau = model.advance(tau, min(tau + step, t_end))
    return np.array(model.state(t_end))


def test_exact_flight_is_the_parabola():
    model = ExactFlight(G)
    model.begin(0.01, 0.02, 0.3, 1.2, 5.0)
    q1, q2, u1, u2 = model.state(0.17)
    assert (q1, q2, u1, u2) == pytest.approx(
        (0.01 + 0.3 * 0.17, 0.02 + 1.2 * 0.17 - 0.5 * G * 0.17**2, 0.3, 1.2 - G * 0.17), abs=1e-15
    )
    assert model.advance(0.0, 0.5) == 0.5


@pytest.mark.parametrize("c_quad", [C_QUAD, 1e-3])
def test_adaptive_flight_matches_a_tight_reference(c_quad):
    y0 = [0.0, 0.02, 0.8, 1.5]
    model = AdaptiveFlight(G, M, C_LIN, c_quad, rtol=1e-10)
    got = fly(model, y0, 0.0, 0.3)
    assert np.abs(got - reference(y0, 0.3, C_LIN, c_quad)).max() < 1e-9


def test_state_inside_a_step_has_step_accuracy():
    y0 = [0.0, 0.02, 0.8, 1.5]
    model = AdaptiveFlight(G, M, C_LIN, 1e-3, rtol=1e-10)
    model.begin(*y0, 0.0)
    tau_b = model.advance(0.0, 0.04)
    for tau in np.linspace(0.0, tau_b, 7)[1:-1]:
        assert np.abs(np.array(model.state(tau)) - reference(y0, tau, C_LIN, 1e-3)).max() < 1e-11


def test_magnus_force_deflects_a_spinning_ball():
    y0 = [0.0, 0.5, 1.0, 0.0]
    spin = 200.0  # counter-clockwise: w x v points up for v along +x
    plain = fly(AdaptiveFlight(G, M, C_LIN, C_QUAD, 0.0, 1e-10), y0, spin, 0.2)
    magnus = fly(AdaptiveFlight(G, M, C_LIN, C_QUAD, 1e-8, 1e-10), y0, spin, 0.2)
    assert magnus[1] > plain[1]
    assert np.abs(magnus - reference(y0, 0.2, C_LIN, C_QUAD, 1e-8, spin)).max() < 1e-9


def test_rk4_is_fourth_order():
    y0 = (0.0, 0.02, 0.8, 1.5)
    exact = reference(list(y0), 0.16, C_LIN, 1e-3)
    errors = []
    for n in (40, 80, 160):
        model = RK4Flight(G, M, C_LIN, 1e-3, step=0.16 / n)
        model.begin(*y0, 0.0)
        y = y0
        for _ in range(n):
            y = model.step(y, 0.16 / n)
        errors.append(np.abs(np.array(y) - exact).max())
    assert 13 < errors[0] / errors[1] < 19 and 13 < errors[1] / errors[2] < 19


def test_model_choice_follows_the_scene():
    scene = load_scene("parabola-5.4hz")
    assert isinstance(flight_model(scene), AdaptiveFlight)
    assert isinstance(flight_model(scene, "rk4"), RK4Flight)
    free = load_scene("parabola-5.4hz", overrides=['air.drag="none"'])
    assert isinstance(flight_model(free), ExactFlight)
    spun = load_scene("parabola-5.4hz", overrides=['air.drag="none"', "air.magnus=1e-8"])
    assert isinstance(flight_model(spun), AdaptiveFlight)


def test_models_share_one_interface():
    """advance/state behave alike for every model (RK4's state inside a step is a shorter
    step from the step start)."""
    y0 = (0.0, 0.02, 0.8, 1.5)
    for model, drag in (
        (ExactFlight(G), (0.0, 0.0)),
        (AdaptiveFlight(G, M, C_LIN, C_QUAD, rtol=1e-12), (C_LIN, C_QUAD)),
        (RK4Flight(G, M, C_LIN, C_QUAD, step=1e-3), (C_LIN, C_QUAD)),
    ):
        model.begin(*y0, 0.0)
        tau = 0.0
        while tau < 0.1:
            tau = model.advance(tau, min(tau + 0.01, 0.1))
        assert tau == 0.1
        for t in (0.1 - 2e-4, 0.1):
            expected = reference(list(y0), t, *drag)
            assert np.abs(np.array(model.state(t)) - expected).max() < 1e-11
