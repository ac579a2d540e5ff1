"""The engine: a simulation built from a scene, advanced one event at a time.

>>> from billiard import Simulation, load_scene
>>> sim = Simulation(load_scene("wedge-6.6hz"))
>>> record = sim.step()          # the next impact, as an ImpactRecord  # doctest: +SKIP
>>> sim.state.impacts            # the complete engine state  # doctest: +SKIP

One engine advances every scene: the compiled trajectory state machine
(:func:`billiard.kernels.machine.run_machine`), called in chunks by
:class:`~billiard.engine.driver.Driver`. :class:`Simulation` builds and validates what
it needs from a scene (the boundary, the drive, the models, which write their constants
into the state vector) and holds the engine state in that vector. :meth:`Simulation.step`
is the one kernel under every analysis (as ``OdeSolver.step`` in scipy, ``bounce!`` in
DynamicalBilliards.jl): it returns the next event's record.
:meth:`Simulation.run` runs many events, appending records to a recorder and looking
after progress, checkpoints and stop requests.

A run is deterministic: the same scene gives the same records bit for bit, compiled or
interpreted (``NUMBA_DISABLE_JIT=1``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from billiard.engine.ctx import (
    COUNT_KEYS,
    constants_vector,
    engine_state,
    put_motion,
    read_ball,
    read_motion,
    write_ball,
    write_motion,
    write_state,
)
from billiard.engine.driver import Driver, RunControl
from billiard.engine.interrupt import StopRequest
from billiard.engine.progress import Progress, report_time
from billiard.engine.state import BallState, EngineState
from billiard.errors import GeometryError, SimulationError
from billiard.geometry.boundary import Boundary, Drive
from billiard.geometry.curves import load_curve
from billiard.kernels import layout as L
from billiard.kernels.rules import COLLAPSE_COUNT, COLLAPSE_SPAN, ZERO_FLIGHT_LIMIT
from billiard.models.contact import ContactModel
from billiard.models.flight import flight_model
from billiard.models.hold import HELD, VertexHold
from billiard.models.impact import ImpactLaw, impact_law
from billiard.models.kinds import require_kernel
from billiard.models.locators import LOCATORS
from billiard.runfile.checkpoint import CheckpointError
from billiard.runfile.record import ContactRecord, ImpactRecord
from billiard.scene.scene import SceneError, with_values
from billiard.status import Status

__all__ = ["COLLAPSE_COUNT", "COLLAPSE_SPAN", "ZERO_FLIGHT_LIMIT", "Simulation"]

#: Wall-clock seconds between two checkpoints (and CSV flushes) of a streamed run.
CHECKPOINT_INTERVAL = 1.0
#: The ``end`` of a contact phase that the run's end cut (contacts.csv).
CUT = "cut"


class Simulation:
    """Everything a run needs, built and validated from a scene, and the engine state.

    Args:
        scene: a :class:`billiard.scene.scene.Scene`.
        method: ``"event"`` or ``"rk4"`` (a key of :data:`billiard.models.locators.LOCATORS`);
            default ``scene.run.method``.
        law: the impact law; default the scene's (:func:`billiard.models.impact.impact_law`).
            It must have a kernel (a kind the state machine runs).

    Raises:
        GeometryError: the ball is too large for the boundary's curvature, the curve
            has no bottom to rest on, or the initial position overlaps the wall or lid.
        SceneError: an unknown method, a curve parameter the curve does not have, or
            an impact law without a kernel.
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
        #: warm starts of the offset inversion, one [s, slope] per surface, for the
        #: geometry queries of the set-up (the engine's own live in its state vector)
        self.warm = self.boundary.initial_warm()
        self.locator = LOCATORS[self.method](
            self.boundary, self.flight, scene.run.gravity, self.warm
        )
        self.impact: ImpactLaw = law if law is not None else impact_law(scene)
        # every model runs on the kernels, chosen there by its kind: one without is
        # refused here, never run another way
        for model, what in ((self.locator, "locator"), (self.flight, "flight model")):
            require_kernel(model, what)
        require_kernel(self.impact, "impact law")
        self.initial = self.initial_state()
        #: simulated time (s) at which a run ends (inf when the scene sets no duration)
        self.end_time = (
            math.inf if scene.run.duration is None else self.initial.t + scene.run.duration
        )
        self.final_time = self.initial.t
        #: how the latest :meth:`run` ended, and why (None while it goes on)
        self.status: Status | None = None
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
        #: sampling: every ``sample_dt`` seconds of simulated time from the start,
        #: ``on_sample(t, q1, q2, v1, v2, omega, energy, mode)`` (trajectory.csv)
        self.sample_dt: float | None = None
        self.on_sample: Callable[..., None] | None = None
        #: the state vector and the calls into the state machine
        self.driver = Driver(self, constants_vector(self))
        self.reset()

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

    @property
    def ctx(self) -> Any:
        """The engine's state vector (:mod:`billiard.kernels.layout`)."""
        return self.driver.ctx

    # ------------------------------------------------------------------ engine state

    def reset(self, ball: BallState | None = None) -> None:
        """Start the event count afresh from ``ball`` (default: the scene's initial
        state), e.g. a state in flight or just after an impact. The warm starts, the
        flight's step proposal and the regime counters are kept."""
        ball = self.initial if ball is None else ball
        ctx = self.ctx
        write_ball(ctx, ball)
        put_motion(ctx, "flight", (), {}, ball.t)
        ctx[L.SM_K] = 0.0
        ctx[L.SM_PENDING] = 0.0
        ctx[L.MC_FINAL] = self.final_time
        if self.phases:
            self._start_in_contact(ball)

    @property
    def counts(self) -> dict[str, int]:
        """Impacts per regime of the impact law, and resting relaunches."""
        ctx = self.ctx
        keys = (*self.impact.regimes, "resting")
        return {key: int(ctx[L.COUNTS + COUNT_KEYS.index(key)]) for key in keys}

    @counts.setter
    def counts(self, value: dict[str, int]) -> None:
        for i, key in enumerate(COUNT_KEYS):
            self.ctx[L.COUNTS + i] = float(value.get(key, 0))

    @property
    def ball(self) -> BallState:
        """The ball after the last event (a copy)."""
        return read_ball(self.ctx)

    @property
    def mode(self) -> str:
        """The ball's motion state: ``flight``, ``roll``, ``slide`` or ``held``."""
        return L.MOTION_NAMES[int(self.ctx[L.MC_MODE])]

    @property
    def phase_time(self) -> dict[str, float]:
        """Simulated time (s) spent in finished rolling, sliding and held phases."""
        return read_motion(self.ctx)["phase_time"]

    def mode_times(self) -> dict[str, float]:
        """Simulated time (s) spent flying, rolling, sliding and held by two walls from
        the scene's start to ``final_time`` (an unfinished contact phase counted up to
        it)."""
        motion = read_motion(self.ctx)
        times = motion["phase_time"]
        ball_t = float(self.ctx[L.EN_T])
        end = self.final_time if math.isfinite(self.final_time) else ball_t
        mode = motion["mode"]
        if mode != "flight":
            # (none before a landing at the end of a chatter series, still ahead)
            times[mode] += max(0.0, end - motion["contact"][4])
        return {"flight": end - self.initial.t - sum(times.values()), **times}

    @property
    def pending_stop(self) -> SimulationError | None:
        """The stop detected after the last impact (an inelastic collapse), which the
        next :meth:`step` raises; None when the run can go on."""
        return self.driver.pending_stop()

    @property
    def state(self) -> EngineState:
        """The complete engine state after the last event (a snapshot)."""
        ctx = self.ctx
        state = engine_state(ctx, self.impact.regimes, len(self.boundary.offsets))
        state.locator = self.driver.locator_memory()
        state.samples = int(ctx[L.SM_K])
        if self.phases:
            motion = read_motion(ctx)
            state.mode, state.contact = motion["mode"], motion["contact"]
            state.phase_time, state.last_impact = motion["phase_time"], motion["last_impact"]
        return state

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
            self.driver.set_locator_memory(state.locator)
        except ValueError as exc:
            raise CheckpointError(f"its engine state does not fit this engine: {exc}") from None
        for warm, (s, slope) in zip(self.warm, state.walls, strict=False):
            warm[0], warm[1] = s, slope
        ctx = self.ctx
        write_state(ctx, state)
        write_motion(ctx, state)
        if not self.phases:
            ctx[L.MC_LAST_IMPACT] = state.ball.t
        ctx[L.SM_K] = float(state.samples)
        ctx[L.SM_PENDING] = 0.0
        self.final_time = state.ball.t
        ctx[L.MC_FINAL] = self.final_time

    def _start_in_contact(self, ball: BallState) -> None:
        """A ball that starts lying on a wall (gap and relative normal speed zero to
        rounding, 1e-12 m and 1e-12 m/s) while the wall presses it starts in contact,
        without an impact: rolling or sliding on one wall, or held by two."""
        px, py, vx, vy = self.drive.to_boundary_frame(
            ball.theta, ball.q1, ball.q2, ball.u1, ball.u2
        )
        model = self.contact_model
        touching = []
        for j, surface in enumerate(self.boundary.offsets):
            warm = list(self.warm[j])
            gap, rate = surface.gap_rate(px, py, vx, vy, warm)
            s, z, cz = surface.contact(px, warm)
            if abs(gap) > 1e-12 or abs(rate * cz) > 1e-12 or not surface.lo <= s <= surface.hi:
                continue
            touching.append((j, z))
        contact: tuple[float, ...] | None = None
        if len(touching) == 2:
            (a, za), (b, zb) = touching
            if self.vertex_hold.holds(za, zb, ball.theta, ball.u3):
                # held where it is, moving with the boundary, its spin kept
                u1, u2 = self.drive.boundary_velocity(ball.theta)
                ball = BallState(ball.t, ball.theta, ball.q1, ball.q2, u1, u2, ball.u3, ball.q3)
                write_ball(self.ctx, ball)
                mode, contact = HELD, (float(a), float(b), px, py, ball.t, ball.t)
        if contact is None:
            for j, _ in touching:
                surface = self.boundary.offsets[j]
                s, _, _ = surface.contact(px, list(self.warm[j]))
                wall = surface.piece(s)
                sd = model.s_dot(wall, ball.theta, s, ball.u1, ball.u2)
                mode, sgn = model.mode_for(wall, ball.theta, s, sd, ball.u3)
                if model.forces(wall, mode, sgn, ball.theta, (s, sd, ball.u3))[2] > 0.0:
                    contact = (float(j), s, sd, sgn, ball.t, ball.t)
                    break
        if contact is not None:
            ctx = self.ctx
            ctx[L.MC_MODE] = float(L.MOTION_NAMES.index(mode))
            for i, value in enumerate(contact):
                ctx[L.MC_CONTACT + i] = value

    # ------------------------------------------------------------------ one event

    def step(self, until: float = math.inf) -> ImpactRecord | ContactRecord | None:
        """Advance the engine to the next event and return its record: the next
        impact, or under contact phases the end of a phase (an impact that ends a
        phase returns the impact; the phase's record goes to ``on_contact``).

        Args:
            until: simulated time (s): when the next event comes after it, None is
                returned (a phase under way is cut there: ``on_contact_cut``).

        Raises:
            SimulationError: a documented stop (``.status`` says which): the ball
                escaped, a search failed, a non-finite state, an arithmetic fault in the
                equations, or an inelastic collapse detected after the previous impact.
                The state is left as it was after the previous event.
        """
        self._prepare_run()
        return self.driver.step(until)

    def _prepare_run(self) -> None:
        """What a run or step reads of the simulation's attributes: the samples."""
        ctx = self.ctx
        sampled = self.sample_dt is not None and self.on_sample is not None
        ctx[L.SM_DT] = float(self.sample_dt) if sampled else 0.0
        ctx[L.MC_FINAL] = self.final_time

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
        """Run until ``collisions`` impacts (or ``until``), appending each record to
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
            stop: a stop request set by a signal handler: the run ends at the next
                chunk's end by raising :class:`~billiard.engine.interrupt.RunInterrupted`,
                its state matching the records handed out.
            until: simulated time (s) at which the run ends; default ``self.end_time``.
            on_record: called with the impact number after each record is appended
                (a hook for tests and audits).
        """
        if start is not None:
            self.restore(start)
        control = RunControl(
            collisions,
            recorder,
            self.end_time if until is None else until,
            progress,
            checkpoint,
            stop if stop is not None else StopRequest(),
            on_record,
            CHECKPOINT_INTERVAL,
        )
        self.status = None
        self._prepare_run()
        try:
            status, reason = self.driver.run(control)
        finally:
            if progress is not None:
                report_time(progress, self.final_time)
                progress(self.driver.impacts, collisions)
        self.status = status
        return reason
