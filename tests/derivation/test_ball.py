"""The derivation and its generated code against independent results.

Independent here means: written from textbook mechanics in this file, without the
derivation's sympy objects (closed-form impact of a solid sphere on a rough plane,
Newton-Euler equations of flight, brute-force nearest points).
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys

import numpy as np
import pytest
from billiard.generated import ball

from billiard.geometry.curves import load_curve
from tests.derivation import needs_generating_sympy

M, R, K, G = 1.3028e-4, 1.55e-3, 0.4, 9.81


def rotate(vx, vy, z):
    """Lab components -> contact-frame components (along c1, c2)."""
    return vx * math.cos(z) + vy * math.sin(z), -vx * math.sin(z) + vy * math.cos(z)


def unrotate(vt, vn, z):
    return vt * math.cos(z) - vn * math.sin(z), vt * math.sin(z) + vn * math.cos(z)


def sphere_on_plane(vt, vn, w, e, k, r, m, mu_s, mu_k):
    """Closed-form impact of a solid sphere on a fixed rough plane (textbook).

    Plane tangent c1, normal c2 into the ball's side; vn < 0 approaching. The impulse
    R = Rt c1 + Rn c2 acts at the contact point -r c2 from the centre, whose moment about
    the centre is +r Rt about n3. Slip velocity of the contact point: s = vt + r w.
    No slip: s+ = 0 and vn+ = -e vn. Valid if |Rt| <= mu_s Rn, else Rt = -mu_k Rn sign(s).
    """
    rn = -(1 + e) * m * vn
    s = vt + r * w
    rt = -k * m * s / (1 + k)
    regime = "stick"
    if abs(rt) > mu_s * rn:
        rt = -mu_k * rn * math.copysign(1.0, s)
        regime = "slip"
    return vt + rt / m, -e * vn, w + r * rt / (k * m * r * r), rt, rn, regime


def kane_levinson(u1, u2, u3, z, vb1, vb2, e, mu_s, mu_k, k=K, r=R, m=M):
    """The generated maps with the stick/slip choice of the theory."""
    out = ball.impact_stick(u1, u2, u3, z, vb1, vb2, m, r, k, e)
    if abs(out[3]) <= mu_s * out[4]:
        return out + ("stick",)
    wt, _ = ball.contact_velocity(u1, u2, u3, z, vb1, vb2, r)
    return ball.impact_slip(u1, u2, u3, z, vb1, vb2, m, r, k, e, mu_k, math.copysign(1.0, wt)) + (
        "slip",
    )


def random_impacts(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        z = rng.uniform(-1.4, 1.4)
        speed = rng.uniform(0.01, 3.0)
        angle = rng.uniform(0.02, math.pi - 0.02)  # incoming direction, approaching the wall
        vt, vn = speed * math.cos(angle), -speed * math.sin(angle)
        w = rng.normal(0, 2 * speed / R)
        e = rng.uniform(0, 1)
        mu_k = rng.uniform(0, 0.8)
        mu_s = mu_k + rng.uniform(0, 0.4)
        yield z, vt, vn, w, e, mu_s, mu_k


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_impact_maps_match_sphere_on_rough_plane(seed):
    regimes = set()
    for z, vt, vn, w, e, mu_s, mu_k in random_impacts(400, seed):
        u1, u2 = unrotate(vt, vn, z)
        *post, rt, rn, regime = kane_levinson(u1, u2, w, z, 0.0, 0.0, e, mu_s, mu_k)
        vt_ref, vn_ref, w_ref, rt_ref, rn_ref, regime_ref = sphere_on_plane(
            vt, vn, w, e, K, R, M, mu_s, mu_k
        )
        assert regime == regime_ref
        regimes.add(regime)
        vt_new, vn_new = rotate(post[0], post[1], z)
        scale = abs(vt) + abs(vn) + 1e-300
        assert vt_new == pytest.approx(vt_ref, abs=1e-12 * scale)
        assert vn_new == pytest.approx(vn_ref, abs=1e-12 * scale)
        assert post[2] == pytest.approx(w_ref, abs=1e-12 * (abs(w) + scale / R))
        assert rt == pytest.approx(rt_ref, abs=1e-12 * M * scale)
        assert rn == pytest.approx(rn_ref, abs=1e-12 * M * scale)
    assert regimes == {"stick", "slip"}


def test_stick_slip_boundary_and_spin_sign():
    """At |Rt| = mu_s Rn both hypotheses give the same impulse if mu_k = mu_s."""
    e, z = 0.5, 0.3
    vn = -1.0
    # s such that k s/(1+k) = mu (1+e) |vn|: exactly at the boundary.
    mu = 0.3
    s = mu * (1 + e) * abs(vn) * (1 + K) / K
    w = 20.0
    vt = s - R * w
    u1, u2 = unrotate(vt, vn, z)
    stick = ball.impact_stick(u1, u2, w, z, 0.0, 0.0, M, R, K, e)
    slip = ball.impact_slip(u1, u2, w, z, 0.0, 0.0, M, R, K, e, mu, 1.0)
    assert abs(stick[3]) == pytest.approx(mu * stick[4], rel=1e-12)
    for a, b in zip(stick, slip, strict=True):
        assert a == pytest.approx(b, rel=1e-10, abs=1e-15)
    # A ball sliding forward without spin onto a flat floor leaves with backspin-free
    # rolling: the friction impulse spins it forwards, i.e. clockwise (negative w) for
    # motion along +n1.
    post = ball.impact_stick(1.0, -1.0, 0.0, 0.0, 0.0, 0.0, M, R, K, 0.5)
    assert post[2] < 0
    assert post[0] + R * post[2] == pytest.approx(0.0, abs=1e-15)
    assert post[0] == pytest.approx(5 / 7, rel=1e-12)  # solid sphere: vt+ = 5/7 vt


def test_moving_boundary_is_a_galilean_shift():
    rng = np.random.default_rng(7)
    for z, vt, vn, w, e, mu_s, mu_k in random_impacts(300, 11):
        vb1, vb2 = rng.normal(0, 0.5, 2)
        u1, u2 = unrotate(vt, vn, z)
        moving = kane_levinson(u1 + vb1, u2 + vb2, w, z, vb1, vb2, e, mu_s, mu_k)
        fixed = kane_levinson(u1, u2, w, z, 0.0, 0.0, e, mu_s, mu_k)
        assert moving[5] == fixed[5]
        assert moving[0] - vb1 == pytest.approx(fixed[0], abs=1e-12)
        assert moving[1] - vb2 == pytest.approx(fixed[1], abs=1e-12)
        assert moving[2] == pytest.approx(fixed[2], rel=1e-12, abs=1e-9)


def test_impacts_never_create_energy_in_the_boundary_frame():
    rng = np.random.default_rng(3)
    for _ in range(3000):
        z = rng.uniform(-1.5, 1.5)
        k = rng.uniform(0.05, 1.0)
        r, m = rng.uniform(1e-4, 0.05), rng.uniform(1e-5, 1.0)
        e = rng.uniform(0, 1)
        mu_k = rng.uniform(0, 1.0)
        mu_s = mu_k + rng.uniform(0, 0.5)
        vb1, vb2 = rng.normal(0, 1, 2)
        vt, vn = rng.normal(0, 2), -abs(rng.normal(0, 2)) - 1e-6
        w = rng.normal(0, 3 / r)
        u1, u2 = unrotate(vt, vn, z)
        u1, u2 = u1 + vb1, u2 + vb2
        post = kane_levinson(u1, u2, w, z, vb1, vb2, e, mu_s, mu_k, k=k, r=r, m=m)

        def kinetic(a, b, c, k=k, r=r, m=m, vb1=vb1, vb2=vb2):
            return 0.5 * m * ((a - vb1) ** 2 + (b - vb2) ** 2) + 0.5 * k * m * r * r * c * c

        before, after = kinetic(u1, u2, w), kinetic(*post[:3])
        assert after <= before * (1 + 1e-12) + 1e-300
        assert post[4] >= 0  # the boundary pushes, never pulls


def test_kane_flight_equations_match_newton_euler():
    rng = np.random.default_rng(5)
    for _ in range(200):
        u1, u2, u3 = rng.normal(0, 2), rng.normal(0, 2), rng.normal(0, 300)
        m, g = rng.uniform(1e-4, 1), rng.uniform(1, 20)
        c_lin, c_quad, c_mag = rng.uniform(0, 1e-3), rng.uniform(0, 1e-4), rng.uniform(0, 1e-5)
        speed = math.hypot(u1, u2)
        # Newton: m dv/dt = -m g n2 - (c_lin + c_quad |v|) v + c_mag (w n3 x v)
        drag = c_lin + c_quad * speed
        a1 = (-drag * u1 - c_mag * u3 * u2) / m
        a2 = (-m * g - drag * u2 + c_mag * u3 * u1) / m
        assert ball.flight_rhs_magnus(u1, u2, u3, m, g, c_lin, c_quad, c_mag) == pytest.approx(
            (a1, a2), rel=1e-12, abs=1e-12
        )
        assert ball.flight_rhs_drag(u1, u2, m, g, c_lin, c_quad) == pytest.approx(
            ((-drag * u1) / m, (-m * g - drag * u2) / m), rel=1e-12, abs=1e-12
        )
        # Euler: I dw/dt = 0, no aerodynamic torque; forcing carries no moment.
        assert ball.forcing_drag(u1, u2, u3, m, g, c_lin, c_quad)[2] == 0
    mm = ball.mass_matrix(M, R, K)
    assert mm == ((M, 0, 0), (0, M, 0), (0, 0, K * M * R * R))
    # Exact drag-free flight: the textbook parabola.
    q1, q2, v1, v2 = ball.flight_exact(0.3, 0.1, 0.2, 1.5, 2.0, G)
    assert (q1, q2, v1, v2) == pytest.approx(
        (0.1 + 0.45, 0.2 + 0.6 - 0.5 * G * 0.09, 1.5, 2.0 - G * 0.3), rel=1e-15
    )


@pytest.mark.parametrize("name", ["parabola", "wedge", "hyperbola"])
def test_nearest_point_polynomial_against_brute_force(name):
    curve = load_curve(name)
    rng = np.random.default_rng(17)
    s_grid = np.linspace(-0.12, 0.12, 240_001)
    heights = np.max(
        [np.vectorize(lambda x, w=w: w.f(x, w.p))(s_grid) for w in curve.walls], axis=0
    )
    for trial in range(60):
        px = rng.uniform(-0.05, 0.05)
        if trial < 20:  # near the symmetry axis, above the evolute's cusp: several roots
            px = rng.uniform(-2e-3, 2e-3)
        py = curve.f(px) + rng.uniform(1e-3, 0.06)
        d2 = (s_grid - px) ** 2 + (heights - py) ** 2
        i = int(np.argmin(d2))
        best_brute = math.sqrt(d2[i])
        candidates = []
        for w in curve.walls:
            roots = np.roots(w.poly(px, py, w.p))
            for root in roots[np.abs(roots.imag) < 1e-9].real:
                # Squaring away a square root (hyperbola) adds extraneous roots: a
                # candidate counts only if it satisfies the unsquared condition.
                if w.lo <= root <= w.hi and abs(w.near(root, px, py, w.p)) < 1e-9:
                    candidates.append(math.hypot(root - px, w.f(root, w.p) - py))
        assert candidates, (px, py)
        best = min(candidates)
        # Grid spacing 1e-6 m bounds the brute force's excess distance.
        assert best <= best_brute + 1e-12
        assert best == pytest.approx(best_brute, abs=2e-9)


@needs_generating_sympy
def test_generated_modules_are_current():
    from billiard.derivation import build

    assert build.check() == []


@needs_generating_sympy
def test_check_detects_a_one_character_edit(tmp_path):
    from billiard.derivation import build

    copy = tmp_path / "generated"
    shutil.copytree(build.GENERATED, copy)
    assert build.check(copy) == []
    targets = [copy / "ball.py", *sorted((copy / "curves").glob("[!_]*.py"))]
    for path in targets:
        original = path.read_text()
        i = original.index("return") + 2  # inside the code, not the header
        path.write_text(original[:i] + ("X" if original[i] != "X" else "Y") + original[i + 1 :])
        problems = build.check(copy)
        assert len(problems) == 1 and str(path) in problems[0]
        path.write_text(original)
    assert build.check(copy) == []


def test_derive_user_curve_and_use_it(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    from billiard.cli import main

    assert main(["derive", "--name", "bowl", "--curve", "30*x**4 + 0.0063"]) == 0
    curve = load_curve("bowl")
    wall = curve.walls[0]
    for x in (-0.03, 0.0, 0.02):
        assert wall.f(x, wall.p) == pytest.approx(30 * x**4 + 0.0063, rel=1e-15)
        assert wall.df(x, wall.p) == pytest.approx(120 * x**3, rel=1e-15, abs=1e-300)
        assert wall.d2f(x, wall.p) == pytest.approx(360 * x**2, rel=1e-15, abs=1e-300)
    assert len(wall.poly(0.01, 0.05, wall.p)) == 8  # degree 7: (s - px) + (f - py) f'


@pytest.mark.parametrize(
    "text",
    [
        "__import__('os').system('echo hacked')",
        "x.__class__",
        "lambda: 1",
        "x**10**10",
        "open('/etc/passwd')",
        "-abs(x) + x**2",  # concave kink: the ball could touch the corner
    ],
)
def test_derive_refuses_bad_curves_in_one_line(text, tmp_path):
    env_home = str(tmp_path)
    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "derive", "--name", "bad", "--curve", text],
        capture_output=True,
        text=True,
        env={"BILLIARD_HOME": env_home, "PATH": ""},
        timeout=120,
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: error:"), proc.stderr
    assert "Traceback" not in proc.stderr
    assert not list(tmp_path.rglob("*.py"))


# --- billiard derive: what a user hits -----------------------------------------------------


def _derive(capsys, *args):
    from billiard.cli import main

    code = main(["derive", *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("sqrt(abs(x))", "cusp at x = 0"),
        ("abs(x)**0.5", "cusp at x = 0"),
        ("1/0*x", "divides by zero"),
        ("1/x", "not real and finite at x = 0"),
        ("log(x)", "not real and finite at x = 0"),
        ("tan(x)", "not convex"),
        ("exp(x)", "does not open upward on the left"),
        ("-x**2", "does not open upward"),
        ("1 - x**2", "does not open upward"),
        ("x**4 - x**2", "not convex at x = 0"),
        # C1 at 0: one chain, each piece evaluated on its own side; f' is 0/0 as written at 0
        ("abs(x)**1.5", "is not real and finite at x = 0 m"),
        ("sqrt(0.0025 - x**2)", "not real and finite"),
    ],
)
def test_derive_refuses_curves_that_cannot_hold_a_ball(text, reason, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    code, _, err = _derive(capsys, "--name", "c", "--curve", text)
    assert code == 2 and len(err) == 1 and err[0].startswith("billiard: error:"), err
    assert reason in err[0]
    assert not list(tmp_path.rglob("*.py*"))


@pytest.mark.parametrize(
    "text",
    ["0.001", "0.5*x + 0.001", "-0.001 + 30*x**4", "cosh(x) - 1", "2*abs(x) + 0.001*x**2"],
)
def test_derive_accepts_curves_that_hold_a_ball(text, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    code, out, err = _derive(capsys, "--name", "ok", "--curve", text)
    assert code == 0 and not err and "a scene can now use" in out


def test_printer_never_emits_an_undefined_name():
    import sympy as sm
    from billiard.derivation import codegen

    x = sm.Symbol("x")
    for bad in (sm.nan, sm.zoo, sm.oo, -sm.oo, sm.zoo * x, x + sm.nan, sm.I * x):
        with pytest.raises(codegen.NonFiniteConstantError):
            codegen.pyexpr(bad)
    assert codegen.pyexpr(sm.Integer(2)) == "2.0"


def test_derive_refuses_builtin_names_and_replaces_only_with_force(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    code, _, err = _derive(capsys, "--name", "parabola", "--curve", "30*x**4 + 0.0063")
    assert code == 2 and len(err) == 1 and "built-in curve" in err[0]
    assert _derive(capsys, "--name", "bowl2", "--curve", "30*x**4 + 0.0063")[0] == 0
    code, _, err = _derive(capsys, "--name", "bowl2", "--curve", "40*x**4 + 0.0063")
    assert code == 2 and len(err) == 1 and "already exists" in err[0] and "--force" in err[0]
    assert load_curve("bowl2").f(0.1) == pytest.approx(30e-4 + 0.0063, rel=1e-14)
    assert _derive(capsys, "--name", "bowl2", "--curve", "40*x**4 + 0.0063", "--force")[0] == 0
    code, _, err = _derive(capsys, "--name", "expr_1", "--curve", "40*x**4 + 0.0063")
    assert code == 2 and "kept for cached expressions" in err[0]


def test_derive_accepts_a_curve_starting_with_minus(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    code, _, err = _derive(capsys, "--name", "low", "--curve", "-0.001+30*x**4")
    assert code == 0, err
    assert load_curve("low").f(0.0) == pytest.approx(-0.001, rel=1e-15)
    code, _, err = _derive(capsys, "--name", "hill", "--curve", "-x**2")
    assert code == 2 and len(err) == 1 and "does not open upward" in err[0]


def test_derive_dir_problems_are_one_line(tmp_path, monkeypatch, capsys):
    import os

    from billiard.derivation import build

    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    curve = ["--name", "d", "--curve", "30*x**4 + 0.0063"]
    a_file = tmp_path / "file"
    a_file.write_text("")
    code, _, err = _derive(capsys, *curve, "--dir", str(a_file))
    assert code == 2 and len(err) == 1 and "not a directory" in err[0]
    code, _, err = _derive(capsys, *curve, "--dir", str(tmp_path / "no" / "such"))
    assert code == 2 and len(err) == 1 and "does not exist" in err[0]
    read_only = tmp_path / "ro"
    read_only.mkdir()
    if os.geteuid() != 0:  # root writes anyway; the monkeypatched case below covers it
        read_only.chmod(0o500)
        code, _, err = _derive(capsys, *curve, "--dir", str(read_only))
        assert code == 2 and len(err) == 1 and f"cannot write the curve to {read_only}" in err[0]
        read_only.chmod(0o700)

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(build.tempfile, "mkstemp", refuse)
    code, _, err = _derive(capsys, *curve, "--dir", str(read_only))
    assert code == 2 and len(err) == 1
    assert f"cannot write the curve to {read_only}: Permission denied" in err[0]


@needs_generating_sympy
def test_derive_says_which_directory_it_acts_on(capsys, monkeypatch):
    from billiard.derivation import build

    code, out, _ = _derive(capsys, "--check")
    assert code == 0 and f"checking {build.GENERATED} (source checkout" in out
    monkeypatch.setattr(build, "repo_root", lambda: None)
    monkeypatch.setattr(build, "check", lambda: [])
    code, out, _ = _derive(capsys, "--check")
    assert code == 0 and "the installed package, not a source checkout" in out


# --- billiard bench finds the checkout without sys.path edits ----------------------------


def test_bench_finds_the_checkout_from_inside_it(tmp_path, monkeypatch, capsys):
    from pathlib import Path

    from billiard.cli import bench

    root = Path(bench.__file__).resolve().parents[2]
    # as after a non-editable install: nothing beside the installed package
    monkeypatch.setattr(bench, "__file__", str(tmp_path / "site" / "billiard" / "cli" / "bench.py"))
    assert bench.find_checkout(root / "docs") == root
    path = list(sys.path)
    run = bench._bench_package(root)
    assert sys.path == path and Path(run.__file__).resolve() == root / "bench" / "run.py"

    monkeypatch.chdir(tmp_path)
    assert bench.find_checkout() is None
    from billiard.cli import main

    assert main(["bench", "--quick"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs a source checkout" in err[0]
