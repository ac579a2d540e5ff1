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
"""

from __future__ import annotations

import math

import numpy as np

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
