"""Where methods fail: one flight at a time from many real states, against a trusted
next impact.

The states are the post-impact states of the first impacts of each paper scene from
rest (the start, the chattering and the lift-off included), and for the wedge also
states near its vertex. From each state every method flies to its next impact, and
that impact is compared with the truth:

* drag off, the truth is the default method (exact parabola); it is checked itself
  against an independent geometry: the Euclidean clearance (``Boundary.clearance``) of
  the exact arc, sampled along the flight and at the impact point;
* drag on, the truth is the default method at rtol 1e-13 (for its own rtol ladder).

A method's impact more than SAME_IMPACT later than the truth is a *missed* impact (the
ball went through the wall), earlier a *spurious* one; penetration is how far the ball
is inside the wall at the impact the method reports (for a missed impact: the deepest
point of the true arc before it), energy error the relative error of the energy just
after a correctly found impact.
"""

from __future__ import annotations

import math

import numpy as np
from billiard.generated import ball as _ball

from bench.common import SAME_IMPACT, Config, one_flight, post_impact_state
from bench.peer import SolveIvpPeer
from billiard.run.simulate import BallState, Simulation, simulate
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import Scene, load_scene, with_values

TRUTH_RTOL = 1e-13
#: samples of an arc when its clearance is checked
SAMPLES = 24
#: the truth is trusted if its arc stays out of the wall by this much (m)
CLEARANCE_TOLERANCE = 1e-10


def scene_states(name: str, cfg: Config) -> tuple[Scene, list[BallState]]:
    """Post-impact states of the first ``cfg.flights`` impacts of the scene from rest."""
    scene = load_scene(name)
    c = simulate(scene, collisions=cfg.flights).columns
    drive = Simulation(scene).drive
    return scene, [post_impact_state(c, i, drive) for i in range(len(c["t"]))]


def vertex_states(cfg: Config) -> tuple[Scene, list[BallState]]:
    """States of balls dropped near the wedge's vertex (0.5 to 5 mm above the bottom,
    up to 1.5 mm off-centre, four drive phases) and of their first 15 impacts."""
    scene = with_values(load_scene("wedge-6.6hz"), {"air.drag": "none"})
    sim = Simulation(scene)
    rng = np.random.default_rng(1)
    states = []
    for _ in range(cfg.vertex_drops):
        x, h = rng.uniform(-1.5e-3, 1.5e-3), rng.uniform(0.5e-3, 5e-3)
        theta = rng.uniform(0.0, 2.0 * math.pi)
        q1, q2 = sim.drive.to_lab_frame(theta, x, sim.boundary.offset_height(x) + h)
        drop = BallState(0.0, theta, q1, q2, 0.0, 0.0, 0.0)
        states.append(drop)
        sim.reset(drop)
        recorder = MemoryRecorder()
        sim.run(15, recorder)
        c = recorder.columns()
        states += [post_impact_state(c, i, sim.drive, theta) for i in range(len(c["t"]))]
    return load_scene("wedge-6.6hz"), states


def clearance(sim: Simulation, theta: float, q1: float, q2: float) -> float:
    px, py, _, _ = sim.drive.to_boundary_frame(theta, q1, q2, 0.0, 0.0)
    return sim.boundary.clearance(px, py)


def arc_clearance(sim: Simulation, state: BallState, t0: float, t1: float) -> float:
    """Smallest clearance (m) of the exact drag-free arc from ``state`` on (t0, t1)."""
    g = sim.scene.run.gravity
    lowest = math.inf
    for tau in np.linspace(t0, t1, SAMPLES + 2)[1:-1]:
        q1, q2, _, _ = _ball.flight_exact(tau, state.q1, state.q2, state.u1, state.u2, g)
        lowest = min(lowest, clearance(sim, state.theta + sim.drive.omega * tau, q1, q2))
    return lowest


def runner(scene: Scene, kind: str, value: float):
    """A function state -> next-impact record (dict with tof, q1, q2, energy) or None."""
    if kind == "peer" or kind == "careful":
        peer = SolveIvpPeer(scene, value, careful=kind == "careful")

        def fly(state: BallState) -> dict | None:
            c, _, _ = peer.run(state, 1)
            return {k: v[0] for k, v in c.items()} if len(c["t"]) else None

        return fly
    key = "run.step" if kind == "rk4" else "run.rtol"
    sim = Simulation(with_values(scene, {key: value}), kind)
    return lambda state: one_flight(sim, state)


def compare(sim: Simulation, states: list, truth: list, fly, check_arc: bool) -> dict:
    """Classify a method's next impacts against the truth (see the module docstring)."""
    missed = spurious = 0
    depth = 0.0
    dtaus, energy = [], []
    for state, ref in zip(states, truth, strict=True):
        got = fly(state)
        tau = got["tof"] if got is not None else math.inf
        if tau > ref["tof"] + SAME_IMPACT:
            missed += 1
            if check_arc:
                end = min(tau, ref["tof"] + 0.05)
                depth = max(depth, -arc_clearance(sim, state, ref["tof"], end))
            continue
        theta = state.theta + sim.drive.omega * tau
        depth = max(depth, -clearance(sim, theta, got["q1"], got["q2"]))
        if tau < ref["tof"] - SAME_IMPACT:
            spurious += 1
            continue
        dtaus.append(abs(tau - ref["tof"]))
        energy.append(abs(got["energy"] - ref["energy"]) / abs(ref["energy"]))
    return _failure_row(
        len(states),
        missed,
        spurious,
        depth,
        float(np.median(dtaus)) if dtaus else math.nan,
        float(np.median(energy)) if energy else math.nan,
        float(np.max(energy)) if energy else math.nan,
    )


def check_truth(sim: Simulation, states: list, truth: list) -> dict:
    """The default method against the independent Euclidean clearance: arcs that enter
    the wall before the impact found (missed) and impact points off the wall
    (spurious)."""
    missed = spurious = 0
    depth = 0.0
    for state, ref in zip(states, truth, strict=True):
        lowest = arc_clearance(sim, state, 0.0, ref["tof"]) if ref["tof"] > 0 else math.inf
        theta = state.theta + sim.drive.omega * ref["tof"]
        end = clearance(sim, theta, ref["q1"], ref["q2"])
        missed += lowest < -CLEARANCE_TOLERANCE
        spurious += abs(end) > 1e-9
        depth = max(depth, -lowest, -end)
    # the reference itself: no impact-time or energy error by construction
    return _failure_row(len(states), missed, spurious, depth, 0.0, 0.0, 0.0)


def _failure_row(
    n: int,
    missed: int,
    spurious: int,
    depth: float,
    median_dtau: float,
    median_energy: float,
    max_energy: float,
) -> dict:
    """One row of the failure table: counts per 1,000 flights, deepest penetration (m),
    impact-time error (s) and relative energy error per impact."""
    return {
        "flights": n,
        "missed": missed,
        "spurious": spurious,
        "per_1000": 1000.0 * (missed + spurious) / max(n, 1),
        "penetration": max(depth, 0.0),
        "median_dtau": median_dtau,
        "median_energy": median_energy,
        "max_energy": max_energy,
    }


def measure_set(label: str, scene: Scene, states: list, cfg: Config) -> list[dict]:
    rows = []
    off = with_values(scene, {"air.drag": "none"})
    sim = Simulation(off)
    exact = runner(off, "event", scene.run.rtol)
    kept = [(s, exact(s)) for s in states]
    kept = [(s, t) for s, t in kept if t is not None]
    states, truth = [s for s, _ in kept], [t for _, t in kept]
    rows.append(
        {
            "set": label,
            "drag": "none",
            "method": "event",
            "setting": "exact flight",
            "value": 0.0,
            **check_truth(sim, states, truth),
        }
    )
    methods = [("rk4", "rk4", h, f"step {h:g} s") for h in cfg.rk4_steps]
    methods += [("DOP853", "peer", r, f"rtol {r:g}") for r in cfg.peer_rtols]
    methods += [("DOP853 careful", "careful", r, f"rtol {r:g}") for r in cfg.peer_rtols]
    for method, kind, value, setting in methods:
        result = compare(sim, states, truth, runner(off, kind, value), check_arc=True)
        rows.append(
            {
                "set": label,
                "drag": "none",
                "method": method,
                "setting": setting,
                "value": value,
                **result,
            }
        )
        print(
            f"  {label} {method} {setting}: {result['missed']} missed, "
            f"{result['spurious']} spurious of {result['flights']}",
            flush=True,
        )
    on_truth = runner(scene, "event", TRUTH_RTOL)
    truth_on = [on_truth(s) for s in states]
    pairs = [(s, t) for s, t in zip(states, truth_on, strict=True) if t is not None]
    for rtol in cfg.event_rtols:
        result = compare(
            sim,
            [s for s, _ in pairs],
            [t for _, t in pairs],
            runner(scene, "event", rtol),
            check_arc=False,
        )
        rows.append(
            {
                "set": label,
                "drag": "fowles",
                "method": "event",
                "setting": f"rtol {rtol:g}",
                "value": rtol,
                **result,
            }
        )
    return rows


def measure(cfg: Config) -> list[dict]:
    rows = []
    for name in cfg.scenes:
        scene, states = scene_states(name, cfg)
        rows += measure_set(name, scene, states, cfg)
    scene, states = vertex_states(cfg)
    rows += measure_set("wedge vertex drops", scene, states, cfg)
    return rows


def threshold_scan(cfg: Config, starts: dict[str, Scene]) -> list[dict]:
    """The low-velocity rule: for each contact.elastic_below, from rest and from the
    attractor state, impacts per simulated second, elastic share and how the run ended."""
    rows = []
    for name in cfg.scenes:
        for start, base in (("rest", load_scene(name)), ("in flight", starts[name])):
            for value in cfg.thresholds:
                scene = with_values(base, {"contact.elastic_below": value})
                result = simulate(scene, collisions=cfg.threshold_impacts)
                c = result.columns
                n = len(c["t"])
                span = float(c["t"][-1] - scene.initial.t) if n else 0.0
                rows.append(
                    {
                        "scene": name,
                        "start": start,
                        "elastic_below": value,
                        "impacts": n,
                        "sim_time": span,
                        "rate": n / span if span > 0 else math.inf,
                        "elastic": float(np.mean(c["regime"] == "elastic")) if n else math.nan,
                        "mean_q2": float(np.mean(c["q2"])) if n else math.nan,
                        "collapse": "collapse" in (result.stop_reason or ""),
                        "stop": result.stop_reason or "",
                        "wall_time": result.wall_time,
                    }
                )
    return rows
