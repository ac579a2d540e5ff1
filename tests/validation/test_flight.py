"""Validation 5: flight with air drag against independent solutions.

References, both written here from Newton's law m dv/dt = -m g n2 - (c_lin + c_quad |v|) v
(Fowles' linear plus quadratic drag) and nothing of the project:

* quadratic + linear drag: scipy's DOP853 at rtol = 1e-13, atol = 1e-15 (an 8th-order
  method with its own error control, unrelated to the engine's Dormand-Prince 5(4));
* linear drag alone (c_quad = 0): the closed form, with k = c_lin / m,
  x(t) = x0 + v0x (1 - exp(-k t)) / k,
  y(t) = y0 + (v0y + g / k) (1 - exp(-k t)) / k - g t / k,
  evaluated with 40 significant digits (mpmath) so that its own rounding is nil.

The engine's flight is error-controlled with rtol (default 1e-10, atol = rtol x 1 m or
1 m/s); its results are expected within a small multiple of rtol, and to approach the
reference in proportion when rtol is tightened.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from billiard.models.flight import AdaptiveFlight, flight_model
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, scene_from_dict, with_values

M, R, K, G = 1.3028e-4, 1.55e-3, 0.4, 9.81
D = 2 * R
C_LIN, C_QUAD = 1.55e-4 * D, 0.22 * D * D  # Fowles, for the 3.1 mm ball
A_PARABOLA, C = 26.0, 0.0063
FLOOR = 0.001


def newton_rhs(c_lin: float, c_quad: float):
    def rhs(_t, y):
        speed = math.hypot(y[2], y[3])
        k = (c_lin + c_quad * speed) / M
        return [y[2], y[3], -k * y[2], -G - k * y[3]]

    return rhs


def dop853(y0, t: float, c_lin: float = C_LIN, c_quad: float = C_QUAD) -> np.ndarray:
    sol = solve_ivp(
        newton_rhs(c_lin, c_quad), (0.0, t), y0, method="DOP853", rtol=1e-13, atol=1e-15
    )
    return sol.y[:, -1]


def linear_drag(y0, t, c_lin: float) -> np.ndarray:
    """Closed form of the flight with linear drag only (40 digits)."""
    with mpmath.workdps(40):
        x0, z0, vx, vz = (mpmath.mpf(v) for v in y0)
        k = mpmath.mpf(c_lin) / mpmath.mpf(M)
        g = mpmath.mpf(G)
        t = mpmath.mpf(t)
        decay = mpmath.exp(-k * t)
        return np.array(
            [
                float(x0 + vx * (1 - decay) / k),
                float(z0 + (vz + g / k) * (1 - decay) / k - g * t / k),
                float(vx * decay),
                float((vz + g / k) * decay - g / k),
            ]
        )


def fly(model, y0, t_end: float) -> np.ndarray:
    model.begin(*y0, 0.0)
    tau = 0.0
    while tau < t_end:
        tau = model.advance(tau, t_end)
    return np.array(model.state(t_end))


STARTS = [(0.0, 0.02, 0.8, 1.5), (0.01, 0.1, -2.0, -1.0), (0.0, 0.0, 3.0, 4.0)]


@pytest.mark.parametrize("y0", STARTS)
def test_fowles_flight_matches_dop853(y0):
    """The flight model a paper scene builds, against the independent integration."""
    model = flight_model(load_scene("parabola-5.4hz"))
    assert isinstance(model, AdaptiveFlight)
    worst = 0.0
    for t in (0.05, 0.2, 0.5):
        error = np.abs(fly(model, y0, t) - dop853(y0, t))
        worst = max(worst, float(error.max()))
    print(f"[validation] Fowles flight from {y0}: largest error {worst:.1e} (m, m/s)")
    # the engine's tolerance, rtol = 1e-10; measured 5.8e-11, 5.3e-11, 1.5e-11
    assert worst < 1e-10


@pytest.mark.parametrize(
    "c_lin, bound",
    [
        (C_LIN, 3e-11),  # measured 5.0e-13: the drag, and its error, are small
        (2.0 * M, 1e-10),  # rtol; measured 8.8e-11
    ],
)
def test_linear_drag_flight_matches_the_closed_form(c_lin, bound):
    """c_quad = 0: the real ball's c_lin (drag 0.4 % of gravity at 1 m/s) and one 540
    times stronger (k = 2 /s), where drag dominates the flight."""
    model = AdaptiveFlight(G, M, c_lin, 0.0, rtol=1e-10)
    worst = 0.0
    for y0 in STARTS:
        for t in (0.01, 0.1, 0.4, 1.0):
            error = np.abs(fly(model, y0, t) - linear_drag(y0, t, c_lin))
            worst = max(worst, float(error.max()))
    print(f"[validation] linear drag c_lin = {c_lin:.3g} N s/m: largest error {worst:.1e}")
    assert worst < bound


# ------------------------------------------------------------------ impacts in a run


def parabola_gap(px: float, py: float) -> tuple[float, float]:
    """Signed distance from the centre to y = a x^2 + c minus r, and the nearest
    point's abscissa (the real roots of the cubic 2 a^2 s^3 + (1 + 2 a (c - py)) s - px)."""
    roots = np.roots([2 * A_PARABOLA**2, 0.0, 1 + 2 * A_PARABOLA * (C - py), -px])
    best = min(
        (math.hypot(px - s, py - (A_PARABOLA * s * s + C)), s)
        for s in roots[np.abs(roots.imag) < 1e-9].real
    )
    sign = 1.0 if py >= A_PARABOLA * px * px + C else -1.0
    return sign * best[0] - R, best[1]


def rough_impact(u1, u2, w, z, e, mu_s, mu_k):
    """Sphere on a fixed rough plane with tangent angle z (closed form, lab frame):
    (u1+, u2+, w+, regime)."""
    c, s = math.cos(z), math.sin(z)
    vt, vn = c * u1 + s * u2, -s * u1 + c * u2
    rn = -(1 + e) * M * vn
    slip = vt + R * w
    rt = -K * M * slip / (1 + K)
    regime = "stick"
    if abs(rt) > mu_s * rn:
        rt = -mu_k * rn * math.copysign(1.0, slip)
        regime = "slip"
    vt, vn, w = vt + rt / M, vn + rn / M, w + rt / (K * M * R)
    return c * vt - s * vn, s * vt + c * vn, w, regime


def independent_run(y0, w0: float, impacts: int) -> np.ndarray:
    """Rows (t, q1, q2, v1, v2, omega) of the first impacts in the paper's parabola at
    rest, Fowles drag, e = 0.393, mu_s = 0.61, mu_k = 0.47: DOP853 with an event on the
    signed gap (steps of at most 1 ms so that short hops are not stepped over)."""

    def gap(_t, y):
        return parabola_gap(y[0], y[1])[0]

    gap.terminal = True
    gap.direction = -1
    rows = []
    t0, y, w = 0.0, list(y0), w0
    for _ in range(impacts):
        sol = solve_ivp(
            newton_rhs(C_LIN, C_QUAD),
            (0.0, 5.0),
            y,
            method="DOP853",
            rtol=1e-13,
            atol=1e-15,
            events=gap,
            max_step=1e-3,
        )
        (tau,), (ye,) = sol.t_events[0], sol.y_events[0]
        z = math.atan(2 * A_PARABOLA * parabola_gap(ye[0], ye[1])[1])
        u1, u2, w, regime = rough_impact(ye[2], ye[3], w, z, 0.393, 0.61, 0.47)
        t0 += tau
        rows.append((t0, ye[0], ye[1], u1, u2, w, regime))
        y = [ye[0], ye[1], u1, u2]
    return rows


def test_first_impacts_of_a_run_with_drag():
    start = {"q1": 0.01, "q2": 0.06, "v1": 0.4, "v2": 0.5, "omega": 30.0}
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {"drive.amplitude": 0.0, "boundary.ceiling": None}
        | {f"initial.{k}": v for k, v in start.items()},
    )
    rows = independent_run([0.01, 0.06, 0.4, 0.5], 30.0, 6)
    reference = np.array([row[:6] for row in rows])
    errors = {}
    for rtol in (1e-10, 1e-12):
        c = simulate(with_values(scene, {"run.rtol": rtol}), collisions=6).columns
        assert list(c["regime"]) == [row[6] for row in rows]
        got = np.column_stack([c[k] for k in ("t", "q1", "q2", "v1", "v2")])
        spin = np.abs(c["omega"] - reference[:, 5]) * R  # contact-point speed, m/s
        errors[rtol] = (
            float(np.max(np.abs(got[:, 0] - reference[:, 0]))),
            float(np.max(np.abs(got[:, 1:3] - reference[:, 1:3]))),
            float(max(np.max(np.abs(got[:, 3:] - reference[:, 3:5])), spin.max())),
        )
        print(
            f"[validation] first 6 impacts with drag, rtol = {rtol:g}: largest error "
            f"in t {errors[rtol][0]:.1e} s, position {errors[rtol][1]:.1e} m, "
            f"speed {errors[rtol][2]:.1e} m/s"
        )
    t_err, q_err, v_err = errors[1e-10]
    gains = [a / b for a, b in zip(errors[1e-10], errors[1e-12], strict=True)]
    print(
        f"[validation] first 6 impacts with drag: rtol 1e-10 -> 1e-12 errors "
        f"{', '.join(f'{g:.1f}' for g in gains)} times smaller (t, q, v)"
    )
    # measured t 1.5e-11 s, q 6.7e-12 m, v 1.7e-10 m/s
    assert t_err < 1e-10 and q_err < 1e-10 and v_err < 1e-9
    # tightening the engine's tolerance brings it closer to the reference; measured
    # 31, 20.3, 20.2 times (t, q, v) for 100 times in rtol: the bound of 20 is kept as
    # it was (at 1 % of the figure, it would fail on a platform that gains less)
    assert all(g > 20 for g in gains)


def linear_drag_bounces(c_lin: float, e: float, mu_s: float, mu_k: float, impacts: int):
    """Rows (t, q1, q2, v1, v2, omega, regime, vn) of a ball thrown from (0, 0.05) with
    v = (1.2, 0.6) m/s and 500 rad/s onto the floor y = FLOOR, linear drag only: flight in
    closed form, impact time its root to 40 digits, impacts in closed form."""
    level = FLOOR + R
    y, w, t0 = (0.0, 0.05, 1.2, 0.6), 500.0, 0.0
    rows = []
    for _ in range(impacts):
        with mpmath.workdps(40):
            k = mpmath.mpf(c_lin) / M
            vz, z0, g = mpmath.mpf(y[3]), mpmath.mpf(y[1]), mpmath.mpf(G)

            def height(t, vz=vz, z0=z0, g=g, k=k):
                return z0 + (vz + g / k) * (1 - mpmath.exp(-k * t)) / k - g * t / k - level

            guess = (y[3] + math.sqrt(y[3] ** 2 + 2 * G * max(y[1] - level, 0.0))) / G
            tau = float(mpmath.findroot(height, mpmath.mpf(guess)))
        q1, _, v1, v2 = linear_drag(y, tau, c_lin)
        u1, u2, w, regime = rough_impact(v1, v2, w, 0.0, e, mu_s, mu_k)
        t0 += tau
        rows.append((t0, q1, level, u1, u2, w, regime, v2))
        y = (q1, level, u1, u2)
    return rows


def test_bounces_with_linear_drag_match_the_closed_form(tmp_path, monkeypatch):
    """A ball thrown onto a flat floor with strong linear drag (k = 2 /s). The engine's
    errors are of the order of its tolerance: position and speed within 10 rtol (m, m/s),
    impact time within 10 rtol (m) / |vn| (the gap error over the approach speed), and
    they shrink in proportion when rtol goes from 1e-10 to 1e-12."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    c_lin = 2.0 * M
    e, mu_s, mu_k = 0.7, 0.5, 0.35
    rows = linear_drag_bounces(c_lin, e, mu_s, mu_k, 5)
    reference = np.array([row[:6] for row in rows])
    approach = min(abs(row[7]) for row in rows)
    errors = {}
    for rtol in (1e-10, 1e-12):
        scene = scene_from_dict(
            {
                "boundary": {"curve": "0.001", "escape_height": 1.0},
                "contact": {
                    "restitution": e,
                    "mu_static": mu_s,
                    "mu_kinetic": mu_k,
                    "elastic_below": 0.0,
                },
                "air": {"drag": "fowles", "c_lin": c_lin, "c_quad": 0.0},
                "initial": {"q1": 0.0, "q2": 0.05, "v1": 1.2, "v2": 0.6, "omega": 500.0},
                "run": {"rtol": rtol},
            }
        )
        c = simulate(scene, collisions=5).columns
        assert list(c["regime"]) == [row[6] for row in rows]
        got = np.column_stack([c[k] for k in ("t", "q1", "q2", "v1", "v2", "omega")])
        diff = np.abs(got - reference)
        errors[rtol] = (
            float(diff[:, 0].max()),
            float(diff[:, 1:3].max()),
            float(max(diff[:, 3:5].max(), R * diff[:, 5].max())),
        )
        print(
            f"[validation] 5 bounces with linear drag, rtol = {rtol:g}: largest error in "
            f"t {errors[rtol][0]:.1e} s, position {errors[rtol][1]:.1e} m, "
            f"speed {errors[rtol][2]:.1e} m/s"
        )
    t_err, q_err, v_err = errors[1e-10]
    gains = [a / b for a, b in zip(errors[1e-10], errors[1e-12], strict=True)]
    print(
        f"[validation] 5 bounces with linear drag: slowest approach {approach:.3g} m/s; "
        f"rtol 1e-10 -> 1e-12 errors {', '.join(f'{g:.1f}' for g in gains)} times smaller"
    )
    # measured t 1.1e-10 s (bound 5e-9 s at 0.2 m/s), q 2.8e-11 m, v 1.3e-10 m/s
    assert t_err < 10 * 1e-10 / approach and q_err < 10 * 1e-10 and v_err < 10 * 1e-10
    assert all(g > 20 for g in gains)  # measured 99.9, 99.8, 98.6
