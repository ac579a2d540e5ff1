"""Validation of the contact phases (``contact.model = "phases"``) against closed forms.

Each test builds a scene, runs the engine and compares with a formula derived here, not
with the engine's own equations:

* rolling down a straight wall at angle theta (tan theta <= 7/2 mu_s): the centre
  accelerates at (5/7) g sin theta along the wall and spins at -v/r; without friction it
  accelerates at g sin theta; when tan theta > 7/2 mu_s it slips, at
  g (sin theta - mu_k cos theta);
* small oscillations at the bottom of the static parabola y = a x^2: the centre's path
  has radius of curvature rho = 1/(2a) - r there, so rolling oscillations have the
  period 2 pi sqrt(7 rho / (5 g)) and frictionless sliding ones 2 pi sqrt(rho / g);
* a ball at rest at the bottom of a static bowl stays there, with no impact;
* a ball dropped on a static floor: the rebound speeds form a geometric series, so the
  impacts accumulate at t0 + 2 e v0 / (g (1 - e)) (v0 the first impact's speed at t0);
* a ball lying on a vertically shaken table D = A sin(w t) stays on it while
  Gamma = A w^2 / g < 1 and leaves it where the table's downward acceleration reaches g,
  sin(w t) = 1 / Gamma, when Gamma > 1.
"""

from __future__ import annotations

import math

import pytest
from billiard.generated import contact as _c

from billiard.engine.simulation import Simulation
from billiard.runfile.record import ContactRecord, ImpactRecord
from billiard.scene.scene import scene_from_dict

G = 9.81
R = 1.55e-3
K = 0.4


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def scene(curve, parameters=None, contact=None, initial=None, drive=None, run=None):
    data = {
        "boundary": {"curve": curve, "escape_height": 10.0, "ceiling": 5.0},
        "drive": drive or {"amplitude": 0.0, "frequency": 1.0},
        "contact": {"model": "phases", **(contact or {})},
        "air": {"drag": "none"},
        "initial": initial or {},
        "run": {"collisions": 1000, **(run or {})},
    }
    if parameters:
        data["boundary"]["parameters"] = parameters
    return scene_from_dict(data)


def incline(theta, s0, contact):
    """The wedge's right wall y = tan(theta) x as a straight wall; the ball at rest on it
    at the contact abscissa s0 (m)."""
    b = math.tan(theta)
    q1, q2, _, _ = _c.centre_state(s0, 0.0, b * s0, b, 0.0, 0.0, 0.0, 0.0, 0.0, R)
    return scene("wedge", {"b": b, "c": 0.0}, contact, {"q1": q1, "q2": q2, "v1": 0.0, "v2": 0.0})


def count_forces(monkeypatch) -> list:
    """A list that grows by one at each evaluation of the contact forces in a phase."""
    from billiard.kernels.interpreted import contact_forces as contact

    calls: list = []
    forces = contact.forces
    monkeypatch.setattr(contact, "forces", lambda *a: calls.append(1) or forces(*a))
    return calls


def first_phase(sim: Simulation) -> ContactRecord:
    """The first finished contact phase (a phase that ends at an impact makes the step
    return the impact; every phase goes to ``on_contact``)."""
    phases: list[ContactRecord] = []
    sim.on_contact = phases.append
    for _ in range(10):
        sim.step()
        if phases:
            return phases[0]
    raise AssertionError("no contact phase ended")


def along_wall(record: ContactRecord, theta: float) -> tuple[float, float]:
    """Distance travelled down the wall (m) and the speed down it at the end (m/s)."""
    c, s = math.cos(theta), math.sin(theta)
    dist = -((record.q1_end - record.q1_start) * c + (record.q2_end - record.q2_start) * s)
    speed = -(record.v1_end * c + record.v2_end * s)
    return dist, speed


@pytest.mark.parametrize(
    ("theta", "mu_s", "mu_k", "mode", "accel"),
    [
        (0.3, 0.61, 0.47, "roll", 5 / 7 * G * math.sin(0.3)),
        (0.3, 0.0, 0.0, "slide", G * math.sin(0.3)),
        (0.6, 0.1, 0.08, "slide", G * (math.sin(0.6) - 0.08 * math.cos(0.6))),
    ],
)
def test_down_a_straight_wall(theta, mu_s, mu_k, mode, accel):
    sim = Simulation(incline(theta, 0.05, {"mu_static": mu_s, "mu_kinetic": mu_k}))
    assert sim.mode == mode
    record = first_phase(sim)
    assert record.mode == mode and record.end == "impact"  # it reaches the other wall
    t = record.t_end - record.t_start
    dist, speed = along_wall(record, theta)
    assert t > 0.05
    errors = [speed / (accel * t) - 1, dist / (0.5 * accel * t * t) - 1]
    if mode == "roll":
        errors.append(record.omega_end / (speed / R) - 1)  # -v/r, v = -speed
    worst = max(abs(e) for e in errors)
    print(f"[validation] down a wall, {mode} at {theta} rad: speed, distance, spin {worst:.1e}")
    assert worst <= 4e-14  # measured 4.4e-16 (max over the 3 cases)


def test_rolling_needs_enough_friction():
    # tan(theta) = 3.5 mu_s is the threshold: just below it the ball rolls
    theta = math.atan(3.5 * 0.2) * (1 - 1e-6)
    assert Simulation(incline(theta, 0.05, {"mu_static": 0.2, "mu_kinetic": 0.1})).mode == "roll"
    theta = math.atan(3.5 * 0.2) * (1 + 1e-6)
    assert Simulation(incline(theta, 0.05, {"mu_static": 0.2, "mu_kinetic": 0.1})).mode == "slide"


def bowl(a, s0, contact):
    f0, fp, f2 = a * s0 * s0, 2 * a * s0, 2 * a
    q1, q2, _, _ = _c.centre_state(s0, 0.0, f0, fp, f2, 0.0, 0.0, 0.0, 0.0, R)
    return scene(
        "parabola", {"a": a, "c": 0.0}, contact, {"q1": q1, "q2": q2, "v1": 0.0, "v2": 0.0}
    )


@pytest.mark.parametrize(("mu", "factor"), [(0.61, 7 / 5), (0.0, 1.0)])
def test_small_oscillations_in_a_bowl(mu, factor):
    a, s0 = 10.0, 1e-4
    rho = 1 / (2 * a) - R
    period = 2 * math.pi * math.sqrt(factor * rho / G)
    sim = Simulation(bowl(a, s0, {"mu_static": mu, "mu_kinetic": mu}))
    assert sim.mode == ("roll" if mu else "slide")
    rows = []
    sim.sample_dt = period / 200
    sim.on_sample = lambda *row: rows.append(row)
    assert sim.step(until=100.25 * period) is None  # no event: one phase throughout
    assert len(rows) > 20000
    # upward crossings of q1 = 0, interpolated between samples (error ~ dt^3 curvature)
    ups = [
        t0 - x0 * (t1 - t0) / (x1 - x0)
        for (t0, x0, *_), (t1, x1, *_) in zip(rows, rows[1:], strict=False)
        if x0 < 0.0 <= x1
    ]
    assert len(ups) == 100
    measured = (ups[-1] - ups[0]) / (len(ups) - 1)
    # amplitude 1e-4 m against rho = 0.05 m: the anharmonic shift is O((s0/rho)^2) = 4e-6
    print(f"[validation] bowl, mu {mu}: period {measured / period - 1:+.2e} rel.")
    # measured +1.02e-6 (both cases): the anharmonic shift, not an error of the engine
    assert measured == pytest.approx(period, rel=2e-5)
    energy = [row[6] for row in rows]
    swing = max(energy) - min(energy)
    # the oscillation's energy, m g s0^2 / (2 rho) (about), against the drift
    oscillation = 1.3028e-4 * G * s0 * s0 / (2 * rho)
    print(f"[validation] bowl, mu {mu}: energy swing {swing / oscillation:.2e} of its energy")
    assert swing < 1e-6 * oscillation  # measured 5.5e-7 (max over the 2 cases)


def test_rest_in_a_static_bowl_is_kept_cheaply(monkeypatch):
    # the cost counted as evaluations of the contact forces (never as time in a test):
    # the phase kernel's, which the interpreted twin looks up at each call
    calls = count_forces(monkeypatch)
    sim = Simulation(bowl(10.0, 0.0, {}))
    assert sim.mode == "roll"
    calls.clear()
    assert sim.step(until=10.0) is None
    assert len(calls) < 200
    assert sim.state.impacts == 0
    ball = sim.state.ball
    assert (ball.u1, ball.u2) == (0.0, 0.0)


def flat(contact=None, initial=None, drive=None):
    return scene("0.001", None, contact, initial, drive)


def test_chattering_on_a_floor_ends_at_the_geometric_sum():
    e, h = 0.5, 0.01
    sim = Simulation(flat({"restitution": e}, {"q1": 0.0, "q2": 0.001 + R + h}))
    assert sim.mode == "flight"
    t0, v0 = math.sqrt(2 * h / G), math.sqrt(2 * G * h)
    impacts = []
    while sim.mode == "flight":
        record = sim.step()
        assert isinstance(record, ImpactRecord)
        impacts.append(record)
    first = impacts[0].t / t0 - 1
    # landing: the last impact's rebound e |wn| is below contact.elastic_below
    assert impacts[-2].v2 > 0.01 >= impacts[-1].v2
    settle = sim.state.contact[5] / (t0 + 2 * e * v0 / (G * (1 - e))) - 1
    print(f"[validation] floor: first impact {first:+.1e}, settle {settle:+.1e} rel.")
    assert abs(first) <= 2e-13  # measured 2.4e-15
    assert abs(settle) <= 1e-12  # measured 5.2e-14
    assert sim.step(until=10.0) is None  # then it rests: no impact, no lift-off
    assert sim.state.impacts == len(impacts)


def table(gamma, f=20.0):
    w = 2 * math.pi * f
    amplitude = gamma * G / w**2
    initial = {"q1": 0.0, "q2": 0.001 + R, "v2": amplitude * w}
    drive = {"amplitude": amplitude, "frequency": f, "direction": "vertical"}
    return flat({"restitution": 0.5}, initial, drive), w


def test_a_shaken_table_keeps_the_ball_below_gamma_one():
    sc, _ = table(0.9)
    sim = Simulation(sc)
    assert sim.mode == "roll"
    assert sim.step(until=2.0) is None
    assert sim.state.impacts == 0


def test_a_ball_resting_on_a_shaken_table_moves_with_it_at_the_cost_of_one_period(monkeypatch):
    # at rest relative to the table through a drive period, the periods after it repeat
    # it exactly: skipped, with the samples taken at the rest state
    calls = count_forces(monkeypatch)
    sc, w = table(0.9)
    amplitude = sc.drive.amplitude
    sim = Simulation(sc)
    rows = []
    sim.sample_dt = 0.001
    sim.on_sample = lambda *row: rows.append(row)
    calls.clear()
    assert sim.step(until=20.0) is None
    assert len(rows) == 20001
    q2_rest = 0.001 + R
    worst = max(abs(q2 - (q2_rest + amplitude * math.sin(w * t))) for t, _, q2, *_ in rows)
    print(f"[validation] resting on a shaken table: q2 {worst:.1e} m from the table's")
    assert worst < 4e-17  # measured 4.3e-19 m, one ulp of q2
    assert len(calls) < 2_000  # 20 s at 20 Hz is 400 periods (56,000 calls); one is integrated


@pytest.mark.parametrize("gamma", [1.2, 2.5])
def test_a_shaken_table_throws_the_ball_where_it_falls_faster_than_g(gamma):
    sc, w = table(gamma)
    sim = Simulation(sc)
    assert sim.mode == "roll"
    record = sim.step()
    assert isinstance(record, ContactRecord) and record.end == "lift-off"
    error = record.t_end - math.asin(1 / gamma) / w
    print(f"[validation] shaken table, Gamma {gamma}: lift-off {error:+.1e} s")
    assert abs(error) <= 3e-14  # measured 0 (Gamma 1.2) and 3.5e-16 s (Gamma 2.5)


def test_a_ball_resting_on_a_shaken_table_ends_an_unlimited_run():
    # at rest relative to the table through a whole drive period: it stays for ever
    from billiard.run.simulate import simulate
    from billiard.status import Status

    sc, _ = table(0.9)
    result = simulate(sc, collisions=100)
    assert len(result) == 0 and result.status is Status.AT_REST and result.status.finished
    assert result.stop_reason is None and "rests on the boundary" in result.message
