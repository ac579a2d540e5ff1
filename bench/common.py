"""Shared pieces of the benchmarks: settings per mode, start states, timed runs.

Every measurement starts from a scene whose ``initial`` section holds a state on the
scene's attractor, in mid-flight, with the drive phase shifted so that the clock starts
at t = 0 (see :func:`start_scene`). Times are CPU seconds (``time.process_time``) of the
run alone, not of building the simulation; a fast run is repeated and the median kept.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from billiard.generated import ball as _ball

from billiard.errors import SimulationError
from billiard.run.simulate import BallState, Simulation, simulate
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import PAPER_SCENES, Scene, load_scene, with_values

SCENES = PAPER_SCENES
#: A run shorter than this (CPU s) is repeated and the median of the repeats kept.
SHORT_RUN = 0.5
#: Impact time of the event found by two methods differs by more than this (s): the two
#: flights ended at different impacts.
SAME_IMPACT = 1e-6


@dataclass(frozen=True)
class Config:
    """Sizes of every measurement; ``full()`` for the documented run, ``quick()`` for a
    smoke run of a couple of minutes."""

    quick: bool
    scenes: tuple[str, ...]
    transient: int  # impacts from rest before the start state
    checkpoints: tuple[int, ...]  # impacts at which errors are measured
    event_rtols: tuple[float, ...]
    rk4_steps: tuple[float, ...]
    peer_rtols: tuple[float, ...]
    repeats: int  # runs of a short measurement
    flights: int  # one-flight tests per scene (failure analysis)
    vertex_drops: int  # drops into the wedge's vertex (failure analysis)
    thresholds: tuple[float, ...]  # contact.elastic_below values
    threshold_impacts: int
    ladder_impacts: int
    throughput_impacts: int
    throughput_repeats: int
    startup_repeats: int
    memory_sizes: tuple[int, ...]
    million_impacts: int  # the long wedge run of the throughput section
    profile_impacts: int
    contact_paper_duration: float  # simulated s per run of a paper scene (contact section)
    contact_duration: float  # simulated s per run of a closed-form case (contact section)
    contact_repeats: int  # runs of each case and contact model (median kept)
    contact_max_impacts: int  # impact cap of one run (contact section)

    @classmethod
    def full(cls) -> Config:
        return cls(
            quick=False,
            scenes=SCENES,
            transient=2000,
            checkpoints=(50, 500),
            event_rtols=(1e-6, 1e-8, 1e-10, 1e-12),
            rk4_steps=(3e-3, 1e-3, 3e-4, 1e-4, 3e-5),
            peer_rtols=(1e-5, 1e-7, 1e-9, 1e-11),
            repeats=3,
            flights=1000,
            vertex_drops=84,
            thresholds=(0.0, 1e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1),
            threshold_impacts=5000,
            ladder_impacts=25000,
            throughput_impacts=25000,
            throughput_repeats=3,
            startup_repeats=5,
            memory_sizes=(10_000, 100_000),
            million_impacts=1_000_000,
            profile_impacts=25000,
            contact_paper_duration=600.0,
            contact_duration=30.0,
            contact_repeats=5,
            contact_max_impacts=200_000,
        )

    @classmethod
    def quick_mode(cls) -> Config:
        return cls(
            quick=True,
            scenes=SCENES,
            transient=500,
            checkpoints=(20, 50),
            event_rtols=(1e-6, 1e-10),
            rk4_steps=(1e-3, 3e-4),
            peer_rtols=(1e-6, 1e-10),
            repeats=1,
            flights=60,
            vertex_drops=12,
            thresholds=(0.0, 1e-3, 1e-2, 1e-1),
            threshold_impacts=1200,
            ladder_impacts=1500,
            throughput_impacts=4000,
            throughput_repeats=3,
            startup_repeats=3,
            memory_sizes=(5_000, 20_000),
            million_impacts=50_000,
            profile_impacts=3000,
            contact_paper_duration=60.0,
            contact_duration=5.0,
            contact_repeats=3,
            contact_max_impacts=20_000,
        )


def full_model(name: str) -> Scene:
    """The built-in scene with every physical term on (Fowles drag included, even where
    the shipped scene switches it off because it changes nothing there)."""
    return with_values(load_scene(name), {"air.drag": "fowles"})


def start_scene(name: str, transient: int) -> Scene:
    """The built-in scene, full model, started on its attractor: the ball in mid-flight a
    third of the way through the first flight of at least 0.05 s after ``transient``
    impacts from rest (drag-free arc, so the start is the same for every model), with
    the drive phase shifted so that the run starts at t = 0."""
    scene = full_model(name)
    c = simulate(scene, collisions=transient + 2000).columns
    i = next(
        (k for k in range(transient, len(c["t"]) - 1) if c["tof"][k + 1] > 0.05),
        transient,
    )
    tau = min(c["tof"][i + 1], 0.15) / 3.0
    q1, q2, u1, u2 = _ball.flight_exact(
        tau, c["q1"][i], c["q2"][i], c["v1"][i], c["v2"][i], scene.run.gravity
    )
    phase = (scene.drive.omega * (c["t"][i] + tau) + scene.drive.phase) % (2.0 * math.pi)
    return with_values(
        scene,
        {
            "drive.phase": phase,
            "initial.t": 0.0,
            "initial.q1": q1,
            "initial.q2": q2,
            "initial.v1": u1,
            "initial.v2": u2,
            "initial.omega": c["omega"][i],
        },
    )


def engine_run(scene: Scene, impacts: int, method: str = "event") -> tuple[dict, float, str]:
    """Run the engine from the scene's initial state: (columns, CPU s of the run, stop
    reason or "")."""
    sim = Simulation(scene, method)
    recorder = MemoryRecorder()
    start = time.process_time()
    stop = sim.run(impacts, recorder)
    cpu = time.process_time() - start
    return recorder.columns(), cpu, stop or ""


def timed(run: Callable[[], tuple[Any, float, str]], repeats: int) -> tuple[Any, float, str]:
    """Call ``run`` (returning (result, cpu, stop)) once, and again up to ``repeats``
    times in all while a run takes less than SHORT_RUN; the CPU time returned is the
    median, the result and stop reason those of the first call."""
    result, cpu, stop = run()
    times = [cpu]
    while len(times) < repeats and cpu < SHORT_RUN:
        times.append(run()[1])
    return result, statistics.median(times), stop


def post_impact_state(c: dict, i: int, drive: Any, theta0: float | None = None) -> BallState:
    """The state just after impact row i of a run, as a flight start at t = 0; the run
    started at drive angle ``theta0`` (default: the scene's phase at t = 0)."""
    t = float(c["t"][i])
    theta = drive.angle(t) if theta0 is None else (theta0 + drive.omega * t) % (2.0 * math.pi)
    return BallState(
        0.0,
        theta,
        float(c["q1"][i]),
        float(c["q2"][i]),
        float(c["v1"][i]),
        float(c["v2"][i]),
        float(c["omega"][i]),
    )


def one_flight(sim: Simulation, state: BallState) -> dict | None:
    """The engine's next impact from ``state``: the record of that impact (scalars), or
    None when the run stopped instead."""
    sim.reset(state)
    try:
        record = sim.step()
    except SimulationError:
        return None
    return None if record is None else record._asdict()


def first_difference(a: np.ndarray, b: np.ndarray, k: int) -> float:
    """|a[k-1] - b[k-1]|, inf when either run has fewer than k impacts."""
    if len(a) < k or len(b) < k:
        return math.inf
    return float(abs(a[k - 1] - b[k - 1]))


def position_difference(a: dict, b: dict, k: int) -> float:
    """Distance (m) between the k-th impact points of two runs, inf if one is short."""
    if len(a["q1"]) < k or len(b["q1"]) < k:
        return math.inf
    return float(math.hypot(a["q1"][k - 1] - b["q1"][k - 1], a["q2"][k - 1] - b["q2"][k - 1]))


def section_arguments(prog: str, description: str | None, quick: str, argv: list[str] | None):
    """The command line of a bench that measures one section by itself (``--quick``
    with its help ``quick``, ``--docs``, ``--render``), and the documentation folder
    it writes to: (args, docs)."""
    parser = argparse.ArgumentParser(prog=prog, description=description)
    parser.add_argument("--quick", action="store_true", help=quick)
    parser.add_argument(
        "--docs", help="documentation folder (default docs, or runs/bench-quick with --quick)"
    )
    parser.add_argument(
        "--render", action="store_true", help="measure nothing: rewrite the section from bench.json"
    )
    args = parser.parse_args(argv)
    return args, Path(args.docs or ("runs/bench-quick" if args.quick else "docs"))
