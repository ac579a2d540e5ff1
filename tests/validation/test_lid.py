"""The lid holds a ball the drive presses against it (``contact.model = "phases"``).

Under a vertical drive D = A sin(w t + phase) a ball against the flat lid moves with it
while N = m (A w^2 sin(theta) - g) > 0. The references here come from the drive alone,
not from the engine's closed forms:

* release where N falls to zero, sin(theta) = g / (A w^2) on the way down;
* a sliding ball stops slipping where the friction impulse has taken its slip (the
  velocity of its top relative to the lid, v1 - r omega) to zero:
  mu_k (1 + 1/k) times the integral of N / m over the phase = |slip| (that integral
  by quadrature);
* rolling on the flat lid needs no friction: v1 and omega stay, v1 = r omega.
"""

from __future__ import annotations

import math

import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from billiard.run.simulate import simulate
from billiard.runfile.record import LID_WALL
from billiard.scene.scene import scene_from_dict
from billiard.status import Status
from tests.engine.test_run_ends import lid_release_time

R = 1.55e-3
K = 0.4
MU_K = 0.2
B = 1.85  # the wedge's slope
CEILING = 0.05
#: the time (s) of a phase's end against its reference: the engine finds the end to
#: rounding of the clock (1e-16 s at t ~ 0.1 s); the quadrature is good to 1e-12
TIME_TOL = 1e-9


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def lid_scene(curve: str, parameters: dict | None, v1: float, gamma: float = 3.0):
    """A container shaken vertically at 10 Hz with acceleration gamma g, the ball just
    below its lid moving up into it at 0.05 m/s relative to it and sideways at v1 (m/s),
    when the lid accelerates downward at its fastest (phase pi/2)."""
    w = 2.0 * math.pi * 10.0
    amplitude = gamma * 9.81 / (w * w)
    data = {
        "boundary": {"curve": curve, "escape_height": 1.0, "ceiling": CEILING},
        "drive": {"amplitude": amplitude, "frequency": 10.0, "direction": "vertical",
                  "phase": math.pi / 2.0},
        "ball": {"radius": R, "inertia_factor": K},
        "contact": {"model": "phases", "restitution": 0.3, "mu_static": 0.3,
                    "mu_kinetic": MU_K, "elastic_below": 0.5},
        "air": {"drag": "none"},
        "initial": {"q1": 0.0, "q2": CEILING + amplitude - R - 1e-4, "v1": v1, "v2": 0.05},
        "run": {"collisions": 1000, "duration": 0.08},
    }  # fmt: skip
    if parameters:
        data["boundary"]["parameters"] = parameters
    return scene_from_dict(data)


def press(scene, t: float) -> float:
    """N / m (m/s^2) of the lid on a ball moving with it at t (s)."""
    w = 2.0 * math.pi * scene.drive.frequency
    a = scene.drive.amplitude * w * w
    return a * math.sin(w * t + scene.drive.phase) - scene.run.gravity


def lid_rows(result) -> list[dict]:
    c = result.contacts
    names = ("t_start", "t_end", "mode", "end", "v1_start", "omega_start", "v1_end",
             "omega_end", "q1_start", "q1_end", "q2_start", "q2_end")  # fmt: skip
    return [{n: getattr(c, n)[i] for n in names} for i in range(c.rows) if c.wall[i] == LID_WALL]


def test_a_ball_sliding_against_a_shaken_lid_rolls_then_lets_go_at_the_closed_forms():
    scene = lid_scene("0", None, v1=0.2)
    result = simulate(scene, collisions=1000)
    assert result.status is Status.TIME_LIMIT, result.message
    rows = lid_rows(result)
    assert [(r["mode"], r["end"]) for r in rows[:2]] == [("slide", "roll"), ("roll", "lift-off")]
    slide, roll = rows[0], rows[1]
    t0 = float(slide["t_start"])
    assert press(scene, t0) > 0.0
    # sliding to rolling: the friction impulse takes the slip of the ball's top to zero
    slip = slide["v1_start"] - R * slide["omega_start"]
    assert abs(slip) > 0.05  # the impact left the ball sliding

    def taken(t):
        return MU_K * (1.0 + 1.0 / K) * quad(lambda s: press(scene, s), t0, t, epsabs=1e-14)[0]

    t_roll = brentq(lambda t: taken(t) - abs(slip), t0, lid_release_time(scene, t0), xtol=1e-14)
    assert abs(slide["t_end"] - t_roll) < TIME_TOL
    assert roll["t_start"] == slide["t_end"]
    # rolling on the flat lid: no force along it, the top of the ball at rest on the lid
    assert roll["v1_end"] == roll["v1_start"] and roll["omega_end"] == roll["omega_start"]
    assert abs(roll["v1_end"] - R * roll["omega_end"]) < 1e-12
    # the lid lets go where it no longer presses the ball
    assert abs(roll["t_end"] - lid_release_time(scene, t0)) < TIME_TOL
    assert abs(press(scene, float(roll["t_end"]))) < 1e-6


@pytest.mark.parametrize("v1", [0.0, 2.0])
def test_a_ball_against_the_lid_of_a_shaken_wedge_is_let_go_or_meets_a_wall(v1):
    """Along the lid of a wedge the ball is let go at the closed-form release time, or,
    fast enough (2 m/s), reaches a wall first: the wall-lid corner, where its centre is
    on both offset lines; the run goes on to its limit."""
    scene = lid_scene("wedge", {"b": B, "c": 0.0}, v1=v1)
    result = simulate(scene, collisions=1000)
    assert result.status is Status.TIME_LIMIT, result.message
    rows = lid_rows(result)
    assert rows
    for row in rows:
        if row["end"] == "lift-off":
            assert abs(row["t_end"] - lid_release_time(scene, float(row["t_start"]))) < TIME_TOL
    first = rows[0]
    if v1 == 0.0:
        assert [(r["mode"], r["end"]) for r in rows] == [("roll", "lift-off")]
        return
    assert first["end"] == "impact"
    t = float(first["t_end"])
    assert t < lid_release_time(scene, float(first["t_start"]))
    # the corner in the boundary's frame: the lid's offset line and the wall's,
    # y = b |x| + r sqrt(1 + b^2)
    w = 2.0 * math.pi * scene.drive.frequency
    y = first["q2_end"] - scene.drive.amplitude * math.sin(w * t + scene.drive.phase)
    assert abs(y - (CEILING - R)) < 1e-12
    assert abs(y - (B * abs(first["q1_end"]) + R * math.sqrt(1.0 + B * B))) < 1e-9
