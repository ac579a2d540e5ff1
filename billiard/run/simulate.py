"""Running a scene: :func:`simulate`, the one call behind ``billiard run`` and the API.

>>> from billiard import load_scene, simulate
>>> result = simulate(load_scene("parabola-5.4hz"), collisions=200)
>>> result.columns["q2"][:3]  # doctest: +SKIP

The pieces live in their own modules: the engine and its one-event step on the
compiled state machine (:mod:`billiard.engine.simulation`), the state it carries
(:mod:`billiard.engine.state`), streamed runs and resuming them
(:mod:`billiard.run.persist`), interruption (:mod:`billiard.engine.interrupt`) and the
result container (:mod:`billiard.run.result`). Their public names are re-exported here.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from typing import Any

from billiard.engine.interrupt import RunInterrupted
from billiard.engine.simulation import (
    COLLAPSE_COUNT,
    COLLAPSE_SPAN,
    ZERO_FLIGHT_LIMIT,
    Progress,
    Simulation,
)
from billiard.engine.state import BallState, EngineState
from billiard.run.output_size import check_samples, estimate_samples, guard_samples
from billiard.run.persist import (
    CHECKPOINT_NAME,
    CSV_NAME,
    SCENE_NAME,
    RunWriteError,
    resume,
    run_streamed,
)
from billiard.run.result import Result
from billiard.runfile.record import CONTACT_COLUMNS, TRAJECTORY_COLUMNS, MemoryRecorder
from billiard.scene.scene import Scene, SceneError, load_scene, with_values
from billiard.scene.spec import check_collisions
from billiard.status import Status

__all__ = [
    "CHECKPOINT_NAME",
    "COLLAPSE_COUNT",
    "COLLAPSE_SPAN",
    "CSV_NAME",
    "SCENE_NAME",
    "ZERO_FLIGHT_LIMIT",
    "BallState",
    "EngineState",
    "Result",
    "RunInterrupted",
    "RunWriteError",
    "Simulation",
    "Status",
    "resume",
    "run_streamed",
    "simulate",
]


def simulate(
    scene: Scene | str | os.PathLike[str],
    *,
    collisions: int | None = None,
    method: str | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    progress: Progress | None = None,
    duration: float | None = None,
    on_record: Callable[[int], None] | None = None,
    sample: float | None = None,
    allow_large: bool = False,
    store: str = "csv",
    notify: Callable[[str], None] | None = None,
) -> Result:
    """Run a scene.

    Args:
        scene: a :class:`billiard.scene.scene.Scene`, the name of a built-in scene
            (``"parabola-5.4hz"``) or the path of a scene file (``.toml``), loaded with
            :func:`~billiard.scene.scene.load_scene`.
        collisions: number of impacts; default ``scene.run.collisions``.
        method: ``"event"`` (default from the scene) or ``"rk4"`` (the paper's scheme).
        out_dir: stream the run to ``out_dir`` (``collisions.csv``, ``scene.toml`` and
            ``checkpoint.json``, see :mod:`billiard.run.persist`) instead of memory.
        progress: called as ``progress(n_done, n_total)`` every few impacts.
        duration: simulated time (s) after which the run stops, whichever of the two
            limits comes first; default ``scene.run.duration`` (None: no limit).
        on_record: called with the impact number after each record (a hook for tests
            and audits).
        sample: sampling interval (s) of simulated time: the state every ``sample``
            seconds in ``result.trajectory`` (and ``trajectory.csv``).
        allow_large: sample even when the trajectory may take more than 1 GB (of
            memory, or of ``trajectory.csv`` with ``out_dir``); see
            :mod:`billiard.run.output_size`.
        store: with ``out_dir``, the files' format: ``"csv"`` (``collisions.csv``, the
            default), ``"npy"`` (``collisions.npy``, typed binary rows: see
            :mod:`billiard.runfile.npyfile`) or ``"auto"`` (binary when the CSV files
            would be over 100 MB, :mod:`billiard.run.store`).
        notify: called with a one-line note when ``store="auto"`` chose binary files.

    Returns:
        A :class:`Result`; a run that had to stop early (ball escaped, inelastic
        collapse, non-finite numbers, a root solve that failed) keeps the records so
        far and says why in ``status`` and ``stop_reason``.

    Raises:
        GeometryError: the scene's geometry cannot be simulated.
        SceneError: the scene (or the impact count) is invalid, or ``scene`` names
            neither a built-in scene nor a scene file.
        OutputSizeError: (a ``SceneError``) the samples may take more than 1 GB and
            ``allow_large`` is False, checked before the run starts; or the run made more
            samples than estimated (the time in contact phases is not in the estimate
            without a duration), raised when it gets there.
        RunBusyError: another process is writing a run in ``out_dir``.
        RunInterrupted: a streamed run got SIGINT or SIGTERM; its files are complete up
            to the last impact and :func:`resume` continues it.
        RunWriteError: a streamed run could not write its files (a full disk; an
            ``OSError``): its message says how many impacts are kept and how to continue.
    """
    scene = _scene_of(scene)
    if duration is not None:
        scene = with_values(scene, {"run.duration": duration})  # validates it
    sim = Simulation(scene, method)
    total = scene.run.collisions if collisions is None else check_collisions(collisions)
    resolved = sim.resolved_scene(total)  # validates the impact count before any work
    if sample is not None:
        if not (isinstance(sample, (int, float)) and math.isfinite(sample) and sample > 0):
            raise SceneError(f"the sampling interval must be a number > 0 s, got {sample!r}")
        sim.sample_dt = float(sample)
    if out_dir is not None:
        return run_streamed(
            sim, out_dir, collisions=total, progress=progress, on_record=on_record,
            allow_large=allow_large, store=store, notify=notify,
        )  # fmt: skip
    recorder = MemoryRecorder()
    contacts = trajectory = None
    if sim.phases:
        contacts = MemoryRecorder(CONTACT_COLUMNS)
        sim.on_contact = sim.on_contact_cut = contacts.append
    if sim.sample_dt is not None:
        estimate = estimate_samples(
            sim, total, start_time=sim.initial.t, start_impacts=0, in_memory=True
        )
        if not allow_large:
            estimate = check_samples(estimate, sample=sim.sample_dt, allow="allow_large=True")
        trajectory = MemoryRecorder(TRAJECTORY_COLUMNS)
        sim.on_sample = guard_samples(trajectory.append, estimate, 0, sim.sample_dt)
    start = time.perf_counter()
    reason = sim.run(total, recorder, progress, on_record=on_record)
    wall_time = time.perf_counter() - start
    status = sim.status if sim.status is not None else Status.COMPLETE
    return Result(
        resolved,
        recorder,
        status,
        reason,
        wall_time,
        sim.counts,
        sim.final_time,
        regimes=sim.impact.regimes,
        mode_times=sim.mode_times() if sim.phases or sim.sample_dt else None,
        contacts=contacts,
        trajectory=trajectory,
        final_mode=sim.mode,
    )


def _scene_of(scene: Any) -> Scene:
    """The scene ``simulate`` was given: a Scene, or one loaded by name or path."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(scene)
    raise SceneError(
        f"simulate() takes a Scene, a built-in scene name or a scene file's path, "
        f"got {type(scene).__name__}"
    )
