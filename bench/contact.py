"""Contact phases against the hops they replace: CPU per simulated second, both models.

Every case is run under ``contact.model = "impacts"`` (the paper's impact-only model: a
ball lying on a wall is relaunched at ``contact.elastic_below`` and hops) and
``"phases"`` (rolling and sliding phases on a wall), from the same start state, for the
same simulated duration (``run.duration``). The two models are run alternately, so
their times share the machine's load; the CPU time (``time.process_time``) of the run
loop alone is kept (building the simulation, including deriving a curve on first use,
is excluded), and the median of the repeats is divided by the simulated time.

A run that ends early because the ball is at rest for good (under "phases": the ball
rests on the boundary, moving with it: ``Status.AT_REST``) has simulated its whole
duration: nothing
more happens, and the rest of the duration is counted as time in its contact mode. A run
that stops for another reason (an inelastic collapse, the impact cap) is measured over
the simulated time it reached, and is not compared.
"""

from __future__ import annotations

import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass

from billiard.generated import contact as _c

import billiard
from billiard.engine.simulation import Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import PAPER_SCENES, Scene, load_scene, scene_from_dict, with_values
from billiard.status import Status

MODELS = ("impacts", "phases")
#: a case where at least this share of the impact model's impacts relaunch a resting
#: ball is one where chatter dominates
CHATTER_SHARE = 0.5
#: the issue's target there: a contact phase at least this many times cheaper
TARGET = 10.0
#: the target on the paper's scenes: phases never dearer than the hops they replace
PAPER_TARGET = 1.0
#: the target on one contact phase, all in (us of CPU)
PHASE_TARGET_US = 15.0
#: the cases whose phases run makes at least this many contact phases give its cost
PHASE_COUNT = 100
#: the target on the first-use compile of every kernel (s of wall time)
COMPILE_TARGET = 20.0
#: a ratio within this of 1 is "about equal": the spread of single times on this machine
NOISE = 0.1
#: the flat floor of the drop and table cases (derived on first use, as in the tests)
FLOOR = "0.001"
GAMMA = 0.9  # the shaken table's peak acceleration over g: below 1, the ball stays on it
TABLE_FREQUENCY = 20.0  # Hz
DROP_HEIGHT = 0.01  # m, from the floor to the bottom of the ball
ROLL_AMPLITUDE = 2e-3  # m, contact abscissa of the rolling ball's start
SLIDE_SLOPE = 3.0  # tan(theta) > 7/2 mu_s = 2.135 with the paper's friction: it slides
SLIDE_START = 2.5  # m, contact abscissa of the sliding ball's start (7.5 m up)


@dataclass(frozen=True)
class Case:
    name: str
    kind: str  # "paper" or "closed form"
    what: str  # one line for the table
    build: Callable[[str], Scene]  # the scene under a contact model
    longest: float = math.inf  # s, the case's own limit on the simulated duration

    @property
    def target(self) -> float:
        """The least ratio impacts / phases the issue asks for: >= 1x on the paper's
        scenes, >= 10x on the closed-form cases (where chatter, rest or a contact
        phase dominates)."""
        return PAPER_TARGET if self.kind == "paper" else TARGET


def _with_model(scene: Scene, model: str, **changes) -> Scene:
    return with_values(scene, {"contact.model": model, **changes})


def _paper(name: str) -> Callable[[str], Scene]:
    return lambda model: _with_model(load_scene(name), model)


def _static(name: str, model: str, **changes) -> Scene:
    return _with_model(load_scene(name), model, **{"drive.amplitude": 0.0, **changes})


def _on_wall(s0: float, f: float, fp: float, f2: float, r: float) -> dict:
    """Initial keys of a ball at rest touching the curve at contact abscissa s0."""
    q1, q2, _, _ = _c.centre_state(s0, 0.0, f, fp, f2, 0.0, 0.0, 0.0, 0.0, r)
    return {"initial.q1": q1, "initial.q2": q2, "initial.v1": 0.0, "initial.v2": 0.0}


def _bowl_roll(model: str) -> Scene:
    base = load_scene("parabola-5.4hz")
    p = dict(base.boundary.parameters) or {"a": 26.0, "c": 0.0063}
    a, c, s = p.get("a", 26.0), p.get("c", 0.0063), ROLL_AMPLITUDE
    start = _on_wall(s, a * s * s + c, 2 * a * s, 2 * a, base.ball.radius)
    return _static("parabola-5.4hz", model, **start)


def _floor(model: str, drive: dict | None = None, initial: dict | None = None) -> Scene:
    paper = load_scene("parabola-5.4hz").contact
    return scene_from_dict(
        {
            "name": "floor",
            "boundary": {"curve": FLOOR, "escape_height": 10.0, "ceiling": 5.0},
            "drive": drive or {"amplitude": 0.0, "frequency": 1.0},
            "contact": {
                "model": model,
                "restitution": paper.restitution,
                "mu_static": paper.mu_static,
                "mu_kinetic": paper.mu_kinetic,
                "elastic_below": paper.elastic_below,
            },
            "air": {"drag": "none"},
            "initial": initial or {},
        }
    )


def _drop(model: str) -> Scene:
    radius = load_scene("parabola-5.4hz").ball.radius
    return _floor(model, initial={"q1": 0.0, "q2": 0.001 + radius + DROP_HEIGHT})


def _table(model: str) -> Scene:
    radius = load_scene("parabola-5.4hz").ball.radius
    w = 2 * math.pi * TABLE_FREQUENCY
    amplitude = GAMMA * 9.81 / w**2
    drive = {"amplitude": amplitude, "frequency": TABLE_FREQUENCY, "direction": "vertical"}
    # at rest on the table, moving with it: D = A sin(w t), D'(0) = A w
    return _floor(model, drive, {"q1": 0.0, "q2": 0.001 + radius, "v2": amplitude * w})


def _slide_geometry() -> tuple[float, float, float]:
    """(c of the wedge, ball radius, time (s) the sliding ball takes to reach the
    vertex: (1/2) g (sin - mu_k cos) t^2 = the length of wall it slides down)."""
    base = load_scene("wedge-6.6hz")
    c = dict(base.boundary.parameters).get("c", 0.0063)
    theta = math.atan(SLIDE_SLOPE)
    accel = 9.81 * (math.sin(theta) - base.contact.mu_kinetic * math.cos(theta))
    length = SLIDE_START / math.cos(theta)
    return c, base.ball.radius, math.sqrt(2 * length / accel)


def _slide(model: str) -> Scene:
    c, r, _ = _slide_geometry()
    b, s = SLIDE_SLOPE, SLIDE_START
    start = _on_wall(s, b * s + c, b, 0.0, r)
    return _static(
        "wedge-6.6hz",
        model,
        **{
            "boundary.parameters.b": b,
            "boundary.ceiling": 10.0,
            "boundary.escape_height": 10.0,
            **start,
        },
    )


def cases() -> list[Case]:
    paper = [
        Case(n, "paper", "built-in scene, from rest at the bottom", _paper(n)) for n in PAPER_SCENES
    ]
    return paper + [
        Case(
            "bowl at rest",
            "closed form",
            "ball at rest at the bottom of the static parabola",
            lambda m: _static("parabola-5.4hz", m),
        ),
        Case(
            "vertex at rest",
            "closed form",
            "ball at rest in the static wedge's vertex",
            lambda m: _static("wedge-6.6hz", m),
        ),
        Case(
            "bowl rolling",
            "closed form",
            f"static parabola, released at rest {1e3 * ROLL_AMPLITUDE:g} mm from the bottom:"
            " small rolling oscillations",
            _bowl_roll,
        ),
        Case(
            "floor drop",
            "closed form",
            f"dropped {1e3 * DROP_HEIGHT:g} mm onto a static flat floor: chattering, then rest",
            _drop,
        ),
        Case(
            "steep wall slide",
            "closed form",
            f"released on a straight wall of slope {SLIDE_SLOPE:g} (paper friction: it slides)"
            ", stopped before the vertex",
            _slide,
            longest=0.9 * _slide_geometry()[2],
        ),
        Case(
            "shaken table",
            "closed form",
            f"resting on a flat table shaken vertically at {TABLE_FREQUENCY:g} Hz,"
            f" Gamma = {GAMMA:g}",
            _table,
        ),
    ]


def at_rest(status: Status, reason: str | None) -> bool:
    """The run ended early because nothing more happens (the ball rests for good):
    ``Status.AT_REST``, or a ``TIME_LIMIT`` carrying a stop reason (how older results
    files recorded it)."""
    return status == Status.AT_REST or (status == Status.TIME_LIMIT and bool(reason))


def run_once(scene: Scene, duration: float, max_impacts: int) -> dict:
    """One run of ``duration`` simulated seconds (at most ``max_impacts`` impacts): CPU s
    of the run loop and what the run did."""
    scene = with_values(scene, {"run.duration": duration})
    sim = Simulation(scene)
    phases: list = []
    sim.on_contact = phases.append
    recorder = MemoryRecorder()
    start = time.process_time()
    reason = sim.run(max_impacts, recorder)
    cpu = time.process_time() - start
    return {"cpu": cpu, **summary(sim, duration, reason, len(recorder), len(phases))}


def summary(sim: Simulation, duration: float, reason: str | None, impacts: int, finished: int):
    """What a run of ``duration`` simulated seconds did, from the simulation after its
    ``run`` (which returned ``reason``), its impact count and its finished phases."""
    scene = sim.scene
    status = sim.status if sim.status is not None else Status.COMPLETE
    t0 = scene.initial.t if scene.initial.t is not None else 0.0
    end = sim.final_time if math.isfinite(sim.final_time) else sim.ball.t
    rest = at_rest(status, reason)
    reached = duration if (rest or status == Status.TIME_LIMIT) else end - t0
    in_contact = sim.mode != "flight"
    if sim.phases:
        times = sim.mode_times()
        if rest:  # the rest of the duration, at rest in the final contact mode
            times[sim.mode if in_contact else "flight"] += max(0.0, duration - (end - t0))
    else:
        times = {"flight": reached, "roll": 0.0, "slide": 0.0, "held": 0.0}
    resting = sim.counts.get("resting", 0)
    ended = "time" if status == Status.TIME_LIMIT and not reason else status.name.lower()
    if rest:
        ended = "at rest"
    elif status == Status.COMPLETE:
        ended = "impact cap"
    return {
        "duration": duration,
        "simulated": reached,
        "reached": end - t0,
        "impacts": impacts,
        "resting": resting,
        "resting_share": resting / impacts if impacts else 0.0,
        "phases": finished + (1 if sim.phases and in_contact else 0),
        "finished_phases": finished,
        "times": times,
        "status": status.name,
        "ended": ended,
        "stop": reason or "",
        "comparable": status in (Status.TIME_LIMIT, Status.AT_REST),
    }


def measure_case(
    case: Case, duration: float, repeats: int, max_impacts: int, models: tuple[str, ...] = MODELS
) -> dict:
    """Both models on one case, alternately, ``repeats`` times each: the first run's
    counts, the median CPU time, CPU per simulated second and the ratio impacts/phases."""
    duration = min(duration, case.longest)
    scenes = {m: case.build(m) for m in models}
    runs: dict[str, list[dict]] = {m: [] for m in models}
    for _ in range(repeats):
        for m in models:
            runs[m].append(run_once(scenes[m], duration, max_impacts))
    out: dict = {
        "case": case.name,
        "kind": case.kind,
        "what": case.what,
        "duration": duration,
        "target": case.target,
    }
    for m in models:
        first = dict(runs[m][0])
        cpus = [r["cpu"] for r in runs[m]]
        first.pop("cpu")
        first["cpus"] = cpus
        first["cpu"] = statistics.median(cpus)
        first["cpu_per_s"] = (
            first["cpu"] / first["simulated"] if first["simulated"] > 0 else math.inf
        )
        first["impacts_per_s"] = (
            first["impacts"] / first["simulated"] if first["simulated"] > 0 else math.inf
        )
        first["same_every_repeat"] = all(
            (r["impacts"], r["phases"]) == (first["impacts"], first["phases"]) for r in runs[m]
        )
        out[m] = first
    if set(MODELS) <= set(models):
        a, b = out["impacts"], out["phases"]
        both = a["comparable"] and b["comparable"]
        out["ratio"] = (
            (a["cpu_per_s"] / b["cpu_per_s"] if b["cpu_per_s"] > 0 else math.inf) if both else None
        )
        out["chatter"] = a["resting_share"] >= CHATTER_SHARE
        out["phase_us"] = phase_cost(a, b)
    return out


def phase_cost(impacts: dict, phases: dict) -> float | None:
    """CPU (us) of one contact phase all in, from the phases run: its CPU less what its
    impacts cost at the impact model's CPU per impact in the same case, over its contact
    phases; None with fewer than :data:`PHASE_COUNT` phases (a few phases that each last
    seconds do not measure the cost of one)."""
    if phases["phases"] < PHASE_COUNT or not impacts["impacts"]:
        return None
    per_impact = impacts["cpu"] / impacts["impacts"]
    return 1e6 * (phases["cpu"] - per_impact * phases["impacts"]) / phases["phases"]


def measure(cfg) -> dict:
    """Every case under both models, with the durations and repeats of ``cfg``."""
    rows = []
    for case in cases():
        duration = cfg.contact_paper_duration if case.kind == "paper" else cfg.contact_duration
        began = time.perf_counter()
        row = measure_case(case, duration, cfg.contact_repeats, cfg.contact_max_impacts)
        rows.append(row)
        ratio = row.get("ratio")
        print(
            f"  contact {case.name}: {row['duration']:g} s simulated, impacts "
            f"{1e3 * row['impacts']['cpu_per_s']:.3g} ms/s, phases "
            f"{1e3 * row['phases']['cpu_per_s']:.3g} ms/s, ratio "
            f"{'-' if ratio is None else f'{ratio:.3g}'} ({time.perf_counter() - began:.0f} s)",
            flush=True,
        )
    began = time.perf_counter()
    sampled = measure_sampled(max(3, cfg.contact_repeats))
    print(
        f"  contact sampled run: {sampled['samples']:,} samples, the engine "
        f"{sampled['ratio']:.2f}x the run without them ({sampled['per_sample_us']:.2f} us a "
        f"sample; handing each out {sampled['handout_us']:.2f} us) "
        f"({time.perf_counter() - began:.0f} s)",
        flush=True,
    )
    began = time.perf_counter()
    compiled = measure_compile()
    print(
        f"  contact first-use compile: {compiled['compile_s']:.1f} s, "
        f"{compiled['waits']} wait(s) ({time.perf_counter() - began:.0f} s)",
        flush=True,
    )
    return {
        "rows": rows,
        "compile": compiled,
        "sampled": sampled,
        "repeats": cfg.contact_repeats,
        "paper_duration": cfg.contact_paper_duration,
        "duration": cfg.contact_duration,
        "max_impacts": cfg.contact_max_impacts,
        "chatter_share": CHATTER_SHARE,
        "target": TARGET,
        "date": time.strftime("%Y-%m-%d %H:%M"),
    }


def paired_ratios(row: dict) -> list[float]:
    """The ratio impacts / phases of each repeat's pair of runs (run one after the other):
    its spread shows how much the machine's load moved the ratio of the medians."""
    a, b = row["impacts"], row["phases"]
    if row.get("ratio") is None:
        return []
    return [
        (x / a["simulated"]) / (y / b["simulated"]) if y > 0 else math.inf
        for x, y in zip(a["cpus"], b["cpus"], strict=True)
    ]


def verdict(rows: list[dict]) -> dict:
    """The target where chatter dominates: the ratios there, and the cases short of it."""
    chatter = [r for r in rows if r.get("chatter")]
    compared = [r for r in chatter if r.get("ratio") is not None]
    short = [r for r in compared if r["ratio"] < TARGET]
    slower = [r for r in rows if r.get("ratio") is not None and r["ratio"] < 1.0 - NOISE]
    equal = [r for r in rows if r.get("ratio") is not None and abs(r["ratio"] - 1.0) <= NOISE]
    return {
        "chatter": [r["case"] for r in chatter],
        "compared": [r["case"] for r in compared],
        "not_compared": [r["case"] for r in chatter if r.get("ratio") is None],
        "short": [r["case"] for r in short],
        "slower": [r["case"] for r in slower],
        "equal": [r["case"] for r in equal],
        "met": bool(compared) and not short,
    }


#: a sampled run: the scene (the paper's wedge under contact phases: flights, landings,
#: phases, lift-offs), its impacts, the sample interval (s) and the target: the run
#: costs at most SAMPLED_TARGET times the run without samples, the samples' hand-out
#: (a Python call per sample, what writing them starts with) not counted
SAMPLED_SCENE = ("wedge-6.6hz", 1500, 1e-3)
SAMPLED_TARGET = 1.5


def measure_sampled(repeats: int) -> dict:
    """CPU s of a run without samples, of the same run sampled with its samples kept in
    the engine's buffer (not handed out), and sampled with each sample handed to a
    receiver that keeps nothing (a Python call per sample, where writing them starts),
    alternately, medians of ``repeats``. The ratio compares the first two: what making
    the samples costs the engine."""
    name, impacts, dt = SAMPLED_SCENE
    scene = with_values(load_scene(name), {"contact.model": "phases"})
    plain, engine, handed, counts = [], [], [], []

    def keep_nothing(*row) -> None:
        counts.append(1)

    def timed(sampled: bool, hand_out: bool) -> float:
        sim = Simulation(scene)
        if sampled:
            sim.sample_dt, sim.on_sample = dt, keep_nothing
        if not hand_out:
            sim.driver._hand_samples = lambda first, stop: counts.append(stop - first)
        start = time.process_time()
        sim.run(impacts, MemoryRecorder())
        return time.process_time() - start

    for _ in range(repeats + 1):  # the first round loads the kernels
        plain.append(timed(False, True))
        counts.clear()
        engine.append(timed(True, False))
        samples = sum(counts)
        handed.append(timed(True, True))
    a, b, c = (statistics.median(x[1:]) for x in (plain, engine, handed))
    return {
        "scene": name,
        "impacts": impacts,
        "dt": dt,
        "samples": samples,
        "plain_cpu": a,
        "engine_cpu": b,
        "handed_cpu": c,
        "ratio": b / a,
        "per_sample_us": 1e6 * (b - a) / max(1, samples),
        "handout_us": 1e6 * (c - b) / max(1, samples),
        "target": SAMPLED_TARGET,
    }


#: the runs of the first-use compile, in a fresh cache, one process each: the first
#: impacts-model run of a paper scene, then one with air drag, then one under phases,
#: then the first again (warm: what the first costs without compiling)
COMPILE_RUNS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("wedge-6.6hz", ()),
    ("parabola-5.4hz", ()),
    ("wedge-6.6hz", ("--set", "contact.model=phases")),
    ("wedge-6.6hz", ()),
)
#: what a compile notice starts with (billiard.jit, billiard.engine.compile_all)
_NOTICE = "billiard: compiling"


def measure_compile() -> dict:
    """The first-use compile: :data:`COMPILE_RUNS` as ``billiard run SCENE --collisions
    100`` in fresh processes, with an empty numba cache (``NUMBA_CACHE_DIR`` in a new
    folder); each run's wall time (s) and compile notices. The compile is the first
    run's wall time less the last's (the same run, warm); the waits are the runs that
    printed a notice."""
    root = str(os.path.dirname(os.path.dirname(os.path.abspath(billiard.__file__))))
    runs = []
    with tempfile.TemporaryDirectory(prefix="billiard-bench-compile-") as folder:
        env = {**os.environ, "NUMBA_CACHE_DIR": os.path.join(folder, "cache")}
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        env.pop("NUMBA_DISABLE_JIT", None)
        for i, (scene, extra) in enumerate(COMPILE_RUNS):
            command = [sys.executable, "-m", "billiard.cli", "run", scene, *extra]
            command += ["--collisions", "100", "--no-plot", "--out", os.path.join(folder, str(i))]
            began = time.perf_counter()
            done = subprocess.run(command, env=env, cwd=folder, capture_output=True, text=True)
            wall = time.perf_counter() - began
            notices = [x for x in done.stderr.splitlines() if x.startswith(_NOTICE)]
            runs.append(
                {
                    "run": " ".join([scene, *extra]),
                    "wall": wall,
                    "notices": notices,
                    "ok": done.returncode == 0,
                }
            )
    return {
        "runs": runs,
        "compile_s": runs[0]["wall"] - runs[-1]["wall"],
        "waits": sum(bool(r["notices"]) for r in runs),
        "target": COMPILE_TARGET,
    }


def case_target(row: dict) -> float:
    """The ratio target of a measured case (results saved before targets were per case:
    from its kind)."""
    return row.get("target") or (PAPER_TARGET if row["kind"] == "paper" else TARGET)


def ratio_targets(rows: list[dict], kind: str) -> dict:
    """The ratio target on the cases of ``kind`` ("paper", "closed form"): the target,
    the cases compared, those short of it and those not compared."""
    mine = [r for r in rows if r["kind"] == kind]
    compared = [r for r in mine if r.get("ratio") is not None]
    target = case_target(mine[0]) if mine else (PAPER_TARGET if kind == "paper" else TARGET)
    return {
        "target": target,
        "compared": [r["case"] for r in compared],
        "short": [r["case"] for r in compared if r["ratio"] < case_target(r)],
        "not_compared": [r["case"] for r in mine if r.get("ratio") is None],
        "met": bool(compared)
        and all(r["ratio"] >= case_target(r) for r in compared)
        and len(compared) == len(mine),
    }


def phase_costs(rows: list[dict]) -> list[tuple[str, float]]:
    """(case, us of CPU per contact phase all in) where the phases run made enough
    phases to tell (:func:`phase_cost`)."""
    out = []
    for r in rows:
        us = r.get("phase_us")
        if us is None and "impacts" in r and "phases" in r:
            us = phase_cost(r["impacts"], r["phases"])
        if us is not None:
            out.append((r["case"], us))
    return out
