"""One event of the engine on the runtime's classes: locate the next impact, apply the
impact law, record it, keep the clock and the collapse window (a mixin of
:class:`billiard.engine.simulation.Simulation`, working on its state).

A run normally makes its impacts with :func:`billiard.kernels.loop.step` on the kernels
(:mod:`billiard.engine.kernel_engine`; under contact phases the flights between them,
:meth:`billiard.engine.simulation.Simulation._fly`), the same operations in the same
order; this step runs when the kernels cannot (trajectory samples, an impact law
replaced after construction), for :meth:`Simulation.step` under contact phases, and
after a contact phase's impact.
"""

from __future__ import annotations

import math
from typing import Any

from billiard.engine.contact_phases import (
    COLLAPSE_COUNT,
    COLLAPSE_SPAN,
    ZERO_FLIGHT_LIMIT,
    compensated_add,
)
from billiard.engine.state import BallState
from billiard.errors import SimulationError
from billiard.generated import ball as _ball
from billiard.kernels.interpreted import impact as _impact
from billiard.models.corner import is_impact
from billiard.models.event_locator import Event
from billiard.models.impact import Contact
from billiard.runfile.record import COLUMNS, ContactRecord, ImpactRecord
from billiard.status import Status

__all__ = ["EventStep", "check_finite"]

#: what the flight's step returns at a contact without impulse under contact phases
_NO_IMPULSE = object()

# Floats of a record, by column name, for naming the culprit of a non-finite state.
_ROW_FLOATS = tuple(name for name in COLUMNS if name not in ("n", "regime", "wall"))


class EventStep:
    """The engine's one event on the classes (mixed into ``Simulation``)."""

    _impacts: int
    _ball: BallState
    _fault: Any

    def _pressing(self, ev: Event) -> bool:
        """Does the ball's acceleration relative to the boundary push it into the surface
        it touches (d2G/dt2 < 0)?"""
        return self._gap_acceleration(ev) < 0.0

    def _gap_acceleration(self, ev: Event) -> float:
        """d2G/dt2 (m/s^2) of the surface the ball touches, in free flight (negative:
        its acceleration relative to the boundary pushes it into the surface)."""
        px, py, vx, vy = self.drive.to_boundary_frame(ev.theta, ev.q1, ev.q2, ev.u1, ev.u2)
        a1, a2 = self.flight.acceleration(ev.u1, ev.u2)
        ab = self.drive.acceleration(ev.theta)
        ax, ay = (a1 - ab, a2) if self.drive.horizontal else (a1, a2 - ab)
        return ev.surface.gap_accel(px, py, vx, vy, ax, ay, self.warm[ev.index])

    def _step(self, until: float) -> ImpactRecord | ContactRecord | None:
        while True:
            if self._mode != "flight":
                return self._contact_step(until)
            record = self._flight_step(until)
            if record is not _NO_IMPULSE:
                return record
            # a contact without impulse (contact phases): on from it, or from its landing
            if self._fault is not None:
                raise self._fault

    def _flight_step(self, until: float) -> Any:
        """The flight to the next contact and the impact there (its record), None after
        ``until``, or ``_NO_IMPULSE``: under contact phases a contact that gives no
        impulse is no impact (``billiard.models.corner``): no record, nothing counted,
        the ball on from there (``loop.no_impulse``)."""
        state = self._ball
        n = self._impacts
        try:
            ev = self.locator.locate(state.theta, state.q1, state.q2, state.u1, state.u2, state.u3)
        except SimulationError as exc:
            raise SimulationError(
                f"{exc} after impact {n} (t = {state.t:.9g} s)", exc.status
            ) from None
        tau = ev.tau
        total, error = compensated_add(self._clock, self._clock_error, tau)
        t = total + error
        if self.on_sample is not None:
            self._sample_flight_to(state, min(t, until))
        if t > until:
            return None
        if ev.surface.kind == "escape":
            raise SimulationError(
                f"ball escaped above escape_height = {self.scene.boundary.escape_height!r} m "
                f"at t = {t:.9g} s after impact {n}",
                Status.ESCAPED,
            )
        q3 = state.q3 + state.u3 * tau
        before = BallState(t, ev.theta, ev.q1, ev.q2, ev.u1, ev.u2, state.u3, q3)
        vb1, vb2 = self.drive.boundary_velocity(ev.theta)
        accel = -self._gap_acceleration(ev)
        # under contact phases a lying ball lands or reflects: the low-velocity rule's
        # relaunch (which adds energy) is the impacts model's alone
        pressing = accel > 0.0 and not self.phases
        try:
            res = self.impact.apply(before, Contact(ev.z, vb1, vb2, pressing))
        except SimulationError as exc:
            raise SimulationError(f"{exc} at impact {n + 1} (t = {t:.9g} s)", exc.status) from None
        u4, un = _ball.frame_velocity(res.u1, res.u2, ev.z)
        energy = _ball.energy(ev.q2, res.u1, res.u2, res.u3, *self._ball_constants)
        record = ImpactRecord(
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
            ev.surface.code,
            res.Rt,
            res.Rn,
            ev.s,
            q3,
        )
        # a non-finite number is never recorded (the sum of finite numbers of physical
        # size is finite, so one addition chain tests them all)
        if not math.isfinite(
            t + ev.q1 + ev.q2 + res.u1 + res.u2 + res.u3 + u4 + un + tau + ev.z + energy
            + res.Rt + res.Rn + ev.s + q3
        ):  # fmt: skip
            check_finite(record)
        if self.phases and not is_impact(res):
            self._ball = BallState(t, ev.theta, ev.q1, ev.q2, res.u1, res.u2, res.u3, q3)
            self._clock, self._clock_error = total, error
            self._zero_flights = self._zero_flights + 1 if tau == 0.0 else 0
            self.final_time = t
            # as loop.no_impulse: such contacts enter the collapse window too
            recent = self._recent
            recent.append(t)
            while t - recent[0] >= COLLAPSE_SPAN:
                recent.popleft()
            if self._zero_flights >= ZERO_FLIGHT_LIMIT or len(recent) > COLLAPSE_COUNT:
                self._fault = pressed_stop(ev.surface.kind == "lid", n, t)
            self._land_after(ev, res, accel, t)
            return _NO_IMPULSE
        # commit: from here on nothing can fail, so the state always matches the records
        self._impacts = n + 1
        self._last_impact = t
        self._ball = BallState(t, ev.theta, ev.q1, ev.q2, res.u1, res.u2, res.u3, q3)
        self._clock, self._clock_error = total, error
        counts = self._counts
        counts[res.regime] = counts.get(res.regime, 0) + 1
        if res.resting:
            counts["resting"] += 1
        self._zero_flights = self._zero_flights + 1 if tau == 0.0 else 0
        # collapse window: the impact times within COLLAPSE_SPAN of this one (the times
        # are non-decreasing, so those form the deque's tail)
        recent = self._recent
        recent.append(t)
        while t - recent[0] >= COLLAPSE_SPAN:
            recent.popleft()
        self.final_time = t
        if len(recent) > COLLAPSE_COUNT or self._zero_flights >= ZERO_FLIGHT_LIMIT:
            self._fault = self._collapse(n + 1, t)
        if self.phases:
            self._land_after(ev, res, accel, t)
        return record

    def _land_after(self, ev: Event, res: Any, accel: float, t: float) -> None:
        """Land the ball after a flight's contact at t if the chattering it starts
        settles (``ContactPhases._land``; ``accel``: the free flight's acceleration
        into the surface, m/s^2)."""
        e = self.contact_model.e
        tail = ev.surface.kind != "lid" and _impact.chatter_tail(e, res.wn, accel, self.drive.omega)
        self._land(ev.index, ev.s, ev.theta, res, t, tail)

    def _collapse(self, n: int, t: float) -> SimulationError | None:
        """The inelastic-collapse stop after impact n, if the impacts have piled up.

        Two criteria, both meaning that the ball has stopped flying and is in sustained
        contact, which an impact-only model cannot represent:

        * COLLAPSE_COUNT (200) impacts within COLLAPSE_SPAN (1e-6 s) of simulated time:
          flights of 5e-9 s on average. Under an acceleration a toward the wall (gravity
          plus the drive's, 10 to 1000 m/s^2) a hop of duration t rises a t^2 / 8, below
          1e-14 m here, far below the locators' resolution of the gap (1e-12 m): these
          are no longer flights. This is what an inelastic collapse looks like: the
          flight times of a ball bouncing on a table with e < 1 form a geometric series
          (ratio about e^2) whose sum converges to the time the ball comes to rest, so
          the impacts accumulate at that point; the criterion stops it within a few
          hundred impacts of the flights falling below 1e-6 s. 1e-6 s is also
          negligible against any drive period (0.01 to 1 s). The paper scenes never
          have two impacts within 1e-6 s in 25,000 impacts each (their shortest flights
          are 5e-6 s, in the wedge's vertex).
        * ZERO_FLIGHT_LIMIT (1,000) consecutive impacts with a time of flight of
          exactly zero, which do not advance the clock at all.
        """
        if len(self._recent) > COLLAPSE_COUNT:
            return SimulationError(
                f"inelastic collapse: {COLLAPSE_COUNT} impacts within "
                f"{COLLAPSE_SPAN:g} s of simulated time, at impact {n} (t = {t:.9g} s)",
                Status.COLLAPSE,
            )
        if self._zero_flights >= ZERO_FLIGHT_LIMIT:
            return SimulationError(
                f"inelastic collapse: {ZERO_FLIGHT_LIMIT} consecutive impacts with "
                f"zero time of flight, at impact {n} (t = {t:.9g} s)",
                Status.COLLAPSE,
            )
        return None


def pressed_stop(lid: bool, n: int, t: float) -> SimulationError:
    """The stop of a ball that meets a surface (``lid``: the lid) without impulse again
    and again while the clock no longer advances (``loop.no_impulse``): pressed against
    a surface that cannot hold it, the run would turn for ever at time t."""
    where = "the lid (which cannot hold a ball)" if lid else "a wall"
    return SimulationError(
        f"no progress in simulated time: the ball is pressed against {where} and meets "
        f"it without impulse again and again ({COLLAPSE_COUNT} contacts within "
        f"{COLLAPSE_SPAN:g} s or {ZERO_FLIGHT_LIMIT} at one time) after impact {n} "
        f"(t = {t:.9g} s)",
        Status.COLLAPSE,
    )


def check_finite(record: ImpactRecord) -> None:
    """Raise SimulationError naming the first non-finite quantity of an impact's record."""
    for name in _ROW_FLOATS:
        value = getattr(record, name)
        if not math.isfinite(value):
            raise SimulationError(
                f"non-finite state at impact {record.n} (t = {record.t:.9g} s): {name} = {value!r}",
                Status.NON_FINITE,
            )
