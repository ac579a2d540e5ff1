"""Soak test: many impacts across the paper's scenes and random valid scenes, every impact
audited.

    python -m bench.soak --impacts 1000000     # the full soak (a few minutes, 2 cores)
    python -m bench.soak --quick               # 20,000 impacts (seconds)

Run from the root of a source checkout (it is a test harness, not part of the installed
package).

Every run is streamed to a temporary directory exactly as ``billiard run`` streams it
(CSV, scene file, checkpoints), with the impact law wrapped by :class:`ImpactAudit`;
afterwards every CSV row is checked against the geometry with :func:`audit_rows`.
Counted, and required to be zero:

penetrations
    impacts at which the ball overlaps the wall or the lid by more than ``GAP_LIMIT``
    (1e-9 m): the clearance from :meth:`billiard.boundary.Boundary.clearance`, the
    Euclidean distance from the ball's centre to the curve (global nearest point) minus r.
detached impacts
    impacts recorded with the ball more than ``GAP_LIMIT`` away from every surface.
non-finite values
    in any CSV row.
energy created
    impacts after which the kinetic energy relative to the boundary (translation
    relative to the boundary's velocity at the impact, plus spin) exceeds the energy
    before by more than rounding (1e-12 of the energies involved). The low-velocity
    rule's lift of a ball lying on the surface adds energy by design: it is allowed
    exactly the designed amount, m (v_e^2 - w_n^2) / 2 (v_e = ``elastic_below``, w_n the
    normal velocity it replaces), and counted separately.
resume mismatches
    for every few random scenes the run is also interrupted (a real SIGTERM the process
    sends itself after a random impact, ``BILLIARD_STOP_AFTER``), resumed from its
    checkpoint, and compared byte for byte with the audited uninterrupted run.

Early stops (escape from an open container, inelastic collapse, numerical faults) end
a run with a documented reason; they are tallied by kind, and random scenes are added
until the requested number of impacts has been simulated. The scene generator
:func:`scene_from_draw` is shared with the property-based tests.
"""

from __future__ import annotations

import argparse
import filecmp
import json
import math
import multiprocessing
import os
import random
import signal
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from billiard.boundary import Boundary, Drive
from billiard.curves import load_curve
from billiard.errors import GeometryError
from billiard.impact import ImpactResult
from billiard.interrupt import signal_after
from billiard.record import read_collisions
from billiard.scene import PAPER_SCENES, Scene, fowles_coefficients, load_scene, with_values
from billiard.simulate import (
    RunInterrupted,
    Simulation,
    resume,
    run_streamed,
    simulate,
)
from billiard.status import Status

__all__ = [
    "CURVES",
    "GAP_LIMIT",
    "PAPER_SCENES",
    "ImpactAudit",
    "audit_rows",
    "random_draw",
    "scene_from_draw",
    "stop_kind",
]

#: Curves of the random scenes: the paper's three and two expressions (a flat-bottomed
#: quartic bowl and a sharply rounded V, whose radius of curvature at the bottom, 5 mm,
#: is close to the ball's).
CURVES = ("parabola", "wedge", "hyperbola", "30*x**4 + 0.0063", "sqrt(0.0001 + 2*x**2) + 0.005")
#: |clearance| (m) beyond which an impact counts as a penetration or as detached.
GAP_LIMIT = 1e-9
#: Relative rounding allowance of the energy audit.
ENERGY_ROUNDING = 1e-12
_LARGEST_RADIUS = 4e-3  # m; random balls are at most this large
_STOP_KINDS = {
    Status.COMPLETE: "complete",
    Status.TIME_LIMIT: "complete",
    Status.ESCAPED: "escape",
    Status.COLLAPSE: "collapse",
    Status.NON_FINITE: "non-finite",
    Status.NUMERICAL_FAULT: "numerical",
    Status.SOLVER_FAILED: "root",
}


# ----------------------------------------------------------------------------------
# random valid scenes


def random_draw(rng: random.Random) -> dict[str, Any]:
    """One random set of the primitive choices :func:`scene_from_draw` turns into a scene
    (the property-based tests draw the same keys with hypothesis)."""
    uniform = rng.uniform
    mu_s = uniform(0.0, 1.2)
    return {
        "curve": rng.choice(CURVES),
        "lid": rng.random() < 0.7,
        "top": uniform(0.0, 1.0),
        "amplitude": 0.0 if rng.random() < 0.15 else uniform(0.0, 0.03),
        "frequency": uniform(1.0, 12.0),
        "direction": rng.choice(("horizontal", "vertical")),
        "phase": uniform(0.0, 2.0 * math.pi),
        "restitution": uniform(0.0, 1.0),
        "mu_static": mu_s,
        "mu_kinetic_fraction": uniform(0.0, 1.0),
        "elastic_below": rng.choice((0.0, 1e-3, 1e-2, 3e-2)),
        "radius_fraction": uniform(0.05, 0.97),
        "log_mass": uniform(-5.0, -2.0),
        "inertia_factor": uniform(0.1, 1.0),
        "drag": rng.choice(("fowles", "none")),
        "magnus": 0.0 if rng.random() < 0.7 else uniform(0.0, 1e-8),
        "start": rng.choice(("rest", "inside", "inside")),
        "x_fraction": uniform(0.0, 1.0),
        "y_fraction": 0.0 if rng.random() < 0.1 else uniform(0.0, 0.95),
        "v1": uniform(-2.0, 2.0),
        "v2": uniform(-2.0, 2.0),
        "omega": uniform(-300.0, 300.0),
        "t0": uniform(0.0, 50.0),
    }


_RADIUS_LIMITS: dict[tuple[str, float], float] = {}


def radius_limit(curve: str, top: float) -> float:
    """Smallest radius of curvature (m) of ``curve`` below height ``top``: the largest
    ball that still touches it at single points (inf for straight walls)."""
    key = (curve, top)
    if key not in _RADIUS_LIMITS:
        walls = load_curve(curve).walls
        probe = Boundary(walls, 1e-6, Drive(0.0, 0.0, 0.0, True), ceiling=top)
        xl, xr = probe.x_range
        rho = math.inf
        for wall in walls:
            lo, hi = max(wall.lo, xl), min(wall.hi, xr)
            for x in np.linspace(lo, hi, 4001) if hi > lo else ():
                f2 = float(wall.d2f(float(x), wall.p))
                if f2 > 0.0:
                    fp = float(wall.df(float(x), wall.p))
                    rho = min(rho, (1.0 + fp * fp) ** 1.5 / f2)
        _RADIUS_LIMITS[key] = rho
    return _RADIUS_LIMITS[key]


def scene_from_draw(draw: Mapping[str, Any]) -> Scene:
    """A valid scene from the primitive choices of :func:`random_draw`.

    Every parameter is within its documented range: mu_k <= mu_s, a ball radius below
    the curve's smallest radius of curvature, a lid (or escape level) above the bottom,
    and an initial position inside the container (on or above the wall, below the lid),
    or at rest on the bottom.
    """
    curve = draw["curve"]
    bottom = load_curve(curve).f(0.0)
    top = bottom + 0.04 + 0.2 * draw["top"]
    limit = min(radius_limit(curve, top), _LARGEST_RADIUS)
    radius = draw["radius_fraction"] * limit
    c_lin, c_quad = fowles_coefficients(radius)
    amplitude = draw["amplitude"]
    values: dict[str, Any] = {
        "boundary.curve": curve,
        "boundary.ceiling": top if draw["lid"] else None,
        "boundary.escape_height": top,
        "drive.amplitude": amplitude,
        "drive.frequency": draw["frequency"] if amplitude > 0.0 else 0.0,
        "drive.direction": draw["direction"],
        "drive.phase": draw["phase"],
        "contact.restitution": draw["restitution"],
        "contact.mu_static": draw["mu_static"],
        "contact.mu_kinetic": draw["mu_static"] * draw["mu_kinetic_fraction"],
        "contact.elastic_below": draw["elastic_below"],
        "ball.radius": radius,
        "ball.mass": 10.0 ** draw["log_mass"],
        "ball.inertia_factor": draw["inertia_factor"],
        "air.drag": draw["drag"],
        "air.c_lin": c_lin,
        "air.c_quad": c_quad,
        "air.magnus": draw["magnus"],
        "initial.q1": None,
        "initial.q2": None,
        "initial.v1": 0.0,
        "initial.v2": 0.0,
        "initial.omega": 0.0,
        "initial.t": draw["t0"],
    }
    scene = with_values(load_scene("parabola-5.4hz"), values)
    scene = with_values(scene, {"name": "random", "description": "random valid scene"})
    if draw["start"] != "inside":
        return scene
    walls = load_curve(curve).walls
    boundary = Boundary.from_scene(scene, walls)
    xl, xr = boundary.x_range
    px = xl + draw["x_fraction"] * (xr - xl)
    low = boundary.offset_height(px)
    high = (top - radius) if draw["lid"] else top
    if not low < high:
        return scene  # the rim: no room inside at this abscissa
    py = low + draw["y_fraction"] * (high - low)
    theta = boundary.drive.angle(draw["t0"])
    q1, q2 = boundary.drive.to_lab_frame(theta, px, py)
    return with_values(
        scene,
        {
            "initial.q1": q1,
            "initial.q2": q2,
            "initial.v1": draw["v1"],
            "initial.v2": draw["v2"],
            "initial.omega": draw["omega"],
        },
    )


# ----------------------------------------------------------------------------------
# audits


@dataclass
class ImpactAudit:
    """An impact law wrapped to check every impact for energy created in the boundary's
    frame (see the module docstring); use as ``sim.impact = ImpactAudit(sim.impact)``.

    Attributes:
        impacts: impacts seen.
        created: impacts that created energy beyond rounding (lifts beyond their
            designed allowance included).
        lifts: lifts of a lying ball by the low-velocity rule.
        separating: impacts applied although the contact point was not approaching the
            boundary (relative normal velocity w_n >= 0 before; lifts excepted): Newton's
            law then turns a separating velocity into an approaching one with a pulling
            (negative) normal impulse, the known source of created energy.
        worst: largest (energy after - before - allowance) / scale seen, scale being
            the energies involved; rounding keeps it near 1e-16.
        examples: the first few violations, for a report.
    """

    law: Any
    impacts: int = 0
    created: int = 0
    lifts: int = 0
    separating: int = 0
    worst: float = -math.inf
    examples: list[str] = field(default_factory=list)
    #: when a list, gets (energy before, energy after, allowance) of every impact
    history: list[tuple[float, float, float]] | None = None

    @property
    def regimes(self) -> tuple[str, ...]:
        return self.law.regimes

    def apply(self, state: Any, contact: Any) -> ImpactResult:
        res = self.law.apply(state, contact)
        law = self.law
        m, inertia = law.m, law.k * law.m * law.r * law.r
        vb1, vb2 = contact.vb1, contact.vb2
        w1, w2 = state.u1 - vb1, state.u2 - vb2
        x1, x2 = res.u1 - vb1, res.u2 - vb2
        before = 0.5 * m * (w1 * w1 + w2 * w2) + 0.5 * inertia * state.u3 * state.u3
        after = 0.5 * m * (x1 * x1 + x2 * x2) + 0.5 * inertia * res.u3 * res.u3
        allowance = 0.0
        if res.resting:
            self.lifts += 1
            allowance = 0.5 * m * max(0.0, law.elastic_below**2 - res.wn * res.wn)
        elif res.wn >= 0.0:
            self.separating += 1
        # rounding scale: every energy that went into the comparison
        scale = (
            before
            + allowance
            + 0.5 * m * (state.u1**2 + state.u2**2 + vb1 * vb1 + vb2 * vb2)
            + 0.5 * inertia * res.u3 * res.u3
        )
        excess = (after - before - allowance) / scale if scale > 0.0 else 0.0
        self.impacts += 1
        self.worst = max(self.worst, excess)
        if self.history is not None:
            self.history.append((before, after, allowance))
        if excess > ENERGY_ROUNDING:
            self.created += 1
            if len(self.examples) < 5:
                self.examples.append(
                    f"impact {self.impacts} (t = {state.t!r} s, {res.regime}"
                    f"{', lift' if res.resting else ''}, w_n = {res.wn:.3g} m/s, "
                    f"Rn = {res.Rn:.3g} N s): relative-frame energy {before!r} -> {after!r} J "
                    f"(+{(after - before) / before:.2g}), allowance {allowance!r} J"
                )
        return res


def audit_rows(boundary: Boundary, drive: Any, columns: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Check a run's rows against the geometry: penetrations and detached impacts
    (clearance beyond ``GAP_LIMIT``), non-finite values; with the extreme clearances."""
    floats = [name for name, values in columns.items() if values.dtype.kind == "f"]
    finite = np.ones(len(columns["n"]), dtype=bool)
    for name in floats:
        finite &= np.isfinite(columns[name])
    penetrations = detached = 0
    lowest, highest = math.inf, -math.inf
    examples: list[str] = []
    for i, (t, q1, q2) in enumerate(
        zip(columns["t"].tolist(), columns["q1"].tolist(), columns["q2"].tolist(), strict=True)
    ):
        if not finite[i]:
            continue
        px, py, _, _ = drive.to_boundary_frame(drive.angle(t), q1, q2, 0.0, 0.0)
        gap = boundary.clearance(px, py)
        lowest, highest = min(lowest, gap), max(highest, gap)
        if gap < -GAP_LIMIT or gap > GAP_LIMIT:
            if gap < 0.0:
                penetrations += 1
            else:
                detached += 1
            if len(examples) < 5:
                examples.append(f"impact {i + 1} (t = {t!r} s): clearance {gap:.3g} m")
    return {
        "rows": len(finite),
        "penetrations": penetrations,
        "detached": detached,
        "non_finite_rows": int((~finite).sum()),
        "lowest_clearance": lowest,
        "highest_clearance": highest,
        "examples": examples,
    }


def stop_kind(status: Status) -> str:
    """Category of a run's status: complete, escape, collapse, non-finite, numerical, or
    root (a root or step-size solve that failed)."""
    return _STOP_KINDS[Status(status)]


# ----------------------------------------------------------------------------------
# jobs


@dataclass(frozen=True)
class Job:
    """One audited run: a paper scene by name, or a random scene by its draw."""

    label: str
    impacts: int
    method: str = "event"
    scene_name: str | None = None
    draw: dict[str, Any] | None = None
    resume_at: int | None = None


def run_job(job: Job) -> dict[str, Any]:
    """Run one job (in a worker process) and return its report."""
    started = time.process_time()
    report: dict[str, Any] = {"label": job.label, "method": job.method, "impacts": 0}
    try:
        scene = load_scene(job.scene_name) if job.scene_name else scene_from_draw(job.draw or {})
        sim = Simulation(scene, job.method)
    except GeometryError as exc:
        report.update(stop="geometry", reason=str(exc), cpu=time.process_time() - started)
        return report
    audit = ImpactAudit(sim.impact)
    sim.impact = audit
    with tempfile.TemporaryDirectory(prefix="billiard-soak-") as tmp:
        result = run_streamed(sim, Path(tmp) / "a", collisions=job.impacts)
        columns = read_collisions(Path(tmp) / "a" / "collisions.csv")
        report.update(audit_rows(sim.boundary, sim.drive, columns))
        report.update(
            impacts=len(result),
            stop=stop_kind(result.status),
            reason=result.stop_reason,
            energy_created=audit.created,
            lifts=audit.lifts,
            separating=audit.separating,
            elastic_below=scene.contact.elastic_below,
            worst_energy_excess=audit.worst,
            energy_examples=audit.examples,
        )
        if job.resume_at is not None:
            report["resume_checked"] = 1
            try:
                simulate(
                    scene,
                    collisions=job.impacts,
                    method=job.method,
                    out_dir=Path(tmp) / "b",
                    on_record=signal_after(job.resume_at, signal.SIGTERM),
                )
                interrupted = False
            except RunInterrupted:
                interrupted = True
            if interrupted:
                resume(Path(tmp) / "b")
            same = filecmp.cmp(
                Path(tmp) / "a" / "collisions.csv",
                Path(tmp) / "b" / "collisions.csv",
                shallow=False,
            )
            report["resume_mismatches"] = 0 if same else 1
            report["resume_interrupted"] = int(interrupted)
    report["cpu"] = time.process_time() - started
    return report


def plan(total: int, seed: int) -> tuple[list[Job], random.Random]:
    """The paper-scene jobs for ``total`` impacts (60 %, 15 % per scene, each one long
    run from rest) and the random generator of the rest."""
    rng = random.Random(seed)
    paper = int(0.15 * total)
    jobs = [Job(name, paper, scene_name=name) for name in PAPER_SCENES]
    return jobs, rng


def random_jobs(rng: random.Random, impacts: int, quick: bool, start: int) -> list[Job]:
    """Random-scene jobs worth about ``impacts`` impacts; every fifth is also
    interrupted and resumed; one scene in sixteen uses rk4 (with a quarter of the
    impacts)."""
    size = 1000 if quick else 4000
    jobs: list[Job] = []
    count = max(1, math.ceil(impacts / size))
    for i in range(start, start + count):
        draw = random_draw(rng)
        method = "rk4" if rng.random() < 1 / 16 else "event"
        n = size // 4 if method == "rk4" else size  # rk4 is some 30 times slower
        resume_at = rng.randrange(1, n) if i % 5 == 0 else None
        jobs.append(Job(f"random-{i}", n, method, draw=draw, resume_at=resume_at))
    return jobs


def soak(
    total: int, *, seed: int = 2024, workers: int = 2, quick: bool = False, echo: Any = print
) -> dict[str, Any]:
    """Run the soak and return the aggregated report (see the module docstring)."""
    started = time.perf_counter()
    for curve in CURVES:  # derive the expressions once, before the workers need them
        load_curve(curve)
    jobs, rng = plan(total, seed)
    paper_impacts = sum(job.impacts for job in jobs)
    reports: list[dict[str, Any]] = []
    context = multiprocessing.get_context("fork" if sys.platform != "win32" else "spawn")
    with context.Pool(workers, maxtasksperchild=20) as pool:
        pending = jobs + random_jobs(rng, total - paper_impacts, quick, 0)
        made = len(pending) - len(jobs)
        while pending:
            for report in pool.imap_unordered(run_job, pending):
                reports.append(report)
                echo(_job_line(report))
            done = sum(r["impacts"] for r in reports)
            # runs that stopped early leave impacts to make up with more random scenes
            pending = random_jobs(rng, total - done, quick, made) if done < total else []
            made += len(pending)
    summary = _aggregate(reports)
    summary.update(
        requested=total,
        seed=seed,
        workers=workers,
        wall_time=time.perf_counter() - started,
    )
    return summary


def _job_line(report: dict[str, Any]) -> str:
    extra = f" ({report['reason']})" if report.get("stop") not in (None, "complete") else ""
    return (
        f"{report['label']:>14} {report['method']:>5} e_below {report.get('elastic_below')} "
        f"{report['impacts']:>7} impacts "
        f"{report.get('cpu', 0.0):6.1f} s  pen {report.get('penetrations', 0)} "
        f"det {report.get('detached', 0)} nonfin {report.get('non_finite_rows', 0)} "
        f"energy {report.get('energy_created', 0)} "
        f"resume {report.get('resume_mismatches', '-')}  {report.get('stop')}{extra}"
    )


def _aggregate(reports: list[dict[str, Any]]) -> dict[str, Any]:
    def total(key: str) -> int:
        return int(sum(r.get(key, 0) for r in reports))

    paper = [r for r in reports if r["label"] in PAPER_SCENES]
    random_runs = [r for r in reports if r["label"] not in PAPER_SCENES]
    stops = Counter(r.get("stop", "?") for r in random_runs)
    lowest = min((r.get("lowest_clearance", math.inf) for r in reports), default=math.inf)
    highest = max((r.get("highest_clearance", -math.inf) for r in reports), default=-math.inf)
    worst = max((r.get("worst_energy_excess", -math.inf) for r in reports), default=-math.inf)
    return {
        "impacts": total("impacts"),
        "paper_impacts": sum(r["impacts"] for r in paper),
        "random_impacts": sum(r["impacts"] for r in random_runs),
        "rk4_impacts": sum(r["impacts"] for r in reports if r["method"] == "rk4"),
        "runs": len(reports),
        "random_scenes": len(random_runs),
        "penetrations": total("penetrations"),
        "detached": total("detached"),
        "non_finite_rows": total("non_finite_rows"),
        "energy_created": total("energy_created"),
        "lifts": total("lifts"),
        "separating": total("separating"),
        "separating_rule_on": int(
            sum(r.get("separating", 0) for r in reports if r.get("elastic_below", 0.0) > 0.0)
        ),
        "energy_created_rule_off": int(
            sum(r.get("energy_created", 0) for r in reports if r.get("elastic_below") == 0.0)
        ),
        "energy_created_rk4": int(
            sum(r.get("energy_created", 0) for r in reports if r["method"] == "rk4")
        ),
        "resume_checks": total("resume_checked"),
        "resume_interrupted": total("resume_interrupted"),
        "resume_mismatches": total("resume_mismatches"),
        "lowest_clearance": lowest,
        "highest_clearance": highest,
        "worst_energy_excess": worst,
        "stops": dict(sorted(stops.items())),
        "paper": {r["label"]: {"impacts": r["impacts"], "stop": r.get("stop")} for r in paper},
        "cpu": sum(r.get("cpu", 0.0) for r in reports),
        "violations": [
            f"{r['label']}: {e}"
            for r in reports
            for e in r.get("examples", []) + r.get("energy_examples", [])
        ][:20],
        "stop_reasons": sorted(
            {
                f"{r['stop']}: {r['reason']}"
                for r in random_runs
                if r.get("stop") not in ("complete", "escape")
            }
        )[:20],
    }


MUST_BE_ZERO = (
    "penetrations",
    "detached",
    "non_finite_rows",
    "energy_created",
    "resume_mismatches",
)


def format_summary(s: dict[str, Any]) -> str:
    """The aggregated report as text."""
    lines = [
        f"soak: {s['impacts']:,} impacts in {s['runs']} runs "
        f"({s['paper_impacts']:,} on the paper scenes, {s['random_impacts']:,} on "
        f"{s['random_scenes']} random scenes, {s['rk4_impacts']:,} of them with rk4), "
        f"seed {s['seed']}, {s['workers']} workers, {s['wall_time']:.0f} s wall, "
        f"{s['cpu']:.0f} s CPU",
    ]
    for key in MUST_BE_ZERO:
        lines.append(f"  {key:<20} {s[key]}")
    lines += [
        f"  clearance at impacts: {s['lowest_clearance']:.3g} .. {s['highest_clearance']:.3g} m",
        f"  worst energy excess (relative): {s['worst_energy_excess']:.3g}",
        f"  lifts of a lying ball (designed energy input, audited): {s['lifts']:,}",
        f"  impacts at a separating contact (w_n >= 0, no lift): {s['separating']:,} "
        f"({s['separating_rule_on']:,} with elastic_below > 0)",
        f"  energy created with elastic_below = 0: {s['energy_created_rule_off']}, "
        f"with rk4: {s['energy_created_rk4']}",
        f"  resume checks: {s['resume_checks']} ({s['resume_interrupted']} interrupted mid-run)",
        f"  random-scene outcomes: {s['stops']}",
    ]
    lines += [f"  violation: {v}" for v in s["violations"]]
    lines += [f"  stop: {r}" for r in s["stop_reasons"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.soak",
        description="Soak test: impacts on the paper scenes and random valid scenes, "
        "each audited for penetration, non-finite values, energy creation "
        "and resume equality.",
    )
    parser.add_argument("--impacts", type=int, default=1_000_000, help="total impacts")
    parser.add_argument("--quick", action="store_true", help="20,000 impacts, small jobs")
    parser.add_argument("--seed", type=int, default=2024, help="random seed (default 2024)")
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (default: all cores)",
    )
    parser.add_argument("--json", metavar="PATH", help="also write the report as JSON")
    parser.add_argument("--verbose", action="store_true", help="one line per run")
    args = parser.parse_args(argv)
    total = 20_000 if args.quick else args.impacts
    echo = (lambda line: print(line, flush=True)) if args.verbose else (lambda line: None)
    summary = soak(total, seed=args.seed, workers=args.workers, quick=args.quick, echo=echo)
    print(format_summary(summary))
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1) + "\n")
    return 1 if any(summary[key] for key in MUST_BE_ZERO) else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
