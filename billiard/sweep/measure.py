"""Points of a sweep: simulate their scenes and measure the attractors they reach.

A worker (a local process or a Dask worker) runs one :class:`ChunkTask` at a time:
:func:`measure_chunk` measures the chunk's points and returns their columns
(:class:`~billiard.sweep.columns.ChunkResult`). :func:`measure_point` measures one point
and returns a plain dict of numbers, strings and lists (no timings): the same scene gives
the same dict bit for bit wherever it runs, so a point's result does not depend on the
chunk it came in.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard.runfile.record import LID_WALL
from billiard.sweep.attractor import classify, contact_class, find_period
from billiard.sweep.columns import ChunkResult, empty_columns, set_row

__all__ = ["ChunkTask", "PointTask", "measure_chunk", "measure_point"]


@dataclass(frozen=True)
class ChunkTask:
    """Everything a worker needs for a chunk of points.

    Attributes:
        sweep: the sweep (its base scene, axes and measurement settings).
        start, stop: the chunk's points are indices in [start, stop) of the sweep.
        indices: the points to measure, sorted, within [start, stop) (int64); None for
            every point of the range (points already stored or invalid are left out).
        device: where the ensemble kernel runs the points it takes (``cpu``, ``gpu``).
    """

    sweep: Any
    start: int
    stop: int
    indices: np.ndarray | None = None
    device: str = "cpu"

    def points(self) -> np.ndarray:
        """The indices of the points to measure (int64)."""
        if self.indices is None:
            return np.arange(self.start, self.stop, dtype=np.int64)
        return np.asarray(self.indices, dtype=np.int64)

    def __len__(self) -> int:
        return self.stop - self.start if self.indices is None else len(self.indices)


def measure_chunk(task: ChunkTask) -> ChunkResult:
    """Measure every point of a chunk; never raises for a point that fails.

    Each point is measured on its own (its result is the same in any chunk): the points
    the ensemble kernel takes together (:func:`billiard.sweep.batch.measure_batch`), the
    rest one by one through :func:`_measure_points`. Which path a point takes depends on
    its scene and the settings alone, never on the chunk. Rows in index order.
    """
    from billiard.sweep.batch import measure_batch

    indices = task.points()
    batch, rest = measure_batch(task.sweep, indices, task.sweep.settings(), task.device)
    if batch is None:
        return _measure_points(task, indices)
    if not rest:
        return ChunkResult(batch)
    single = _measure_points(task, np.asarray(rest, dtype=np.int64))
    columns = {k: np.concatenate([batch[k], single.columns[k]]) for k in batch}
    order = np.argsort(columns["index"], kind="stable")
    return ChunkResult({k: v[order] for k, v in columns.items()}, single.reasons)


def _measure_points(task: ChunkTask, indices: np.ndarray) -> ChunkResult:
    """The points ``indices`` of the chunk, one :func:`measure_point` each."""
    from billiard.scene.scene import with_values

    sweep = task.sweep
    settings = sweep.settings()
    columns = empty_columns(len(indices), sweep.keep)
    reasons: dict[int, str] = {}
    for row, index in enumerate(indices.tolist()):
        values = sweep.point_values(index)
        try:
            scene = with_values(sweep.scene, values)
        except ValueError as exc:  # checked before the sweep started: not expected
            record = empty_record(index, values, "invalid", str(exc))
        else:
            record = measure_point(PointTask(index, values, scene, settings))
        set_row(columns, row, record)
        if record["reason"]:
            reasons[index] = record["reason"]
    return ChunkResult(columns, reasons)


@dataclass(frozen=True)
class PointTask:
    """Everything a worker needs for one point.

    Attributes:
        index: the point's index in the sweep (C order of the axes).
        values: the swept keys' values at this point.
        scene: the point's validated scene.
        settings: the sweep's measurement settings (see :class:`Sweep`).
    """

    index: int
    values: dict[str, Any]
    scene: Any
    settings: dict[str, Any]


def _finite(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def _rest_height(scene: Any) -> float:
    """Centre height (m) of the ball at rest at the bottom of the point's container.

    The engine places a ball without a start position at rest on the bottom when it is
    set up; nothing is simulated (a run from rest under ``contact.model = "phases"`` may
    roll for ever, and the set-up gives the same height a one-impact run reports)."""
    from billiard.engine.ensemble import at_rest_scene

    return _rest_height_of(at_rest_scene(scene))


@functools.lru_cache(maxsize=256)
def _rest_height_of(at_rest: Any) -> float:
    """The resting height of a scene whose ball starts at rest: once per distinct
    parameter set in a worker (a basin map's points share one; setting up the
    simulation is half the cost of a short point)."""
    from billiard.run.simulate import Simulation

    return float(Simulation(at_rest).initial.q2)


def _failed(task: PointTask, reason: str, total: int = 0) -> dict[str, Any]:
    record = empty_record(task.index, task.values, "failed", reason)
    record["total_impacts"] = total
    return record


def empty_record(index: int, values: dict[str, Any], status: str, reason: str) -> dict[str, Any]:
    """The record of a point without measurements (failed, or invalid and skipped)."""
    return {
        "index": index,
        "values": values,
        "status": status,
        "reason": " ".join(reason.split()),
        "attractor": status,
        "period": 0,
        "drive_periods": 0,
        "impacts": 0,
        "total_impacts": 0,
        "rest_height": None,
        "height_mean": None,
        "height_std": None,
        "height_max": None,
        "tof_mean": None,
        "tof_std": None,
        "elastic_share": None,
        "lid_share": None,
        "lyapunov": None,
        "lyapunov_per_second": None,
        "last_height": [],
        "last_tof": [],
        "run_status": "",
        "final_mode": "",
    }


def measure_point(task: PointTask) -> dict[str, Any]:
    """Simulate one point and measure it; never raises for a point that fails."""
    try:
        return _measure(task)
    except Exception as exc:  # a fault in one point must not end the sweep
        return _failed(task, f"{type(exc).__name__}: {exc}")


def _measure(task: PointTask) -> dict[str, Any]:
    from billiard.run.simulate import simulate

    s = task.settings
    scene = task.scene
    transient, impacts = int(s["transient"]), int(s["impacts"])
    result = simulate(scene, collisions=transient + impacts, duration=s["duration"])
    cols = result.columns
    total = len(cols["n"])
    ended = {"run_status": result.status.name.lower(), "final_mode": result.final_mode or ""}
    if result.stop_reason:
        return _failed(task, result.stop_reason, total) | ended
    post = {name: np.asarray(col[transient:]) for name, col in cols.items()}
    n = len(post["n"])
    # under contact.model = "phases" a ball can end at rest, rolling, sliding or held
    # in the vertex, with no impacts left to measure: that is its attractor
    in_contact = contact_class(result.status, result.final_mode, n)
    if n == 0 and in_contact is None:
        return (
            _failed(
                task,
                f"no impacts after the transient: {result.message} after {total} impacts",
                total,
            )
            | ended
        )
    rest = _rest_height(scene)
    keep = int(s["keep"])
    record = empty_record(task.index, task.values, "ok", "") | ended
    if n == 0:
        record.update(attractor=in_contact, total_impacts=total, rest_height=rest)
        return record
    q2, tof = post["q2"].astype(float), post["tof"].astype(float)
    elastic_share = float(np.mean(post["regime"] == "elastic"))
    lid_share = float(np.mean(post["wall"] == LID_WALL))
    measured = dict(
        impacts=n,
        total_impacts=total,
        rest_height=rest,
        **_impact_statistics(q2, tof, keep),
        elastic_share=elastic_share,
        lid_share=lid_share,
    )
    if in_contact is not None:  # impacts after the transient, then the ball stayed down
        record.update(attractor=in_contact, **measured)
        return record
    period = find_period(
        post,
        frequency=scene.drive.frequency,
        phase=scene.drive.phase,
        radius=scene.ball.radius,
        g=scene.run.gravity,
        tolerance=s["tolerance"],
        max_period=s["max_period"],
    )
    drive_periods = 0
    if period and scene.drive.frequency > 0.0:
        drive_periods = round(float(np.sum(tof[-period:])) * scene.drive.frequency)
    lyap = lyap_s = None
    if s["lyapunov"]:
        from billiard.analysis.lyapunov import lyapunov_exponent

        estimate = lyapunov_exponent(scene, impacts=impacts, transient=transient)
        lyap, lyap_s = _finite(estimate.per_impact), _finite(estimate.per_second)
    attractor = classify(
        failed=False,
        period=period,
        rise=float(np.max(q2)) - rest,
        elastic_share=elastic_share,
        rest_band=s["rest_band"],
        lyapunov=lyap,
        chaos_threshold=s["chaos_threshold"],
    )
    record.update(
        attractor=attractor,
        period=int(period),
        drive_periods=int(drive_periods),
        **measured,
        lyapunov=lyap,
        lyapunov_per_second=lyap_s,
    )
    return record


def _impact_statistics(q2: np.ndarray, tof: np.ndarray, keep: int) -> dict[str, Any]:
    """Heights and times of flight of the measured impacts (at least one)."""
    return {
        "height_mean": float(np.mean(q2)),
        "height_std": float(np.std(q2)),
        "height_max": float(np.max(q2)),
        "tof_mean": float(np.mean(tof)),
        "tof_std": float(np.std(tof)),
        "last_height": [float(x) for x in q2[-keep:]],
        "last_tof": [float(x) for x in tof[-keep:]],
    }
