"""The compiled engine for impact-only scenes (``contact.model = "impacts"``, method
``event``): :func:`simulate_compiled` builds the kernels' state vector from a scene and
streams chunks of impacts from :func:`billiard.kernels.loop.run_chunk` into the same
records, and the same ``collisions.csv`` bytes, as :class:`billiard.engine.Simulation`.

The kernels are compiled by numba when it is there (:mod:`billiard.jit`) and run
interpreted otherwise (or with ``NUMBA_DISABLE_JIT=1``): one source either way.

A curve's wall functions are handed to the kernels as first-class function values of
one type, ``float64(float64, float64[::1])`` (numba's ``FunctionType``): each generated
function is compiled once under the same decorator and passed by address
(:class:`WallFunction`), so the kernels are compiled once for every curve, and cached.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.engine import Simulation
from billiard.errors import SimulationError
from billiard.kernels import layout as L
from billiard.kernels.state import state_vector
from billiard.record import COLUMNS, ImpactRecord, MemoryRecorder
from billiard.status import Status

__all__ = ["CompiledRun", "Prepared", "WallFunction", "prepare", "simulate_compiled", "supports"]

#: impacts per call of run_chunk
CHUNK = 4096

_MESSAGES = {
    L.E_ESCAPED: (Status.ESCAPED, "ball escaped above escape_height"),
    L.E_NO_IMPACT: (Status.SOLVER_FAILED, "no impact found within 1000 s of flight"),
    L.E_ROOT: (Status.SOLVER_FAILED, "the impact time did not converge"),
    L.E_EXTREMUM: (Status.SOLVER_FAILED, "the gap's extremum did not converge"),
    L.E_STEP_CONTROL: (Status.SOLVER_FAILED, "the flight's step-size control failed"),
    L.E_INVERSION: (Status.SOLVER_FAILED, "offset-curve inversion did not converge"),
    L.E_NON_FINITE: (Status.NON_FINITE, "non-finite state"),
    L.E_COLLAPSE: (Status.COLLAPSE, "inelastic collapse"),
}


# ---------------------------------------------------------------------- wall functions

_SIGNATURE = None
_compiled_walls: dict[Any, Any] = {}


def _wall_signature() -> Any:
    global _SIGNATURE
    if _SIGNATURE is None:
        from numba import types

        _SIGNATURE = types.float64(types.float64, types.float64[::1])
    return _SIGNATURE


def _wall_function_class() -> type:
    import numba.experimental.function_type  # noqa: F401  (typeof of the protocol)
    from numba.core.types import WrapperAddressProtocol

    class _WallFunction(WrapperAddressProtocol):
        """A generated wall function, compiled for ``float64(float64, float64[::1])``,
        as a first-class function value: numba types it by its signature alone, so a
        kernel taking it is compiled (and cached) once for every curve."""

        def __init__(self, fn: Any):
            sig = _wall_signature()
            self.dispatcher = _jit.jit(fn)
            self.dispatcher.compile(sig.args)
            result = self.dispatcher.get_compile_result(sig)
            self.address = result.library.get_pointer_to_function(
                result.fndesc.llvm_cfunc_wrapper_name
            )

        def __wrapper_address__(self) -> int:
            return self.address

        def signature(self) -> Any:
            return _wall_signature()

    return _WallFunction


_WallFunctionClass: type | None = None


def WallFunction(fn: Any) -> Any:  # noqa: N802  (a factory standing for a class)
    """``fn`` as the kernels take it: a compiled first-class function value, or ``fn``
    itself when the kernels run interpreted."""
    global _WallFunctionClass
    if not _jit.ENABLED:
        return fn
    if fn not in _compiled_walls:
        if _WallFunctionClass is None:
            _WallFunctionClass = _wall_function_class()
        _compiled_walls[fn] = _WallFunctionClass(fn)
    return _compiled_walls[fn]


def wall_functions(sim: Simulation) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f): one tuple per function, one entry per wall of the curve."""
    walls = sim.boundary.walls
    return (
        tuple(WallFunction(w.f) for w in walls),
        tuple(WallFunction(w.df) for w in walls),
        tuple(WallFunction(w.d2f) for w in walls),
    )


# ---------------------------------------------------------------------- state vector


def supports(sim: Simulation) -> str | None:
    """None when the compiled engine runs this simulation, else why not."""
    if sim.method != "event":
        return f"method {sim.method!r} (the compiled engine has the event locator only)"
    if sim.phases:
        return "contact.model = 'phases' (the compiled engine has impacts only)"
    if len(sim.boundary.surfaces) > L.MAX_SURFACES:
        return f"more than {L.MAX_SURFACES} surfaces"
    if type(sim.impact).__name__ != "KaneLevinsonImpact":
        return "an impact law other than Kane-Levinson"
    return None


# ---------------------------------------------------------------------- the run


@dataclass
class CompiledRun:
    """The outcome of :func:`simulate_compiled`."""

    recorder: Any
    status: Status
    reason: str | None
    counts: dict[str, int]
    #: CPU time (s) of the impact loop, rows to records included
    cpu_time: float
    #: impacts simulated
    impacts: int
    compiled: bool = field(default=False)

    @property
    def columns(self) -> dict[str, np.ndarray]:
        return self.recorder.columns()


def _records(buffer: Any, rows: int) -> list[ImpactRecord]:
    if isinstance(buffer, np.ndarray):
        table = buffer[: rows * L.NCOL].reshape(rows, L.NCOL).tolist()
    else:
        table = [buffer[i * L.NCOL : (i + 1) * L.NCOL] for i in range(rows)]
    records = []
    for row in table:
        wall = row[13]
        records.append(
            ImpactRecord(
                int(row[0]),
                *row[1:10],
                L.REGIMES[int(row[10])],
                row[11],
                row[12],
                "lid" if wall == L.LID_LABEL else str(int(wall)),
                *row[14:18],
            )
        )
    return records


@dataclass
class Prepared:
    """The arguments of :func:`billiard.kernels.loop.run_chunk` for a scene."""

    sim: Simulation
    ctx: Any
    params: Any
    walls: tuple[tuple[Any, ...], ...]
    buffer: Any
    chunk: int


def prepare(scene: Any, collisions: int | None = None, chunk: int = CHUNK) -> Prepared:
    """Build the engine for ``scene`` and the kernels' arguments, at its start state.

    Raises:
        ValueError: a scene the compiled engine does not cover (:func:`supports`).
    """
    _jit.notice()
    sim = Simulation(scene)
    why = supports(sim)
    if why is not None:
        raise ValueError(f"the compiled engine does not run this scene: {why}")
    total = scene.run.collisions if collisions is None else int(collisions)
    sim.resolved_scene(total)  # validates the impact count
    sim.reset()
    values = state_vector(sim)
    values[L.EN_TARGET] = float(total)
    walls = wall_functions(sim)
    p = sim.boundary.walls[0].p
    if _jit.ENABLED:
        ctx: Any = np.array(values, dtype=np.float64)
        params: Any = np.array(p, dtype=np.float64)
        buffer: Any = np.empty(chunk * L.NCOL, dtype=np.float64)
    else:
        ctx, params, buffer = values, p, [0.0] * (chunk * L.NCOL)
    return Prepared(sim, ctx, params, walls, buffer, chunk)


def simulate_compiled(
    scene: Any,
    collisions: int | None = None,
    *,
    out_dir: str | os.PathLike[str] | None = None,
    chunk: int = CHUNK,
) -> CompiledRun:
    """Run an impact-only scene on the kernels: the same records as
    :func:`billiard.simulate.simulate`; with ``out_dir``, ``DIR/collisions.csv`` with
    the same bytes (no checkpoints or resume yet).

    Raises:
        ValueError: a scene the compiled engine does not cover (:func:`supports`).
    """
    from billiard.kernels.loop import run_chunk

    run = prepare(scene, collisions, chunk)
    ctx, params, walls, buffer = run.ctx, run.params, run.walls, run.buffer
    if out_dir is not None:
        from billiard.stream import CsvRecorder

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        recorder: Any = CsvRecorder(out / "collisions.csv", COLUMNS)
    else:
        recorder = MemoryRecorder()
    status, reason = Status.COMPLETE, None
    started = time.process_time()
    try:
        while True:
            before = int(ctx[L.EN_IMPACTS])
            try:
                code, rows = run_chunk(ctx, params, walls, buffer, chunk)
            except SimulationError:
                raise
            except L.KernelError as exc:
                rows = int(ctx[L.EN_IMPACTS]) - before
                for record in _records(buffer, rows):
                    recorder.append(record)
                status, text = _MESSAGES[exc.args[0]]
                n = int(ctx[L.EN_IMPACTS])
                reason = f"{text} after impact {n} (t = {ctx[L.EN_T]:.9g} s)"
                break
            except (ArithmeticError, ValueError) as exc:
                rows = int(ctx[L.EN_IMPACTS]) - before
                for record in _records(buffer, rows):
                    recorder.append(record)
                status = Status.NUMERICAL_FAULT
                reason = f"numerical failure after impact {int(ctx[L.EN_IMPACTS])}: {exc}"
                break
            for record in _records(buffer, rows):
                recorder.append(record)
            if code == L.FULL:
                continue
            if code == L.TIME_LIMIT:
                status = Status.TIME_LIMIT
            elif code == L.COLLAPSE:
                status = Status.COLLAPSE
                reason = f"inelastic collapse at impact {int(ctx[L.EN_IMPACTS])}"
            break
    finally:
        cpu = time.process_time() - started
        recorder.close()
    counts = {
        key: int(ctx[L.COUNTS + i]) for i, key in enumerate(("stick", "slip", "elastic", "resting"))
    }
    if math.isnan(cpu):  # pragma: no cover
        cpu = 0.0
    return CompiledRun(
        recorder, status, reason, counts, cpu, int(ctx[L.EN_IMPACTS]), compiled=_jit.ENABLED
    )
