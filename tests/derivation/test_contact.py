"""The generated equations of sustained contact (billiard.generated.contact) against
closed forms and against Newton-Euler equations written by hand in this file.

Nothing here uses the derivation's sympy objects: the wall derivatives are written out by
hand, and the reference mechanics is textbook (a sphere on an incline, small oscillations
in a bowl, a ball on a shaken table, Newton-Euler for a ball on a curved wall).
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from billiard.generated import contact

from billiard.geometry.curves import load_curve
from tests.derivation import needs_generating_sympy

M, R, G = 1.3028e-4, 1.55e-3, 9.81
K = 2 / 5  # solid sphere
MU_S, MU_K = 0.61, 0.47


def roll(s_dot, fp, f2, f3, ab=(0.0, 0.0), vb=(0.0, 0.0), k=K, drag=(0.0, 0.0), m=M, r=R):
    return contact.roll_rhs(s_dot, fp, f2, f3, *ab, *vb, m, r, k, G, *drag)


def slide(s_dot, fp, f2, f3, mu_k, sgn, ab=(0.0, 0.0), vb=(0.0, 0.0), k=K, drag=(0.0, 0.0)):
    return contact.slide_rhs(s_dot, fp, f2, f3, *ab, *vb, M, R, k, G, *drag, mu_k, sgn)


# --- walls, derivatives by hand --------------------------------------------------------


def quartic(x, b=30.0, c=0.0063):
    """f = b x^4 + c and its first three derivatives."""
    return b * x**4 + c, 4 * b * x**3, 12 * b * x**2, 24 * b * x


def hyperbola(x, alpha=40.3e-4, beta=0.08e4, delta=4.45e-2):
    """f = sqrt(alpha (1 + beta x^2)) - delta. With h = sqrt(alpha (1 + beta x^2)):
    f' = alpha beta x / h, f'' = alpha^2 beta / h^3, f''' = -3 alpha^3 beta^2 x / h^5."""
    h = math.sqrt(alpha * (1 + beta * x * x))
    return (
        h - delta,
        alpha * beta * x / h,
        alpha**2 * beta / h**3,
        -3 * alpha**3 * beta**2 * x / h**5,
    )


# --- a ball on a straight incline --------------------------------------------------------


@pytest.mark.parametrize("theta", [0.1, 0.35, -0.5, 1.1])
@pytest.mark.parametrize("s_dot", [0.0, 0.2, -0.35])
def test_rolling_down_an_incline(theta, s_dot):
    """f = tan(theta) x + c: the centre moves along c1 at L s_dot, L = 1/cos(theta), and
    accelerates at -(5/7) g sin(theta) along c1 (down the slope); the wall holds it with
    N = m g cos(theta) and friction F = (2/7) m g sin(theta) along c1 (up the slope)."""
    fp = math.tan(theta)
    L = 1 / math.cos(theta)
    s_ddot, n, f = roll(s_dot, fp, 0.0, 0.0)
    assert L * s_ddot == pytest.approx(-5 / 7 * G * math.sin(theta), rel=1e-13)
    assert n == pytest.approx(M * G * math.cos(theta), rel=1e-13)
    assert f == pytest.approx(2 / 7 * M * G * math.sin(theta), rel=1e-13)
    # No slip: the spin is -v/r, v the centre's speed along c1 (clockwise when moving +c1).
    spin = contact.roll_spin(s_dot, fp, 0.0, R)
    assert spin == pytest.approx(-L * s_dot / R, rel=1e-13, abs=1e-300)
    assert contact.slip_velocity(s_dot, spin, fp, 0.0, R) == pytest.approx(0.0, abs=1e-15)
    # Any inertia factor: g sin(theta) / (1 + k) and F = k/(1+k) m g sin(theta).
    s_ddot, n, f = roll(s_dot, fp, 0.0, 0.0, k=0.5)
    assert L * s_ddot == pytest.approx(-G * math.sin(theta) / 1.5, rel=1e-13)
    assert f == pytest.approx(M * G * math.sin(theta) / 3, rel=1e-13)


@pytest.mark.parametrize("theta", [0.2, -0.7, 1.2])
def test_sliding_down_an_incline(theta):
    fp = math.tan(theta)
    L = 1 / math.cos(theta)
    # Without friction: g sin(theta) down the slope, no torque.
    s_ddot, spin_dot, n, f = slide(0.1, fp, 0.0, 0.0, 0.0, 1.0)
    assert L * s_ddot == pytest.approx(-G * math.sin(theta), rel=1e-13)
    assert spin_dot == 0.0 and f == 0.0
    assert n == pytest.approx(M * G * math.cos(theta), rel=1e-13)
    # With friction, moving down the slope without spin: the slip points down the slope,
    # friction mu_k N up it: g (sin - mu_k cos) down the slope, spin-up F r / I.
    down = -math.copysign(1.0, theta)  # direction of s down the slope
    s_dot = 0.3 * down
    slip = contact.slip_velocity(s_dot, 0.0, fp, 0.0, R)
    sgn = math.copysign(1.0, slip)
    assert sgn == down
    s_ddot, spin_dot, n, f = slide(s_dot, fp, 0.0, 0.0, MU_K, sgn)
    sin, cos = math.sin(abs(theta)), math.cos(theta)
    assert L * s_ddot * down == pytest.approx(G * (sin - MU_K * cos), rel=1e-13)
    assert f == pytest.approx(-down * MU_K * M * G * cos, rel=1e-13)
    assert spin_dot == pytest.approx(f * R / (K * M * R * R), rel=1e-13)


@pytest.mark.parametrize("tan_theta", [0.5, 2.0, 2.2, 4.0])
def test_rolling_needs_tan_theta_below_three_and_a_half_mu_s(tan_theta):
    """A solid sphere rolls down an incline while |F| <= mu_s N, i.e. tan(theta) <= 3.5 mu_s
    (2.135 for steel on aluminium)."""
    _, n, f = roll(0.1, tan_theta, 0.0, 0.0)
    assert (abs(f) <= MU_S * n) == (tan_theta <= 3.5 * MU_S)


# --- small oscillations at the bottom of a bowl ------------------------------------------


@pytest.mark.parametrize("a", [26.0, 5.0, 120.0])
def test_small_oscillations_at_the_bottom_of_a_parabola(a):
    """f = a x^2 + c. The wall's radius of curvature at the vertex is 1/(2a); the centre's
    path, offset by r towards the centre of curvature, has rho = 1/(2a) - r. Rolling:
    period 2 pi sqrt(7 rho / (5 g)); sliding without friction: 2 pi sqrt(rho / g).
    The linearized equation s_ddot = -omega^2 s is read off at a tiny s (the centre's arc
    length is (1 - 2 a r) s near the vertex, a constant factor that cancels)."""
    rho = 1 / (2 * a) - R
    s = 1e-7
    fp, f2, f3 = 2 * a * s, 2 * a, 0.0
    omega2_roll = -roll(0.0, fp, f2, f3)[0] / s
    omega2_slide = -slide(0.0, fp, f2, f3, 0.0, 1.0)[0] / s
    assert 2 * math.pi / math.sqrt(omega2_roll) == pytest.approx(
        2 * math.pi * math.sqrt(7 * rho / (5 * G)), rel=1e-9
    )
    assert 2 * math.pi / math.sqrt(omega2_slide) == pytest.approx(
        2 * math.pi * math.sqrt(rho / G), rel=1e-9
    )
    # The centripetal part of N at the vertex: m (g + v^2 / rho), v the centre's speed.
    v = 0.2
    s_dot = v / (1 - 2 * a * R)
    assert roll(s_dot, 0.0, f2, f3)[1] == pytest.approx(M * (G + v * v / rho), rel=1e-12)


# --- a ball on a shaken floor --------------------------------------------------------------


@pytest.mark.parametrize("gamma", [1.5, 3.0])
def test_ball_on_a_vertically_shaken_floor_leaves_where_the_floor_falls_at_g(gamma):
    """Floor f = c shaken vertically, D = A sin(theta), theta = w t: ab2 = -A w^2 sin(theta)
    = -gamma g sin(theta). N = m (g + ab2) in either mode; it reaches zero (lift-off)
    at sin(theta) = 1/gamma."""
    for theta in np.linspace(0, 2 * math.pi, 41):
        ab2 = -gamma * G * math.sin(theta)
        vb2 = gamma * G * math.cos(theta)  # A w cos(theta) with A w^2 = gamma g, w = 1
        for s_dot in (0.0, 0.3):
            assert roll(s_dot, 0.0, 0.0, 0.0, ab=(0.0, ab2), vb=(0.0, vb2))[1] == pytest.approx(
                M * (G + ab2), rel=1e-12, abs=1e-18
            )
            assert slide(s_dot, 0.0, 0.0, 0.0, MU_K, 1.0, ab=(0.0, ab2))[2] == pytest.approx(
                M * (G + ab2), rel=1e-12, abs=1e-18
            )
    theta_off = math.asin(1 / gamma)
    before, at, after = (
        roll(0.0, 0.0, 0.0, 0.0, ab=(0.0, -gamma * G * math.sin(th)))[1]
        for th in (theta_off - 1e-3, theta_off, theta_off + 1e-3)
    )
    assert before > 0 > after
    assert at == pytest.approx(0.0, abs=1e-15 * M * G)


@pytest.mark.parametrize("ab1", [-3.0, 0.5, 12.0])
def test_ball_on_a_horizontally_shaken_floor(ab1):
    """In the floor's frame the inertial force -m ab1 acts at the centre: a rolling sphere
    accelerates at -(5/7) ab1 relative to the floor, driven by friction F = (2/7) m ab1;
    a sliding one at -ab1 - mu_k g sgn."""
    s_ddot, n, f = roll(0.1, 0.0, 0.0, 0.0, ab=(ab1, 0.0))
    assert s_ddot == pytest.approx(-5 / 7 * ab1, rel=1e-13)
    assert f == pytest.approx(2 / 7 * M * ab1, rel=1e-13)
    assert n == pytest.approx(M * G, rel=1e-13)
    for sgn in (1.0, -1.0):
        s_ddot, spin_dot, n, f = slide(0.1, 0.0, 0.0, 0.0, MU_K, sgn, ab=(ab1, 0.0))
        assert s_ddot == pytest.approx(-ab1 - MU_K * G * sgn, rel=1e-13)
        assert spin_dot == pytest.approx(-MU_K * G * sgn / (K * R), rel=1e-13)


# --- Newton-Euler on a curved wall ----------------------------------------------------------


def newton_euler(mode, s_dot, fp, f2, f3, ab, vb, m, r, k, g, c_lin, c_quad, mu_k=0.0, sgn=1.0):
    """The ball on the wall by Newton and Euler, lab components, solved with numpy.

    Centre C(s) = (s, f) + r n, n = (-f', 1)/sigma, t = (1, f')/sigma, sigma = sqrt(1+f'^2).
    Componentwise: C' = q (1, f') with q = 1 - r f''/sigma^3, and
    C'' = q' (1, f') + q (0, f''), q' = -r (f'''/sigma^3 - 3 f' f''^2/sigma^5).
    Newton: m (a_B + C'' s_dot^2 + C' s_ddot) = N n + F t - m g y + drag, drag on the lab
    velocity v = v_B + C' s_dot. Euler about C: I w_dot = r F (F t acts at C - r n).
    Rolling: the slip (C'.t) s_dot + r w stays zero; as C' is parallel to t and dt/ds
    normal to t, its rate is (C''.t) s_dot^2 + (C'.t) s_ddot + r w_dot = 0.
    Sliding: F = -mu_k N sgn.
    """
    sigma = math.sqrt(1 + fp * fp)
    t = np.array([1.0, fp]) / sigma
    n = np.array([-fp, 1.0]) / sigma
    q = 1 - r * f2 / sigma**3
    dq = -r * (f3 / sigma**3 - 3 * fp * f2 * f2 / sigma**5)
    c1 = q * np.array([1.0, fp])
    c2 = dq * np.array([1.0, fp]) + q * np.array([0.0, f2])
    v = np.array(vb) + c1 * s_dot
    drag = -(c_lin + c_quad * np.linalg.norm(v)) * v
    rhs = -m * (np.array(ab) + c2 * s_dot**2) - m * g * np.array([0.0, 1.0]) + drag
    inertia = k * m * r * r
    if mode == "roll":  # unknowns s_ddot, w_dot, N, F
        A = np.zeros((4, 4))
        b = np.zeros(4)
        A[:2, 0], A[:2, 2], A[:2, 3], b[:2] = m * c1, -n, -t, rhs
        A[2, 1], A[2, 3] = inertia, -r
        A[3, 0], A[3, 1], b[3] = c1 @ t, r, -(c2 @ t) * s_dot**2
        s_ddot, w_dot, normal, friction = np.linalg.solve(A, b)
        return s_ddot, normal, friction
    # sliding: unknowns s_ddot, w_dot, N
    A = np.zeros((3, 3))
    b = np.zeros(3)
    A[:2, 0], A[:2, 2], b[:2] = m * c1, -(n - mu_k * sgn * t), rhs
    A[2, 1], A[2, 2] = inertia, r * mu_k * sgn
    s_ddot, w_dot, normal = np.linalg.solve(A, b)
    return s_ddot, w_dot, normal, -mu_k * sgn * normal


def random_states(wall, n, seed):
    rng = np.random.default_rng(seed)
    for i in range(n):
        x = rng.uniform(-0.05, 0.05)
        _, fp, f2, f3 = wall(x)
        s_dot = rng.normal(0, 0.5)
        amplitude, w, phase = (
            rng.uniform(1e-3, 1e-2),
            2 * math.pi * rng.uniform(3, 8),
            rng.uniform(0, 2 * math.pi),
        )
        a, v = -amplitude * w * w * math.sin(phase), amplitude * w * math.cos(phase)
        horizontal = i % 2 == 0
        ab = (a, 0.0) if horizontal else (0.0, a)
        vb = (v, 0.0) if horizontal else (0.0, v)
        m, r, k = rng.uniform(1e-5, 1e-2), rng.uniform(5e-4, 5e-3), rng.uniform(0.2, 0.7)
        # Drag well above the real ball's, so that it shows in the comparison.
        c_lin, c_quad = rng.uniform(0, 1e-2) * m, rng.uniform(0, 1e-2) * m
        mu_k = rng.uniform(0, 0.8)
        sgn = rng.choice([-1.0, 1.0])
        yield s_dot, fp, f2, f3, ab, vb, m, r, k, c_lin, c_quad, mu_k, sgn


@pytest.mark.parametrize("wall", [quartic, hyperbola])
def test_rolling_and_sliding_match_newton_euler_on_a_curved_wall(wall):
    for state in random_states(wall, 300, 4):
        s_dot, fp, f2, f3, ab, vb, m, r, k, c_lin, c_quad, mu_k, sgn = state
        gen = contact.roll_rhs(s_dot, fp, f2, f3, *ab, *vb, m, r, k, G, c_lin, c_quad)
        ref = newton_euler("roll", s_dot, fp, f2, f3, ab, vb, m, r, k, G, c_lin, c_quad)
        scale = (abs(ref[0]) + G, m * G + abs(ref[1]), m * G + abs(ref[2]))
        for a, b, sc in zip(gen, ref, scale, strict=True):
            assert a == pytest.approx(b, rel=1e-12, abs=1e-12 * sc)
        gen = contact.slide_rhs(s_dot, fp, f2, f3, *ab, *vb, m, r, k, G, c_lin, c_quad, mu_k, sgn)
        ref = newton_euler("slide", s_dot, fp, f2, f3, ab, vb, m, r, k, G, c_lin, c_quad, mu_k, sgn)
        scale = (abs(ref[0]) + G, abs(ref[1]) + G / r, m * G + abs(ref[2]), m * G)
        for a, b, sc in zip(gen, ref, scale, strict=True):
            assert a == pytest.approx(b, rel=1e-12, abs=1e-12 * sc)


# --- kinematics for the transitions ------------------------------------------------------


@pytest.mark.parametrize("wall", [quartic, hyperbola])
def test_centre_state_lies_on_the_offset_curve(wall):
    rng = np.random.default_rng(9)
    for _ in range(50):
        s, s_dot = rng.uniform(-0.05, 0.05), rng.normal(0, 0.5)
        d1, d2, vb1, vb2 = rng.normal(0, 0.01, 4)
        f0, fp, f2, _ = wall(s)
        q1, q2, u1, u2 = contact.centre_state(s, s_dot, f0, fp, f2, d1, d2, vb1, vb2, R)
        # A radius from the wall point, along the normal (-f', 1)/sigma.
        sigma = math.hypot(1.0, fp)
        assert q1 - d1 - s == pytest.approx(-R * fp / sigma, rel=1e-12)
        assert q2 - d2 - f0 == pytest.approx(R / sigma, rel=1e-12)
        # Its velocity relative to the boundary is the derivative along the offset curve.
        h = 1e-6

        def position(x):
            fx = wall(x)
            return np.array(contact.centre_state(x, 0, fx[0], fx[1], fx[2], 0, 0, 0, 0, R)[:2])

        derivative = (position(s + h) - position(s - h)) / (2 * h)
        assert u1 - vb1 == pytest.approx(derivative[0] * s_dot, rel=1e-7, abs=1e-12)
        assert u2 - vb2 == pytest.approx(derivative[1] * s_dot, rel=1e-7, abs=1e-12)
        assert contact.s_dot_of_velocity(u1, u2, fp, f2, vb1, vb2, R) == pytest.approx(
            s_dot, rel=1e-12, abs=1e-15
        )


def rk4(rhs, y, dt, steps):
    """The classical Runge-Kutta method; returns the final state and the smallest s."""
    lowest = y[0]
    for _ in range(steps):
        k1 = rhs(y)
        k2 = rhs(y + 0.5 * dt * k1)
        k3 = rhs(y + 0.5 * dt * k2)
        k4 = rhs(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        lowest = min(lowest, y[0])
    return y, lowest


@pytest.mark.parametrize("mode", ["roll", "slide"])
def test_energy_is_conserved_on_a_still_hyperbola(mode):
    """Boundary still, drag off: rolling (friction does no work) and frictionless sliding
    conserve the energy in the boundary's frame; the spin stays on the no-slip relation
    while rolling and constant while sliding without friction."""

    def rhs(y):
        s, s_dot, spin = y
        _, fp, f2, f3 = hyperbola(s)
        if mode == "roll":
            s_ddot = roll(s_dot, fp, f2, f3)[0]
            spin_dot = 0.0  # not integrated: it follows from roll_spin
        else:
            s_ddot, spin_dot, _, _ = slide(s_dot, fp, f2, f3, 0.0, 1.0)
        return np.array([s_dot, s_ddot, spin_dot])

    def energy(y):
        s, s_dot, spin = y
        f0, fp, f2, _ = hyperbola(s)
        if mode == "roll":
            spin = contact.roll_spin(s_dot, fp, f2, R)
        return contact.contact_energy(s_dot, spin, f0, fp, f2, M, R, K, G)

    y0 = np.array([0.03, 0.0, 50.0])
    y1, lowest = rk4(rhs, y0, 2e-4, 2500)
    assert lowest < -0.02  # it swung through the bottom
    assert energy(y1) == pytest.approx(energy(y0), rel=1e-9)
    # Rolling: the generated energy is m g h + (1 + k) m v^2 / 2 with v = the centre's speed.
    f0, fp, f2, _ = hyperbola(0.01)
    v = contact.centre_state(0.01, 0.4, f0, fp, f2, 0, 0, 0, 0, R)[2:]
    height = contact.centre_state(0.01, 0.4, f0, fp, f2, 0, 0, 0, 0, R)[1]
    spin = contact.roll_spin(0.4, fp, f2, R)
    assert contact.contact_energy(0.4, spin, f0, fp, f2, M, R, K, G) == pytest.approx(
        M * G * height + 0.5 * (1 + K) * M * (v[0] ** 2 + v[1] ** 2), rel=1e-13
    )


# --- curves supply f''' ----------------------------------------------------------------------


def test_paper_curves_supply_the_third_derivative():
    from billiard.derivation import build

    from billiard.geometry import walls

    assert build.CURVE_FORMAT == walls.CURVE_FORMAT >= 3
    xs = np.linspace(-0.06, 0.06, 25)
    for name in ("parabola", "wedge"):
        for w in load_curve(name).walls:
            assert all(w.d3f(x, w.p) == 0.0 for x in xs)
    (w,) = load_curve("hyperbola").walls
    for x in xs:
        assert w.d3f(x, w.p) == pytest.approx(hyperbola(x)[3], rel=1e-12, abs=1e-12)
        assert w.d2f(x, w.p) == pytest.approx(hyperbola(x)[2], rel=1e-12)


def test_user_curves_supply_the_third_derivative(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    from billiard.cli import main

    assert main(["derive", "--name", "quartic3", "--curve", "30*x**4 + 0.0063"]) == 0
    (w,) = load_curve("quartic3").walls
    for x in (-0.03, 0.0, 0.02):
        assert w.d3f(x, w.p) == pytest.approx(quartic(x)[3], rel=1e-15, abs=1e-300)
    # An expression in a scene, derived on first use, too.
    (w,) = load_curve("2*x**3 + 40*x**2 + 0.001").walls
    assert w.d3f(0.01, w.p) == pytest.approx(12.0, rel=1e-15)


@pytest.mark.slow  # the whole derivation again (8 s); `derive --check` runs in test_derivation
@needs_generating_sympy
def test_check_detects_an_edit_of_the_contact_module(tmp_path):
    from billiard.derivation import build

    copy = tmp_path / "generated"
    shutil.copytree(build.GENERATED, copy)
    path = copy / "contact.py"
    original = path.read_text()
    i = original.index("return") + 2
    path.write_text(original[:i] + "X" + original[i + 1 :])
    problems = build.check(copy)
    assert len(problems) == 1 and str(path) in problems[0]
