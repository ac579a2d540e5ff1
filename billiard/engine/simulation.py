"""The engine: a simulation built from a scene, advanced one event at a time.

>>> from billiard import Simulation, load_scene
>>> sim = Simulation(load_scene("wedge-6.6hz"))
>>> record = sim.step()          # the next impact, as an ImpactRecord  # doctest: +SKIP
>>> sim.state.impacts            # the complete engine state  # doctest: +SKIP

:meth:`Simulation.step` is the one kernel under every run and analysis (as
``OdeSolver.step`` in scipy, ``bounce!`` in DynamicalBilliards.jl): it locates the next
impact with the scene's locator, applies the impact law, and returns one record.
:meth:`Simulation.run` is a thin loop over it that appends records to a recorder and
looks after progress, checkpoints and stop requests.

A run is deterministic: the same scene gives the same records bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any, NamedTuple

from billiard.engine.contact_phases import (
    COLLAPSE_COUNT,
    COLLAPSE_SPAN,
    ZERO_FLIGHT_LIMIT,
    ContactPhases,
)
from billiard.engine.ctx import write_motion
from billiard.engine.event_step import EventStep
from billiard.engine.interrupt import RunInterrupted, StopRequest
from billiard.engine.kernel_engine import KernelEngine, supports
from billiard.engine.progress import Progress, report_time
from billiard.engine.state import BallState, EngineState
from billiard.errors import GeometryError, SimulationError
from billiard.geometry.boundary import Boundary, Drive
from billiard.geometry.curves import load_curve
from billiard.kernels import layout as L
from billiard.models.contact import ContactModel
from billiard.models.flight import flight_model
from billiard.models.hold import VertexHold
from billiard.models.impact import ImpactLaw, impact_law
from billiard.models.locators import LOCATORS
from billiard.runfile.checkpoint import CheckpointError
from billiard.runfile.record import ContactRecord, ImpactRecord
from billiard.scene.scene import SceneError, with_values
from billiard.status import Status

__all__ = ["COLLAPSE_COUNT", "COLLAPSE_SPAN", "ZERO_FLIGHT_LIMIT", "Simulation"]

_PROGRESS_EVERY = 100
#: Wall-clock seconds between two checkpoints (and CSV flushes) of a streamed run.
CHECKPOINT_INTERVAL = 1.0


class Settled(NamedTuple):
    """What landing needs of the impact that settles (``ImpactResult``'s fields)."""

    u1: float
    u2: float
    u3: float
    regime: str
    wn: float


class Simulation(ContactPhases, EventStep):
    """Everything a run needs, built and validated from a scene, and the engine state.

    Args:
        scene: a :class:`billiard.scene.scene.Scene`.
        method: ``"event"`` or ``"rk4"`` (a key of :data:`billiard.models.event_locator.LOCATORS`);
            default ``scene.run.method``.
        law: the impact law; default the scene's (:func:`billiard.models.impact.impact_law`).

    Raises:
        GeometryError: the ball is too large for the boundary's curvature, the curve
            has no bottom to rest on, or the initial position overlaps the wall or lid.
        SceneError: an unknown method, or a curve parameter the curve does not have.
    """

    def __init__(self, scene: Any, method: str | None = None, law: ImpactLaw | None = None):
        self.scene = scene
        self.method = method or scene.run.method
        if self.method not in LOCATORS:
            raise SceneError(
                f"unknown method {self.method!r}: choose from {', '.join(map(repr, LOCATORS))}"
            )
        try:
            self.curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
        except ValueError as exc:
            if type(exc) is not ValueError:  # the curve modules' own errors say what failed
                raise
            # a parameter the named curve does not have: bad input, not a crash
            raise SceneError(str(exc)) from None
        self.boundary = Boundary.from_scene(scene, self.curve.walls)
        self.drive: Drive = self.boundary.drive
        self.flight = flight_model(scene, self.method)
        #: warm starts of the offset inversion, one [s, slope] per surface: engine state
        #: passed to every geometry query (see billiard.geometry.surfaces)
        self.warm = self.boundary.initial_warm()
        self.locator = LOCATORS[self.method](
            self.boundary, self.flight, scene.run.gravity, self.warm
        )
        self.impact: ImpactLaw = law if law is not None else impact_law(scene)
        self.initial = self.initial_state()
        #: (m, r, k, g) of the energy formula, looked up once rather than per impact
        self._ball_constants = (
            scene.ball.mass,
            scene.ball.radius,
            scene.ball.inertia_factor,
            scene.run.gravity,
        )
        #: simulated time (s) at which a run ends (inf when the scene sets no duration)
        self.end_time = (
            math.inf if scene.run.duration is None else self.initial.t + scene.run.duration
        )
        #: the state vector when the engine runs on the kernels (see supports), else None
        self._kernel: KernelEngine | None = None
        self._counts: dict[str, int] = dict.fromkeys(self.impact.regimes, 0)
        self._counts["resting"] = 0
        self.final_time = self.initial.t
        #: how the latest :meth:`run` ended, and why (None while it goes on)
        self.status: Status | None = None
        self._fault: SimulationError | None = None
        #: ``contact.model = "phases"``: rolling and sliding phases besides impacts
        self.phases = getattr(scene.contact, "model", "impacts") == "phases"
        self.contact_model = ContactModel(scene, self.drive) if self.phases else None
        #: the ball held by two walls at once (the wedge's vertex)
        self.vertex_hold = VertexHold(self.contact_model) if self.phases else None
        #: called with each finished contact phase's record (contacts.csv)
        self.on_contact: Callable[[ContactRecord], None] | None = None
        #: called with the record of the phase in progress when a run ends inside it
        #: (``end`` = ``cut``); the engine's state stays at that phase's start
        self.on_contact_cut: Callable[[ContactRecord], None] | None = None
        #: while :meth:`run` runs: its stop request, and the pause of long contact
        #: phases (the stop request looked at, progress reported)
        self._request: StopRequest | None = None
        self._pause: Callable[[float], bool] | None = None
        #: sampling: every ``sample_dt`` seconds of simulated time from the start,
        #: ``on_sample(t, q1, q2, v1, v2, omega, energy, mode)`` (trajectory.csv)
        self.sample_dt: float | None = None
        self.on_sample: Callable[..., None] | None = None
        self._sample_flight = flight_model(scene, self.method)
        self.reset()
        if supports(self) is None:
            self._kernel = KernelEngine(self)
        #: contact phases: the kernels that run the flights between them (see fly)
        self._flights: KernelEngine | None = None
        if self.phases and supports(self, flights=True) is None:
            self._flights = KernelEngine(self)

    # ------------------------------------------------------------------ set-up

    def initial_state(self) -> BallState:
        """The scene's initial state; a missing q2 puts the ball at rest on the bottom
        (at the lowest admissible point, or below a given q1)."""
        init = self.scene.initial
        theta = self.drive.angle(init.t)
        q1, q2 = init.q1, init.q2
        if q2 is None:
            if q1 is None:
                x, y = self.boundary.resting_position(self.warm)
                xl, xr = self.boundary.x_range
                if not xl < x < xr:
                    raise GeometryError(
                        f"the boundary curve has no bottom to rest on: its lowest point in "
                        f"reach is at the edge of the container, x = {x:.4g} m (the curve must "
                        f"rise on both sides); give initial.q1 and initial.q2 to start elsewhere"
                    )
            else:
                x = self.drive.to_boundary_frame(theta, q1, 0.0, 0.0, 0.0)[0]
                y = self.boundary.offset_height(x, self.warm)
            q1, q2 = self.drive.to_lab_frame(theta, x, y)
            if init.q1 is not None:
                q1 = init.q1
        elif q1 is None:
            q1 = self.drive.to_lab_frame(theta, self.boundary.resting_position(self.warm)[0], 0.0)[
                0
            ]
        self.boundary.check_initial_position(q1, q2, theta, self.warm)
        return BallState(init.t, theta, q1, q2, init.v1, init.v2, init.omega, 0.0)

    def resolved_scene(self, collisions: int) -> Any:
        """The scene as run: initial position resolved, impact count and method set."""
        return with_values(
            self.scene,
            {
                "initial.q1": self.initial.q1,
                "initial.q2": self.initial.q2,
                "run.collisions": collisions,
                "run.method": self.method,
            },
        )

    # ------------------------------------------------------------------ engine state

    def reset(self, ball: BallState | None = None) -> None:
        """Start the event count afresh from ``ball`` (default: the scene's initial
        state), e.g. a state in flight or just after an impact. The components' memories
        (warm starts, step proposals) and the regime counters are kept."""
        ball = self.initial if ball is None else ball
        self._ball = ball.copy()
        self._impacts = 0
        # The clock is a sum of tens of thousands of flight times: keep it with
        # Neumaier's compensated summation so that t stays the correctly rounded sum
        # (a plain sum drifts by ~1e-13 s, ~1e-12 rad of drive phase, by 3000 impacts).
        self._clock, self._clock_error = ball.t, 0.0
        self._zero_flights = 0
        self._recent: deque[float] = deque(maxlen=COLLAPSE_COUNT + 1)
        self._fault = None
        self._mode = "flight"
        #: in contact: (surface index, s, s_dot, slip sign, phase start t, settle t)
        self._contact: tuple[float, ...] = ()
        self._samples = 0
        self._phase_time = {"roll": 0.0, "slide": 0.0, "held": 0.0}
        self._last_impact = ball.t
        if self._kernel is not None:
            self._kernel.reset(ball)
        if self.phases:
            self._start_in_contact()

    @property
    def counts(self) -> dict[str, int]:
        """Impacts per regime of the impact law, and resting relaunches."""
        if self._kernel is not None:
            return self._kernel.counts()
        return self._counts

    @counts.setter
    def counts(self, value: dict[str, int]) -> None:
        self._counts = dict(value)
        if self._kernel is not None:
            self._kernel.set_counts(self._counts)

    @property
    def ball(self) -> BallState:
        """The ball after the last event (a copy)."""
        if self._kernel is not None:
            return self._kernel.state().ball
        return self._ball.copy()

    @property
    def pending_stop(self) -> SimulationError | None:
        """The stop detected after the last impact (an inelastic collapse), which the
        next :meth:`step` raises; None when the run can go on."""
        if self._kernel is not None:
            return self._kernel.pending_stop()
        return self._fault

    @property
    def state(self) -> EngineState:
        """The complete engine state after the last event (a snapshot)."""
        if self._kernel is not None:
            # the ball, clock and counters live in the kernels' state vector; the warm
            # starts and the step proposal belong to sim.warm and sim.flight
            return dataclasses.replace(self._kernel.state(), **self._held_state())
        return self._python_state()

    def _object_state(self) -> dict[str, Any]:
        """The parts of the engine state the Python objects hold in every engine (the
        state machine holds the motion state itself)."""
        return {
            "walls": tuple((w[0], w[1]) for w in self.warm[: len(self.boundary.offsets)]),
            "flight": self.flight.memory(),
            "locator": self.locator.memory(),
            "samples": self._samples,
        }

    def _held_state(self) -> dict[str, Any]:
        """The parts of the engine state the Python objects hold in either engine."""
        if self._kernel is not None and self._kernel.machine:
            return self._object_state()
        return {
            **self._object_state(),
            "mode": self._mode,
            "contact": self._contact,
            "phase_time": dict(self._phase_time),
            "last_impact": self._last_impact if self.phases else None,
        }

    def _python_state(self) -> EngineState:
        return EngineState(
            ball=self._ball.copy(),
            impacts=self._impacts,
            clock=self._clock,
            clock_error=self._clock_error,
            zero_flights=self._zero_flights,
            recent=tuple(self._recent),
            counts=dict(self._counts),
            **self._held_state(),
        )

    def start_state(self) -> EngineState:
        """The engine state before the first impact of the scene."""
        self.reset()
        return self.state

    def restore(self, state: EngineState) -> None:
        """Put the engine where ``state`` says.

        Raises:
            CheckpointError: the state was not made by an engine of this scene.
        """
        offsets = self.boundary.offsets
        if len(state.walls) != len(offsets):
            raise CheckpointError(
                f"its engine state has {len(state.walls)} walls, the scene's curve {len(offsets)}"
            )
        if set(state.counts) != set(self.counts):
            raise CheckpointError("its engine state has the wrong regime counters")
        try:
            self.flight.restore_memory(state.flight)
            self.locator.restore_memory(state.locator)
        except ValueError as exc:
            raise CheckpointError(f"its engine state does not fit this engine: {exc}") from None
        for warm, (s, slope) in zip(self.warm, state.walls, strict=False):
            warm[0], warm[1] = s, slope
        self._counts = dict(state.counts)
        self._ball = state.ball.copy()
        self._impacts = state.impacts
        self._clock, self._clock_error = state.clock, state.clock_error
        self._zero_flights = state.zero_flights
        self._recent = deque(state.recent, maxlen=COLLAPSE_COUNT + 1)
        self._fault = None
        self.final_time = state.ball.t
        self._mode = state.mode
        self._contact = tuple(state.contact)
        self._samples = state.samples
        self._phase_time = {"roll": 0.0, "slide": 0.0, "held": 0.0, **state.phase_time}
        self._last_impact = state.ball.t if state.last_impact is None else state.last_impact
        if self._kernel is not None:
            self._kernel.restore(state)

    # ------------------------------------------------------------------ one event
    def step(self, until: float = math.inf) -> ImpactRecord | None:
        """Advance the engine to the next impact and return its record.

        Args:
            until: simulated time (s): when the next impact comes after it, nothing
                changes and None is returned.

        Raises:
            SimulationError: a documented stop (``.status`` says which): the ball
                escaped, a search failed, a non-finite state, an arithmetic fault in the
                equations, or an inelastic collapse detected after the previous impact.
                The state is left as it was after the previous impact.
        """
        kernel = self._engine()
        if kernel is not None:
            return kernel.step(until)
        if self._fault is not None:
            raise self._fault
        try:
            return self._step(until)
        except (ArithmeticError, ValueError) as exc:
            # Only the equations' arithmetic faults are a documented stop: overflow,
            # division by zero, and math's domain error (the square root or logarithm of
            # a negative number). Any other ValueError is a bug and surfaces as one.
            if isinstance(exc, ValueError) and str(exc) != "math domain error":
                raise
            raise SimulationError(
                f"numerical failure after impact {self._impacts} "
                f"(t = {self._ball.t:.9g} s): {type(exc).__name__}: {exc}",
                Status.NUMERICAL_FAULT,
            ) from None

    @property
    def kernel_engine(self) -> KernelEngine | None:
        """The compiled kernels' engine this simulation runs on (its state vector
        ``ctx``), or None while it runs on the models' classes."""
        return self._kernel

    def _engine(self) -> KernelEngine | None:
        """The kernels, while they can run this simulation: an impact law replaced after
        construction (an audit wrapping it) or trajectory sampling, which the kernels do
        not do, hand the state over to the classes for good."""
        kernel = self._kernel
        if kernel is not None and (self.impact is not kernel.law or self.on_sample is not None):
            state, fault, final_time = self.state, kernel.pending_stop(), self.final_time
            self._kernel = None
            self.restore(state)
            self._fault, self.final_time = fault, final_time
        return self._kernel

    # ------------------------------------------------------------------ the loop

    def run(
        self,
        collisions: int,
        recorder: Any,
        progress: Progress | None = None,
        *,
        start: EngineState | None = None,
        checkpoint: Callable[[EngineState], None] | None = None,
        stop: StopRequest | None = None,
        until: float | None = None,
        on_record: Callable[[int], None] | None = None,
    ) -> str | None:
        """Step until ``collisions`` impacts (or ``until``), appending each record to
        ``recorder``. Returns None, or the one-line reason the run stopped early;
        ``self.status`` says how it ended.

        Args:
            collisions: impact number to stop at (counted from the scene's start, so a
                run continued from ``start`` does ``collisions - start.impacts`` more).
            recorder: gets ``append(record)`` for each impact.
            progress: called as ``progress(n_done, collisions)`` every few impacts.
            start: continue from this engine state (default: from the current one).
            checkpoint: called with the engine state after the last appended record,
                about every ``CHECKPOINT_INTERVAL`` seconds of wall-clock time.
            stop: a stop request set by a signal handler: the loop ends at the next
                impact boundary by raising :class:`RunInterrupted`.
            until: simulated time (s) at which the run ends; default ``self.end_time``.
            on_record: called with the impact number after each record is appended
                (a hook for tests and audits).
        """
        if start is not None:
            self.restore(start)
        until = self.end_time if until is None else until
        request = stop if stop is not None else StopRequest()
        kernel = self._engine()
        if kernel is not None:
            self.status = None
            self.status, reason = kernel.run(
                collisions, recorder, progress, checkpoint, request, until, on_record,
                interval=CHECKPOINT_INTERVAL,
            )  # fmt: skip
            return reason
        monotonic = time.monotonic
        next_save = monotonic() + CHECKPOINT_INTERVAL if checkpoint is not None else math.inf
        self.status = None
        self._request = request
        self._pause = self._pause_for(request, progress, collisions)
        reason: str | None = None
        status = Status.COMPLETE
        # the flights between contact phases run on the kernels, as long as nothing
        # needs the classes (trajectory samples, an impact law replaced)
        flights = self._flights
        if flights is not None and (self.on_sample is not None or self.impact is not flights.law):
            flights = None
        if flights is not None and flights.machine:
            self._request = self._pause = None
            return self._run_machine(
                flights, collisions, recorder, progress, checkpoint, request, until, on_record
            )
        try:
            while self._impacts < collisions:
                # a signal arrived: stop here, where the state matches the records exactly
                if request.signum:
                    raise RunInterrupted(request.signum)
                if flights is not None and self._mode == "flight" and self._fault is None:
                    ended = self._fly(
                        flights, collisions, recorder, progress, checkpoint, request,
                        until, on_record, next_save, CHECKPOINT_INTERVAL,
                    )  # fmt: skip
                    next_save = flights.next_save
                    if ended is not None:
                        status, reason = ended
                        break
                    continue
                record = self.step(until)
                if record is None:
                    status = Status.TIME_LIMIT
                    self.final_time = until
                    break
                if type(record) is ContactRecord:
                    if self._fault is not None:
                        raise self._fault
                    continue
                recorder.append(record)
                n = record.n
                if on_record is not None:
                    on_record(n)
                if progress is not None and n % _PROGRESS_EVERY == 0:
                    progress(n, collisions)
                if checkpoint is not None and monotonic() >= next_save:
                    checkpoint(self.state)
                    next_save = monotonic() + CHECKPOINT_INTERVAL
                if self._fault is not None:
                    raise self._fault
        except SimulationError as exc:
            # a ball at rest ends the run complete: a status, not a stop reason
            status, reason = exc.status, None if exc.status.finished else str(exc)
        finally:
            self._request = self._pause = None
            if progress is not None:
                report_time(progress, self.final_time)
                progress(self._impacts, collisions)
        self.status = status
        return reason

    def _pause_for(
        self, request: StopRequest, progress: Progress | None, collisions: int
    ) -> Callable[[float], bool]:
        """The pause of a long contact phase (every few thousand steps): True stops it
        (a stop request arrived); progress is reported about ten times a second with
        the simulated time reached (``tau`` after the phase's start)."""
        monotonic = time.monotonic
        last = [monotonic()]

        def pause(tau: float) -> bool:
            if request.signum:
                return True
            if progress is not None and monotonic() - last[0] >= 0.1:
                last[0] = monotonic()
                report_time(progress, self._ball.t + tau)
                progress(self._impacts, collisions)
            return False

        return pause

    # ------------------------------------------------------------------ the state machine
    def _run_machine(
        self,
        machine: Any,
        collisions: int,
        recorder: Any,
        progress: Progress | None,
        checkpoint: Callable[[EngineState], None] | None,
        request: StopRequest,
        until: float,
        on_record: Callable[[int], None] | None,
    ) -> str | None:
        """:meth:`run` under contact phases on the compiled state machine
        (:meth:`billiard.engine.kernel_engine.KernelEngine.run_phases`): the engine
        state goes into its state vector, and back when the run ends."""
        if self._fault is not None and self._impacts < collisions:
            # a stop detected before (the next step raises it)
            fault = self._fault
            self.status = fault.status
            return None if fault.status.finished else str(fault)
        state = self._python_state()
        machine.restore(state)
        write_motion(machine.ctx, state)
        machine.ctx[L.MC_FINAL] = self.final_time
        # while the machine runs, the engine's state is its (hooks and checkpoints see it)
        self._kernel = machine
        try:
            status, reason = machine.run_phases(
                collisions, recorder, progress, checkpoint, request, until, on_record,
                interval=CHECKPOINT_INTERVAL,
            )  # fmt: skip
        finally:
            self._kernel = None
            state = dataclasses.replace(machine.state(), **self._object_state())
            fault, final_time = machine.pending_stop(), self.final_time
            self.restore(state)
            self._fault, self.final_time = fault, final_time
            if progress is not None:
                report_time(progress, self.final_time)
                progress(self._impacts, collisions)
        self.status = status
        return reason

    # ------------------------------------------------------------------ flights on the kernels
    def _fly(
        self,
        flights: Any,
        collisions: int,
        recorder: Any,
        progress: Callable[[int, int], None] | None,
        checkpoint: Callable[[Any], None] | None,
        request: StopRequest,
        until: float,
        on_record: Callable[[int], None] | None,
        next_save: float,
        interval: float,
    ) -> tuple[Status, str | None] | None:
        """Fly the ball (in flight, no pending stop) on its kernels ``flights`` (a
        :class:`billiard.engine.kernel_engine.KernelEngine`) until an impact settles or the run
        ends; the arguments are :meth:`run`'s. Returns None when the run goes on
        (the ball landed, or flies on when the wall does not press it), else the run's
        (status, stop reason). The next checkpoint's time is left in ``flights.next_save``.
        """
        flights.restore(self._python_state())
        ctx = flights.ctx
        ctx[L.EN_SETTLES] = 0.0
        # while the kernels fly, the engine's state is theirs (hooks and checkpoints see it)
        self._kernel = flights
        impacts = self._impacts
        try:
            status, reason = flights.run(
                collisions, recorder, progress, checkpoint, request, until, on_record,
                next_save=next_save, interval=interval, final_progress=False,
            )  # fmt: skip
        finally:
            self._kernel = None
            state = dataclasses.replace(flights.state(), **self._held_state())
            fault, final_time = flights.pending_stop(), self.final_time
            self.restore(state)
            self._fault, self.final_time = fault, final_time
            if self._impacts > impacts:
                # the kernels stop after an impact (or a contact without impulse after it)
                self._last_impact = float(ctx[L.MC_LAST_IMPACT])
        if ctx[L.EN_SETTLES] != 0.0:
            ball = self._ball
            settled = Settled(
                ball.u1, ball.u2, ball.u3, L.REGIMES[int(ctx[L.EN_LAST_REGIME])],
                float(ctx[L.EN_LAST_WN]),
            )  # fmt: skip
            tail = int(ctx[L.EN_SETTLES]) & 2 != 0  # loop.SETTLES_TAIL: may be summed
            self._land(
                int(ctx[L.EN_LAST_J]), float(ctx[L.EN_LAST_S]), ball.theta, settled, ball.t, tail
            )
        return None if status is None else (status, reason)
