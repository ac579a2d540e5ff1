""":class:`billiard.engine.simulation.Simulation` on the kernels (:mod:`billiard.kernels`),
for Kane and Levinson's law with method ``event`` or ``rk4``: the impact model
(``contact.model = "impacts"``, the four paper scenes), and the flights between contact
phases (``contact.model = "phases"``,
:meth:`billiard.engine.simulation.Simulation._fly`). Compiled by numba when it is there,
interpreted otherwise (or with ``NUMBA_DISABLE_JIT=1``): one source either way.

:class:`KernelEngine` owns the engine state as the state vector ``ctx``
(:mod:`billiard.engine.ctx`); the warm starts, the flight's step proposal and the
rk4 locator's memory stay with the ``Simulation``'s objects (``sim.warm``,
``sim.flight``, ``sim.locator``), which the geometry queries outside the event loop
share, and are copied into ``ctx`` before and out of it after every call. A fixed-step
search that needs the curve's global nearest point (``E_FOOT``) is answered here and
runs again (:func:`billiard.models.rk4_locator.answer_foot`).

A run calls :func:`billiard.kernels.loop.run_chunk` chunk by chunk (64 impacts first,
doubling to 4096 while a chunk takes under 0.05 s) and hands the rows out as today's loop
hands out records: to the recorder (as arrays when it takes them), ``on_record`` after
each, ``progress`` every 100 impacts. A stop request seen after impact K of a chunk stops
the run there: ``ctx`` goes back to the chunk's start and the chunk runs again up to K,
which reproduces the state after impact K bit for bit (the run is deterministic).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.engine.ctx import (
    COUNT_KEYS,
    engine_state,
    read_motion,
    state_vector,
    write_ball,
    write_state,
)
from billiard.engine.interrupt import RunInterrupted, StopRequest
from billiard.engine.progress import report_time
from billiard.errors import BallAtRest, SimulationError
from billiard.kernels import layout as L
from billiard.kernels.interpreted import stop_text
from billiard.models.rk4_locator import answer_foot
from billiard.runfile.npystream import NpyRecorder
from billiard.runfile.record import NO_WALL, ContactRecord, MemoryRecorder, record_of
from billiard.runfile.rows import as_block
from billiard.runfile.stream import CsvRecorder
from billiard.status import Status

__all__ = ["FIRST_CHUNK", "LAST_CHUNK", "KernelEngine", "rows_sink", "supports"]

#: impacts of the first chunk of a run, and of the longest
FIRST_CHUNK = 64
LAST_CHUNK = 4096
#: contact rows of a chunk of the state machine (contact.model = "phases")
CONTACT_ROWS = 4096
#: (kernel, wall table type) pairs this process has called (see KernelEngine._call)
_CALLED: set[tuple[Any, Any]] = set()
#: the fixed-step detection's memory between flights: the departures in a row, the feet
_FIXED_MEMORY = (
    slice(L.RK_DEPARTURES, L.RK_DEPARTURES + 1),
    slice(L.RK_FEET, L.RK_FEET + L.MAX_SURFACES),
)
#: a chunk that took less wall time (s) than this is followed by one twice as long
_FAST_CHUNK = 0.05
_PROGRESS_EVERY = 100


def supports(sim: Any, *, flights: bool = False) -> str | None:
    """None when ``sim`` runs on the kernels (``flights``: its flights between contact
    phases, under ``contact.model = "phases"``), else why not."""
    if sim.method not in ("event", "rk4"):
        return f"method {sim.method!r} (the kernels have the event and rk4 locators only)"
    if sim.phases and not flights:
        return "contact.model = 'phases' (the kernels run its flights only)"
    if len(sim.boundary.surfaces) > L.MAX_SURFACES:
        return f"more than {L.MAX_SURFACES} surfaces"
    if type(sim.impact).__name__ != "KaneLevinsonImpact":
        return "an impact law other than Kane-Levinson"
    if type(sim.flight).__name__ not in ("ExactFlight", "AdaptiveFlight", "RK4Flight"):
        return f"the flight model {type(sim.flight).__name__}"
    if sim.phases and (sim.impact.e, sim.impact.elastic_below) != (
        sim.contact_model.e,
        sim.scene.contact.elastic_below,
    ):
        # the kernels' landing test reads the law's IM_E and IM_EB, the one-event step's
        # (ContactPhases._settles) the scene's: another law's flights stay on the classes
        return "an impact law whose restitution or elastic_below is not the scene's"
    return None


def rows_sink(recorder: Any) -> Callable[[np.ndarray], None] | None:
    """``recorder.append_rows`` when the recorder takes rows as arrays (and does not
    override ``append``, which then has to see every record), else None."""
    for base in (MemoryRecorder, CsvRecorder, NpyRecorder):
        if isinstance(recorder, base) and type(recorder).append is base.append:
            return recorder.append_rows
    return None


class KernelEngine:
    """The state vector of one ``Simulation`` and the calls into the kernels."""

    def __init__(self, sim: Any):
        self.sim = sim
        #: the impact law the kernels stand for
        self.law = sim.impact
        values = state_vector(sim)
        p = sim.boundary.walls[0].p
        if _jit.ENABLED:
            self.ctx: Any = np.array(values, dtype=np.float64)
            self.params: Any = np.array(p, dtype=np.float64)
        else:
            self.ctx, self.params = values, p
        if sim.phases:
            # a chunk ends after an impact that settles: the engine lands the ball (the
            # landing test reads the law's restitution and elastic_below, IM_E and IM_EB)
            self.ctx[L.EN_LAND_ON] = 1.0
        #: the whole trajectory on the state machine (:mod:`billiard.kernels.machine`):
        #: contact phases with the event locator
        self.machine = bool(sim.phases) and sim.method == "event"
        if self.machine:
            self._machine_constants()
        self.offsets = len(sim.boundary.offsets)
        #: when the next checkpoint is due (time.monotonic), as the latest run left it
        self.next_save = math.inf
        self.adaptive = self.ctx[L.FL_KIND] == L.FLIGHT_ADAPTIVE
        #: the paper's fixed-step detection (method rk4): its memory is the locator's
        self.fixed = sim.method == "rk4"
        self._buffer: Any = None
        self._walls: Any = None
        self._nears: Any = None
        self._entry: Any = None
        self._contacts: Any = None

    def _machine_constants(self) -> None:
        """The contact phases' constants (as the contact model's own ``ctx`` holds
        them), the contact span, the container's range of x and the walls' intervals."""
        sim, ctx = self.sim, self.ctx
        phase = sim.contact_model.new_ctx()
        ctx[L.PH_M : L.PH_RTOL + 1] = phase[L.PH_M : L.PH_RTOL + 1]
        ctx[L.MC_SPAN] = float(sim.scene.run.contact_span)
        ctx[L.MC_X_LO], ctx[L.MC_X_HI] = (float(x) for x in sim.boundary.x_range)
        for wall in sim.boundary.walls:
            ctx[L.MC_WALL_LO + wall.index] = float(wall.lo)
            ctx[L.MC_WALL_HI + wall.index] = float(wall.hi)

    # ------------------------------------------------------------------ state

    def reset(self, ball: Any) -> None:
        write_ball(self.ctx, ball)

    def restore(self, state: Any) -> None:
        write_state(self.ctx, state)

    def state(self) -> Any:
        state = engine_state(self.ctx, self.sim.impact.regimes, self.offsets)
        if self.machine:
            return dataclasses.replace(state, **read_motion(self.ctx))
        return state

    @property
    def impacts(self) -> int:
        return int(self.ctx[L.EN_IMPACTS])

    def counts(self) -> dict[str, int]:
        ctx = self.ctx
        keys = (*self.sim.impact.regimes, "resting")
        return {key: int(ctx[L.COUNTS + COUNT_KEYS.index(key)]) for key in keys}

    def set_counts(self, counts: dict[str, int]) -> None:
        for i, key in enumerate(COUNT_KEYS):
            self.ctx[L.COUNTS + i] = float(counts.get(key, 0))

    def pending_stop(self) -> SimulationError | None:
        """The inelastic collapse detected after the last impact, as the engine words it."""
        ctx = self.ctx
        if ctx[L.EN_FAULT] == 0.0:
            return None
        from billiard.kernels.rules import COLLAPSE_COUNT, COLLAPSE_SPAN, ZERO_FLIGHT_LIMIT

        n, t = int(ctx[L.EN_IMPACTS]), float(ctx[L.EN_T])
        from billiard.kernels.loop import FAULT_PRESSED

        if ctx[L.EN_FAULT] == FAULT_PRESSED:
            from billiard.engine.event_step import pressed_stop

            j = int(ctx[L.EN_ERR_VALUE])
            return pressed_stop(self.sim.boundary.surfaces[j].kind == "lid", n, t)
        if ctx[L.EN_FAULT] == 2.0:
            return SimulationError(
                f"contact phases of zero duration piled up at t = {float(ctx[L.MC_FINAL]):.9g} s",
                Status.COLLAPSE,
            )
        if ctx[L.EN_RCOUNT] > COLLAPSE_COUNT:
            return SimulationError(
                f"inelastic collapse: {COLLAPSE_COUNT} impacts within "
                f"{COLLAPSE_SPAN:g} s of simulated time, at impact {n} (t = {t:.9g} s)",
                Status.COLLAPSE,
            )
        return SimulationError(
            f"inelastic collapse: {ZERO_FLIGHT_LIMIT} consecutive impacts with "
            f"zero time of flight, at impact {n} (t = {t:.9g} s)",
            Status.COLLAPSE,
        )

    def _sync_in(self) -> None:
        """The warm starts and the step proposal, owned by the Simulation's objects."""
        ctx = self.ctx
        for j, warm in enumerate(self.sim.warm):
            base = L.SURF + j * L.SURF_STRIDE
            ctx[base + L.S_WS] = warm[0]
            ctx[base + L.S_WSLOPE] = warm[1]
        if self.adaptive:
            ctx[L.FL_H] = self.sim.flight.step_proposal
        if self.fixed:
            for slots in _FIXED_MEMORY:
                ctx[slots] = self.sim.locator.ctx[slots]

    def _sync_out(self) -> None:
        ctx = self.ctx
        for j, warm in enumerate(self.sim.warm):
            base = L.SURF + j * L.SURF_STRIDE
            warm[0] = float(ctx[base + L.S_WS])
            warm[1] = float(ctx[base + L.S_WSLOPE])
        if self.adaptive:
            self.sim.flight.step_proposal = float(ctx[L.FL_H])
        if self.fixed:
            for slots in _FIXED_MEMORY:
                self.sim.locator.ctx[slots] = [float(x) for x in ctx[slots]]

    # ------------------------------------------------------------------ calls

    def _prepare(self) -> None:
        from billiard.geometry.wall_functions import (
            near_functions,
            phase_wall_functions,
            wall_functions,
        )

        _jit.notice()
        if self.machine:
            self._walls = phase_wall_functions(self.sim)
            # arrays also interpreted: the machine hands run_chunk a view of the rows
            self._buffer = np.empty(LAST_CHUNK * L.NCOL, dtype=np.float64)
            self._contacts = np.empty(CONTACT_ROWS * L.CCOL, dtype=np.float64)
            return
        self._walls = wall_functions(self.sim)
        if self.fixed:
            self._nears = near_functions(self.sim)
        if _jit.ENABLED:
            self._buffer = np.empty(LAST_CHUNK * L.NCOL, dtype=np.float64)
        else:
            self._buffer = [0.0] * (LAST_CHUNK * L.NCOL)

    def _call(self, rows: int, first: int = 0) -> tuple[int, int]:
        """``run_chunk`` (``run_chunk_fixed`` for method rk4) for up to ``rows`` impacts
        into the row buffer from row ``first`` on; compiled, through numba's dispatcher,
        whose first call in the run may compile (:func:`billiard.jit.compiling`)."""
        first_call = self._entry is None
        if first_call:
            from billiard.kernels.loop import run_chunk, run_chunk_fixed

            if self._walls is None:
                self._prepare()
            self._entry = run_chunk_fixed if self.fixed else run_chunk
            if self.machine:
                from billiard.kernels.machine import run_machine

                self._entry = run_machine
        out = self._rows_from(first)
        # the first call of a kernel for a wall table's type in this process may compile
        # it (with the notices); later ones, of any engine, load nothing
        key = (self._entry, getattr(self._walls, "numba_type", None))
        try:
            if key not in _CALLED:
                with _jit.compiling(self._entry):
                    result = self._result(self._entry(*self._arguments(out, rows)))
                _CALLED.add(key)
                return result
            return self._result(self._entry(*self._arguments(out, rows)))
        finally:
            if out is not self._buffer and isinstance(out, list):
                # interpreted, the rows went into a copy of the list's tail
                self._buffer[first * L.NCOL :] = out

    def _result(self, result: Any) -> tuple[int, int]:
        """(status, impact rows written) of a kernel call."""
        if self.machine:
            return int(result), int(self.ctx[L.MC_ROW])
        return result

    def _arguments(self, out: Any, rows: int) -> tuple:
        if self.machine:
            return (self.ctx, self.params, self._walls, out, rows, self._contacts, CONTACT_ROWS)
        if self.fixed:
            return (self.ctx, self.params, self._walls, self._nears, out, rows)
        return (self.ctx, self.params, self._walls, out, rows)

    def _chunk(self, rows: int, target: int, until: float) -> tuple[int, int, Exception | None]:
        """(status, rows written, the stop as a SimulationError or None)."""
        ctx = self.ctx
        before = int(ctx[L.EN_IMPACTS])
        ctx[L.EN_TARGET] = float(target)
        ctx[L.EN_UNTIL] = until
        self._sync_in()
        done = 0
        try:
            while True:
                try:
                    code, written = self._call(rows - done, done)
                    done += written
                    error = None
                    break
                except L.KernelError as exc:
                    if exc.args[0] != L.E_FOOT:
                        raise
                    # the fixed-step search asks for the curve's global nearest point:
                    # answered, the search runs again from its flight's start
                    done = int(ctx[L.EN_IMPACTS]) - before
                    answer_foot(ctx, self.sim.boundary)
        except (L.KernelError, ArithmeticError, ValueError) as exc:
            code, done = L.DONE, int(ctx[L.EN_IMPACTS]) - before
            error = self._stop(exc, done)
        finally:
            self._sync_out()
        return code, done, error

    def _rows_from(self, row: int) -> Any:
        """The row buffer from row ``row`` on."""
        if row == 0:
            return self._buffer
        return self._buffer[row * L.NCOL :]

    def _stop(self, exc: Exception, row: int) -> SimulationError:
        """The engine's stop for an exception out of the kernels, worded as the
        interpreted classes worded it (``row``: the row of the impact being made)."""
        ctx = self.ctx
        n, t_last, t = int(ctx[L.EN_IMPACTS]), float(ctx[L.EN_T]), float(ctx[L.EN_EVENT_T])
        if not isinstance(exc, L.KernelError):
            # only the equations' arithmetic faults are a documented stop (see step)
            if isinstance(exc, ValueError) and str(exc) != "math domain error":
                raise exc
            return SimulationError(
                f"numerical failure after impact {n} (t = {t_last:.9g} s): "
                f"{type(exc).__name__}: {exc}",
                Status.NUMERICAL_FAULT,
            )
        code = exc.args[0]
        if self.machine and ctx[L.MC_FLYING] == 0.0:
            return self._phase_stop(code)
        if code == L.E_NON_FINITE:
            from billiard.engine.event_step import check_finite

            try:
                check_finite(record_of(as_block(self._buffer, row, row + 1)[0].tolist()))
            except SimulationError as stop:
                return stop
            return SimulationError(
                f"non-finite state at impact {n + 1} (t = {t:.9g} s)", Status.NON_FINITE
            )
        if code == L.E_ESCAPED:
            escape = self.sim.scene.boundary.escape_height
            return SimulationError(
                f"ball escaped above escape_height = {escape!r} m "
                f"at t = {t:.9g} s after impact {n}",
                Status.ESCAPED,
            )
        if code == L.E_COLLAPSE:
            return self.pending_stop() or SimulationError("inelastic collapse", Status.COLLAPSE)
        text = stop_text(code, float(ctx[L.EN_ERR_VALUE]))
        if math.isnan(t):
            return SimulationError(f"{text} after impact {n} (t = {t_last:.9g} s)")
        return SimulationError(f"{text} at impact {n + 1} (t = {t:.9g} s)")

    def _phase_stop(self, code: int) -> SimulationError:
        """The stop out of the state machine's contact logic, worded as the engine's
        contact phases word it (:mod:`billiard.engine.contact_phases`)."""
        ctx, sim = self.ctx, self.sim
        n, t = int(ctx[L.EN_IMPACTS]), float(ctx[L.MC_FINAL])
        if code == L.E_AT_REST:
            held = ctx[L.MC_MODE] == L.M_HELD
            since = float(ctx[L.VX_RSINCE] if held else ctx[L.PH_RSINCE])
            sim.final_time = float(ctx[L.EN_T]) + since
            return BallAtRest(since)
        if code == L.E_PHASE_STEPS:
            return SimulationError(
                "the contact phase's step-size control failed (60 rejected steps)",
                Status.SOLVER_FAILED,
            )
        if code == L.E_PHASE_NON_FINITE:
            return SimulationError(
                "non-finite state at the end of a contact phase "
                f"(t = {float(ctx[L.EN_ERR_VALUE]):.9g} s)",
                Status.NON_FINITE,
            )
        if code == L.E_LEFT:
            xl, xr = sim.boundary.x_range
            return SimulationError(
                f"the ball left the container's range x in [{xl:.6g}, {xr:.6g}] m at "
                f"x = {float(ctx[L.EN_ERR_VALUE]):.6g} m, t = {t:.9g} s, after impact {n}",
                Status.ESCAPED,
            )
        if code == L.E_ESCAPED:
            escape = sim.scene.boundary.escape_height
            return SimulationError(
                f"ball escaped above escape_height = {escape!r} m "
                f"at t = {float(ctx[L.EN_EVENT_T]):.9g} s after impact {n}",
                Status.ESCAPED,
            )
        return SimulationError(stop_text(code, float(ctx[L.EN_ERR_VALUE])))

    # ------------------------------------------------------------------ step and run

    def step(self, until: float) -> Any:
        """``Simulation.step``: one impact, its record, or None after ``until``."""
        fault = self.pending_stop()
        if fault is not None:
            raise fault
        code, done, error = self._chunk(1, self.impacts + 1, until)
        while code == L.FULL and done == 0 and error is None:
            # a chunk returns after QUIET_STEPS contacts without impulse: go on
            fault = self.pending_stop()
            if fault is not None:
                raise fault
            code, done, error = self._chunk(1, self.impacts + 1, until)
        if error is not None:
            raise error
        if done == 0:
            return None
        self.sim.final_time = float(self.ctx[L.EN_T])
        return record_of(as_block(self._buffer, 0, 1)[0].tolist())

    def run(
        self,
        collisions: int,
        recorder: Any,
        progress: Callable[[int, int], None] | None,
        checkpoint: Callable[[Any], None] | None,
        request: StopRequest,
        until: float,
        on_record: Callable[[int], None] | None,
        *,
        next_save: float | None = None,
        interval: float = 1.0,
        final_progress: bool = True,
    ) -> tuple[Status | None, str | None]:
        """``Simulation.run`` in chunks; returns (status, stop reason). Under contact
        phases the run also ends after an impact that settles, with status None: the
        engine puts the ball in contact (and takes no checkpoint before that).

        Args:
            interval: wall-clock seconds between two checkpoints.
            next_save: when the first checkpoint is due (``time.monotonic``; default a
                checkpoint interval from now); the run leaves the next in ``next_save``.
            final_progress: report progress when the run ends.
        """
        sim, ctx = self.sim, self.ctx
        sink = rows_sink(recorder)
        monotonic = time.monotonic
        interval = interval if checkpoint is not None else math.inf
        if next_save is None:
            next_save = monotonic() + interval
        # chunks end at least as often as checkpoints are asked for (every impact when
        # the interval is zero): a checkpoint is taken at the end of a chunk
        fast = min(_FAST_CHUNK, interval)
        rows = FIRST_CHUNK if fast > 0.0 else 1
        status, reason = Status.COMPLETE, None
        try:
            while self.impacts < collisions:
                if request.signum:
                    raise RunInterrupted(request.signum)
                fault = self.pending_stop()
                if fault is not None:
                    raise fault
                start = self.impacts
                saved = ctx.copy()
                began = monotonic()
                t_before = float(ctx[L.EN_T])
                code, done, error = self._chunk(rows, min(collisions, start + rows), until)
                elapsed = monotonic() - began
                if done or float(ctx[L.EN_T]) != t_before:
                    # the last impact, or a contact without impulse after it (phases)
                    sim.final_time = float(ctx[L.EN_T])
                cut = self._hand_out(
                    recorder, sink, start, done, collisions, progress, on_record, request
                )
                if cut is not None:
                    self._redo(saved, rows, start, cut, until)
                    sim.final_time = float(ctx[L.EN_T])
                    raise RunInterrupted(request.signum)
                if error is not None:
                    raise error
                if code == L.TIME_LIMIT:
                    status = Status.TIME_LIMIT
                    sim.final_time = until
                    break
                if code == L.LAND:
                    status = None
                    break
                next_save, rows = self._chunk_ended(
                    checkpoint, next_save, interval, elapsed < fast, rows
                )
        except SimulationError as exc:
            # a ball at rest ends the run complete: a status, not a stop reason
            status, reason = exc.status, None if exc.status.finished else str(exc)
        finally:
            self.next_save = next_save
            if progress is not None and final_progress:
                progress(self.impacts, collisions)
        return status, reason

    def run_phases(
        self,
        collisions: int,
        recorder: Any,
        progress: Callable[[int, int], None] | None,
        checkpoint: Callable[[Any], None] | None,
        request: StopRequest,
        until: float,
        on_record: Callable[[int], None] | None,
        *,
        interval: float = 1.0,
    ) -> tuple[Status, str | None]:
        """``Simulation.run`` under contact phases on the state machine
        (:func:`billiard.kernels.machine.run_machine`), in chunks as :meth:`run`; the
        finished and cut phases go to the simulation's ``on_contact`` and
        ``on_contact_cut`` in the order the engine made them. Returns (status, stop
        reason); the simulation's ``final_time`` follows the run."""
        sim, ctx = self.sim, self.ctx
        sink = rows_sink(recorder)
        monotonic = time.monotonic
        interval = interval if checkpoint is not None else math.inf
        next_save = monotonic() + interval
        fast = min(_FAST_CHUNK, interval)
        rows = FIRST_CHUNK if fast > 0.0 else 1
        status, reason = Status.COMPLETE, None
        shown = monotonic()
        try:
            while self.impacts < collisions:
                if request.signum:
                    if ctx[L.MC_PHASE_ON] != 0.0:
                        self._cut_phase(until)
                    raise RunInterrupted(request.signum)
                fault = self.pending_stop()
                if fault is not None:
                    raise fault
                start = self.impacts
                saved = ctx.copy()
                began = monotonic()
                code, done, error = self._chunk(rows, min(collisions, start + rows), until)
                elapsed = monotonic() - began
                if error is not None:
                    self._flights_stopped()
                if error is None or not isinstance(error, BallAtRest):
                    sim.final_time = float(ctx[L.MC_FINAL])
                cut = self._hand_out(
                    recorder, sink, start, done, collisions, progress, on_record, request,
                    contacts=int(ctx[L.MC_CROW]),
                )  # fmt: skip
                if cut is not None:
                    self._redo(saved, rows, start, cut, until)
                    sim.final_time = float(ctx[L.MC_FINAL])
                    raise RunInterrupted(request.signum)
                if error is not None:
                    raise error
                if code == L.TIME_LIMIT:
                    status = Status.TIME_LIMIT
                    sim.final_time = until
                    break
                if code == L.IN_CONTACT:
                    span = sim.scene.run.contact_span
                    raise SimulationError(
                        f"no impact for run.contact_span = {span:g} s "
                        f"(t = {sim.final_time:.9g} s): the ball stays in contact",
                        Status.IN_CONTACT,
                    )
                if code == L.PAUSED:
                    # a long phase: progress about ten times a second
                    if progress is not None and monotonic() - shown >= 0.1:
                        shown = monotonic()
                        report_time(progress, float(ctx[L.EN_T] + ctx[L.PH_TAU]))
                        progress(self.impacts, collisions)
                    continue
                next_save, rows = self._chunk_ended(
                    checkpoint, next_save, interval, elapsed < fast, rows
                )
        except SimulationError as exc:
            # a ball at rest ends the run complete: a status, not a stop reason
            status, reason = exc.status, None if exc.status.finished else str(exc)
        return status, reason

    def _chunk_ended(
        self,
        checkpoint: Callable[[Any], None] | None,
        next_save: float,
        interval: float,
        fast: bool,
        rows: int,
    ) -> tuple[float, int]:
        """After a chunk that leaves the run going on: the checkpoint when one is due,
        the stop detected after its last impact (raised), and the next chunk's size
        (twice as many rows after a ``fast`` chunk). Returns (next_save, rows)."""
        if checkpoint is not None and time.monotonic() >= next_save:
            checkpoint(self.sim.state)
            next_save = time.monotonic() + interval
        fault = self.pending_stop()
        if fault is not None:
            raise fault
        if fast and rows < LAST_CHUNK:
            rows *= 2
        return next_save, rows

    def _flights_stopped(self) -> None:
        """A stop inside the machine's flights (``run_chunk``) after impacts they made:
        the run has reached the last of them (as flights that return say in MC_FINAL;
        loop.impact keeps MC_LAST_IMPACT)."""
        ctx = self.ctx
        if ctx[L.MC_FLYING] == 1.0 and ctx[L.EN_T] != ctx[L.MC_FLIGHT_FROM]:
            ctx[L.MC_FINAL] = ctx[L.EN_T]

    def _cut_phase(self, until: float) -> None:
        """A stop request inside a phase: its row, cut where it is (``end`` = ``cut``),
        goes to ``on_contact_cut``; the engine's state stays at the phase's start."""
        ctx = self.ctx
        ctx[L.MC_PHASE_ON] = 3.0  # machine.PHASE_CUT
        self._chunk(1, int(ctx[L.EN_IMPACTS]) + 1, until)
        self._hand_contacts(0, int(ctx[L.MC_CROW]))
        self.sim.final_time = float(self._contacts[3])  # t_end of the cut row

    def _hand_contacts(self, first: int, stop: int) -> None:
        """Contact rows ``first`` to ``stop`` as records, to the simulation's hooks."""
        sim = self.sim
        surfaces = sim.boundary.surfaces
        rows = self._contacts[first * L.CCOL : stop * L.CCOL].reshape(-1, L.CCOL).tolist()
        for row in rows:
            # the surfaces' indices in the row (b < 0: one wall); their wall codes here
            a, b = int(row[4]), int(row[5])
            other = surfaces[b].code if b >= 0 else NO_WALL
            record = ContactRecord(
                row[2], row[3], surfaces[a].code, L.MOTION_NAMES[int(row[6])],
                L.END_NAMES[int(row[7])], row[8], *row[9:19], other,
            )  # fmt: skip
            hook = sim.on_contact if row[0] == 0.0 else sim.on_contact_cut
            if hook is not None:
                hook(record)

    def _redo(self, saved: Any, rows: int, start: int, cut: int, until: float) -> None:
        """A stop request after impact start + cut of a chunk begun from ``saved``: back
        to the chunk's start and up to there again, so that the state matches the
        records handed out."""
        self.ctx[:] = saved
        self._sync_out()
        again, written, error = self._chunk(rows, start + cut, until)
        assert error is None and written == cut, (again, written, error)

    def _hand_out(
        self,
        recorder: Any,
        sink: Callable[[np.ndarray], None] | None,
        start: int,
        done: int,
        collisions: int,
        progress: Callable[[int, int], None] | None,
        on_record: Callable[[int], None] | None,
        request: StopRequest,
        contacts: int = 0,
    ) -> int | None:
        """Give the chunk's rows to the recorder and the hooks, in the order the
        one-impact loop calls them; returns the row after which a stop was requested
        (by a hook, before the chunk's last row), else None. ``contacts``: contact rows
        of the state machine, each handed out before the first impact after it."""
        buffer = self._buffer
        handed = 0
        i = 0
        while i < done:
            if on_record is not None:
                j = i + 1
            elif progress is not None:
                j = min(
                    done, (start + i) // _PROGRESS_EVERY * _PROGRESS_EVERY + _PROGRESS_EVERY - start
                )
            else:
                j = done
            if contacts:
                # the phases that ended before impact start + j
                last = handed
                cbuf = self._contacts
                while last < contacts and cbuf[last * L.CCOL + 1] < start + j:
                    last += 1
                self._hand_contacts(handed, last)
                handed = last
            block = as_block(buffer, i, j)
            if sink is not None:
                sink(block)
            else:
                for row in block.tolist():
                    recorder.append(record_of(row))
            n = start + j
            if on_record is not None:
                on_record(n)
            if progress is not None and n % _PROGRESS_EVERY == 0:
                report_time(progress, float(buffer[(j - 1) * L.NCOL + 1]))  # column 1: t
                progress(n, collisions)
            if request.signum and j < done:
                return j
            i = j
        if handed < contacts:
            self._hand_contacts(handed, contacts)
        return None
