"""Boundary geometry: offset-curve gaps, nearest points, rest position, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.errors import GeometryError
from billiard.geometry.boundary import Boundary, Drive
from billiard.geometry.curves import load_curve

R = 1.55e-3
CURVES = {
    "parabola": lambda x: 26.0 * x**2 + 0.0063,
    "wedge": lambda x: 1.85 * abs(x) + 0.0063,
    "hyperbola": lambda x: math.sqrt(40.3e-4 * (1.0 + 800.0 * x**2)) - 0.0445,
}
AT_REST = Drive(amplitude=0.0, omega=0.0, phase=0.0, horizontal=True)


def boundary(name, radius=R, ceiling=0.15, drive=AT_REST):
    return Boundary(load_curve(name).walls, radius, drive, ceiling=ceiling)


def brute_distance(f, px, py, lo=-0.6, hi=0.6, n=200001):
    xs = np.linspace(lo, hi, n)
    ys = np.array([f(x) for x in xs]) if n < 1000 else np.vectorize(f)(xs)
    k = int(np.argmin((xs - px) ** 2 + (ys - py) ** 2))
    # refine by golden-section search around the best sample
    a, b = xs[max(k - 1, 0)], xs[min(k + 1, n - 1)]
    g = (math.sqrt(5) - 1) / 2
    for _ in range(100):
        c, d = b - g * (b - a), a + g * (b - a)
        if (c - px) ** 2 + (f(c) - py) ** 2 < (d - px) ** 2 + (f(d) - py) ** 2:
            b = d
        else:
            a = c
    x = 0.5 * (a + b)
    return math.hypot(x - px, f(x) - py), x


@pytest.mark.parametrize("name", ["parabola", "wedge", "hyperbola"])
def test_offset_curve_is_the_locus_of_contact(name):
    """A ball centred on the offset curve touches the curve: its distance is r."""
    b = boundary(name)
    f = CURVES[name]
    for x in np.linspace(-0.12, 0.12, 25):
        y = b.offset_height(float(x))
        d, _ = brute_distance(f, float(x), y, lo=x - 0.01, hi=x + 0.01, n=20001)
        assert d == pytest.approx(R, abs=1e-12)


@pytest.mark.parametrize("name", ["parabola", "wedge", "hyperbola"])
def test_gap_sign_and_rate(name):
    b = boundary(name)
    rng = np.random.default_rng(1)
    for _ in range(40):
        x = rng.uniform(-0.08, 0.08)
        y = b.offset_height(x) + rng.uniform(-3e-3, 3e-3)
        d, _ = brute_distance(CURVES[name], x, y, lo=x - 0.02, hi=x + 0.02, n=40001)
        below = y < CURVES[name](x)
        clearance = (-d if below else d) - R
        gap = min(o.gap_rate(x, y, 0.0, 0.0, o.initial_warm())[0] for o in b.offsets)
        assert np.sign(gap) == np.sign(clearance)
    # dG/dt = v_y - F'(x) v_x with F' the slope at the contact point
    for o in b.offsets:
        x, vx, vy, h = 0.03, 0.7, -0.2, 1e-7
        warm = o.initial_warm()
        g0, rate = o.gap_rate(x, o.height(x, warm) + 1e-3, vx, vy, warm)
        g1, _ = o.gap_rate(x + vx * h, o.height(x, warm) + 1e-3 + vy * h, vx, vy, warm)
        assert rate == pytest.approx((g1 - g0) / h, rel=1e-6)


@pytest.mark.parametrize("name", ["parabola", "wedge", "hyperbola"])
def test_nearest_point_matches_brute_force(name):
    b = boundary(name)
    f = CURVES[name]
    rng = np.random.default_rng(7)
    for _ in range(30):
        x = rng.uniform(-0.1, 0.1)
        y = f(x) + rng.uniform(-0.005, 0.06)
        near = b.nearest_point(x, y)
        d, s = brute_distance(f, x, y)
        assert near.distance == pytest.approx(d, abs=1e-12)
        assert near.below == (y < f(x))


def test_rest_position_is_the_bottom():
    for name, height in (
        ("parabola", 0.0063 + R),
        ("hyperbola", math.sqrt(40.3e-4) - 0.0445 + R),
        ("wedge", 0.0063 + R * math.sqrt(1 + 1.85**2)),
    ):
        x, y = boundary(name).resting_position()
        assert abs(x) < 1e-15
        assert y == pytest.approx(height, abs=1e-15)


def test_container_range_reaches_the_lid():
    xl, xr = boundary("parabola").x_range
    assert xr == pytest.approx(math.sqrt((0.15 - 0.0063) / 26.0), abs=1e-11)
    assert xl == pytest.approx(-xr, abs=1e-11)


def test_radius_against_curvature():
    with pytest.raises(GeometryError, match=r"0\.0197 m at x = 0: single"):
        boundary("hyperbola", radius=0.02)
    boundary("hyperbola", radius=0.019)  # just fits
    boundary("wedge", radius=0.05)  # straight walls: any radius


def test_initial_overlap_is_reported():
    b = boundary("wedge")
    with pytest.raises(GeometryError, match=r"q1 = 0\.02 m, q2 = 0\.04 m puts the ball 0\.00"):
        b.check_initial_position(0.02, 0.04, 0.0)
    b.check_initial_position(0.0, 0.03, 0.0)


def test_drive_frames():
    d = Drive(amplitude=0.01, omega=30.0, phase=0.3, horizontal=True)
    theta = d.angle(0.2)
    assert theta == pytest.approx((30.0 * 0.2 + 0.3) % (2 * math.pi))  # reduced
    px, py, vx, vy = d.to_boundary_frame(theta, 0.05, 0.02, 1.0, 2.0)
    assert px == pytest.approx(0.05 - 0.01 * math.sin(theta))
    assert vx == pytest.approx(1.0 - 0.3 * math.cos(theta)) and (py, vy) == (0.02, 2.0)
    assert d.to_lab_frame(theta, px, py) == pytest.approx((0.05, 0.02))
    v = Drive(amplitude=0.01, omega=30.0, phase=0.0, horizontal=False)
    assert v.boundary_velocity(0.0) == (0.0, pytest.approx(0.3))
    assert d.period == pytest.approx(2 * math.pi / 30.0) and AT_REST.period == math.inf
