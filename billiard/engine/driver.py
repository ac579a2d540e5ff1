"""The one engine's driver: the state vector ``ctx`` of a
:class:`~billiard.engine.simulation.Simulation` and the chunked calls into the
trajectory state machine (:func:`billiard.kernels.machine.run_machine`), which advances
every scene: impacts or contact phases, method ``event`` or ``rk4``, sampled or not.
Compiled by numba when it is there, interpreted otherwise (or with
``NUMBA_DISABLE_JIT=1``): one source either way. Python never steps the physics here;
it hands the rows the machine wrote to the recorder and the hooks, takes checkpoints,
reports progress and looks at stop requests.

A run (:meth:`Driver.run`) calls the machine chunk by chunk (64 impacts first, doubling
to 4096 while a chunk takes under 0.05 s) with one :class:`RunControl`. A stop request
seen after impact K of a chunk stops the run there: ``ctx`` goes back to the chunk's
start and the chunk runs again up to K, which reproduces the state after impact K bit
for bit (the run is deterministic). A fixed-step search (method ``rk4``) that needs the
curve's global nearest point (``E_FOOT``) is answered here
(:func:`billiard.models.rk4_locator.answer_foot`) and the machine goes on.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.engine.interrupt import RunInterrupted, StopRequest
from billiard.engine.progress import Progress, report_time
from billiard.errors import BallAtRest, SimulationError
from billiard.kernels import layout as L
from billiard.kernels.interpreted import engine_modules, kernel_errors, stop_text
from billiard.kernels.loop import FAULT_PRESSED
from billiard.kernels.rules import COLLAPSE_COUNT, COLLAPSE_SPAN, ZERO_FLIGHT_LIMIT
from billiard.models.rk4_locator import answer_foot
from billiard.runfile.npystream import NpyRecorder
from billiard.runfile.record import COLUMNS, NO_WALL, ContactRecord, MemoryRecorder, record_of
from billiard.runfile.rows import as_block
from billiard.runfile.stream import CsvRecorder
from billiard.status import Status

__all__ = [
    "FIRST_CHUNK",
    "LAST_CHUNK",
    "Driver",
    "RunControl",
    "check_finite",
    "pressed_stop",
    "rows_sink",
]

#: impacts of the first chunk of a run, and of the longest
FIRST_CHUNK = 64
LAST_CHUNK = 4096
#: contact rows of a chunk of the state machine
CONTACT_ROWS = 4096
#: sample rows of a chunk (``--sample``)
SAMPLE_ROWS = 16384
#: (kernel, wall table type) pairs this process has called (see Driver._call)
_CALLED: set[tuple[Any, Any]] = set()
#: a chunk that took less wall time (s) than this is followed by one twice as long
_FAST_CHUNK = 0.05
_PROGRESS_EVERY = 100
#: the fixed-step detection's memory between flights: the departures in a row, the feet
_FIXED_MEMORY = (
    slice(L.RK_DEPARTURES, L.RK_DEPARTURES + 1),
    slice(L.RK_FEET, L.RK_FEET + L.MAX_SURFACES),
)
# Floats of a record, by column name, for naming the culprit of a non-finite state.
_ROW_FLOATS = tuple(name for name in COLUMNS if name not in ("n", "regime", "wall"))


@dataclass
class RunControl:
    """What a run hands the driver besides the engine state: where rows go, when it
    ends, and what it reports on the way.

    Attributes:
        collisions: impact number to stop at (counted from the scene's start).
        recorder: gets ``append(record)`` (or ``append_rows``) for each impact.
        until: simulated time (s) at which the run ends (inf: none).
        progress: called as ``progress(n_done, collisions)`` every 100 impacts and
            about ten times a second in long phases.
        checkpoint: called with the engine state every ``interval`` seconds of wall time.
        request: the stop request a signal handler sets.
        on_record: called with the impact number after each record (tests, audits).
        interval: wall-clock seconds between two checkpoints.
    """

    collisions: int
    recorder: Any
    until: float = math.inf
    progress: Progress | None = None
    checkpoint: Callable[[Any], None] | None = None
    request: StopRequest = field(default_factory=StopRequest)
    on_record: Callable[[int], None] | None = None
    interval: float = 1.0


def rows_sink(recorder: Any) -> Callable[[np.ndarray], None] | None:
    """``recorder.append_rows`` when the recorder takes rows as arrays (and does not
    override ``append``, which then has to see every record), else None."""
    for base in (MemoryRecorder, CsvRecorder, NpyRecorder):
        if isinstance(recorder, base) and type(recorder).append is base.append:
            return recorder.append_rows
    return None


def pressed_stop(lid: bool, n: int, t: float) -> SimulationError:
    """The stop of a ball that meets a surface (``lid``: the lid) without impulse again
    and again while the clock no longer advances (``loop.no_impulse``): pressed against
    a surface that does not hold it (the lid holds a ball only where a vertical drive
    presses it against it: kernels/lid.py), the run would turn for ever at time t."""
    where = "the lid" if lid else "a wall"
    return SimulationError(
        f"no progress in simulated time: the ball is pressed against {where} and meets "
        f"it without impulse again and again ({COLLAPSE_COUNT} contacts within "
        f"{COLLAPSE_SPAN:g} s or {ZERO_FLIGHT_LIMIT} at one time) after impact {n} "
        f"(t = {t:.9g} s)",
        Status.COLLAPSE,
    )


def check_finite(record: Any) -> None:
    """Raise SimulationError naming the first non-finite quantity of an impact's record."""
    for name in _ROW_FLOATS:
        value = getattr(record, name)
        if not math.isfinite(value):
            raise SimulationError(
                f"non-finite state at impact {record.n} (t = {record.t:.9g} s): {name} = {value!r}",
                Status.NON_FINITE,
            )


class Driver:
    """The state vector of one ``Simulation`` and the calls into the state machine.

    Args:
        sim: the simulation (its scene objects: boundary, flight, locator, models).
        ctx: its state vector (a list of floats), constants and state written.
    """

    def __init__(self, sim: Any, ctx: list[float]):
        self.sim = sim
        p = sim.boundary.walls[0].p
        if _jit.ENABLED:
            self.ctx: Any = np.array(ctx, dtype=np.float64)
            self.params: Any = np.array(p, dtype=np.float64)
        else:
            self.ctx, self.params = ctx, p
        #: the sample flight's state: the flight model's constants, its own step
        #: proposal (:mod:`billiard.kernels.samples`)
        self.sctx: Any = self.ctx.copy()
        self.offsets = len(sim.boundary.offsets)
        self.fixed = sim.method == "rk4"
        #: when the next checkpoint is due (time.monotonic), as the latest run left it
        self.next_save = math.inf
        self._walls: Any = None
        self._nears: Any = None
        self._buffer: Any = None
        self._contacts: Any = None
        self._samples: Any = None
        self._interpreted = not _jit.ENABLED
        # the twin's KernelError, and the compiled package's (a class of its own)
        self._errors = (*kernel_errors(), L.KernelError)

    @property
    def interpreted(self) -> bool:
        """The engine runs interpreted: the same kernels' source as plain Python (the
        twin package :mod:`billiard.kernels.interpreted`), on a state vector of Python
        floats. Set it to compare a compiled run with an interpreted one bit for bit."""
        return self._interpreted

    @interpreted.setter
    def interpreted(self, value: bool) -> None:
        if value and isinstance(self.ctx, np.ndarray):
            self.ctx, self.sctx = self.ctx.tolist(), self.sctx.tolist()
        self._interpreted = bool(value) or not _jit.ENABLED
        self._walls = None

    def _modules(self) -> tuple[Any, Any, Any]:
        """(machine, loop, samples): compiled, or the interpreted twin's."""
        if self._interpreted and _jit.ENABLED:
            return engine_modules()
        from billiard.kernels import loop, machine, samples

        return machine, loop, samples

    # ------------------------------------------------------------------ counters

    @property
    def impacts(self) -> int:
        return int(self.ctx[L.EN_IMPACTS])

    def pending_stop(self) -> SimulationError | None:
        """The stop detected after the last impact (an inelastic collapse), which the
        next call raises; None when the run can go on."""
        ctx = self.ctx
        fault = ctx[L.EN_FAULT]
        if fault == 0.0:
            return None
        n, t = int(ctx[L.EN_IMPACTS]), float(ctx[L.EN_T])
        if fault == FAULT_PRESSED:
            j = int(ctx[L.EN_ERR_VALUE])
            return pressed_stop(self.sim.boundary.surfaces[j].kind == "lid", n, t)
        if fault == 2.0:
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

    def locator_memory(self) -> dict[str, list[float]]:
        """The fixed-step locator's memory in ``ctx`` as its ``memory()`` words it."""
        if self.fixed:
            locator = self.sim.locator
            for slots in _FIXED_MEMORY:
                locator.ctx[slots] = [float(x) for x in self.ctx[slots]]
        return self.sim.locator.memory()

    def set_locator_memory(self, memory: Any) -> None:
        """Check ``memory`` with the locator (ValueError) and put it into ``ctx``."""
        locator = self.sim.locator
        locator.restore_memory(memory)
        if self.fixed:
            for slots in _FIXED_MEMORY:
                self.ctx[slots] = locator.ctx[slots]

    # ------------------------------------------------------------------ calls

    def _prepare(self) -> None:
        from billiard.geometry.wall_functions import near_functions, phase_wall_functions

        _jit.notice()
        machine, _, samples = self._modules()
        self._run_machine = machine.run_machine
        self._pending_samples = machine.pending_samples
        self._start_flight_samples = samples.start_flight_samples
        sim = self.sim
        self._walls = phase_wall_functions(sim)
        self._nears = near_functions(sim)
        # arrays also interpreted: the machine hands the flights a view of the rows
        self._buffer = np.empty(LAST_CHUNK * L.NCOL, dtype=np.float64)
        self._contacts = np.empty(CONTACT_ROWS * L.CCOL, dtype=np.float64)
        self._samples = np.empty(SAMPLE_ROWS * L.SCOL, dtype=np.float64)

    def _call(self, crows: int) -> int:
        """One call of the state machine into the buffers from their rows MC_ROW,
        MC_CROW and SM_ROW on; compiled, through numba's dispatcher, whose first call in
        the process may compile it (:func:`billiard.jit.compiling`)."""
        if self._walls is None:
            self._prepare()
        run_machine = self._run_machine
        ctx = self.ctx
        arguments = (
            ctx, self.params, self._walls, self._nears, self._buffer, LAST_CHUNK,
            self._contacts, crows, self.sctx, self._samples, SAMPLE_ROWS,
        )  # fmt: skip
        # the first call for a wall table's type in this process may compile the machine
        # (with the notices); later ones, of any engine, load nothing
        key = (run_machine, getattr(self._walls, "numba_type", None))
        if key not in _CALLED and not self._interpreted:
            with _jit.compiling(run_machine):
                code = run_machine(*arguments)
            _CALLED.add(key)
            return int(code)
        return int(run_machine(*arguments))

    def _chunk(
        self, rows: int, target: int, until: float, crows: int = CONTACT_ROWS
    ) -> tuple[int, Exception | None]:
        """Run the machine up to impact ``target`` (at most ``rows`` impact rows) or one
        buffer full (``crows`` contact rows); returns (status, the stop as a
        SimulationError or None). The rows written are counted in MC_ROW, MC_CROW and
        SM_ROW from zero."""
        ctx = self.ctx
        before = int(ctx[L.EN_IMPACTS])
        ctx[L.EN_TARGET] = float(min(target, before + rows))
        ctx[L.EN_UNTIL] = until
        ctx[L.MC_ROW] = ctx[L.MC_CROW] = ctx[L.SM_ROW] = 0.0
        try:
            while True:
                try:
                    return self._call(crows), None
                except self._errors as exc:
                    if exc.args[0] != L.E_FOOT:
                        raise
                    # the fixed-step search asks for the curve's global nearest point:
                    # answered, the search runs again from its flight's start
                    ctx[L.MC_ROW] = float(int(ctx[L.EN_IMPACTS]) - before)
                    answer_foot(ctx, self.sim.boundary)
        except (*self._errors, ArithmeticError, ValueError) as exc:
            ctx[L.MC_ROW] = float(int(ctx[L.EN_IMPACTS]) - before)
            return L.DONE, self._stop(exc)

    def _stop(self, exc: Exception) -> SimulationError:
        """The engine's stop for an exception out of the kernels."""
        ctx = self.ctx
        n, t_last, t = int(ctx[L.EN_IMPACTS]), float(ctx[L.EN_T]), float(ctx[L.EN_EVENT_T])
        if not isinstance(exc, self._errors):
            # only the equations' arithmetic faults are a documented stop: overflow,
            # division by zero, and math's domain error (the square root or logarithm of
            # a negative number). Any other ValueError is a bug and surfaces as one.
            if isinstance(exc, ValueError) and str(exc) != "math domain error":
                raise exc
            return SimulationError(
                f"numerical failure after impact {n} (t = {t_last:.9g} s): "
                f"{type(exc).__name__}: {exc}",
                Status.NUMERICAL_FAULT,
            )
        code = exc.args[0]
        if ctx[L.MC_FLYING] == 0.0:
            return self._phase_stop(code)
        if code in (L.E_ESCAPED, L.E_NON_FINITE) and ctx[L.SM_DT] > 0.0:
            # the flight's samples up to the event (handed out before the stop)
            self._start_flight_samples(ctx, self.sctx, t)
            ctx[L.SM_AFTER] = -1.0
        if code == L.E_NON_FINITE:
            row = int(ctx[L.MC_ROW])
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
        """The stop out of the state machine's contact logic."""
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

    def _flights_stopped(self) -> None:
        """A stop inside the machine's flights after impacts they made: the run has
        reached the last of them (as flights that return say in MC_FINAL)."""
        ctx = self.ctx
        if ctx[L.MC_FLYING] == 1.0 and ctx[L.EN_T] != ctx[L.MC_FLIGHT_FROM]:
            ctx[L.MC_FINAL] = ctx[L.EN_T]

    # ------------------------------------------------------------------ hand-out

    def _hand_contacts(self, first: int, stop: int) -> None:
        """Contact rows ``first`` to ``stop`` as records, to the simulation's hooks."""
        sim = self.sim
        surfaces = sim.boundary.surfaces
        rows = self._contacts[first * L.CCOL : stop * L.CCOL].reshape(-1, L.CCOL).tolist()
        for row in rows:
            # the surfaces' indices in the row (b < 0: one wall); their wall codes here
            wall, other = _row_walls(surfaces, row[4], row[5])
            record = ContactRecord(
                row[2], row[3], wall, L.MOTION_NAMES[int(row[6])],
                L.END_NAMES[int(row[7])], row[8], *row[9:19], other,
            )  # fmt: skip
            hook = sim.on_contact if row[0] == 0.0 else sim.on_contact_cut
            if hook is not None:
                hook(record)

    def _hand_samples(self, first: int, stop: int) -> None:
        """Sample rows ``first`` to ``stop`` to the simulation's ``on_sample``."""
        on_sample = self.sim.on_sample
        if on_sample is None or stop <= first:
            return
        names = L.MOTION_NAMES
        rows = self._samples[first * L.SCOL : stop * L.SCOL].reshape(-1, L.SCOL).tolist()
        for t, q1, q2, u1, u2, u3, energy, mode in rows:
            on_sample(t, q1, q2, u1, u2, u3, energy, names[int(mode)])

    def _samples_before(self, first: int, stop: int, t: float) -> int:
        """The first sample row from ``first`` (before ``stop``) later than t (s)."""
        buf = self._samples
        while first < stop and buf[first * L.SCOL] <= t:
            first += 1
        return first

    def _drain(self) -> None:
        """Finish a pending emission of samples, handing them out as the buffer fills
        (before a stop: the samples up to the state's time are the state's)."""
        ctx = self.ctx
        while ctx[L.SM_PENDING] != 0.0:
            ctx[L.SM_ROW] = 0.0
            self._pending_samples(
                ctx, self.params, self._walls, self.sctx, self._samples, SAMPLE_ROWS
            )
            self._hand_samples(0, int(ctx[L.SM_ROW]))
        ctx[L.SM_ROW] = 0.0

    def _hand_out(
        self, control: RunControl, sink: Any, start: int, done: int, contacts: int, samples: int
    ) -> int | None:
        """Give the chunk's rows to the recorder and the hooks in the order of time:
        each impact after the samples up to its time and the contact phases that ended
        before it. Returns the row after which a stop was requested (by a hook, before
        the chunk's last row, or while the samples before a row or after the last were
        handed out: then the row before them), else None."""
        buffer = self._buffer
        progress, on_record = control.progress, control.on_record
        handed = handed_samples = 0
        i = 0
        while i < done:
            if on_record is not None or samples:
                # one impact a block: a stop among the samples lands on the impact before
                j = i + 1
            elif progress is not None:
                j = min(
                    done, (start + i) // _PROGRESS_EVERY * _PROGRESS_EVERY + _PROGRESS_EVERY - start
                )
            else:
                j = done
            if samples:
                last = self._samples_before(handed_samples, samples, buffer[(j - 1) * L.NCOL + 1])
                self._hand_samples(handed_samples, last)
                handed_samples = last
                if control.request.signum:
                    # a stop among the samples before this block: the state before it
                    return i
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
                    control.recorder.append(record_of(row))
            n = start + j
            if on_record is not None:
                on_record(n)
            if progress is not None and n % _PROGRESS_EVERY == 0:
                report_time(progress, float(buffer[(j - 1) * L.NCOL + 1]))  # column 1: t
                progress(n, control.collisions)
            if control.request.signum and j < done:
                return j
            i = j
        if handed_samples < samples:
            self._hand_samples(handed_samples, samples)
            if control.request.signum and done:
                # a stop among the samples after the last impact: the state after it
                return done
        if handed < contacts:
            self._hand_contacts(handed, contacts)
        return None

    def _redo(self, saved: Any, saved_samples: Any, start: int, cut: int, until: float) -> None:
        """A stop request after impact start + cut of a chunk begun from ``saved``: back
        to the chunk's start and up to there again, so that the state matches the
        records handed out."""
        self.ctx[:] = saved
        self.sctx[:] = saved_samples
        while True:
            code, error = self._chunk(cut, start + cut, until)
            assert error is None, error
            if self.impacts == start + cut and self.ctx[L.SM_PENDING] == 0.0:
                return
            assert code in (L.PAUSED, L.SAMPLES_FULL, L.CONTACTS_FULL, L.FULL), code

    def _cut_phase(self, until: float) -> None:
        """A stop request inside a phase or a sampled hold: its row, cut where it is
        (``end`` = ``cut``), goes to ``on_contact_cut``; the engine's state stays at
        the phase's start."""
        ctx = self.ctx
        ctx[L.MC_PHASE_ON] = 3.0  # machine.PHASE_CUT
        self._chunk(1, int(ctx[L.EN_IMPACTS]) + 1, until)
        self._hand_contacts(0, int(ctx[L.MC_CROW]))
        self.sim.final_time = float(self._contacts[3])  # t_end of the cut row

    # ------------------------------------------------------------------ step and run

    def step(self, until: float) -> Any:
        """``Simulation.step``: the next event (an impact, or under contact phases the
        end of a phase), its record, or None after ``until``."""
        fault = self.pending_stop()
        if fault is not None:
            raise fault
        ctx, sim = self.ctx, self.sim
        start = self.impacts
        while True:
            code, error = self._chunk(1, start + 1, until, crows=1)
            self._hand_samples(0, int(ctx[L.SM_ROW]))
            done, contacts = int(ctx[L.MC_ROW]), int(ctx[L.MC_CROW])
            if error is not None:
                self._flights_stopped()
                self._drain()
                self._hand_contacts(0, contacts)
                if not isinstance(error, BallAtRest):
                    sim.final_time = float(ctx[L.MC_FINAL])
                raise error
            if done or contacts or code in (L.TIME_LIMIT, L.IN_CONTACT):
                break
            if code in (L.DONE, L.COLLAPSE):
                # a pressed ball's stop detected without an impact
                fault = self.pending_stop()
                if fault is not None:
                    raise fault
        self._drain()
        self._hand_contacts(0, contacts)
        # the time reached: the event's, or where a chatter series ended before a cut
        sim.final_time = float(ctx[L.MC_FINAL])
        if done:
            return record_of(as_block(self._buffer, 0, 1)[0].tolist())
        if code == L.IN_CONTACT:
            raise self._in_contact()
        if code == L.TIME_LIMIT or self._contacts[0] != 0.0:
            # the run's end first (a phase under way cut there: on_contact_cut)
            return None
        rows = self._contacts[: L.CCOL].tolist()
        surfaces = sim.boundary.surfaces
        wall, other = _row_walls(surfaces, rows[4], rows[5])
        return ContactRecord(
            rows[2], rows[3], wall, L.MOTION_NAMES[int(rows[6])],
            L.END_NAMES[int(rows[7])], rows[8], *rows[9:19], other,
        )  # fmt: skip

    def _in_contact(self) -> SimulationError:
        span = self.sim.scene.run.contact_span
        return SimulationError(
            f"no impact for run.contact_span = {span:g} s "
            f"(t = {self.sim.final_time:.9g} s): the ball stays in contact",
            Status.IN_CONTACT,
        )

    def run(self, control: RunControl) -> tuple[Status, str | None]:
        """``Simulation.run`` in chunks; returns (status, stop reason). The finished
        and cut phases go to the simulation's ``on_contact`` and ``on_contact_cut``, the
        samples to its ``on_sample``, in the order of time; the simulation's
        ``final_time`` follows the run."""
        sim, ctx = self.sim, self.ctx
        request, until, collisions = control.request, control.until, control.collisions
        sink = rows_sink(control.recorder)
        monotonic = time.monotonic
        interval = control.interval if control.checkpoint is not None else math.inf
        next_save = monotonic() + interval
        # chunks end at least as often as checkpoints are asked for (every impact when
        # the interval is zero): a checkpoint is taken at the end of a chunk
        fast = min(_FAST_CHUNK, interval)
        rows = FIRST_CHUNK if fast > 0.0 else 1
        status, reason = Status.COMPLETE, None
        shown = monotonic()
        try:
            while self.impacts < collisions:
                if request.signum:
                    self._drain()
                    if ctx[L.MC_PHASE_ON] != 0.0 or ctx[L.MC_HOLD_ON] != 0.0:
                        self._cut_phase(until)
                    raise RunInterrupted(request.signum)
                fault = self.pending_stop()
                if fault is not None:
                    raise fault
                start = self.impacts
                saved, saved_samples = ctx.copy(), self.sctx.copy()
                began = monotonic()
                code, error = self._chunk(rows, min(collisions, start + rows), until)
                elapsed = monotonic() - began
                if error is not None:
                    self._flights_stopped()
                if error is None or not isinstance(error, BallAtRest):
                    sim.final_time = float(ctx[L.MC_FINAL])
                done = int(ctx[L.MC_ROW])
                cut = self._hand_out(
                    control, sink, start, done, int(ctx[L.MC_CROW]), int(ctx[L.SM_ROW])
                )
                if cut is not None:
                    self._redo(saved, saved_samples, start, cut, until)
                    sim.final_time = float(ctx[L.MC_FINAL])
                    if ctx[L.MC_PHASE_ON] != 0.0 or ctx[L.MC_HOLD_ON] != 0.0:
                        # back at a chunk's start inside a phase: cut it there
                        self._cut_phase(until)
                    raise RunInterrupted(request.signum)
                if error is not None:
                    self._drain()
                    raise error
                if code == L.TIME_LIMIT:
                    status = Status.TIME_LIMIT
                    sim.final_time = until
                    break
                if code == L.IN_CONTACT:
                    raise self._in_contact()
                if code in (L.PAUSED, L.SAMPLES_FULL):
                    # a long phase, or a buffer of samples: progress ten times a second
                    if control.progress is not None and monotonic() - shown >= 0.1:
                        shown = monotonic()
                        tau = ctx[L.PH_TAU] if ctx[L.MC_PHASE_ON] != 0.0 else 0.0
                        report_time(control.progress, float(ctx[L.EN_T] + tau))
                        control.progress(self.impacts, collisions)
                    if code == L.PAUSED or monotonic() < next_save:
                        continue
                next_save, rows = self._chunk_ended(
                    control.checkpoint, next_save, interval, elapsed < fast, rows
                )
        except SimulationError as exc:
            # a ball at rest ends the run complete: a status, not a stop reason
            status, reason = exc.status, None if exc.status.finished else str(exc)
        finally:
            self.next_save = next_save
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
        if checkpoint is not None and time.monotonic() >= next_save and self.checkpointable():
            checkpoint(self.sim.state)
            next_save = time.monotonic() + interval
        fault = self.pending_stop()
        if fault is not None:
            raise fault
        if fast and rows < LAST_CHUNK:
            rows *= 2
        return next_save, rows

    def checkpointable(self) -> bool:
        """Is the engine between two events (no phase, hold or emission under way),
        where its state is an EngineState?"""
        ctx = self.ctx
        return ctx[L.MC_PHASE_ON] == 0.0 and ctx[L.MC_HOLD_ON] == 0.0 and ctx[L.SM_PENDING] == 0.0


def _row_walls(surfaces: Any, a: float, b: float) -> tuple[int, int]:
    """The ``wall`` and ``wall_other`` of a contact row whose surfaces are a and b: held
    by two (b >= 0), their codes; on one wall w (b = ONE_WALL - w, see
    :func:`billiard.kernels.machine.contact_row`), w itself, the piece of a chain."""
    if b >= 0.0:
        return surfaces[int(a)].code, surfaces[int(b)].code
    if b <= -2.0:
        return int(-2.0 - b), NO_WALL
    return surfaces[int(a)].code, NO_WALL
