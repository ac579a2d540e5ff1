"""The run loop: alternate flights and impacts, one record per impact; streamed runs that
survive interruptions.

>>> from billiard.scene import load_scene
>>> from billiard.simulate import simulate
>>> result = simulate(load_scene("parabola-5.4hz"), collisions=200)
>>> result.columns["q2"][:3]  # doctest: +SKIP

A run is deterministic: the same scene gives the same records bit for bit (wall-clock
time only decides when a streamed file is flushed and what ``wall_time`` says).

A streamed run (``simulate(..., out_dir=DIR)``) keeps three files in DIR:

``scene.toml``
    the fully resolved scene, written before the first impact.
``collisions.csv``
    one row per impact, written in whole rows and synced at least once a second.
``checkpoint.json``
    written atomically with every flush: the number of rows on disk and the complete
    :class:`EngineState` after the last of them. :func:`resume` continues from it, and
    the finished CSV equals that of an uninterrupted run byte for byte, because the
    engine state holds everything the loop carries from one impact to the next (the
    compensated clock, the collapse detector's window, the surfaces' Newton warm starts,
    the flight integrator's step proposal), written with :func:`repr` so that every
    float reads back exactly.

SIGINT (Ctrl-C) and SIGTERM during a streamed run stop it at the next impact boundary:
the rows so far are flushed, a final checkpoint is written and :class:`RunInterrupted`
(a ``KeyboardInterrupt``) is raised. A second signal stops at once; the files then still
hold a valid prefix of the run and the last checkpoint, from which :func:`resume` redoes
the few impacts after it. A SIGKILL leaves the last checkpoint (at most a second old) and
possibly rows after it, even an unterminated last line; :func:`resume` cuts those off.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import signal
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from billiard.boundary import Boundary, Drive
from billiard.curves import load_curve
from billiard.errors import GeometryError, SimulationError
from billiard.events import Event, EventLocator, FixedStepLocator
from billiard.flight import RK4Flight, flight_model
from billiard.generated import ball as _ball
from billiard.impact import Contact, KaneLevinsonImpact
from billiard.record import (
    COLUMNS,
    CheckpointError,
    CsvMark,
    CsvRecorder,
    MemoryRecorder,
    Truncation,
    read_checkpoint,
    read_collisions,
    write_checkpoint,
    write_text_atomic,
)
from billiard.scene import SceneError, scene_from_toml, scene_to_toml, with_values

__all__ = [
    "BallState",
    "EngineState",
    "Result",
    "RunInterrupted",
    "Simulation",
    "resume",
    "run_streamed",
    "simulate",
]

#: Inelastic collapse: this many impacts ...
COLLAPSE_COUNT = 10_000
#: ... within this much simulated time (s) stop the run.
COLLAPSE_SPAN = 1e-6
#: So does this many consecutive impacts at zero time of flight.
ZERO_FLIGHT_LIMIT = 1_000
_PROGRESS_EVERY = 100
#: Wall-clock seconds between two checkpoints (and CSV flushes) of a streamed run.
CHECKPOINT_INTERVAL = 1.0
#: File names inside a run directory.
CSV_NAME = "collisions.csv"
SCENE_NAME = "scene.toml"
CHECKPOINT_NAME = "checkpoint.json"
#: Testing hook: ``BILLIARD_STOP_AFTER=K`` (or ``K:KILL``, ``K:TERM``, ``K:INT``) makes a
#: streamed run send itself that signal (default SIGINT) right after impact K, so that
#: interruptions can be tested at an exact place.
STOP_AFTER_VARIABLE = "BILLIARD_STOP_AFTER"

Progress = Callable[[int, int], None]

# Floats of a row, by column name, for naming the culprit of a non-finite state.
_ROW_FLOATS = (
    "t",
    "q1",
    "q2",
    "v1",
    "v2",
    "omega",
    "u4",
    "un",
    "tof",
    "z",
    "energy",
    "Rt",
    "Rn",
    "s",
    "q3",
)


@dataclass(slots=True)
class BallState:
    """State of the ball at one instant: time t (s), drive angle theta (rad, reduced
    modulo 2 pi), centre position (m) and velocity (m/s) in the lab frame, spin u3
    (rad/s) and rotation angle q3 (rad)."""

    t: float
    theta: float
    q1: float
    q2: float
    u1: float
    u2: float
    u3: float
    q3: float = 0.0


@dataclass(slots=True)
class EngineState:
    """Everything the run loop carries from one impact to the next, after ``impacts``
    impacts: restored into a :class:`Simulation` built from the same scene, the run
    continues with exactly the floating-point operations of an uninterrupted one.

    Attributes:
        ball: the ball just after the last impact (or at the start).
        impacts: impacts done (rows recorded), counted from the scene's start.
        clock, clock_error: Neumaier's compensated sum of the flight times and its
            running error term (``ball.t == clock + clock_error``).
        zero_flights: consecutive impacts with zero time of flight so far.
        recent: times of the latest impacts that are still within ``COLLAPSE_SPAN`` of
            the last one (the window of the inelastic-collapse detector).
        counts: impacts per regime, and resting lifts.
        walls: per offset wall, the Newton warm start of its foot point and the slope
            there (both feed the next flight's search).
        flight: the flight model's memory (the adaptive integrator's step proposal).
        locator: the impact locator's memory (the fixed-step locator's warm starts).
    """

    ball: BallState
    impacts: int
    clock: float
    clock_error: float
    zero_flights: int
    recent: tuple[float, ...]
    counts: dict[str, int]
    walls: tuple[tuple[float, float], ...]
    flight: dict[str, float]
    locator: dict[str, list[float]]

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready data (floats stay floats; :mod:`json` writes them with
        :func:`repr`, which reads back to the same double)."""
        return {
            "ball": {f.name: getattr(self.ball, f.name) for f in fields(BallState)},
            "impacts": self.impacts,
            "clock": self.clock,
            "clock_error": self.clock_error,
            "zero_flights": self.zero_flights,
            "recent": list(self.recent),
            "counts": dict(self.counts),
            "walls": [list(pair) for pair in self.walls],
            "flight": dict(self.flight),
            "locator": {key: list(value) for key, value in self.locator.items()},
        }

    @classmethod
    def from_dict(cls, data: Any) -> EngineState:
        """Inverse of :meth:`to_dict`; raises :class:`CheckpointError` on malformed data."""
        try:
            ball = data["ball"]
            names = [f.name for f in fields(BallState)]
            if set(ball) != set(names):
                raise CheckpointError("the engine state's ball has the wrong fields")
            state = cls(
                ball=BallState(**{name: _finite(ball[name]) for name in names}),
                impacts=_count(data["impacts"]),
                clock=_finite(data["clock"]),
                clock_error=_finite(data["clock_error"]),
                zero_flights=_count(data["zero_flights"]),
                recent=tuple(_finite(t) for t in data["recent"]),
                counts={str(k): _count(v) for k, v in data["counts"].items()},
                walls=tuple((_finite(s), _finite(slope)) for s, slope in data["walls"]),
                flight={str(k): _finite(v) for k, v in data["flight"].items()},
                locator={str(k): [_finite(x) for x in v] for k, v in data["locator"].items()},
            )
        except CheckpointError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise CheckpointError(f"its engine state is malformed ({exc!r})") from None
        if len(state.recent) > COLLAPSE_COUNT + 1:
            raise CheckpointError("its engine state is malformed (collapse window too long)")
        return state


def _finite(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CheckpointError(f"its engine state holds {value!r} where a number belongs")
    value = float(value)
    if not math.isfinite(value):
        raise CheckpointError("its engine state holds a non-finite number")
    return value


def _count(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise CheckpointError(f"its engine state holds {value!r} where a count belongs")
    return value


class RunInterrupted(KeyboardInterrupt):
    """A streamed run stopped by SIGINT or SIGTERM. Its files are complete up to
    ``rows`` impacts; ``checkpoint_rows`` (normally equal) is where :func:`resume`
    continues from.

    Attributes:
        signum: the signal (``signal.SIGINT`` or ``signal.SIGTERM``).
        rows: impacts kept in the CSV file.
        checkpoint_rows: impacts the checkpoint describes.
        out_dir: the run directory.
    """

    def __init__(
        self,
        signum: int,
        rows: int = 0,
        checkpoint_rows: int = 0,
        out_dir: Path | None = None,
    ):
        super().__init__(f"interrupted by signal {signum}")
        self.signum = signum
        self.rows = rows
        self.checkpoint_rows = checkpoint_rows
        self.out_dir = out_dir


class _StopRequest:
    """Set by the signal handler of a streamed run; the loop looks at it once per impact.

    ``signal_at`` and ``test_signal`` implement the ``BILLIARD_STOP_AFTER`` testing hook.
    """

    __slots__ = ("signum", "signal_at", "test_signal")

    def __init__(self) -> None:
        self.signum = 0
        self.signal_at = -1
        self.test_signal = 0


class Simulation:
    """Everything a run needs, built and validated from a scene.

    Args:
        scene: a :class:`billiard.scene.Scene`.
        method: ``"event"`` or ``"rk4"``; default ``scene.run.method``.

    Raises:
        GeometryError: the ball is too large for the boundary's curvature, the curve
            has no bottom to rest on, or the initial position overlaps the wall or lid.
        SceneError: a curve parameter the named curve does not have.
    """

    def __init__(self, scene: Any, method: str | None = None):
        self.scene = scene
        self.method = method or scene.run.method
        if self.method not in ("event", "rk4"):
            raise ValueError(f"unknown method {self.method!r}: use 'event' or 'rk4'")
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
        if isinstance(self.flight, RK4Flight):
            self.locator: EventLocator | FixedStepLocator = FixedStepLocator(
                self.boundary, self.flight
            )
        else:
            self.locator = EventLocator(self.boundary, self.flight, scene.run.gravity)
        self.impact = KaneLevinsonImpact.from_scene(scene)
        self.initial = self.initial_state()
        #: simulated time (s) at which a run ends (inf when the scene sets no duration)
        self.end_time = (
            math.inf if scene.run.duration is None else self.initial.t + scene.run.duration
        )
        self.counts: dict[str, int] = {"stick": 0, "slip": 0, "elastic": 0, "resting": 0}
        self.final_time = self.initial.t
        #: the engine state after the last recorded impact of the latest :meth:`run`
        #: (None while running, or when a run was broken off by an exception).
        self.state: EngineState | None = None

    def initial_state(self) -> BallState:
        """The scene's initial state; a missing q2 puts the ball at rest on the bottom
        (at the lowest admissible point, or below a given q1)."""
        init = self.scene.initial
        theta = self.drive.angle(init.t)
        q1, q2 = init.q1, init.q2
        if q2 is None:
            if q1 is None:
                x, y = self.boundary.resting_position()
                xl, xr = self.boundary.x_range
                if not xl < x < xr:
                    raise GeometryError(
                        f"the boundary curve has no bottom to rest on: its lowest point in "
                        f"reach is at the edge of the container, x = {x:.4g} m (the curve must "
                        f"rise on both sides); give initial.q1 and initial.q2 to start elsewhere"
                    )
            else:
                x = self.drive.to_boundary_frame(theta, q1, 0.0, 0.0, 0.0)[0]
                y = self.boundary.offset_height(x)
            q1, q2 = self.drive.to_lab_frame(theta, x, y)
            if init.q1 is not None:
                q1 = init.q1
        elif q1 is None:
            q1 = self.drive.to_lab_frame(theta, self.boundary.resting_position()[0], 0.0)[0]
        self.boundary.check_initial_position(q1, q2, theta)
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

    def start_state(self) -> EngineState:
        """The engine state before the first impact (what :meth:`run` starts from when
        given no state)."""
        return self._capture(self.initial, 0, self.initial.t, 0.0, 0, ())

    def _capture(
        self,
        ball: BallState,
        impacts: int,
        clock: float,
        clock_error: float,
        zero_flights: int,
        recent: Any,
    ) -> EngineState:
        return EngineState(
            ball=BallState(*(getattr(ball, f.name) for f in fields(BallState))),
            impacts=impacts,
            clock=clock,
            clock_error=clock_error,
            zero_flights=zero_flights,
            recent=tuple(recent),
            counts=dict(self.counts),
            walls=tuple((wall.s, wall.slope) for wall in self.boundary.offsets),
            flight=self.flight.memory(),
            locator=self.locator.memory(),
        )

    def restore(self, state: EngineState) -> None:
        """Put the components' memories and counters where ``state`` says.

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
        for wall, (s, slope) in zip(offsets, state.walls, strict=True):
            wall.s, wall.slope = s, slope
        self.counts = dict(state.counts)
        self.final_time = state.ball.t

    # ------------------------------------------------------------------ the loop

    def _pressing(self, ev: Event) -> bool:
        """Does the ball's acceleration relative to the boundary push it into the surface
        it touches (d2G/dt2 < 0)?"""
        px, py, vx, vy = self.drive.to_boundary_frame(ev.theta, ev.q1, ev.q2, ev.u1, ev.u2)
        a1, a2 = self.flight.acceleration(ev.u1, ev.u2)
        ab = self.drive.acceleration(ev.theta)
        ax, ay = (a1 - ab, a2) if self.drive.horizontal else (a1, a2 - ab)
        return ev.surface.gap_accel(px, py, vx, vy, ax, ay) < 0.0

    def run(
        self,
        collisions: int,
        recorder: Any,
        progress: Progress | None = None,
        *,
        start: EngineState | None = None,
        checkpoint: Callable[[EngineState], None] | None = None,
        stop: _StopRequest | None = None,
        until: float = math.inf,
    ) -> str | None:
        """Simulate until ``collisions`` impacts, appending one row per impact to
        ``recorder``. Returns None, or the one-line reason the run stopped early.

        Args:
            collisions: impact number to stop at (counted from the scene's start, so a
                run continued from ``start`` does ``collisions - start.impacts`` more).
            recorder: gets ``append(row)`` for each impact.
            progress: called as ``progress(n_done, collisions)`` every few impacts.
            start: continue from this engine state instead of ``self.initial``.
            checkpoint: called with the engine state after the last appended row, about
                every ``CHECKPOINT_INTERVAL`` seconds of wall-clock time.
            stop: a stop request set by a signal handler: the loop ends at the next
                impact boundary by raising :class:`RunInterrupted`.
            until: simulated time (s) at which the run ends: an impact after it is not
                recorded, and ``self.final_time`` becomes ``until``.

        Afterwards ``self.state`` is the engine state after the last recorded impact.
        """
        self.state = None
        if start is not None:
            self.restore(start)
            state = start.ball
            n = start.impacts
            clock, clock_error = start.clock, start.clock_error
            zero_flights = start.zero_flights
            recent: deque[float] = deque(start.recent, maxlen=COLLAPSE_COUNT + 1)
        else:
            state = self.initial
            n = 0
            # The clock is a sum of tens of thousands of flight times: keep it with
            # Neumaier's compensated summation so that t stays the correctly rounded sum
            # (a plain sum drifts by ~1e-13 s, ~1e-12 rad of drive phase, by 3000 impacts).
            clock, clock_error = state.t, 0.0
            zero_flights = 0
            recent = deque(maxlen=COLLAPSE_COUNT + 1)
        scene = self.scene
        m, r, k = scene.ball.mass, scene.ball.radius, scene.ball.inertia_factor
        g = scene.run.gravity
        locate = self.locator.locate
        impact = self.impact
        drive = self.drive
        counts = self.counts
        request = stop if stop is not None else _StopRequest()
        monotonic = time.monotonic
        next_save = monotonic() + CHECKPOINT_INTERVAL if checkpoint is not None else math.inf
        try:
            while n < collisions:
                # a signal arrived: stop here, where the state matches the rows exactly
                if request.signum:
                    raise RunInterrupted(request.signum)
                try:
                    ev = locate(state.theta, state.q1, state.q2, state.u1, state.u2, state.u3)
                except SimulationError as exc:
                    raise SimulationError(f"{exc} after impact {n} (t = {state.t:.9g} s)") from None
                tau = ev.tau
                total = clock + tau
                if abs(clock) >= abs(tau):
                    error = clock_error + ((clock - total) + tau)
                else:
                    error = clock_error + ((tau - total) + clock)
                t = total + error
                if t > until:
                    self.final_time = until
                    break
                if ev.surface.kind == "escape":
                    raise SimulationError(
                        f"ball escaped above escape_height = {scene.boundary.escape_height!r} m "
                        f"at t = {t:.9g} s after impact {n}"
                    )
                q3 = state.q3 + state.u3 * tau
                before = BallState(t, ev.theta, ev.q1, ev.q2, ev.u1, ev.u2, state.u3, q3)
                vb1, vb2 = drive.boundary_velocity(ev.theta)
                try:
                    res = impact.apply(before, Contact(ev.z, vb1, vb2, self._pressing(ev)))
                except SimulationError as exc:
                    raise SimulationError(f"{exc} at impact {n + 1} (t = {t:.9g} s)") from None
                u4, un = _ball.frame_velocity(res.u1, res.u2, ev.z)
                energy = _ball.energy(ev.q2, res.u1, res.u2, res.u3, m, r, k, g)
                # one row, in the order of billiard.record.COLUMNS
                row = (
                    n + 1,
                    t,
                    ev.q1,
                    ev.q2,
                    res.u1,
                    res.u2,
                    res.u3,
                    u4,
                    un,
                    tau,
                    res.regime,
                    ev.z,
                    energy,
                    ev.surface.label,
                    res.Rt,
                    res.Rn,
                    ev.s,
                    q3,
                )
                # a non-finite number is never recorded (the sum of finite numbers of
                # physical size is finite, so one addition chain tests them all)
                if not math.isfinite(
                    t
                    + ev.q1
                    + ev.q2
                    + res.u1
                    + res.u2
                    + res.u3
                    + u4
                    + un
                    + tau
                    + ev.z
                    + energy
                    + res.Rt
                    + res.Rn
                    + ev.s
                    + q3
                ):
                    _check_finite(row, n + 1, t)
                recorder.append(row)
                # commit: from here to the end of the iteration nothing can fail, so the
                # loop variables always describe exactly the rows appended
                n += 1
                state = BallState(t, ev.theta, ev.q1, ev.q2, res.u1, res.u2, res.u3, q3)
                clock, clock_error = total, error
                counts[res.regime] += 1
                if res.resting:
                    counts["resting"] += 1
                zero_flights = zero_flights + 1 if tau == 0.0 else 0
                # collapse window: the impact times within COLLAPSE_SPAN of this one (the
                # times are non-decreasing, so those form the deque's tail)
                recent.append(t)
                while t - recent[0] >= COLLAPSE_SPAN:
                    recent.popleft()
                self.final_time = t
                if progress is not None and n % _PROGRESS_EVERY == 0:
                    progress(n, collisions)
                if checkpoint is not None and monotonic() >= next_save:
                    checkpoint(self._capture(state, n, clock, clock_error, zero_flights, recent))
                    next_save = monotonic() + CHECKPOINT_INTERVAL
                if n == request.signal_at:
                    os.kill(os.getpid(), request.test_signal)
                if len(recent) > COLLAPSE_COUNT:
                    raise SimulationError(
                        f"inelastic collapse: {COLLAPSE_COUNT} impacts within "
                        f"{COLLAPSE_SPAN:g} s of simulated time, at impact {n} (t = {t:.9g} s)"
                    )
                if zero_flights >= ZERO_FLIGHT_LIMIT:
                    raise SimulationError(
                        f"inelastic collapse: {ZERO_FLIGHT_LIMIT} consecutive impacts with "
                        f"zero time of flight, at impact {n} (t = {t:.9g} s)"
                    )
            reason = None
        except SimulationError as exc:
            reason = str(exc)
        except (ArithmeticError, ValueError) as exc:
            kind = type(exc).__name__
            reason = f"numerical failure after impact {n} (t = {state.t:.9g} s): {kind}: {exc}"
        except RunInterrupted:
            self.state = self._capture(state, n, clock, clock_error, zero_flights, recent)
            raise
        finally:
            if progress is not None:
                progress(n, collisions)
        self.state = self._capture(state, n, clock, clock_error, zero_flights, recent)
        return reason


def _check_finite(row: tuple[Any, ...], n: int, t: float) -> None:
    """Raise SimulationError naming the first non-finite quantity of an impact's row."""
    for name in _ROW_FLOATS:
        value = row[COLUMNS.index(name)]
        if not math.isfinite(value):
            raise SimulationError(
                f"non-finite state at impact {n} (t = {t:.9g} s): {name} = {value!r}"
            )


class Result:
    """The outcome of :func:`simulate` or :func:`resume`.

    Attributes:
        scene: the scene as run (initial position resolved, count and method set).
        stop_reason: None when all impacts were simulated, else a one-line reason.
        wall_time: seconds the run took (this session only, for a resumed run).
        counts: impacts per regime (stick, slip, elastic) and how many of the elastic
            ones lifted a ball lying on the surface (resting).
        path: the streamed CSV file, or None for an in-memory run.
        final_time: simulated time of the last impact (s).
        resumed_from: for :func:`resume`, the impacts already on disk when it started
            (None for a fresh run).
        truncation: for :func:`resume`, what was cut off the CSV file's end.
        already_finished: :func:`resume` found the run complete (or stopped) and did
            nothing.
    """

    def __init__(
        self,
        scene: Any,
        recorder: MemoryRecorder | CsvRecorder | _CsvFile,
        stop_reason: str | None,
        wall_time: float,
        counts: dict[str, int],
        final_time: float,
        *,
        resumed_from: int | None = None,
        truncation: Truncation | None = None,
        already_finished: bool = False,
    ):
        self.scene = scene
        self.final_time = final_time
        self._recorder = recorder
        self.stop_reason = stop_reason
        self.wall_time = wall_time
        self.counts = dict(counts)
        self.path: Path | None = getattr(recorder, "path", None)
        self.resumed_from = resumed_from
        self.truncation = truncation
        self.already_finished = already_finished
        self._columns: dict[str, np.ndarray] | None = None

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """Column name -> numpy array (read back from the CSV file on first use)."""
        if self._columns is None:
            self._columns = self._recorder.columns()
        return self._columns

    def __len__(self) -> int:
        return len(self._recorder)

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the records as CSV (floats with repr, so they read back exactly)."""
        self._recorder.write_csv(path)

    def summary(self) -> str:
        n = len(self)
        c = self.counts
        t_end = self.final_time
        done = n - (self.resumed_from or 0)
        rate = done / self.wall_time if self.wall_time > 0 else math.inf
        text = (
            f"{n} impacts ({c['stick']} stick, {c['slip']} slip, {c['elastic']} elastic) "
            f"up to t = {t_end:.6g} s in {self.wall_time:.3g} s ({rate:,.0f} impacts/s)"
        )
        if self.resumed_from is not None:
            text += f"; resumed after impact {self.resumed_from}"
        if self.stop_reason:
            text += f"; stopped: {self.stop_reason}"
        return text


class _CsvFile:
    """A finished run's CSV file, read-only, with the recorder interface of a Result."""

    def __init__(self, path: Path, rows: int):
        self.path = path
        self._rows = rows

    def __len__(self) -> int:
        return self._rows

    def close(self) -> None:
        pass

    def columns(self) -> dict[str, np.ndarray]:
        return read_collisions(self.path)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if Path(path).resolve() != self.path.resolve():
            Path(path).write_bytes(self.path.read_bytes())


def simulate(
    scene: Any,
    *,
    collisions: int | None = None,
    method: str | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    progress: Progress | None = None,
    duration: float | None = None,
) -> Result:
    """Run a scene.

    Args:
        scene: a :class:`billiard.scene.Scene`.
        collisions: number of impacts; default ``scene.run.collisions``.
        method: ``"event"`` (default from the scene) or ``"rk4"`` (the paper's scheme).
        out_dir: stream the run to ``out_dir`` (``collisions.csv``, ``scene.toml`` and
            ``checkpoint.json``, see the module docstring) instead of memory.
        progress: called as ``progress(n_done, n_total)`` every few impacts.
        duration: simulated time (s) after which the run stops, whichever of the two
            limits comes first; default ``scene.run.duration`` (None: no limit).

    Returns:
        A :class:`Result`; a run that had to stop early (ball escaped, inelastic
        collapse, non-finite numbers, a root solve that failed) keeps the records so
        far and says why in ``stop_reason``.

    Raises:
        GeometryError: the scene's geometry cannot be simulated.
        SceneError: the scene (or the impact count) is invalid.
        RunBusyError: another process is writing a run in ``out_dir``.
        RunInterrupted: a streamed run got SIGINT or SIGTERM; its files are complete up
            to the last impact and :func:`resume` continues it.
    """
    if duration is not None:
        scene = with_values(scene, {"run.duration": duration})  # validates it
    sim = Simulation(scene, method)
    total = scene.run.collisions if collisions is None else int(collisions)
    resolved = sim.resolved_scene(total)  # validates the impact count before any work
    if out_dir is None:
        recorder = MemoryRecorder()
        start = time.perf_counter()
        stop_reason = sim.run(total, recorder, progress, until=sim.end_time)
        wall_time = time.perf_counter() - start
        return Result(resolved, recorder, stop_reason, wall_time, sim.counts, sim.final_time)
    return run_streamed(sim, out_dir, collisions=total, progress=progress)


def run_streamed(
    sim: Simulation,
    out_dir: str | os.PathLike[str],
    *,
    collisions: int | None = None,
    progress: Progress | None = None,
) -> Result:
    """``simulate(..., out_dir=...)`` for a :class:`Simulation` built by the caller (who
    may have wrapped its impact law, e.g. to audit every impact): write
    ``out_dir/scene.toml`` first, then stream the run with checkpoints."""
    total = sim.scene.run.collisions if collisions is None else int(collisions)
    resolved = sim.resolved_scene(total)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    # first take the CSV file (locked: a run still going on in DIR is left alone) ...
    stream = CsvRecorder(out / CSV_NAME, autoflush=False)
    try:
        # ... then drop the checkpoint of an earlier run, which must not outlive its CSV
        (out / CHECKPOINT_NAME).unlink(missing_ok=True)
        write_text_atomic(out / SCENE_NAME, scene_to_toml(resolved))
    except BaseException:
        stream.close()
        raise
    return _run_streamed(sim, total, out, stream, sim.start_state(), progress)


def resume(
    out_dir: str | os.PathLike[str],
    *,
    collisions: int | None = None,
    progress: Progress | None = None,
    notify: Callable[[str], None] | None = None,
) -> Result:
    """Continue a streamed run from its checkpoint.

    The CSV file is first cut back to the checkpoint's row (dropping rows written after
    it and an unterminated last line); the finished file then equals that of an
    uninterrupted run byte for byte.

    Args:
        out_dir: the run directory (written by ``simulate(..., out_dir=...)``).
        collisions: a new total number of impacts (to extend a run); default the
            scene's ``run.collisions``.
        progress: as for :func:`simulate`.
        notify: called with a one-line description of where the run continues from,
            before the first new impact.

    Returns:
        A :class:`Result`. A run that is already complete (and not extended) or that
        stopped early is left as it is: ``already_finished`` is True.

    Raises:
        CheckpointError: the directory has no usable checkpoint, or its CSV file or
            scene does not match it, or another process is still writing it.
        SceneError: DIR/scene.toml is not a valid scene.
        RunInterrupted: as for :func:`simulate`.
    """
    out = Path(out_dir)
    if not out.is_dir():
        raise CheckpointError(f"{out} is not a run directory")
    checkpoint_path = out / CHECKPOINT_NAME
    data = read_checkpoint(checkpoint_path)
    try:
        status = data["status"]
        mark = CsvMark.from_dict(data["csv"])
        fingerprint = data["scene_sha256"]
        engine = data["engine"]
        stop_reason = data.get("stop_reason")
    except (KeyError, TypeError):
        raise CheckpointError(f"{checkpoint_path} lacks an entry it needs") from None
    except CheckpointError as exc:
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    if status not in ("running", "interrupted", "complete", "stopped"):
        raise CheckpointError(f"{checkpoint_path} has an unknown status {status!r}")
    scene_path = out / SCENE_NAME
    try:
        text = scene_path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CheckpointError(f"{scene_path} is missing") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CheckpointError(f"{scene_path} cannot be read: {exc}") from None
    scene = scene_from_toml(text, source=f"'{scene_path}'")
    sim = Simulation(scene)
    if _fingerprint(sim) != fingerprint:
        raise CheckpointError(
            f"{scene_path} is not the scene the checkpoint was written for (edited since?)"
        )
    total = scene.run.collisions if collisions is None else int(collisions)
    rows = mark.rows
    by_time = scene.run.duration is not None and collisions is None
    if status == "stopped" or (status == "complete" and (total <= rows or by_time)):
        if collisions is not None and total < rows:
            raise CheckpointError(
                f"the run in {out} already has {rows} impacts; to extend it, ask for more"
            )
        final_time = math.nan
        with contextlib.suppress(CheckpointError):
            last = EngineState.from_dict(engine)
            sim.counts, final_time = dict(last.counts), last.ball.t
        return Result(
            scene,
            _CsvFile(out / CSV_NAME, rows),
            stop_reason,
            0.0,
            sim.counts,
            final_time,
            resumed_from=rows,
            already_finished=True,
        )
    if total < rows:
        raise CheckpointError(f"the run in {out} already has {rows} impacts, more than {total}")
    if engine is None:
        raise CheckpointError(f"{checkpoint_path} holds no engine state to continue from")
    try:
        state = EngineState.from_dict(engine)
    except CheckpointError as exc:
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    if state.impacts != rows:
        raise CheckpointError(
            f"{checkpoint_path} is inconsistent: engine state after impact {state.impacts}, "
            f"CSV position after impact {rows}"
        )
    # check the state before touching the CSV file: a mismatch leaves everything as it was
    try:
        sim.restore(state)
    except CheckpointError as exc:
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    sim.resolved_scene(total)  # validates the new total
    stream, cut = CsvRecorder.reopen(out / CSV_NAME, mark, autoflush=False)
    if notify is not None:
        dropped = []
        if cut.rows:
            dropped.append(f"{cut.rows} row(s) written after the checkpoint")
        if cut.partial_bytes:
            dropped.append(f"an unterminated last line ({cut.partial_bytes} bytes)")
        note = f"; dropped {' and '.join(dropped)}" if dropped else ""
        notify(f"resuming {out} after impact {rows} of {total}{note}")
    if total != scene.run.collisions:
        write_text_atomic(out / SCENE_NAME, scene_to_toml(sim.resolved_scene(total)))
    return _run_streamed(
        sim, total, out, stream, state, progress, resumed_from=rows, truncation=cut
    )


def _fingerprint(sim: Simulation) -> str:
    """sha256 of the resolved scene, impact count aside (a run may be extended)."""
    return hashlib.sha256(scene_to_toml(sim.resolved_scene(1)).encode("utf-8")).hexdigest()


def _stop_after_hook() -> tuple[int, int]:
    """(impact, signal) of the ``BILLIARD_STOP_AFTER`` testing hook, or (-1, 0)."""
    text = os.environ.get(STOP_AFTER_VARIABLE, "").strip()
    if not text:
        return -1, 0
    count, _, name = text.partition(":")
    signals = {
        "": signal.SIGINT,
        "INT": signal.SIGINT,
        "TERM": signal.SIGTERM,
        "KILL": signal.SIGKILL,
    }
    try:
        impact = int(count)
        signum = signals[name.strip().upper()]
    except (ValueError, KeyError):
        raise SceneError(
            f"{STOP_AFTER_VARIABLE}={text!r}: expected K or K:INT, K:TERM, K:KILL"
        ) from None
    return impact, int(signum)


@contextlib.contextmanager
def _signals_deferred(request: _StopRequest) -> Iterator[None]:
    """Turn SIGINT and SIGTERM into a stop request for the duration of a run (main
    thread only; a signal that is ignored or has an application's own handler is left
    alone). A second signal raises KeyboardInterrupt at once."""
    installed: dict[int, Any] = {}

    def handler(signum: int, frame: Any) -> None:
        if request.signum:
            raise KeyboardInterrupt
        request.signum = signum

    if threading.current_thread() is threading.main_thread():
        for sig, default in (
            (signal.SIGINT, signal.default_int_handler),
            (signal.SIGTERM, signal.SIG_DFL),
        ):
            with contextlib.suppress(ValueError, OSError):
                if signal.getsignal(sig) is default:
                    installed[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, previous in installed.items():
            signal.signal(sig, previous)


def _run_streamed(
    sim: Simulation,
    total: int,
    out: Path,
    stream: CsvRecorder,
    start: EngineState,
    progress: Progress | None,
    *,
    resumed_from: int | None = None,
    truncation: Truncation | None = None,
) -> Result:
    """Run ``sim`` from ``start`` to ``total`` impacts, streaming rows to ``stream`` and
    keeping ``out/checkpoint.json`` in step with what the CSV file holds."""
    checkpoint_path = out / CHECKPOINT_NAME
    fingerprint = _fingerprint(sim)
    saved = [stream.mark.rows]

    def save(state: EngineState | None, status: str, reason: str | None = None) -> None:
        mark = stream.flush()
        engine: dict[str, Any] | None = None
        if state is not None:
            if state.impacts != mark.rows:  # pragma: no cover - an engine bug
                raise AssertionError(f"engine state after {state.impacts}, CSV {mark.rows}")
            engine = state.to_dict()
            if not _all_finite(engine):
                # only a stopped run can get here (a fault left a memory non-finite); its
                # checkpoint then records the stop without a state to continue from
                engine = None
        write_checkpoint(
            checkpoint_path,
            {
                "status": status,
                "stop_reason": reason,
                "collisions": total,
                "method": sim.method,
                "scene_sha256": fingerprint,
                "csv": mark.as_dict(),
                "engine": engine,
            },
        )
        saved[0] = mark.rows

    request = _StopRequest()
    request.signal_at, request.test_signal = _stop_after_hook()
    began = time.perf_counter()
    try:
        save(start, "running")
        with _signals_deferred(request):
            try:
                reason = sim.run(
                    total,
                    stream,
                    progress,
                    start=start,
                    checkpoint=lambda state: save(state, "running"),
                    stop=request,
                    until=sim.end_time,
                )
            except RunInterrupted as exc:
                save(sim.state, "interrupted")
                stream.close()
                exc.rows, exc.checkpoint_rows, exc.out_dir = len(stream), saved[0], out
                raise
            except KeyboardInterrupt as exc:
                # a second signal broke off an impact: the rows so far are whole and the
                # last checkpoint still describes a prefix of them
                stream.close()
                raise RunInterrupted(signal.SIGINT, len(stream), saved[0], out) from exc
            save(sim.state, "complete" if reason is None else "stopped", reason)
    finally:
        stream.close()
    if request.signum:
        # the signal came after the last impact: the files are complete; let it act now
        signal.raise_signal(request.signum)
    wall_time = time.perf_counter() - began
    return Result(
        sim.resolved_scene(total),
        stream,
        reason,
        wall_time,
        sim.counts,
        sim.final_time,
        resumed_from=resumed_from,
        truncation=truncation,
    )


def _all_finite(data: Any) -> bool:
    if isinstance(data, float):
        return math.isfinite(data)
    if isinstance(data, Mapping):
        return all(_all_finite(v) for v in data.values())
    if isinstance(data, (list, tuple)):
        return all(_all_finite(v) for v in data)
    return True
