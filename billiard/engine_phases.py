"""The engine's contact phases and sampling: the part of :class:`billiard.engine.Simulation`
that follows a ball rolling or sliding on a wall (``contact.model = "phases"``) and writes
exact samples of the trajectory. A mixin of the engine: it works on the engine's state.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

from billiard.errors import SimulationError
from billiard.generated import ball as _ball
from billiard.impact import Contact
from billiard.record import ContactRecord, ImpactRecord
from billiard.state import BallState
from billiard.status import Status

__all__ = [
    "compensated_add",
    "COLLAPSE_COUNT",
    "COLLAPSE_SPAN",
    "LIFT_OFF_SPEED",
    "ZERO_FLIGHT_LIMIT",
    "ContactPhases",
]

#: Inelastic collapse: this many impacts ...
COLLAPSE_COUNT = 200
#: ... within this much simulated time (s) stop the run (see ``Simulation._collapse``).
COLLAPSE_SPAN = 1e-6
#: So does this many consecutive impacts (or contact phases) of zero duration.
ZERO_FLIGHT_LIMIT = 1_000
#: Normal speed (m/s) a ball leaving a wall at lift-off is given, far below any speed
#: resolved (it moves the ball by 1e-12 m per second of flight).
LIFT_OFF_SPEED = 1e-6


def compensated_add(clock: float, error: float, tau: float) -> tuple[float, float]:
    """Add a duration tau (s) to the engine's clock by Neumaier's compensated summation:
    (new sum, new running error); the time is their sum. The clock is a sum of tens of
    thousands of durations: kept this way it stays the correctly rounded sum."""
    total = clock + tau
    if abs(clock) >= abs(tau):
        return total, error + ((clock - total) + tau)
    return total, error + ((tau - total) + clock)


class ContactPhases:
    """Contact phases and trajectory samples of the engine (mixed into ``Simulation``)."""

    @property
    def mode(self) -> str:
        """The ball's motion state: ``flight``, ``roll`` or ``slide``."""
        return self._mode

    @property
    def phase_time(self) -> dict[str, float]:
        """Simulated time (s) spent in finished rolling and sliding phases."""
        return dict(self._phase_time)

    def mode_times(self) -> dict[str, float]:
        """Simulated time (s) spent flying, rolling and sliding from the scene's start to
        ``final_time`` (an unfinished contact phase counted up to it)."""
        times = dict(self._phase_time)
        if self._mode != "flight" and self._contact:
            end = self.final_time if math.isfinite(self.final_time) else self._ball.t
            times[self._mode] += end - self._contact[4]
        total = (self.final_time if math.isfinite(self.final_time) else self._ball.t) - (
            self.initial.t
        )
        return {"flight": total - times["roll"] - times["slide"], **times}

    def _land(self, index: int, s: float, theta: float, res: Any, t: float) -> None:
        """After an impact: enter contact when the rebound speed e |wn| is below the
        landing speed (``contact.elastic_below``) while the wall presses the ball (the
        contact mode's N > 0). The ball enters contact at this impact; the chattering it
        skips would have ended at the accumulation point t + 2 v / (a (1 - e)), v the
        rebound speed and a = N / m, recorded as the phase's ``t_settle``."""
        surface = self.boundary.surfaces[index]
        model = self.contact_model
        e = model.e
        if surface.kind != "wall" or e >= 1.0:
            return
        rebound = e * abs(res.wn)
        if not (rebound <= self.scene.contact.elastic_below or res.regime == "elastic"):
            return
        wall = surface.wall
        sd = model.s_dot(wall, theta, s, res.u1, res.u2)
        mode, sgn = model.mode_for(wall, theta, s, sd, res.u3)
        n_force = model.forces(wall, mode, sgn, theta, (s, sd, res.u3))[2]
        if not n_force > 0.0:
            return
        settle = t + 2.0 * rebound / (n_force / model.m * (1.0 - e))
        self._mode = mode
        self._contact = (float(index), s, sd, sgn, t, settle)

    def _start_in_contact(self) -> None:
        """A ball that starts lying on a wall (gap and relative normal speed zero to
        rounding, 1e-12 m and 1e-12 m/s) while the wall presses it starts in contact,
        without an impact."""
        ball = self._ball
        px, py, vx, vy = self.drive.to_boundary_frame(
            ball.theta, ball.q1, ball.q2, ball.u1, ball.u2
        )
        model = self.contact_model
        for j, surface in enumerate(self.boundary.offsets):
            warm = list(self.warm[j])
            gap, rate = surface.gap_rate(px, py, vx, vy, warm)
            s, z, cz = surface.contact(px, warm)
            if abs(gap) > 1e-12 or abs(rate * cz) > 1e-12 or not surface.lo <= s <= surface.hi:
                continue
            wall = surface.wall
            sd = model.s_dot(wall, ball.theta, s, ball.u1, ball.u2)
            mode, sgn = model.mode_for(wall, ball.theta, s, sd, ball.u3)
            if model.forces(wall, mode, sgn, ball.theta, (s, sd, ball.u3))[2] > 0.0:
                self._mode = mode
                self._contact = (float(j), s, sd, sgn, ball.t, ball.t)
                return

    def _other_gaps(self, index: int) -> list[Callable[[float, float], float]]:
        """The gaps (m) a phase on surface ``index`` watches, in the order of
        ``boundary.surfaces`` without ``index``: the other walls' offset curves, the lid
        and the escape level (a ball rolling or sliding up a wall reaches them too)."""
        gaps = []
        for j, surface in enumerate(self.boundary.surfaces):
            if j == index:
                continue
            if surface.kind == "wall":
                warm = self.warm[j]
                gaps.append(lambda px, py, o=surface, w=warm: py - o.height(px, w))
            else:
                gaps.append(lambda px, py, level=surface.level: level - py)
        return gaps

    def _emit_samples(self, t_from: float, t_to: float, state_at: Callable) -> None:
        """Report the samples k dt (from the run's start) in [t_from, t_to]."""
        dt, t0 = self.sample_dt, self.initial.t
        while True:
            ts = t0 + self._samples * dt
            if ts > t_to:
                return
            if ts >= t_from:
                self.on_sample(ts, *state_at(ts))
            self._samples += 1

    def _sample_flight_to(self, state: BallState, t_to: float) -> None:
        fl = self._sample_flight
        fl.begin(state.q1, state.q2, state.u1, state.u2, state.u3)
        reached = [0.0]
        sc = self.scene

        def at(ts: float) -> tuple:
            tau = ts - state.t
            if tau < 0.0:
                tau = 0.0
            while reached[0] < tau:
                reached[0] = fl.advance(reached[0], tau)
            q1, q2, u1, u2 = fl.state(tau)
            energy = _ball.energy(q2, u1, u2, state.u3, sc.ball.mass, sc.ball.radius,
                                  sc.ball.inertia_factor, sc.run.gravity)  # fmt: skip
            return q1, q2, u1, u2, state.u3, energy, "flight"

        self._emit_samples(state.t, t_to, at)

    def _contact_step(self, until: float) -> ImpactRecord | ContactRecord | None:
        """One contact phase, to its end (or to ``until``: None, state unchanged)."""
        model = self.contact_model
        ball = self._ball
        index, s, sd, sgn, t_start, settle = self._contact
        index = int(index)
        surface = self.boundary.surfaces[index]
        wall = surface.wall
        mode = self._mode
        t0, theta0 = ball.t, ball.theta
        omega = self.drive.omega
        sc = self.scene

        def sample_times() -> Iterator[float]:
            k = self._samples
            while True:
                ts = self.initial.t + k * self.sample_dt
                if ts > until:
                    return
                if ts >= t0:
                    yield ts - t0
                k += 1

        def on_sample(tau: float, y: tuple) -> None:
            theta = theta0 + omega * tau
            q1, q2, u1, u2, u3 = model.lab_state(wall, theta, y, mode)
            energy = _ball.energy(q2, u1, u2, u3, sc.ball.mass, sc.ball.radius,
                                  sc.ball.inertia_factor, sc.run.gravity)  # fmt: skip
            self.on_sample(t0 + tau, q1, q2, u1, u2, u3, energy, mode)
            self._samples += 1

        end = model.run_phase(
            wall, mode, sgn, theta0, (s, sd, ball.u3), until - t0, self._other_gaps(index),
            sample_times() if self.on_sample is not None else (),
            on_sample if self.on_sample is not None else None,
        )  # fmt: skip
        if end.reason is None:
            return None
        tau = end.tau
        total, error = compensated_add(self._clock, self._clock_error, tau)
        t = total + error
        theta = (theta0 + omega * tau) % (2.0 * math.pi)
        q1, q2, u1, u2, u3 = model.lab_state(wall, theta, end.y, mode)
        if not math.isfinite(q1 + q2 + u1 + u2 + u3):
            raise SimulationError(
                f"non-finite state at the end of a contact phase (t = {t:.9g} s)",
                Status.NON_FINITE,
            )
        q3 = ball.q3 + 0.5 * (ball.u3 + u3) * tau
        record = ContactRecord(
            t_start, t, surface.label, mode, end.reason, settle,
            *model.lab_state(wall, theta0, (s, sd, ball.u3), mode), q1, q2, u1, u2, u3,
        )  # fmt: skip
        self._ball = BallState(t, theta, q1, q2, u1, u2, u3, q3)
        self._clock, self._clock_error = total, error
        self._phase_time[mode] += t - t_start
        self.final_time = t
        self._zero_flights = self._zero_flights + 1 if tau == 0.0 else 0
        if self._zero_flights >= ZERO_FLIGHT_LIMIT:
            self._fault = SimulationError(
                f"contact phases of zero duration piled up at t = {t:.9g} s", Status.COLLAPSE
            )
        s1, sd1 = end.y[0], end.y[1]
        reason = end.reason
        if reason in ("lift-off", "wall-end"):
            # The centre is on the offset curve with a tangent velocity: give it
            # LIFT_OFF_SPEED along the wall's normal so that the flight starts leaving the
            # wall (rounding could make it touch the wall again at once).
            fp = wall.df(s1, wall.p)
            c = 1.0 / math.sqrt(1.0 + fp * fp)
            u1, u2 = u1 - LIFT_OFF_SPEED * fp * c, u2 + LIFT_OFF_SPEED * c
            self._ball = BallState(t, theta, q1, q2, u1, u2, u3, q3)
            self._mode, self._contact = "flight", ()
        elif reason == "slip":
            f = model.forces(wall, "roll", 0.0, theta, (s1, sd1))[3]
            self._mode = "slide"
            self._contact = (float(index), s1, sd1, -1.0 if f > 0.0 else 1.0, t, t)
        elif reason == "roll":
            _, _, n_force, f = model.forces(wall, "roll", 0.0, theta, (s1, sd1))
            if abs(f) <= model.mu_s * n_force:
                self._mode, self._contact = "roll", (float(index), s1, sd1, 0.0, t, t)
            else:
                self._contact = (float(index), s1, sd1, -sgn, t, t)
        if self.on_contact is not None:
            self.on_contact(record)
        if reason == "impact":
            self._mode, self._contact = "flight", ()
            return self._impact_from_contact(end.other, index, t, tau, theta, q3)
        return record

    def _impact_from_contact(
        self, other: int, index: int, t: float, tau: float, theta: float, q3: float
    ) -> ImpactRecord:
        """The ball in contact with one wall reaches another (the wedge's vertex), the
        lid, or the escape level (which ends the run)."""
        j = other if other < index else other + 1
        surface = self.boundary.surfaces[j]
        ball = self._ball
        if surface.kind == "escape":
            raise SimulationError(
                f"ball escaped above escape_height = {self.scene.boundary.escape_height!r} m "
                f"at t = {t:.9g} s after impact {self._impacts}",
                Status.ESCAPED,
            )
        px, py, vx, vy = self.drive.to_boundary_frame(theta, ball.q1, ball.q2, ball.u1, ball.u2)
        s_o, z, _ = surface.contact(px, self.warm[j])
        vb1, vb2 = self.drive.boundary_velocity(theta)
        pressing = True
        if surface.kind == "lid":
            # pressed into the lid when the ball's free acceleration relative to the
            # boundary points up into it
            a1, a2 = self.flight.acceleration(ball.u1, ball.u2)
            ab = self.drive.acceleration(theta)
            ax, ay = (a1 - ab, a2) if self.drive.horizontal else (a1, a2 - ab)
            pressing = surface.gap_accel(px, py, vx, vy, ax, ay, self.warm[j]) < 0.0
        res = self.impact.apply(ball, Contact(z, vb1, vb2, pressing))
        sc = self.scene
        u4, un = _ball.frame_velocity(res.u1, res.u2, z)
        energy = _ball.energy(ball.q2, res.u1, res.u2, res.u3, sc.ball.mass, sc.ball.radius,
                              sc.ball.inertia_factor, sc.run.gravity)  # fmt: skip
        n = self._impacts + 1
        record = ImpactRecord(
            n, t, ball.q1, ball.q2, res.u1, res.u2, res.u3, u4, un, tau, res.regime, z,
            energy, surface.label, res.Rt, res.Rn, s_o, q3,
        )  # fmt: skip
        self._impacts = n
        self._ball = BallState(t, theta, ball.q1, ball.q2, res.u1, res.u2, res.u3, q3)
        self.counts[res.regime] = self.counts.get(res.regime, 0) + 1
        recent = self._recent
        recent.append(t)
        while t - recent[0] >= COLLAPSE_SPAN:
            recent.popleft()
        self._fault = self._collapse(n, t)
        self._land(j, s_o, theta, res, t)
        return record
