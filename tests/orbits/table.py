"""The classical bouncing ball: a flat table (curve "0.001") shaken vertically,
D(t) = A sin(w t), no air, Gamma = A w^2 / g; shared by the orbit tests.

The closed forms are derived here from the exact 2-D map, independently of the engine
(Holmes, J. Sound Vib. 84 (1982) 173, for the model; derived again for the exact flight).
The ball leaves the table at time t_k with vertical speed v_k; the next impact is at
t' with s(t_k) + v_k tau - g tau^2 / 2 = s(t'), tau = t' - t_k, and
v' = (1 + e) s'(t') - e (v_k - g tau) (restitution on the speed relative to the table).

Period-one orbit with flight time n T (T the drive period): the table is back where it
was, so v = g n T / 2 and the arrival speed is -v; v = (1 + e) A w cos(theta) + e v gives
Gamma cos(theta) = pi n (1 - e) / (1 + e) (theta the drive angle at the impact).

Linearizing at it (F(t', t, v) = 0 above; F_t' = -(w_r), F_t = w_r, F_v = tau with
w_r = s'(t') - v^- = u_table + v the approach speed, a = s''(t') the table's acceleration):

    dt'/dt = 1,  dt'/dv = tau / w_r,
    dv'/dt = (1 + e) a,  dv'/dv = (1 + e) a tau / w_r - e (1 - g tau / w_r),

a matrix whose determinant is e^2 and trace 1 + e^2 + (1 + e)^2 a / g. With
a = -A w^2 sin(theta): a fold (multiplier +1: 1 - tr + det = 0) where sin(theta) = 0, the
existence boundary Gamma = Gamma_n; a period doubling (multiplier -1: 1 + tr + det = 0)
where Gamma sin(theta) = 2 (1 + e^2) / (1 + e)^2.

Away from a period-one orbit the same implicit differentiation gives, for a flight of
tau from (t, v) to t' (approach speed w_r = s'(t') - (v - g tau), a = s''(t')),

    dt'/dt = (s'(t) - v + g tau) / w_r,  dt'/dv = tau / w_r,
    dv'/dt = ((1 + e) a + e g) dt'/dt - e g,  dv'/dv = ((1 + e) a + e g) dt'/dv - e,

which reduces to the above where s'(t) = -v + g tau (the period-one orbit). The period-two
orbit born at the period doubling (flights tau_1 + tau_2 = 2 T, tau_1 != T) solves the two
flights' and impacts' equations, three equations in (t_0, v_0, tau_1) at a given Gamma;
:func:`period_two` solves them with Gamma unknown and tau_1 given instead (Gamma grows
with |tau_1 - T| from the doubling), and its multipliers are the eigenvalues of the
product of the two flights' Jacobians.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, fsolve

from billiard.scene.scene import scene_from_dict

G = 9.81
R = 1.55e-3
FLOOR = 0.001
F = 20.0  # Hz
W = 2 * math.pi * F
T = 1 / F


def onset(e: float, n: int = 1) -> float:
    """Gamma_n: the fold, where the period-n orbits are born."""
    return math.pi * n * (1 - e) / (1 + e)


def period_doubling(e: float, n: int = 1) -> float:
    """Gamma at which the stable period-n orbit doubles its period."""
    return math.hypot(onset(e, n), 2 * (1 + e * e) / (1 + e) ** 2)


def amplitude(gamma: float) -> float:
    """A (m) of the drive at Gamma."""
    return gamma * G / W**2


def scene(gamma: float, e: float, **changes):
    """The shaken table at Gamma, restitution e (a scene the engine runs)."""
    table = {
        "boundary": {"curve": str(FLOOR), "escape_height": 10.0},
        "drive": {"amplitude": amplitude(gamma), "frequency": F, "direction": "vertical"},
        "contact": {
            "restitution": e,
            "mu_static": 0.3,
            "mu_kinetic": 0.2,
            "elastic_below": 0.0,
            "model": "impacts",
        },
        "air": {"drag": "none"},
        "initial": {"q1": 0.0, "q2": FLOOR + R + 0.01},
    }
    for key, value in changes.items():
        section, name = key.split(".")
        table.setdefault(section, {})[name] = value
    return scene_from_dict(table)


def orbit(gamma: float, e: float, n: int = 1, stable: bool = True) -> tuple[float, float]:
    """(t, v2) just after the impact of the period-n orbit (t in [0, T)): the stable one
    (table decelerating, sin(theta) > 0) or the unstable one."""
    theta = math.acos(min(1.0, onset(e, n) / gamma))  # at the fold, rounding may pass 1
    theta = theta if stable else 2 * math.pi - theta
    return theta / W, G * n * T / 2


def multipliers(gamma: float, e: float, n: int = 1, stable: bool = True) -> np.ndarray:
    """Eigenvalues of the 2-D map's Jacobian at the orbit (derived above)."""
    t, v = orbit(gamma, e, n, stable)
    a = -amplitude(gamma) * W**2 * math.sin(W * t)
    tau = n * T
    approach = amplitude(gamma) * W * math.cos(W * t) + v
    jac = np.array(
        [
            [1.0, tau / approach],
            [(1 + e) * a, (1 + e) * a * tau / approach - e * (1 - G * tau / approach)],
        ]
    )
    return np.linalg.eigvals(jac)


def _table(gamma: float, t: float) -> tuple[float, float, float]:
    """The table's height (above its mean), velocity and acceleration at t."""
    a = amplitude(gamma)
    return a * math.sin(W * t), a * W * math.cos(W * t), -a * W * W * math.sin(W * t)


def _impact(gamma: float, e: float, t: float, v: float, tau: float) -> tuple[float, float]:
    """(flight's miss of the table at t + tau (m), take-off speed after that impact)."""
    y0, _, _ = _table(gamma, t)
    y1, u1, _ = _table(gamma, t + tau)
    return y0 + v * tau - G * tau * tau / 2 - y1, (1 + e) * u1 - e * (v - G * tau)


def _period_two_equations(u, e: float, tau1: float) -> list[float]:
    t0, v0, gamma = u
    tau2 = 2 * T - tau1
    miss1, v1 = _impact(gamma, e, t0, v0, tau1)
    miss2, v0_again = _impact(gamma, e, t0 + tau1, v1, tau2)
    scale = amplitude(gamma)
    return [miss1 / scale, miss2 / scale, v0_again - v0]


def period_two(tau1: float, e: float) -> tuple[float, np.ndarray, np.ndarray]:
    """(Gamma, [(t, v) just after each of its two impacts], multipliers) of the
    period-two orbit whose first flight takes ``tau1`` (s), walked out from the period
    doubling in eight steps of tau1 (each solve starts from the previous one)."""
    gamma = period_doubling(e)
    u = np.array([math.acos(onset(e) / gamma) / W, G * T / 2, gamma])
    for k in range(1, 9):
        args = (e, T + (tau1 - T) * k / 8)
        # full_output: fsolve reports, rather than warns, that 1e-14 is past rounding
        u = fsolve(_period_two_equations, u, args=args, xtol=1e-14, full_output=True)[0]
    assert max(abs(r) for r in _period_two_equations(u, *args)) < 1e-12
    t0, v0, gamma = (float(c) for c in u)
    _, v1 = _impact(gamma, e, t0, v0, tau1)
    states = np.array([[t0 % T, v0], [(t0 + tau1) % T, v1]])
    jac = _flight_jacobian(gamma, e, t0 + tau1, v1, 2 * T - tau1) @ _flight_jacobian(
        gamma, e, t0, v0, tau1
    )
    return gamma, states, np.linalg.eigvals(jac)


def _flight_jacobian(gamma: float, e: float, t: float, v: float, tau: float) -> np.ndarray:
    """d(t', v')/d(t, v) of a flight of tau from (t, v) and its impact (derived above)."""
    _, u0, _ = _table(gamma, t)
    _, u1, a1 = _table(gamma, t + tau)
    approach = u1 - (v - G * tau)
    dt_dt, dt_dv = (u0 - v + G * tau) / approach, tau / approach
    k = (1 + e) * a1 + e * G
    return np.array([[dt_dt, dt_dv], [k * dt_dt - e * G, k * dt_dv - e]])


def period_two_at(gamma: float, e: float) -> tuple[np.ndarray, np.ndarray]:
    """([(t, v) after each impact], multipliers) of the period-two orbit at ``gamma``
    (above the period doubling), its first flight the longer one."""
    tau1 = brentq(lambda tau: period_two(tau, e)[0] - gamma, T * (1 + 1e-9), 1.3 * T, xtol=1e-15)
    return period_two(tau1, e)[1:]


def period_two_doubling(e: float) -> float:
    """Gamma at which the period-two orbit doubles its period in turn (a multiplier -1
    of its map: det(J + I) = 0), found on tau1 in (1.05 T, 1.3 T)."""
    tau1 = brentq(
        lambda tau: np.prod(period_two(tau, e)[2] + 1.0).real, 1.05 * T, 1.3 * T, xtol=1e-16
    )
    return period_two(tau1, e)[0]
