"""Validation 4: impacts with friction against the closed form for a sphere on a plane.

Reference (textbook rigid-body impact, e.g. Goldsmith, "Impact" (1960); Brach,
"Mechanical Impact Dynamics" (1991)), written out here without the project's symbolic
derivation. In the frame of the plane (moving with velocity V_B, a Galilean shift), with
c1 along the plane and c2 its normal towards the ball, the centre velocity (vt, vn),
vn < 0, the spin w (counter-clockwise) and the contact point at -r c2 from the centre:

    m dvt = Rt,   m dvn = Rn,   k m r^2 dw = r Rt     (moment of Rt c1 at -r c2 is +r Rt)
    slip velocity of the contact point: s = vt + r w
    Newton:  vn+ = -e vn                         => Rn = -(1 + e) m vn
    stick:   s+ = 0                              => Rt = -k m s / (1 + k)
             valid while |Rt| <= mu_s Rn, else slip: Rt = -mu_k Rn sign(s).

Checked through the runtime's impact law (:class:`billiard.models.impact.KaneLevinsonImpact`)
and through complete simulations of a ball thrown onto a plane (flat, tilted, shaken).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from billiard.models.impact import Contact, KaneLevinsonImpact
from billiard.run.simulate import simulate
from billiard.scene.scene import scene_from_dict

M, R, K, G = 1.3028e-4, 1.55e-3, 0.4, 9.81
FLOOR = 0.001


def sphere_on_plane(vt, vn, w, e, mu_s, mu_k, k=K, r=R, m=M):
    """Closed-form impact on a plane at rest: (vt+, vn+, w+, Rt, Rn, regime)."""
    rn = -(1.0 + e) * m * vn
    s = vt + r * w
    rt = -k * m * s / (1.0 + k)
    regime = "stick"
    if abs(rt) > mu_s * rn:
        rt = -mu_k * rn * math.copysign(1.0, s)
        regime = "slip"
    return vt + rt / m, vn + rn / m, w + rt / (k * m * r), rt, rn, regime


def lab_impact(u1, u2, w, z, vb1, vb2, e, mu_s, mu_k, k=K, r=R, m=M):
    """The closed form for a plane with tangent angle z moving with (vb1, vb2):
    lab-frame (u1+, u2+, w+, Rt, Rn, regime)."""
    c, s = math.cos(z), math.sin(z)
    x1, x2 = u1 - vb1, u2 - vb2
    vt, vn = c * x1 + s * x2, -s * x1 + c * x2
    vt2, vn2, w2, rt, rn, regime = sphere_on_plane(vt, vn, w, e, mu_s, mu_k, k, r, m)
    return vb1 + c * vt2 - s * vn2, vb2 + s * vt2 + c * vn2, w2, rt, rn, regime


def law(e, mu_s, mu_k):
    return KaneLevinsonImpact(M, R, K, e, mu_s, mu_k, elastic_below=0.0)


def test_impact_law_matches_the_closed_form_on_random_impacts():
    rng = np.random.default_rng(2024)
    regimes = set()
    worst = worst_w = 0.0
    for _ in range(2000):
        z = rng.uniform(-1.3, 1.3)
        if rng.uniform() < 0.1:
            z = math.pi  # the lid
        vb1, vb2 = rng.normal(0.0, 0.3, 2)
        speed = rng.uniform(0.02, 3.0)
        angle = rng.uniform(0.05, math.pi - 0.05)
        vt, vn = speed * math.cos(angle), -speed * math.sin(angle)
        w = rng.normal(0.0, speed / R)
        e = rng.uniform(0.0, 1.0)
        mu_k = rng.uniform(0.0, 0.8)
        mu_s = mu_k + rng.uniform(0.0, 0.4)
        c, s = math.cos(z), math.sin(z)
        u1, u2 = vb1 + c * vt - s * vn, vb2 + s * vt + c * vn
        out = law(e, mu_s, mu_k).apply(SimpleNamespace(u1=u1, u2=u2, u3=w), Contact(z, vb1, vb2))
        ref = lab_impact(u1, u2, w, z, vb1, vb2, e, mu_s, mu_k)
        assert out.regime == ref[5]
        regimes.add(out.regime)
        scale = speed + abs(vb1) + abs(vb2)
        got = np.array([out.u1, out.u2, R * out.u3, out.Rt / M, out.Rn / M])
        want = np.array([ref[0], ref[1], R * ref[2], ref[3] / M, ref[4] / M])
        error = float(np.max(np.abs(got - want)) / scale)
        worst = max(worst, error)
        assert error < 7e-14  # measured 7.6e-16 (the largest of the 2000)
        # the reported pre-impact contact velocity
        wt_err = abs(out.wt - (vt + R * w)) / (scale + abs(R * w))
        worst_w = max(worst_w, wt_err, abs(out.wn - vn) / scale)
    print(
        f"[validation] impact law vs closed form, 2000 random impacts: largest error "
        f"{worst:.1e} of the speed scale; contact velocity before it {worst_w:.1e}"
    )
    assert worst_w < 3e-14  # measured 3.5e-16
    assert regimes == {"stick", "slip"}


@pytest.mark.parametrize("side, regime", [(1 - 1e-9, "stick"), (1 + 1e-9, "slip")])
def test_stick_slip_boundary(side, regime):
    """A slip velocity a hair below / above the cone |Rt| = mu_s Rn, with mu_k < mu_s
    (the impulse jumps there): the law picks the side the closed form picks."""
    e, mu_s, mu_k, z = 0.4, 0.6, 0.45, 0.25
    vn = -0.8
    # |Rt_stick| = k m |s| / (1 + k) = mu_s (1 + e) m |vn| at the boundary
    s_edge = mu_s * (1 + e) * abs(vn) * (1 + K) / K
    w = -150.0
    vt = side * s_edge - R * w
    c, sz = math.cos(z), math.sin(z)
    u1, u2 = c * vt - sz * vn, sz * vt + c * vn
    out = law(e, mu_s, mu_k).apply(SimpleNamespace(u1=u1, u2=u2, u3=w), Contact(z, 0.0, 0.0))
    ref = lab_impact(u1, u2, w, z, 0.0, 0.0, e, mu_s, mu_k)
    assert out.regime == ref[5] == regime
    velocity = max(abs(a / b - 1) for a, b in zip((out.u1, out.u2, out.u3), ref[:3], strict=True))
    # on the stick side the impulse is the no-slip one, `side` times the cone's
    cone = (1 + e) * M * abs(vn)
    expected_rt = -side * mu_s * cone if regime == "stick" else -mu_k * cone
    rt = out.Rt / expected_rt - 1
    print(
        f"[validation] stick/slip boundary, {regime} side: u1, u2, omega {velocity:.1e}, "
        f"Rt {rt:+.1e} rel."
    )
    assert velocity <= 2e-14  # measured 2.2e-16 (both sides)
    assert abs(rt) <= 2e-14  # measured 2.2e-16 (both sides)


def test_spin_after_the_impact_has_the_physical_sign():
    floor = Contact(0.0, 0.0, 0.0)
    impact = law(0.5, 0.61, 0.47)
    rel, rolling = [], []  # relative errors; contact-point speeds after a stick (m/s)
    # sliding to the right without spin, gently: it sticks and leaves rolling, i.e.
    # turning clockwise (negative), with vt+ = vt / (1 + k) = 5/7 vt for a solid sphere
    out = impact.apply(SimpleNamespace(u1=0.3, u2=-1.0, u3=0.0), floor)
    assert out.regime == "stick" and out.u3 < 0.0
    rel.append(out.u1 / (0.3 / (1 + K)) - 1)
    rolling.append(out.u1 + R * out.u3)
    # weak backspin (counter-clockwise while moving right, k r w < vt), sticking: the
    # spin reverses and the ball leaves rolling forwards, vt+ = (vt - k r w) / (1 + k)
    w = 0.5 * 0.3 / (K * R)
    out = impact.apply(SimpleNamespace(u1=0.3, u2=-3.0, u3=w), floor)
    assert out.regime == "stick" and out.u3 < 0.0 < out.u1
    rel.append(out.u1 / ((0.3 - K * R * w) / (1 + K)) - 1)
    # strong backspin (k r w > vt), sticking: the ball bounces back, rolling backwards,
    # so its spin keeps the counter-clockwise sign
    w = 2.0 * 0.3 / (K * R)
    out = impact.apply(SimpleNamespace(u1=0.3, u2=-3.0, u3=w), floor)
    assert out.regime == "stick" and out.u1 < 0.0 < out.u3
    rel.append(out.u1 / ((0.3 - K * R * w) / (1 + K)) - 1)
    rolling.append(out.u1 + R * out.u3)
    # fast sliding with strong backspin: it slips, friction acts backwards (Rt < 0) and
    # its torque r Rt only slows the spin down (by mu_k (1 + e) |vn| / (k r) =
    # 569 rad/s here), which keeps its sign; with 300 rad/s instead it would reverse
    for w, sign in ((2000.0, 1.0), (300.0, -1.0)):
        out = impact.apply(SimpleNamespace(u1=2.0, u2=-0.5, u3=w), floor)
        assert out.regime == "slip" and out.Rt < 0.0 and out.u3 < w
        assert math.copysign(1.0, out.u3) == sign
        rel.append(out.u3 / (w - 0.47 * 1.5 * 0.5 / (K * R)) - 1)
    rel.append(out.Rt / (-0.47 * out.Rn) - 1)
    worst, slip = max(abs(x) for x in rel), max(abs(x) for x in rolling)
    print(
        f"[validation] spin sign: vt+, omega+, Rt {worst:.1e} rel.; contact point after a "
        f"stick {slip:.1e} m/s"
    )
    assert worst <= 2e-14  # measured 2.2e-16
    assert slip <= 1e-15  # measured 0: rolling to the bit, 1e-15 m/s is 18 ulp of 0.3 m/s


# ------------------------------------------------------------ complete simulations


def thrown_scene(curve: str, q2: float, v1: float, v2: float, omega: float, **extra):
    data = {
        "boundary": {"curve": curve, "escape_height": 1.0},
        "contact": {"restitution": 0.6, "mu_static": 0.5, "mu_kinetic": 0.35, "elastic_below": 0.0},
        "air": {"drag": "none"},
        "initial": {"q1": 0.0, "q2": q2, "v1": v1, "v2": v2, "omega": omega},
    }
    for key, value in extra.items():
        section, name = key.split("__")
        data.setdefault(section, {})[name] = value
    return scene_from_dict(data)


def first_contact_on_line(
    slope: float, q2: float, v1: float, v2: float
) -> tuple[float, float, float]:
    """Time and centre position (t, q1, q2) at which a ball thrown from (0, q2) first
    touches the line y = slope x + FLOOR: the centre meets the parallel line shifted by
    r sqrt(1 + slope^2), a quadratic in t."""
    lift = FLOOR + R * math.sqrt(1.0 + slope * slope)
    # q2 + v2 t - g t^2 / 2 = slope v1 t + lift
    a, b, c = 0.5 * G, -(v2 - slope * v1), lift - q2
    t = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
    return t, v1 * t, q2 + v2 * t - 0.5 * G * t * t


CASES = {
    # name: (curve, slope, q2, v1, v2, omega, drive, regime the case is meant to reach)
    "flat, stick": ("0.001", 0.0, 0.05, 0.2, -0.5, 0.0, None, "stick"),
    "flat, backspin reverses the bounce": ("0.001", 0.0, 0.05, 0.2, -1.0, 400.0, None, "stick"),
    "flat, slip forward": ("0.001", 0.0, 0.01, 1.5, -0.1, 0.0, None, "slip"),
    "flat, slip with backspin": ("0.001", 0.0, 0.01, 1.0, -0.1, 900.0, None, "slip"),
    "tilted plane, stick": ("0.5*x + 0.001", 0.5, 0.05, -0.4, 0.3, -200.0, None, "stick"),
    "tilted plane, slip": ("0.5*x + 0.001", 0.5, 0.01, 1.5, 0.5, 300.0, None, "slip"),
    "shaken floor, stick": ("0.001", 0.0, 0.05, 0.3, -0.2, 100.0, (0.004, 7.0, 0.8), "stick"),
    "shaken floor, slip": ("0.001", 0.0, 0.005, 0.3, 0.0, 1200.0, (0.004, 7.0, 0.8), "slip"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_ball_thrown_onto_a_plane(case, tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    curve, slope, q2_0, v1, v2, omega, drive, regime = CASES[case]
    extra = {}
    if drive is not None:
        amplitude, frequency, phase = drive
        extra = {
            "drive__amplitude": amplitude,
            "drive__frequency": frequency,
            "drive__phase": phase,
            "drive__direction": "horizontal",
        }
    scene = thrown_scene(curve, q2_0, v1, v2, omega, **extra)
    row = {k: v[0] for k, v in simulate(scene, collisions=1).columns.items()}
    t, q1, q2 = first_contact_on_line(slope, q2_0, v1, v2)
    t_err = abs(row["t"] / t - 1)
    q_err = max(abs(row["q1"] - q1), abs(row["q2"] - q2))
    vb1 = 0.0
    if drive is not None:
        w = 2 * math.pi * frequency
        vb1 = amplitude * w * math.cos(w * t + phase)
    z = math.atan(slope)
    ref = lab_impact(v1, v2 - G * t, omega, z, vb1, 0.0, 0.6, 0.5, 0.35)
    assert ref[5] == regime  # the case reaches the regime it is meant to test
    assert row["regime"] == ref[5]
    got = (row["v1"], row["v2"], row["omega"], row["Rt"], row["Rn"])
    rel = max(abs(a - b) / abs(b) for a, b in zip(got, ref[:5], strict=True) if b != 0.0)
    print(
        f"[validation] thrown onto a plane, {case}: t {t_err:.1e} rel., q {q_err:.1e} m, "
        f"v, omega, R {rel:.1e} rel., z {abs(row['z'] - z):.1e} rad"
    )
    # measured (max over the 8 cases): t 4.2e-15, q 1.9e-16 m, v, omega, R 3.3e-15, z 0
    assert t_err <= 1e-14
    assert q_err <= 1e-15
    assert (row["v1"], row["v2"]) == pytest.approx(ref[:2], rel=3e-13, abs=1e-14)
    assert row["omega"] == pytest.approx(ref[2], rel=3e-13, abs=1e-10)
    assert (row["Rt"], row["Rn"]) == pytest.approx(ref[3:5], rel=3e-13, abs=1e-18)
    assert row["z"] == pytest.approx(z, abs=1e-15)
