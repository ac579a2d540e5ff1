"""The candidate definitions of the paper's q2max and u4max (billiard.analysis.phase) against
closed forms: where the potential energy is zero (the lab origin, the boundary's vertex,
the lowest position of the ball's centre) and whether the spin's energy counts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.analysis.phase import (
    DEFAULT_PHASE_REFERENCE,
    PAPER_PHASE_POINT,
    PHASE_REFERENCES,
    PHASE_ZEROS,
    candidate_points,
    normalized_points,
    paper_distance,
    phase_frame,
    phase_point,
    phase_scales,
    zero_height,
)
from billiard.scene.scene import load_scene

G = 9.81
R = 1.55e-3  # ball radius (m)
K = 0.4  # I / (m r^2)
C = 0.0063  # the parabola's and the wedge's c (m)
B = 1.85  # the wedge's slope
ALPHA, DELTA = 40.3e-4, 0.0445  # the hyperbola's alpha (m^2) and delta (m)


@pytest.fixture(scope="module")
def parabola():
    return load_scene("parabola-5.4hz")


def test_registry_is_every_zero_with_and_without_the_spin():
    assert set(PHASE_ZEROS) == {"lab-origin", "vertex", "lowest-centre"}
    assert set(PHASE_REFERENCES) == {z + s for z in PHASE_ZEROS for s in ("", "+spin")}
    for name, ref in PHASE_REFERENCES.items():
        assert ref.name == name and ref.zero in PHASE_ZEROS
        assert ref.spin == name.endswith("+spin")
        assert "q2max = E0/(m g)" in ref.formula and "u4max = sqrt(2 E0/m)" in ref.formula
        assert ("I w^2/2" in ref.formula) != ref.spin
    assert DEFAULT_PHASE_REFERENCE == "lowest-centre"
    with pytest.raises(ValueError, match="unknown phase reference"):
        phase_frame(load_scene("parabola-5.4hz"), "bottom")
    with pytest.raises(ValueError, match="unknown phase zero"):
        zero_height(load_scene("parabola-5.4hz"), "bottom")


@pytest.mark.parametrize(
    ("name", "vertex", "lowest"),
    [
        ("parabola-5.4hz", C, C + R),  # smooth bottom, radius of curvature 19 mm > r
        ("wedge-6.6hz", C, C + R * math.sqrt(1 + B**2)),  # r / cos(half-angle) above c
        ("hyperbola-4.5hz", math.sqrt(ALPHA) - DELTA, math.sqrt(ALPHA) - DELTA + R),
    ],
)
def test_zero_heights_of_the_paper_curves(name, vertex, lowest):
    scene = load_scene(name)
    assert zero_height(scene, "lab-origin") == 0.0
    assert zero_height(scene, "vertex") == pytest.approx(vertex, abs=1e-10)
    assert zero_height(scene, "lowest-centre") == pytest.approx(lowest, abs=1e-10)


def test_without_a_reference_the_scales_are_the_lab_origin_with_spin():
    m, energy = 1.3e-4, 2.4e-4
    q2max, u4max = phase_scales(energy, m, G)
    assert q2max == pytest.approx(energy / (m * G))
    assert u4max == pytest.approx(math.sqrt(2 * energy / m))
    assert phase_point(0.075, 0.07, energy, m, G) == pytest.approx((0.075 / q2max, 0.07 / u4max))


def _closed_form(zero: str, spin: bool, q2: float, v: float, omega: float, h: dict) -> tuple:
    """The point of a ball at height q2 moving along the tangent at v with spin omega,
    written out for one candidate (no normal velocity)."""
    m = 1.0  # the point does not depend on the mass
    h0 = h[zero]
    e0 = m * G * (q2 - h0) + 0.5 * m * v**2 + (0.5 * K * m * R**2 * omega**2 if spin else 0.0)
    return (q2 - h0) / (e0 / (m * G)), v / math.sqrt(2 * e0 / m)


@pytest.mark.parametrize("name", sorted(PHASE_REFERENCES))
def test_every_candidate_against_its_closed_form(parabola, name):
    ref = PHASE_REFERENCES[name]
    m = parabola.ball.mass
    h = {"lab-origin": 0.0, "vertex": C, "lowest-centre": C + R}
    frame = phase_frame(parabola, name)
    assert frame.zero_height == pytest.approx(h[ref.zero], abs=1e-10)
    assert frame.inertia == pytest.approx(K * m * R**2)

    def point(q2, v, omega):
        energy = m * G * q2 + 0.5 * m * v**2 + 0.5 * K * m * R**2 * omega**2
        return phase_point(q2, v, energy, m, G, reference=frame, omega=omega)

    # At rest above the zero: all of E0 potential, (1, 0) under every candidate.
    assert point(0.05, 0.0, 0.0) == pytest.approx((1.0, 0.0))
    # Through the lowest centre, rolling (omega = v / r): all kinetic at the bottom for
    # the lowest centre; the spin takes 1 - 1/(1 + k) of it when it counts.
    v = 0.3
    q2n, u4n = point(C + R, v, v / R)
    expected = _closed_form(ref.zero, ref.spin, C + R, v, v / R, h)
    assert (q2n, u4n) == pytest.approx(expected, rel=1e-12, abs=1e-15)
    if name == "lowest-centre":
        assert (q2n, u4n) == pytest.approx((0.0, 1.0), abs=1e-12)
    if name == "lowest-centre+spin":
        assert (q2n, u4n) == pytest.approx((0.0, 1 / math.sqrt(1 + K)), abs=1e-12)
    # A flying, spinning ball: the bound (u4/u4max)^2 + q2n <= 1, equal without the spin.
    q2n, u4n = point(0.075, 0.07, 110.0)
    assert (q2n, u4n) == pytest.approx(
        _closed_form(ref.zero, ref.spin, 0.075, 0.07, 110.0, h), rel=1e-12
    )
    if ref.spin:
        assert u4n**2 + q2n < 1
    else:
        assert u4n**2 + q2n == pytest.approx(1.0)


def test_a_lower_zero_raises_the_point_and_the_spin_lowers_it(parabola):
    m = parabola.ball.mass
    q2, u4, omega = 0.075, 0.0695, 111.0
    energy = m * G * q2 + 0.5 * m * (1.4**2 + 0.45**2) + 0.5 * K * m * R**2 * omega**2
    points = candidate_points(q2, u4, energy, omega, parabola)
    assert set(points) == set(PHASE_REFERENCES)
    for spin in ("", "+spin"):
        lab, vertex, low = (points[z + spin] for z in PHASE_ZEROS)
        assert lab[0] > vertex[0] > low[0]  # more of E at the bottom: a lower height
        assert lab[1] < vertex[1] < low[1]  # less of E to share: a larger u4 fraction
    for zero in PHASE_ZEROS:
        assert points[zero][0] > points[zero + "+spin"][0]
    # candidate_points is phase_point under each phase_frame
    for name in PHASE_REFERENCES:
        frame = phase_frame(parabola, name)
        expected = phase_point(q2, u4, energy, m, G, reference=frame, omega=omega)
        assert points[name] == pytest.approx(expected, rel=1e-12)


def test_normalized_points_of_columns(parabola):
    m = parabola.ball.mass
    h0 = C + R
    columns = {
        "q2": np.array([h0 + 0.02, h0, 0.05]),
        "u4": np.array([0.0, 0.5, 0.1]),
        "omega": np.array([0.0, 0.0, 50.0]),
        "energy": np.array(
            [
                m * G * (h0 + 0.02),
                m * G * h0 + 0.5 * m * 0.25,
                m * G * h0 - 1e-9,  # below the zero: no point
            ]
        ),
    }
    q2n, u4n = normalized_points(columns, parabola)
    np.testing.assert_allclose(q2n[:2], [1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(u4n[:2], [0.0, 1.0], atol=1e-12)
    assert math.isnan(q2n[2]) and math.isnan(u4n[2])
    with pytest.raises(ValueError, match="omega"):
        normalized_points({k: v for k, v in columns.items() if k != "omega"}, parabola)


def test_paper_distance():
    assert paper_distance(PAPER_PHASE_POINT) == 0.0
    q, u = PAPER_PHASE_POINT
    assert paper_distance((q * 1.1, -u)) == pytest.approx(0.1 / math.sqrt(2))
    assert paper_distance((q * 1.03, u * 0.96)) == pytest.approx(0.05 / math.sqrt(2))
