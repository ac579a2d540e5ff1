"""The run loop: alternate flights and impacts, one record per impact.

>>> from billiard.scene import load_scene
>>> from billiard.simulate import simulate
>>> result = simulate(load_scene("parabola-5.4hz"), collisions=200)
>>> result.columns["q2"][:3]  # doctest: +SKIP

A run is deterministic: the same scene gives the same records bit for bit (wall-clock
time only decides when a streamed file is flushed and what ``wall_time`` says).
"""

from __future__ import annotations

import math
import os
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from billiard.boundary import Boundary, Drive
from billiard.curves import load_curve
from billiard.errors import SimulationError
from billiard.events import Event, EventLocator, FixedStepLocator
from billiard.flight import RK4Flight, flight_model
from billiard.generated import ball as _ball
from billiard.impact import Contact, KaneLevinsonImpact
from billiard.record import CsvRecorder, MemoryRecorder
from billiard.scene import with_values

__all__ = ["BallState", "Result", "Simulation", "simulate"]

#: Inelastic collapse: this many impacts ...
COLLAPSE_COUNT = 10_000
#: ... within this much simulated time (s) stop the run.
COLLAPSE_SPAN = 1e-6
#: So does this many consecutive impacts at zero time of flight.
ZERO_FLIGHT_LIMIT = 1_000
_PROGRESS_EVERY = 100

Progress = Callable[[int, int], None]


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


class Simulation:
    """Everything a run needs, built and validated from a scene.

    Args:
        scene: a :class:`billiard.scene.Scene`.
        method: ``"event"`` or ``"rk4"``; default ``scene.run.method``.

    Raises:
        GeometryError: the ball is too large for the boundary's curvature, or its
            initial position overlaps the wall or the lid.
    """

    def __init__(self, scene: Any, method: str | None = None):
        self.scene = scene
        self.method = method or scene.run.method
        if self.method not in ("event", "rk4"):
            raise ValueError(f"unknown method {self.method!r}: use 'event' or 'rk4'")
        self.curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
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
        self.counts: dict[str, int] = {"stick": 0, "slip": 0, "elastic": 0, "resting": 0}
        self.final_time = self.initial.t

    def initial_state(self) -> BallState:
        """The scene's initial state; a missing q2 puts the ball at rest on the bottom
        (at the lowest admissible point, or below a given q1)."""
        init = self.scene.initial
        theta = self.drive.angle(init.t)
        q1, q2 = init.q1, init.q2
        if q2 is None:
            if q1 is None:
                x, y = self.boundary.resting_position()
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

    def _pressing(self, ev: Event) -> bool:
        """Does the ball's acceleration relative to the boundary push it into the surface
        it touches (d2G/dt2 < 0)?"""
        px, py, vx, vy = self.drive.to_boundary_frame(ev.theta, ev.q1, ev.q2, ev.u1, ev.u2)
        a1, a2 = self.flight.acceleration(ev.u1, ev.u2)
        ab = self.drive.acceleration(ev.theta)
        ax, ay = (a1 - ab, a2) if self.drive.horizontal else (a1, a2 - ab)
        return ev.surface.gap_accel(px, py, vx, vy, ax, ay) < 0.0

    def run(self, collisions: int, recorder: Any, progress: Progress | None = None) -> str | None:
        """Simulate until ``collisions`` impacts, appending one row per impact to
        ``recorder``. Returns None, or the one-line reason the run stopped early."""
        state = self.initial
        scene = self.scene
        m, r, k = scene.ball.mass, scene.ball.radius, scene.ball.inertia_factor
        g = scene.run.gravity
        locate = self.locator.locate
        impact = self.impact
        drive = self.drive
        counts = self.counts
        recent: deque[float] = deque(maxlen=COLLAPSE_COUNT + 1)
        zero_flights = 0
        n = 0
        # The clock is a sum of tens of thousands of flight times: keep it with Neumaier's
        # compensated summation so that t stays the correctly rounded sum (a plain sum
        # drifts by ~1e-13 s, which is ~1e-12 rad of drive phase, by 3000 impacts).
        clock, clock_error = state.t, 0.0
        try:
            while n < collisions:
                try:
                    ev = locate(state.theta, state.q1, state.q2, state.u1, state.u2, state.u3)
                except SimulationError as exc:
                    raise SimulationError(f"{exc} after impact {n} (t = {state.t:.9g} s)") from None
                tau = ev.tau
                total = clock + tau
                if abs(clock) >= abs(tau):
                    clock_error += (clock - total) + tau
                else:
                    clock_error += (tau - total) + clock
                clock = total
                t = clock + clock_error
                if ev.surface.kind == "escape":
                    raise SimulationError(
                        f"ball escaped above escape_height = {scene.boundary.escape_height!r} m "
                        f"at t = {t:.9g} s after impact {n}"
                    )
                q3 = state.q3 + state.u3 * tau
                before = BallState(t, ev.theta, ev.q1, ev.q2, ev.u1, ev.u2, state.u3, q3)
                vb1, vb2 = drive.boundary_velocity(ev.theta)
                res = impact.apply(before, Contact(ev.z, vb1, vb2, self._pressing(ev)))
                state = BallState(t, ev.theta, ev.q1, ev.q2, res.u1, res.u2, res.u3, q3)
                self.final_time = t
                n += 1
                if not all(map(math.isfinite, (t, ev.q1, ev.q2, res.u1, res.u2, res.u3))):
                    raise SimulationError(f"non-finite state at impact {n} (t = {t:.9g} s)")
                u4, un = _ball.frame_velocity(res.u1, res.u2, ev.z)
                energy = _ball.energy(ev.q2, res.u1, res.u2, res.u3, m, r, k, g)
                # one row, in the order of billiard.record.COLUMNS
                row = (n, t, ev.q1, ev.q2, res.u1, res.u2, res.u3, u4, un, tau)
                recorder.append(
                    row + (res.regime, ev.z, energy, ev.surface.label) + (res.Rt, res.Rn, ev.s, q3)
                )
                counts[res.regime] += 1
                if res.resting:
                    counts["resting"] += 1
                if progress is not None and n % _PROGRESS_EVERY == 0:
                    progress(n, collisions)
                recent.append(t)
                if len(recent) > COLLAPSE_COUNT and t - recent[0] < COLLAPSE_SPAN:
                    raise SimulationError(
                        f"inelastic collapse: {COLLAPSE_COUNT} impacts within "
                        f"{COLLAPSE_SPAN:g} s of simulated time, at impact {n} (t = {t:.9g} s)"
                    )
                zero_flights = zero_flights + 1 if tau == 0.0 else 0
                if zero_flights >= ZERO_FLIGHT_LIMIT:
                    raise SimulationError(
                        f"inelastic collapse: {ZERO_FLIGHT_LIMIT} consecutive impacts with "
                        f"zero time of flight, at impact {n} (t = {t:.9g} s)"
                    )
        except SimulationError as exc:
            return str(exc)
        except (ArithmeticError, ValueError) as exc:
            kind = type(exc).__name__
            return f"numerical failure after impact {n} (t = {state.t:.9g} s): {kind}: {exc}"
        finally:
            if progress is not None:
                progress(n, collisions)
        return None


class Result:
    """The outcome of :func:`simulate`.

    Attributes:
        scene: the scene as run (initial position resolved, count and method set).
        stop_reason: None when all impacts were simulated, else a one-line reason.
        wall_time: seconds the run took.
        counts: impacts per regime (stick, slip, elastic) and how many of the elastic
            ones lifted a ball lying on the surface (resting).
        path: the streamed CSV file, or None for an in-memory run.
        final_time: simulated time of the last impact (s).
    """

    def __init__(
        self,
        scene: Any,
        recorder: MemoryRecorder | CsvRecorder,
        stop_reason: str | None,
        wall_time: float,
        counts: dict[str, int],
        final_time: float,
    ):
        self.scene = scene
        self.final_time = final_time
        self._recorder = recorder
        self.stop_reason = stop_reason
        self.wall_time = wall_time
        self.counts = dict(counts)
        self.path: Path | None = getattr(recorder, "path", None)
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
        rate = n / self.wall_time if self.wall_time > 0 else math.inf
        text = (
            f"{n} impacts ({c['stick']} stick, {c['slip']} slip, {c['elastic']} elastic) "
            f"up to t = {t_end:.6g} s in {self.wall_time:.3g} s ({rate:,.0f} impacts/s)"
        )
        if self.stop_reason:
            text += f"; stopped: {self.stop_reason}"
        return text


def simulate(
    scene: Any,
    *,
    collisions: int | None = None,
    method: str | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    progress: Progress | None = None,
) -> Result:
    """Run a scene.

    Args:
        scene: a :class:`billiard.scene.Scene`.
        collisions: number of impacts; default ``scene.run.collisions``.
        method: ``"event"`` (default from the scene) or ``"rk4"`` (the paper's scheme).
        out_dir: stream the records to ``out_dir/collisions.csv`` instead of memory.
        progress: called as ``progress(n_done, n_total)`` every few impacts.

    Returns:
        A :class:`Result`; a run that had to stop early (ball escaped, inelastic
        collapse, non-finite numbers, a root solve that failed) keeps the records so
        far and says why in ``stop_reason``.

    Raises:
        GeometryError: the scene's geometry cannot be simulated.
    """
    sim = Simulation(scene, method)
    total = scene.run.collisions if collisions is None else int(collisions)
    if out_dir is not None:
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        recorder: MemoryRecorder | CsvRecorder = CsvRecorder(Path(out_dir) / "collisions.csv")
    else:
        recorder = MemoryRecorder()
    start = time.perf_counter()
    try:
        stop_reason = sim.run(total, recorder, progress)
    finally:
        recorder.close()
    wall_time = time.perf_counter() - start
    return Result(
        sim.resolved_scene(total), recorder, stop_reason, wall_time, sim.counts, sim.final_time
    )
