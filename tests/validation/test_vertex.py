"""The ball held by two walls at once, in the wedge's vertex (``contact.model = "phases"``).

Closed forms written here, for the wedge y = b |x| (walls at angle beta = atan b):

* at rest in the vertex of a still wedge the ball stays, with no impact, and 10 s of
  simulated time take a handful of force evaluations;
* spinning in the vertex, kinetic friction at both contacts stops the spin at
  t* = k m r w0 / (mu_k (N_a + N_b)), with N_a, N_b from the balance of forces
  N_a (n_a - mu_k t_a) + N_b (n_b - mu_k t_b) = m g e_y (solved by hand below);
* in a horizontally shaken wedge (drive D = A sin(w t)) without friction the wall the
  boundary accelerates away from stops pressing when |A w^2 sin(w t)| = g tan(beta):
  released at sin(w t) = g tan(beta) / (A w^2);
* a ball released on a wall rolls down, bounces in the vertex, and comes to rest there.
"""

from __future__ import annotations

import math

import pytest

from billiard.engine.simulation import Simulation
from billiard.run.simulate import simulate
from billiard.runfile.record import ContactRecord
from billiard.scene.scene import with_values
from billiard.status import Status
from tests.validation.test_contact import G, K, R, scene

M = 1.3028e-4  # kg, the default ball
B = 1.85  # the wedge's slope


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def wedge(contact=None, initial=None, drive=None):
    return scene("wedge", {"b": B, "c": 0.0}, contact, initial, drive)


def count_forces(monkeypatch) -> list:
    """A list that grows by one at each evaluation of the held ball's normal forces: the
    hold kernel's, which the interpreted twin looks up at each call."""
    from billiard.kernels.interpreted import vertex

    calls: list = []
    forces = vertex.forces
    monkeypatch.setattr(vertex, "forces", lambda *a: calls.append(1) or forces(*a))
    return calls


def test_rest_in_the_vertex_is_kept_cheaply(monkeypatch):
    # the cost counted as force evaluations (never as time in a test)
    calls = count_forces(monkeypatch)
    sim = Simulation(wedge())
    assert sim.mode == "held"
    assert sim.step(until=10.0) is None
    assert sim.state.impacts == 0 and 0 < len(calls) < 20
    result = simulate(wedge(), collisions=100)
    assert len(result) == 0 and result.status is Status.AT_REST


def test_spin_in_the_vertex_stops_at_the_friction_time():
    w0, mu = 80.0, 0.3
    sim = Simulation(wedge({"mu_static": 0.4, "mu_kinetic": mu}, {"omega": w0}))
    assert sim.mode == "held"
    # balance for spin w0 > 0 (sigma = +1), walls z_a = -beta (left), z_b = +beta (right):
    # horizontal N_a (sin b - mu cos b) - N_b (sin b + mu cos b) = 0,
    # vertical   N_a (cos b + mu sin b) + N_b (cos b - mu sin b) = m g
    beta = math.atan(B)
    s, c = math.sin(beta), math.cos(beta)
    ratio = (s + mu * c) / (s - mu * c)  # N_a / N_b
    n_b = M * G / (ratio * (c + mu * s) + (c - mu * s))
    t_stop = K * M * R * w0 / (mu * (ratio + 1.0) * n_b)
    rows = []
    sim.sample_dt = t_stop / 50
    sim.on_sample = lambda *row: rows.append(row)
    assert sim.step(until=2 * t_stop) is None
    spins = {round(t / t_stop, 9): row[4] for t, *row in rows}
    assert spins[0.5] == pytest.approx(0.5 * w0, rel=1e-12)  # linear decay
    assert spins[1.2] == 0.0 and spins[0.98] == pytest.approx(0.02 * w0, rel=1e-9)


FRICTIONLESS = {"mu_static": 0.0, "mu_kinetic": 0.0}


def test_frictionless_spin_in_the_vertex_of_a_still_wedge_is_kept_at_rest():
    # no friction, no torque: the spin never stops, and the ball held in a still wedge
    # is at rest (as without spin) from the start, with its spin unchanged
    sim = Simulation(wedge(FRICTIONLESS, {"omega": 80.0}))
    assert sim.mode == "held"
    result = simulate(wedge(FRICTIONLESS, {"omega": 80.0}), collisions=100)
    assert len(result) == 0 and result.status is Status.AT_REST, result.message
    assert sim.step(until=10.0) is None  # a time limit: held to it
    assert sim.state.ball.u3 == 80.0


@pytest.mark.parametrize("gamma", [1.5, 3.0])
def test_frictionless_spin_in_a_shaken_wedge_stays_as_it_was(gamma):
    f = 5.0
    w = 2 * math.pi * f
    amplitude = gamma * G * B / w**2
    drive = {"amplitude": amplitude, "frequency": f, "direction": "horizontal"}
    sim = Simulation(wedge(FRICTIONLESS, {"v1": amplitude * w, "omega": -30.0}, drive))
    rows = []
    sim.sample_dt = 1e-3
    sim.on_sample = lambda *row: rows.append(row)
    record = sim.step()
    # released where the frictionless walls cannot hold the ball, spin or not
    assert isinstance(record, ContactRecord) and record.end == "release"
    assert record.t_end == pytest.approx(math.asin(1 / gamma) / w, abs=1e-11)
    assert record.omega_start == record.omega_end == -30.0
    assert rows and {row[5] for row in rows} == {-30.0}  # (t, q1, q2, u1, u2, u3, ...)


@pytest.mark.parametrize("gamma", [1.5, 3.0])
def test_a_shaken_wedge_releases_the_ball_where_the_walls_cannot_hold_it(gamma):
    f = 5.0
    w = 2 * math.pi * f
    amplitude = gamma * G * B / w**2  # gamma = A w^2 / (g tan beta)
    drive = {"amplitude": amplitude, "frequency": f, "direction": "horizontal"}
    # at rest relative to the wedge at t = 0: moving with it at A w
    sim = Simulation(wedge({"mu_static": 0.0, "mu_kinetic": 0.0}, {"v1": amplitude * w}, drive))
    assert sim.mode == "held"
    record = sim.step()
    assert isinstance(record, ContactRecord) and record.mode == "held"
    assert record.end == "release"
    assert record.t_end == pytest.approx(math.asin(1 / gamma) / w, abs=1e-11)
    assert sim.mode == "slide"  # frictionless: it slides up the right wall


def test_a_ball_released_on_a_wall_comes_to_rest_in_the_vertex():
    beta = math.atan(B)
    sc = scene(
        "wedge", {"b": B, "c": 0.0}, {"restitution": 0.5},
        {"q1": 0.01, "q2": B * 0.01 + R / math.cos(beta), "v1": 0.0, "v2": 0.0},
    )  # fmt: skip
    result = simulate(sc, collisions=100_000)
    assert result.status is Status.AT_REST, result.message
    assert 0 < len(result) < 1000
    times = result.mode_times
    assert times["roll"] > 0.05 and times["held"] > 0.0  # rolled down, then held
    assert result.contacts["mode"][-1] == "roll" and result.contacts["end"][-1] == "impact"
    energy = result.columns["energy"]
    assert (energy[1:] <= energy[:-1] * (1 + 1e-12)).all()  # nothing gains energy


def test_a_held_state_round_trips_through_a_checkpoint():
    from billiard.engine.state import EngineState

    f = 5.0
    w = 2 * math.pi * f
    amplitude = 2.0 * G * B / w**2
    drive = {"amplitude": amplitude, "frequency": f, "direction": "horizontal"}
    sc = wedge({"mu_static": 0.3, "mu_kinetic": 0.2}, {"v1": amplitude * w, "omega": 5.0}, drive)
    sim = Simulation(sc)
    assert sim.mode == "held"
    saved = EngineState.from_dict(sim.state.to_dict(), 201)
    first = [sim.step() for _ in range(20)]
    again = Simulation(sc)
    again.restore(saved)
    assert [again.step() for _ in range(20)] == first
    assert any(isinstance(r, ContactRecord) and r.mode == "held" for r in first)


def test_drag_on_a_held_ball_shifts_the_release_as_the_force_balance_says():
    # frictionless wedge shaken horizontally, Fowles drag on the centre moving at the
    # boundary's velocity v = A w cos(w t): the left wall stops pressing where
    # m a(t) + (c_lin + c_quad |v|) v + m g tan(beta) = 0, a = -A w^2 sin(w t)
    from scipy.optimize import brentq

    f, gamma = 5.0, 1.5
    w = 2 * math.pi * f
    amplitude = gamma * G * B / w**2
    c_lin, c_quad = 5e-5, 1e-4  # about a tenth of m g: it moves the release measurably
    drive = {"amplitude": amplitude, "frequency": f, "direction": "horizontal"}
    sc = scene(
        "wedge", {"b": B, "c": 0.0}, {"mu_static": 0.0, "mu_kinetic": 0.0},
        {"v1": amplitude * w}, drive,
    )  # fmt: skip
    sc = with_values(sc, {"air.drag": "fowles", "air.c_lin": c_lin, "air.c_quad": c_quad})
    record = Simulation(sc).step()
    assert isinstance(record, ContactRecord) and record.end == "release"

    def left_wall(t):
        v = amplitude * w * math.cos(w * t)
        return -M * amplitude * w * w * math.sin(w * t) + (c_lin + c_quad * abs(v)) * v + M * G * B

    expected = brentq(left_wall, 0.0, math.pi / (2 * w), xtol=1e-15)
    no_drag = math.asin(1 / gamma) / w
    assert abs(expected - no_drag) > 1e-4  # the drag term matters here
    assert record.t_end == pytest.approx(expected, abs=1e-11)
