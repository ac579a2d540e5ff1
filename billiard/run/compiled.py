"""The compiled engine under its former names: :func:`simulate_compiled` and
:func:`prepare` are thin aliases over :class:`billiard.engine.simulation.Simulation`, which runs
impact-only scenes (``contact.model = "impacts"``, method ``event``, Kane and Levinson's
law: :func:`supports`) on the kernels of :mod:`billiard.kernels` itself
(:mod:`billiard.engine.kernel_engine`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.engine.ctx import state_vector
from billiard.engine.kernel_engine import LAST_CHUNK, supports
from billiard.engine.simulation import Simulation
from billiard.geometry.wall_functions import WallFunction, wall_functions
from billiard.kernels import layout as L
from billiard.kernels.names import write
from billiard.runfile.record import COLUMNS, MemoryRecorder
from billiard.scene.spec import check_collisions
from billiard.status import Status

__all__ = [
    "CompiledRun",
    "Prepared",
    "WallFunction",
    "prepare",
    "simulate_compiled",
    "state_vector",
    "supports",
]

#: impacts per call of run_chunk in :func:`prepare`
CHUNK = LAST_CHUNK


@dataclass
class CompiledRun:
    """The outcome of :func:`simulate_compiled`."""

    recorder: Any
    status: Status
    reason: str | None
    counts: dict[str, int]
    #: CPU time (s) of the run, rows to the recorder included
    cpu_time: float
    #: impacts simulated
    impacts: int
    compiled: bool = field(default=False)

    @property
    def columns(self) -> dict[str, np.ndarray]:
        return self.recorder.columns()


@dataclass
class Prepared:
    """The arguments of :func:`billiard.kernels.loop.run_chunk` for a scene."""

    sim: Simulation
    ctx: Any
    params: Any
    walls: tuple[tuple[Any, ...], ...]
    buffer: Any
    chunk: int


def _simulation(scene: Any, collisions: int | None) -> tuple[Simulation, int]:
    _jit.notice()
    sim = Simulation(scene)
    why = supports(sim)
    if why is not None:
        raise ValueError(f"the compiled engine does not run this scene: {why}")
    total = scene.run.collisions if collisions is None else check_collisions(collisions)
    sim.resolved_scene(total)  # validates the impact count
    return sim, total


def prepare(scene: Any, collisions: int | None = None, chunk: int = CHUNK) -> Prepared:
    """The engine for ``scene`` at its start, and the kernels' arguments (its own state
    vector, aimed at ``collisions``), for calling ``run_chunk`` directly.

    Raises:
        ValueError: a scene the kernels do not cover (:func:`supports`).
    """
    sim, total = _simulation(scene, collisions)
    kernel = sim.kernel_engine
    assert kernel is not None
    ctx, params = kernel.ctx, kernel.params
    write(ctx, "engine.target", float(total))
    if _jit.ENABLED:
        buffer: Any = np.empty(chunk * L.NCOL, dtype=np.float64)
    else:
        buffer = [0.0] * (chunk * L.NCOL)
    return Prepared(sim, ctx, params, wall_functions(sim), buffer, chunk)


def simulate_compiled(
    scene: Any,
    collisions: int | None = None,
    *,
    out_dir: str | os.PathLike[str] | None = None,
    chunk: int = CHUNK,
) -> CompiledRun:
    """Run an impact-only scene: ``Simulation.run`` with the records in memory or, with
    ``out_dir``, in ``DIR/collisions.csv`` (no checkpoints: see
    :func:`billiard.run.simulate.simulate` for streamed runs). ``chunk`` is not used (the
    run sizes its chunks itself); it stays for callers of the former signature.

    Raises:
        ValueError: a scene the kernels do not cover (:func:`supports`).
    """
    del chunk
    sim, total = _simulation(scene, collisions)
    if out_dir is not None:
        from billiard.runfile.stream import CsvRecorder

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        recorder: Any = CsvRecorder(out / "collisions.csv", COLUMNS)
    else:
        recorder = MemoryRecorder()
    started = time.process_time()
    try:
        reason = sim.run(total, recorder)
    finally:
        cpu = time.process_time() - started
        recorder.close()
    status = sim.status if sim.status is not None else Status.COMPLETE
    return CompiledRun(
        recorder, status, reason, sim.counts, cpu, sim.state.impacts, compiled=_jit.ENABLED
    )
