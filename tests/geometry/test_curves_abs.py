"""abs() in a curve that is smooth where its argument vanishes: one wall, no impact there.

``abs(x)**3`` is C^2 at 0. Split there into two walls, a ball rolling through the bottom
met the other wall at the join, and every pass was an impact with the low-velocity rule's
relaunch (an impulse of m x contact.elastic_below); real kinks (the wedge, ``abs(x)``)
stay walls.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from billiard.derivation.build import curve_from_text

from billiard.geometry.curves import load_curve
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values


@pytest.mark.parametrize(
    ("text", "parameters", "kinks"),
    [
        ("abs(x)**3 + 0.005", {}, []),  # C^2 at 0
        ("abs(x)**5 + 2*x**2", {}, []),
        ("abs(x**2 - 1)**3 + x**2", {}, []),  # C^2 at -1 and 1
        ("abs(x)**3 + abs(x - 1)", {}, [1.0]),  # smooth at 0, a kink at 1
        ("abs(x**2 - 1)**3 + 3*abs(x + 1)", {}, [-1.0]),  # smooth at 1, a kink at -1
        ("abs(x)", {}, [0.0]),
        ("b*abs(x) + c", {"b": "1.85", "c": "0.0063"}, [0.0]),  # the wedge
        # smooth only when b = 0: the walls are split for every value of b
        ("b*abs(x) + x**2", {"b": "0"}, [0.0]),
        # C^1, but f'' jumps at 0: two walls (one wall would make the centre's speed
        # jump in the contact equations, which keep ds/dt continuous)
        ("10*x*abs(x) + 20*x**2 + 0.005", {}, [0.0]),
    ],
)
def test_abs_splits_the_curve_only_where_it_is_not_smooth(text, parameters, kinks):
    cd = curve_from_text("c", text, parameters)
    values = {sym: sym.name for sym in cd.parameter_symbols}
    defaults = {sym: float(parameters[name]) for sym, name in values.items()}
    assert [float(b.subs(defaults)) for b in cd.breakpoints] == kinks
    assert len(cd.walls) == len(kinks) + 1


def test_a_smooth_abs_curve_is_one_wall_equal_to_its_branches(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    curve = load_curve("abs(x)**3 + 0.005")
    assert len(curve.walls) == 1 and curve.breakpoints == ()
    wall = curve.walls[0]
    assert (wall.lo, wall.hi) == (-math.inf, math.inf)
    for x in (-0.3, -0.01, -1e-7, 0.0, 1e-7, 0.01, 0.3):
        a = abs(x)
        assert wall.f(x, wall.p) == pytest.approx(a**3 + 0.005, rel=1e-15)
        assert wall.df(x, wall.p) == pytest.approx(3 * x * a, rel=1e-15, abs=1e-300)
        assert wall.d2f(x, wall.p) == pytest.approx(6 * a, rel=1e-15, abs=1e-300)
        assert wall.d3f(x, wall.p) == (0.0 if x == 0 else math.copysign(6.0, x))
        assert wall.poly is None  # the nearest point by Newton's method


def _rolling_scene(curve: str, model: str, parameters: dict | None = None, x0: float = 0.05):
    """A ball lying at rest on the wall at x0 (its centre on the offset curve, so that
    it starts in contact), no drive and no drag: it rolls through the bottom and back."""
    shape = load_curve(curve, parameters)
    wall = shape.walls[-1]
    slope = wall.df(x0, wall.p)
    length = math.sqrt(1.0 + slope * slope)
    r = 1.55e-3
    return with_values(
        load_scene("parabola-5.4hz"),
        {
            "boundary.curve": curve,
            "contact.model": model,
            "drive.amplitude": 0.0,
            "air.drag": "none",
            "initial.q1": x0 - r * slope / length,
            "initial.q2": shape.f(x0) + r / length,
            **{f"boundary.parameters.{k}": v for k, v in (parameters or {}).items()},
        },
    )


def test_a_ball_rolls_through_a_smooth_abs_bottom_without_impacts(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    result = simulate(_rolling_scene("100*abs(x)**3 + 0.005", "phases"), duration=1.0, sample=1e-3)
    trajectory = result.trajectory
    q1 = trajectory["q1"]
    assert np.count_nonzero(np.diff(np.sign(q1))) >= 3  # through the bottom three times
    # split at 0, there was an impact at s = 0 at every pass (Rn = m x elastic_below)
    assert len(result.columns["t"]) == 0
    assert set(trajectory["mode"]) == {"roll"}
    # rolling without drive, drag or slip: the energy stays, the turning points mirror
    energy = trajectory["energy"]
    assert (energy.max() - energy.min()) / energy.max() < 1e-7
    assert q1.min() == pytest.approx(-q1.max(), abs=1e-6)


def test_the_issue_scene_has_no_impacts_at_a_smooth_abs_bottom(tmp_path, monkeypatch):
    """The scene of the report: a gentle drive rolls the ball to and fro through the
    bottom; with the curve 3*x**2 + 0.005 it never has an impact, and with abs(x)**3 +
    0.005 (216 impacts in 20 s when split) neither."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    base = with_values(
        load_scene("parabola-5.4hz"), {"contact.model": "phases", "drive.amplitude": 0.005}
    )
    for curve in ("3*x**2 + 0.005", "abs(x)**3 + 0.005"):
        result = simulate(with_values(base, {"boundary.curve": curve}), duration=2.0)
        assert len(result.columns["t"]) == 0, curve
        assert result.final_time == pytest.approx(2.0)


def test_impacts_on_one_smooth_wall_equal_those_on_its_two_branches(tmp_path, monkeypatch):
    """The impacts model, a ball hopping through the bottom: the one wall of
    100*abs(x)**3 gives the records that its two branches give (the same curve split at
    0 because its b*abs(x) term makes a kink there for b != 0), to rounding."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    one = simulate(_rolling_scene("100*abs(x)**3 + 0.005", "impacts"), duration=0.5)
    split = _rolling_scene("100*abs(x)**3 + b*abs(x) + 0.005", "impacts", {"b": 0.0})
    two = simulate(split, duration=0.5)
    assert len(load_curve("100*abs(x)**3 + b*abs(x) + 0.005", {"b": 0.0}).walls) == 2
    a, b = one.columns, two.columns
    assert len(a["t"]) == len(b["t"]) > 100
    assert np.any(np.abs(a["s"]) < 1e-3)  # it hops through the bottom
    for key in ("t", "q1", "q2", "v1", "v2", "omega"):
        scale = np.max(np.abs(b[key]))
        assert np.max(np.abs(a[key] - b[key])) <= 1e-11 * scale, key


# --- smooth joins: a chain of walls ----------------------------------------------------
# At a C^1 join such as 20*x**2 + 10*x*abs(x) the right piece 30 x^2 lies above the left
# piece 10 x^2 for x < 0 too: taken as the maximum of its walls, the curve was 30 x^2 on
# both sides. Joined smoothly, the two walls are one chain (one offset surface).

C1 = "20*x**2 + 10*x*abs(x) + 0.0063"
SPLIT = "aa*x**2 + bb*x*abs(x) + 0.0063"  # split at 0 for every bb; smooth (C1) unless bb = 0


def test_a_smooth_join_is_derived_as_a_chain(tmp_path, monkeypatch, capsys):
    from billiard.cli import main

    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    assert main(["derive", "--name", "c1", "--curve", C1]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:4] == [
        "chain: 2 piece(s), 1 join(s)",
        "  piece 0: x < 0 m: f = 10*x**2 + 0.0063",
        "  join at x = 0 m: C1, smooth: height and slope continuous, f'' jumps",
        "  piece 1: x > 0 m: f = 30*x**2 + 0.0063",
    ], out
    curve = load_curve("c1")
    assert [w.smooth_hi for w in curve.walls] == [True, False]
    # the height is the piece's that holds x, not the maximum of the formulas
    assert curve.f(-0.05) == pytest.approx(10 * 0.05**2 + 0.0063, rel=1e-15)
    assert curve.f(0.05) == pytest.approx(30 * 0.05**2 + 0.0063, rel=1e-15)
    # the paper's curves pass the same checks with the parameters they ship with
    for name, text, params in (
        ("parab", "a*x**2 + c", ["a=26", "c=0.0063"]),
        ("wedg", "b*abs(x) + c", ["b=1.85", "c=0.0063"]),
        ("hyper", "sqrt(a*(1 + b*x**2)) - c", ["a=40.3e-4", "b=800", "c=0.0445"]),
    ):
        args = [a for p in params for a in ("--param", p)]
        assert main(["derive", "--name", name, "--curve", text, *args]) == 0, capsys.readouterr()


def test_the_joins_are_checked_again_for_the_scenes_values(tmp_path, monkeypatch):
    """Where parameters decide a join's class, the numbers are known only at set-up: a
    module derived for bb = 0 (one curve) runs with bb = 10 as a chain (its join is C1
    for every bb); the wedge with b < 0 is a concave kink, refused in one line."""
    from billiard.errors import GeometryError
    from billiard.geometry.boundary import Boundary

    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    load_curve(SPLIT, {"aa": 26.0, "bb": 0.0})  # derived and cached: accepted
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {"boundary.curve": SPLIT, "boundary.parameters.aa": 20.0, "boundary.parameters.bb": 10},
    )
    curve = load_curve(SPLIT, {"aa": 20.0, "bb": 10.0})
    boundary = Boundary.from_scene(scene, curve.walls)
    assert [len(c) for c in boundary.chains] == [2] and len(boundary.offsets) == 1
    assert simulate(scene, duration=0.5).stop_reason is None
    wedge = with_values(load_scene("wedge-6.6hz"), {"boundary.parameters.b": -1.85})
    with pytest.raises(GeometryError, match=r"concave kink \(slope 1.85 -> -1.85\)") as caught:
        simulate(wedge, collisions=5)
    assert "\n" not in str(caught.value)
    # every built-in scene is accepted (the wedge's kink is convex: the maximum is the curve)
    from billiard.scene.scene import builtin_scene_names

    for name in builtin_scene_names():
        scene = load_scene(name)
        curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
        Boundary.from_scene(scene, curve.walls)


def test_a_join_derived_smooth_but_kinked_at_the_scenes_values_is_refused(tmp_path, monkeypatch):
    """Equal slopes at x = 1 for b = 1 only (2 b on the left, b + 1 on the right): derived
    with b = 1 as C1, run with b = 2 it is a kink the chain cannot take: one line."""
    from billiard.errors import GeometryError

    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    text = "Piecewise((b*x**2, x < 1), (b*x + 2*x**3 - 3*x**2 + x, True))"
    load_curve(text, {"b": 1.0})
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {"boundary.curve": text, "boundary.parameters.b": 2.0, "boundary.escape_height": 3.0},
    )
    with pytest.raises(GeometryError) as caught:
        simulate(scene, collisions=5)
    message = str(caught.value)
    assert "\n" not in message and "the join at x = 1 m was derived smooth" in message
    assert "its slope jumps (4 -> 3)" in message


def _parabola_runs(model: str, amplitude: float):
    """The same scene on aa*x**2 + 0.0063 and on SPLIT with bb = 0 (3 s, sampled)."""
    base = with_values(
        load_scene("parabola-5.4hz"), {"contact.model": model, "drive.amplitude": amplitude}
    )
    runs = []
    for curve, parameters in (("aa*x**2 + 0.0063", {}), (SPLIT, {"bb": 0.0})):
        values = {"boundary.curve": curve, "boundary.parameters.aa": 26.0}
        values.update({f"boundary.parameters.{k}": v for k, v in parameters.items()})
        runs.append(simulate(with_values(base, values), duration=3.0, sample=1e-3))
    return runs


@pytest.mark.parametrize(
    ("model", "amplitude"), [("phases", 0.005), ("phases", 0.02543), ("impacts", 0.02543)]
)
def test_equal_pieces_are_one_wall_that_runs_as_the_plain_curve(
    model, amplitude, tmp_path, monkeypatch
):
    """SPLIT with bb = 0 is the parabola 26 x^2 + 0.0063 split at 0 into two equal
    walls. Kept as two, a ball rolling through the bottom (drive 5 mm) stopped the run
    after 2.1 s on "contact phases of zero duration piled up"; one wall, it runs as the
    plain parabola: rolling for 3 s, and bouncing (the scene's 25.43 mm drive), in both
    contact models.

    Tolerance: the merged wall's formulas (aa*x**2 - bb*x**2 with bb = 0) give the
    parabola's heights to the last bit or so (here exactly, so the runs are the same
    bits), and 3 s of this motion amplify a last-bit difference by far less than the
    1e-11 of each column's scale allowed (as for the two branches of 100*abs(x)**3)."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    curve = load_curve(SPLIT, {"aa": 26.0, "bb": 0.0})
    assert len(curve.walls) == 1 and curve.breakpoints == ()
    assert (curve.walls[0].lo, curve.walls[0].hi, curve.walls[0].index) == (-math.inf, math.inf, 0)
    assert len(load_curve(SPLIT, {"aa": 26.0, "bb": 1.0}).walls) == 2  # not merged
    plain, split = _parabola_runs(model, amplitude)
    assert split.stop_reason is None and split.final_time == pytest.approx(3.0)
    for table in ("columns", "contacts", "trajectory"):
        a, b = getattr(plain, table), getattr(split, table)
        if a is None:  # no contact phases under the impacts model
            assert b is None and model == "impacts"
            continue
        assert list(a) == list(b)
        for key in a:
            x, y = np.asarray(a[key]), np.asarray(b[key])
            assert x.shape == y.shape, (table, key)
            if x.dtype.kind == "f":
                scale = np.max(np.abs(x), initial=0.0)
                assert np.max(np.abs(x - y), initial=0.0) <= 1e-11 * scale, (table, key)
            else:
                assert np.array_equal(x, y), (table, key)
    assert len(plain.trajectory["t"]) > 2000
