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

import numpy as np
import pytest

from billiard.engine.simulation import Simulation
from billiard.run.simulate import simulate
from billiard.runfile.record import LID_WALL, ContactRecord
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
    half, late = spins[0.5] / (0.5 * w0) - 1, spins[0.98] / (0.02 * w0) - 1
    print(f"[validation] spin in the vertex: at t_stop / 2 {half:+.1e}, at 0.98 {late:+.1e} rel.")
    assert abs(half) <= 4e-14  # linear decay; measured 4.4e-16
    assert spins[1.2] == 0.0 and abs(late) <= 2e-12  # measured 2.3e-14


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
    error = record.t_end - math.asin(1 / gamma) / w
    print(f"[validation] spinning ball in a shaken wedge, Gamma {gamma}: release {error:+.1e} s")
    assert abs(error) <= 5e-12  # measured 4.9e-17 (Gamma 1.5), 5.9e-14 s (Gamma 3)
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
    error = record.t_end - math.asin(1 / gamma) / w
    print(f"[validation] shaken wedge, Gamma {gamma}: release {error:+.1e} s")
    assert abs(error) <= 5e-12  # measured 4.9e-17 (Gamma 1.5), 5.9e-14 s (Gamma 3)
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
    gain = float(np.max(energy[1:] / energy[:-1] - 1))
    print(f"[validation] released on a wall: largest energy change between impacts {gain:+.1e}")
    assert gain < 0.0  # nothing gains energy: each impact loses at least 1.8e-3 (measured)


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
    print(f"[validation] shaken wedge with drag: release {record.t_end - expected:+.1e} s")
    assert abs(record.t_end - expected) <= 1e-14  # measured 1.2e-16 s


def test_a_ball_sliding_out_of_the_vertex_comes_back_to_the_other_wall():
    # frictionless still wedge, the ball at the vertex sliding up the left wall at v: it
    # touches the right wall at the start while moving away from it, so it meets it when
    # it comes back, 2 v / (g sin(beta)) later (the centre's deceleration along the wall),
    # here within the phase's first step, from a gap to the right wall of -4e-19 m
    beta = math.atan(B)
    v = 1e-4
    start = {
        "q1": 0.0, "q2": R / math.cos(beta),
        "v1": -v * math.cos(beta), "v2": v * math.sin(beta),
    }  # fmt: skip
    sim = Simulation(wedge(FRICTIONLESS, start))
    assert sim.mode == "slide"
    contacts = []
    sim.on_contact = contacts.append
    impact = sim.step()
    assert [c.end for c in contacts] == ["impact"]
    error = contacts[0].t_end - 2 * v / (G * math.sin(beta))
    print(f"[validation] out of the vertex and back: {error:+.1e} s")
    assert abs(error) <= 1e-13  # measured 1.8e-15 s
    assert impact.t == contacts[0].t_end and impact.wall == 1 and impact.Rn > 0.0


#: A vertically shaken wedge with a light ball at rest in its vertex, in which the ball
#: lands on one wall at the vertex and meets the other there at once, again and again
#: (with restitution and the landing speed of contact.elastic_below).
SHAKEN_VERTEX = {
    "contact.model": "phases",
    "drive.direction": "vertical",
    "drive.amplitude": 0.016488871225231298,
    "drive.frequency": 9.247894177852217,
    "drive.phase": 2.40958170922999,
    "contact.restitution": 0.6754179399974171,
    "contact.mu_static": 0.11706196447135508,
    "contact.mu_kinetic": 0.08944329198868507,
    "contact.elastic_below": 0.001,
    "ball.radius": 0.002013811438399591,
    "ball.mass": 1.789066936383012e-05,
    "ball.inertia_factor": 0.12156603567375565,
    "initial.t": 33.44942940838798,
}


def same_time_runs(t) -> int:
    """The longest run of consecutive records at one time (0: every time differs)."""
    longest = run = 0
    for same in t[1:] == t[:-1]:
        run = run + 1 if same else 0
        longest = max(longest, run)
    return longest


def test_a_vertically_shaken_wedge_keeps_a_ball_in_its_vertex_without_cycles():
    from billiard.scene.scene import load_scene

    sc = with_values(load_scene("wedge-6.6hz"), SHAKEN_VERTEX)
    start = Simulation(sc).initial
    print(f"[validation] shaken vertex: the ball starts {start.q1:+.1e} m from the vertex")
    # at rest in the vertex; measured q1 = 0 m
    assert abs(start.q1) < 1e-15 and start.u1 == start.u2 == 0.0
    result = simulate(sc, collisions=1_000_000, duration=10.0)
    assert result.status is Status.TIME_LIMIT, result.message
    assert len(result) > 50  # it bounces: the drive's peak acceleration is 5.7 g
    t = result.columns["t"]
    assert t[-1] - SHAKEN_VERTEX["initial.t"] > 9.0
    assert same_time_runs(t) <= 3
    assert result.mode_times["held"] > 0.0
    assert not ((result.columns["Rt"] == 0.0) & (result.columns["Rn"] == 0.0)).any()


def shaken_wedge_draw(seed: int) -> dict:
    """A random draw of the soak (bench.soak.random_draw) made a vertically shaken wedge
    under phases, with a landing speed (contact.elastic_below > 0)."""
    import random

    from bench.soak import random_draw

    draw = random_draw(random.Random(seed))
    # the draws named below were found under Kane and Levinson's law; the soak's draws
    # now also pick an impact law, which would change these scenes
    draw.update(curve="wedge", direction="vertical", model="phases", law="kane-levinson")
    draw["amplitude"] = draw["amplitude"] or 0.01
    draw["elastic_below"] = draw["elastic_below"] or 0.01
    return draw


@pytest.mark.parametrize("seed", [34, 129, 312, 353])
def test_random_shaken_wedges_record_only_impacts_with_an_impulse(seed):
    from bench.soak import scene_from_draw

    sc = with_values(scene_from_draw(shaken_wedge_draw(seed)), {"run.duration": 4.0})
    result = simulate(sc, collisions=100_000)
    # run to its end, or thrown out of the open wedge (seed 353): no collapse
    assert result.status.finished or result.status is Status.ESCAPED, result.message
    assert len(result) > 0
    columns = result.columns
    assert not ((columns["Rt"] == 0.0) & (columns["Rn"] == 0.0)).any()
    assert same_time_runs(columns["t"]) <= 10


def test_without_a_landing_speed_a_shaken_vertex_holds_the_ball_without_cycles():
    # elastic_below = 0: no landing speed; the ball meets one wall and the other at one
    # instant (a series of impacts in no time) and is held, instead of piling up impacts
    # at that instant until the collapse stop
    from billiard.scene.scene import load_scene

    sc = with_values(load_scene("wedge-6.6hz"), {**SHAKEN_VERTEX, "contact.elastic_below": 0.0})
    result = simulate(sc, collisions=1_000_000, duration=10.0)
    assert result.status is Status.TIME_LIMIT, result.message
    t = result.columns["t"]
    assert len(result) > 50 and t[-1] - SHAKEN_VERTEX["initial.t"] > 9.0
    assert same_time_runs(t) <= 3
    assert result.mode_times["held"] > 0.0
    assert not ((result.columns["Rt"] == 0.0) & (result.columns["Rn"] == 0.0)).any()


@pytest.mark.parametrize("seed", [34, 312])
def test_without_a_landing_speed_random_shaken_wedges_run_without_zero_time_cycles(seed):
    # two draws whose ball slid into the vertex and met the walls in turn at one
    # instant until 1,000 phases of zero duration stopped the run
    from bench.soak import scene_from_draw

    draw = shaken_wedge_draw(seed)
    draw["elastic_below"] = 0.0
    sc = with_values(scene_from_draw(draw), {"run.duration": 4.0})
    result = simulate(sc, collisions=100_000)
    assert result.status is Status.TIME_LIMIT, result.message
    assert result.mode_times["held"] > 0.0
    columns = result.columns
    assert not ((columns["Rt"] == 0.0) & (columns["Rn"] == 0.0)).any()
    assert same_time_runs(columns["t"]) <= 10


@pytest.mark.parametrize("amplitude", [0.005, 0.01])
def test_a_ball_rolling_into_the_shaken_wedges_vertex_is_held_there(amplitude):
    """The paper's wedge shaken gently (Gamma 0.88 and 1.75, below g tan(beta) = 1.85 g,
    where the walls can always hold a ball at rest in the vertex): the ball rolls into
    the vertex with a sliver of spin whose kinetic friction would pull it off the other
    wall. It used to meet one wall and the other 25,000 times in 43 ms (a stream of
    elastic "impacts" of 1e-10 N s); the friction stops that spin within 1e-6 of a drive
    period, so the ball is held and, the walls holding it for good, at rest."""
    from billiard.scene.scene import load_scene

    sc = load_scene("wedge-6.6hz", ["contact.model=phases", f"drive.amplitude={amplitude}"])
    result = simulate(sc, collisions=25_000)
    assert result.status is Status.AT_REST, result.message
    assert len(result) < 100
    assert result.final_mode == "held"  # at rest from the moment it is held
    t = result.columns["t"]
    assert same_time_runs(t) <= 3


def vertex_family_draw(seed: int) -> dict:
    """A random vertically shaken wedge of the soak's draws with little restitution and
    friction and no landing speed (e = 0.05, mu_s = 0.3, elastic_below = 0): the ball
    ends in the vertex, meeting one wall and the other at one instant, again and again."""
    draw = shaken_wedge_draw(seed)
    draw.update(restitution=0.05, mu_static=0.3, elastic_below=0.0)
    return draw


@pytest.mark.parametrize("seed", range(120))
def test_a_random_vertically_shaken_wedge_never_collapses_in_its_vertex(seed):
    """Every draw runs to its 2 s limit or out of the open wedge, none stopped as a
    collapse: a ball pressed against the lid alone is held by it (seeds 2, 20, 65 and 78
    stopped there before, "pressed against the lid"). A ball that meets one
    wall and the other at one instant makes one impact with both normals (the series
    of impacts there, resolved at once): before, the series was followed impact by
    impact, up to 47 rows at one instant with impulses down to 1e-20 N s, and one draw
    (seed 1) stopped on a wall it had crossed by rounding."""
    from bench.soak import scene_from_draw

    sc = with_values(scene_from_draw(vertex_family_draw(seed)), {"run.duration": 2.0})
    result = simulate(sc, collisions=100_000)
    assert result.status.finished or result.status is Status.ESCAPED, result.message
    columns = result.columns
    assert same_time_runs(columns["t"]) <= 3
    impulse = np.maximum(np.abs(columns["Rn"]), np.abs(columns["Rt"]))
    assert not (impulse < 1e-20).any()


def still_vertex_draw(seed: int) -> dict:
    """A still wedge (no drive, no drag, no lid) of the soak's draws with the ball
    started within 1e-5 .. 1e-1 of the container's width from the vertex, at a speed of
    the same scale (m/s, times 10) and a random spin; e is 0, 0.05 or uniform."""
    import random

    from bench.soak import random_draw

    rng = random.Random(seed)
    draw = random_draw(rng)
    draw.update(curve="wedge", model="phases", amplitude=0.0, lid=False, start="inside")
    draw.update(magnus=0.0, drag="none")
    scale = 10 ** rng.uniform(-5.0, -1.0)
    draw["x_fraction"] = 0.5 + rng.uniform(-1.0, 1.0) * scale
    draw["y_fraction"] = rng.uniform(0.0, 1.0) * scale
    draw["v1"], draw["v2"] = (rng.uniform(-10.0, 10.0) * scale for _ in range(2))
    draw["omega"] = rng.uniform(-1.0, 1.0) * 10 ** rng.uniform(-3.0, 2.5)
    draw["restitution"] = rng.choice([0.0, 0.05, rng.uniform(0.0, 1.0)])
    return draw


def event_energies(sc, duration: float) -> list[tuple[str, float, float]]:
    """(event, t, mechanical energy in J) at the start, after every impact and at both
    ends of every contact phase, in the order the engine makes them, for ``duration``
    seconds of simulated time: E = m |v|^2 / 2 + k m r^2 omega^2 / 2 + m g q2, from the
    recorded states alone."""
    sim = Simulation(sc)
    m, r, k, g = sc.ball.mass, sc.ball.radius, sc.ball.inertia_factor, sc.run.gravity

    def energy(q2, v1, v2, omega):
        return 0.5 * m * (v1 * v1 + v2 * v2) + 0.5 * k * m * r * r * omega * omega + m * g * q2

    b = sim.initial
    events = [("start", b.t, energy(b.q2, b.u1, b.u2, b.u3))]
    seen = []

    def contact(c):
        seen.append(c)
        events.append(
            (
                f"{c.mode} start",
                c.t_start,
                energy(c.q2_start, c.v1_start, c.v2_start, c.omega_start),
            )
        )
        events.append((f"{c.mode} end", c.t_end, energy(c.q2_end, c.v1_end, c.v2_end,
                                                         c.omega_end)))  # fmt: skip

    sim.on_contact = contact
    end = b.t + duration
    for _ in range(20_000):
        record = sim.step(until=end)
        if record is None:
            break
        if isinstance(record, ContactRecord):
            if not seen or seen[-1] != record:
                contact(record)
        else:
            events.append(("impact", record.t, record.energy))
    return events


def test_a_still_wedges_vertex_never_raises_the_energy_at_an_event():
    """60 draws of a still wedge with the ball near the vertex (e, mu_s, mu_k, the
    start, the spin random): the mechanical energy never rises from one event to the
    next by more than 1e-12 of it (no drive, no drag: nothing adds energy), and no two
    impacts in a row share a time. Before, a ball meeting one wall and the other at
    one instant made up to 8 impacts there."""
    from bench.soak import scene_from_draw

    worst, longest = -math.inf, 0
    for seed in range(60):
        events = event_energies(scene_from_draw(still_vertex_draw(seed)), 2.0)
        for (_, _, before), (what, t, after) in zip(events, events[1:], strict=False):
            worst = max(worst, (after - before) / abs(before))
            assert after - before <= 1e-12 * abs(before), (seed, what, t, before, after)
        times = np.array([t for what, t, _ in events if what == "impact"])
        longest = max(longest, same_time_runs(times))
    print(f"[validation] still vertex family: largest energy change at an event {worst:+.1e}")
    assert longest <= 1


@pytest.mark.parametrize("rise", [0.002, 0.005, 0.01])
def test_a_wall_and_the_lid_hold_the_ball_in_their_corner(rise):
    """The frictionless wedge shaken horizontally at Gamma 3 with a lid ``rise`` metres
    above the ball's place in the vertex: released from the vertex, the ball slides up
    the right wall into its corner with the lid, where the two hold it as the vertex's
    walls do (before, the lid held no ball: it chattered between wall and lid). By hand:
    the force on the ball relative to the boundary, m (A w^2 sin(w t), -g), is taken by
    normal forces N_w (b, -1) / sqrt(1 + b^2) of the wall and N_l (0, 1) of the lid;
    N_l = m (A w^2 sin(w t) / b - g) vanishes at sin(w t) = g b / (A w^2) = 1 / Gamma,
    after the half period's peak: released at w t = pi - asin(1 / Gamma)."""
    f, gamma = 5.0, 3.0
    w = 2 * math.pi * f
    amplitude = gamma * G * B / w**2
    drive = {"amplitude": amplitude, "frequency": f, "direction": "horizontal"}
    sc = wedge(FRICTIONLESS, {"v1": amplitude * w}, drive)
    lid = R / math.cos(math.atan(B)) + R + rise
    sim = Simulation(with_values(sc, {"boundary.ceiling": lid, "boundary.escape_height": 1.0}))
    holds = []
    sim.on_contact = lambda c: holds.append(c) if c.mode == "held" else None
    for _ in range(50):
        if holds and holds[-1].wall_other == LID_WALL:
            break
        assert sim.step(until=0.2) is not None
    corner = holds[-1]
    assert (corner.wall, corner.wall_other, corner.end) == (1, LID_WALL, "release")
    error = corner.t_end - (math.pi - math.asin(1 / gamma)) / w
    print(f"[validation] wall-lid corner, lid {rise} m up: released {error:+.1e} s")
    assert abs(error) <= 5e-12  # measured 0 (rise 0.002, 0.005, 0.01 m)
    # held, the ball moves with the boundary: v1 = A w cos(w t)
    assert abs(corner.v1_end - amplitude * w * math.cos(w * corner.t_end)) <= 1e-15
