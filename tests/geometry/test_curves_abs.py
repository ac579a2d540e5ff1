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
