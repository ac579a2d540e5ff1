"""The runs of the paper's reproduction: one scene run and measured (:class:`RunStats`),
the two contact models side by side, and the calibrations they start from.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from billiard.analysis.calibrate import Calibration, calibrate, find_period_one
from billiard.analysis.camera import camera_filter
from billiard.analysis.phase import (
    phase_frame,
)
from billiard.run.simulate import simulate
from billiard.runfile.record import LID_WALL
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import Scene, load_scene, scene_to_toml, with_values

FIG2_SCENES = ("wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz")
# The paper does not give the experiment's camera rate; a standard video frame interval.
CAMERA_FRAME = 1 / 30
#: A return-map point within this of the diagonal (m) is on it, not above it: the tolerance
#: of a period-one orbit (find_period_one), whose heights differ by rounding only.
DIAGONAL_TOL = 1e-6
#: The contact models compared: the paper's, and the one with rolling and sliding phases.
MODELS = ("impacts", "phases")
#: A run under "phases" may record at most this many times the impacts of the run it is
#: compared with before its simulated time is up (a bound on the work, never reached by
#: the paper scenes: contact phases replace impacts, they do not add any).
PHASES_IMPACT_CAP = 4


@dataclass
class RunStats:
    scene: str
    impacts: int
    simulated_time: float
    wall_time: float
    stop_reason: str | None
    counts: dict[str, int]
    q2_mean: float
    q2_max: float
    above_diagonal: float  # fraction of return-map points with q2,n+1 > q2,n + DIAGONAL_TOL
    lid_fraction: float
    tof_median: float
    camera_impacts: int
    camera_above_diagonal: float
    period_one: float | None  # orbit height (m) if the run ends locked
    lyapunov: float | None = None  # per impact
    model: str = "impacts"
    short_flights: float = math.nan  # share of flights shorter than one camera frame
    hop_time: float = 0.0  # s in flights launched by the low-velocity rule
    roll_time: float | None = None  # s rolling (contact.model = "phases")
    slide_time: float | None = None  # s sliding
    contact_phases: int | None = None  # rows of contacts.csv

    @property
    def impacts_per_second(self) -> float:
        return self.impacts / self.simulated_time if self.simulated_time > 0 else math.nan

    @property
    def relaunch_share(self) -> float:
        """Share of the impacts that relaunched a ball lying on the wall."""
        return self.counts.get("resting", 0) / self.impacts if self.impacts else math.nan

    @property
    def contact_time(self) -> float | None:
        """Simulated time (s) rolling or sliding; None under the impacts model."""
        if self.roll_time is None or self.slide_time is None:
            return None
        return self.roll_time + self.slide_time


def _above(q2: np.ndarray) -> float:
    return float(np.mean(q2[1:] > q2[:-1] + DIAGONAL_TOL)) if len(q2) > 1 else math.nan


def _hop_time(cols: dict[str, np.ndarray]) -> float:
    """Simulated time (s) in the flights that follow an impact of the low-velocity rule."""
    elastic = np.asarray(cols["regime"]) == "elastic"
    return float(np.sum(cols["tof"][1:][elastic[:-1]]))


def run_scene(
    name: str,
    runs_dir: Path,
    collisions: int,
    *,
    model: str = "impacts",
    duration: float | None = None,
    scene: Scene | None = None,
) -> RunStats:
    """Run a paper scene under ``contact.model = model`` for ``collisions`` impacts (or
    until the simulated time ``duration``, s, whichever comes first), streamed to
    ``runs_dir / name``, and measure it. ``scene``: the scene to run (default: the
    built-in scene ``name``)."""
    scene = load_scene(name) if scene is None else scene
    if scene.contact.model != model:
        scene = with_values(scene, {"contact.model": model})
    out = runs_dir / name
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    result = simulate(scene, collisions=collisions, out_dir=out, duration=duration)
    wall = time.perf_counter() - started
    (out / "scene.toml").write_text(scene_to_toml(result.scene))
    cols = read_collisions(out / "collisions.csv")
    cam = camera_filter(cols, CAMERA_FRAME)
    orbit = find_period_one(cols, scene.ball.mass, scene.run.gravity, reference=phase_frame(scene))
    wall_kind = cols.get("wall")
    lid = float(np.mean(wall_kind == LID_WALL)) if wall_kind is not None else 0.0
    modes = result.mode_times if model == "phases" else None
    contacts = result.contacts if model == "phases" else None
    return RunStats(
        scene=name,
        impacts=len(cols["n"]),
        simulated_time=float(result.final_time if duration is not None else cols["t"][-1]),
        wall_time=wall,
        stop_reason=result.stop_reason,
        counts=dict(result.counts),
        q2_mean=float(cols["q2"].mean()),
        q2_max=float(cols["q2"].max()),
        above_diagonal=_above(cols["q2"]),
        lid_fraction=lid,
        tof_median=float(np.median(cols["tof"])),
        camera_impacts=len(cam["q2"]),
        camera_above_diagonal=_above(cam["q2"]),
        period_one=orbit.height if orbit else None,
        model=model,
        short_flights=float(np.mean(cols["tof"] < CAMERA_FRAME)),
        hop_time=_hop_time(cols),
        roll_time=None if modes is None else float(modes["roll"]),
        slide_time=None if modes is None else float(modes["slide"]),
        contact_phases=None if contacts is None else len(contacts["t_start"]),
    )


def compare_models(
    name: str, runs_dir: Path, collisions: int, impacts: RunStats | None = None
) -> tuple[RunStats, RunStats]:
    """A paper scene under both contact models, from the same start (the scene's: at rest
    at the bottom) over the same simulated time: ``collisions`` impacts under "impacts"
    (in ``runs_dir / name``, or the measured run ``impacts`` if given), then "phases"
    until that run's last impact (in ``runs_dir / "phases" / name``; at most
    :data:`PHASES_IMPACT_CAP` times as many impacts).

    Same simulated time, not the same impact count: the phases model replaces the impact
    model's rapid hops with rolling and sliding, so its impacts stand for a different
    stretch of motion; over one simulated time both describe the same experiment, and
    impacts per second, camera counts and the maps' shares compare directly.

    Returns:
        (the impacts run, the phases run).
    """
    if impacts is None:
        impacts = run_scene(name, runs_dir, collisions)
    phases = run_scene(
        name,
        runs_dir / "phases",
        PHASES_IMPACT_CAP * collisions,
        model="phases",
        duration=impacts.simulated_time,
    )
    return impacts, phases


@dataclass
class PhasesCalibration:
    """The calibration repeated under contact.model = "phases": its result, or why it
    failed, and its wall time (s)."""

    calibration: Calibration | None
    error: str | None
    wall_time: float


def calibrate_paper(parabola, model: str = "impacts") -> Calibration:
    """The drive amplitude that puts the parabola's period-one orbit at the paper's
    0.075 m (3-point scan over 20 to 30 mm, then Brent's method; 1500 impacts a trial)."""
    if parabola.contact.model != model:
        parabola = with_values(parabola, {"contact.model": model})
    return calibrate(parabola, "drive.amplitude", 0.075, low=0.02, high=0.03, points=3)
