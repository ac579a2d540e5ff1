"""The engine's contact phases and sampling: the part of
:class:`billiard.engine.simulation.Simulation` that follows a ball rolling or sliding on
a wall (``contact.model = "phases"``) and writes exact samples of the trajectory. A
mixin of the engine: it works on the engine's state."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

from billiard.engine.interrupt import RunInterrupted
from billiard.engine.state import BallState
from billiard.errors import BallAtRest, SimulationError
from billiard.generated import ball as _ball
from billiard.kernels.interpreted import impact as _impact
from billiard.kernels.rules import (
    COLLAPSE_COUNT,
    COLLAPSE_SPAN,
    ZERO_FLIGHT_LIMIT,
    compensated_add,
)
from billiard.models import chatter as _chatter
from billiard.models.corner import is_impact
from billiard.models.hold import HELD
from billiard.models.impact import Contact
from billiard.runfile.record import ContactRecord, ImpactRecord
from billiard.status import Status

__all__ = [
    "compensated_add",
    "COLLAPSE_COUNT",
    "CUT",
    "COLLAPSE_SPAN",
    "LIFT_OFF_SPEED",
    "ZERO_FLIGHT_LIMIT",
    "ContactPhases",
]

#: The ``end`` of a contact phase that the run's end cut (contacts.csv).
CUT = "cut"
#: Normal speed (m/s) a ball leaving a wall at lift-off is given, far below any speed
#: resolved (it moves the ball by 1e-12 m per second of flight).
LIFT_OFF_SPEED = 1e-6


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
        """Simulated time (s) spent flying, rolling, sliding and held by two walls from the
        scene's start to
        ``final_time`` (an unfinished contact phase counted up to it)."""
        times = dict(self._phase_time)
        if self._mode != "flight" and self._contact:
            end = self.final_time if math.isfinite(self.final_time) else self._ball.t
            # (none before a landing at the end of a chatter series, still ahead)
            times[self._mode] += max(0.0, end - self._contact[4])
        total = (self.final_time if math.isfinite(self.final_time) else self._ball.t) - (
            self.initial.t
        )
        return {"flight": total - sum(times.values()), **times}

    def _settles(self, res: Any) -> bool:
        """Does the chattering after this impact settle: an inelastic contact (e < 1)
        whose rebound speed e |wn| is at most the landing speed ``contact.elastic_below``
        (or the low-velocity rule applied)? The one criterion for landing on a wall and
        for being held by two."""
        return _impact.rebound_settles(
            self.contact_model.e, self.scene.contact.elastic_below, res.wn,
            res.regime == "elastic",
        )  # fmt: skip

    def _land(
        self, index: int, s: float, theta: float, res: Any, t: float, tail: bool | None = None
    ) -> None:
        """After an impact at t on surface ``index``: enter contact while the wall presses
        the ball (the contact mode's N > 0) when either

        * the chatter series it starts may be summed (:func:`billiard.models.chatter.summed`:
          it ends within 1e-6 of a drive period, and the bound on its end time is within
          ``CHATTER_TOL`` of a period): the ball enters contact at that time,
          t + 2 v / (a (1 - e)), v = e |wn| the rebound speed and a = N / m (the phase
          starts there: ``_end_chatter``), whatever ``contact.elastic_below`` is;
        * or the rebound speed e |wn| is at most the landing speed
          (``contact.elastic_below``): the ball enters contact at this impact, the
          chattering it skips recorded as the phase's ``t_settle``, t + 2 v / (a (1 - e)).

        ``tail``: the free flight's test of the first (``impact.chatter_tail``, which the
        kernels make), None after a contact phase's impact (not made)."""
        surface = self.boundary.surfaces[index]
        model = self.contact_model
        slow = self._settles(res)
        if surface.kind != "wall" or model.e >= 1.0 or not (slow or tail is not False):
            return
        e = model.e
        rebound = e * abs(res.wn)
        wall = surface.wall
        sd = model.s_dot(wall, theta, s, res.u1, res.u2)
        mode, sgn = model.mode_for(wall, theta, s, sd, res.u3)
        n_force = model.forces(wall, mode, sgn, theta, (s, sd, res.u3))[2]
        if not n_force > 0.0:
            if slow:
                self._leave_wall(wall, s, theta)
            return
        if tail is not False:
            omega, u3 = self.drive.omega, res.u3

            def accel(tau: float) -> float:
                y = (s + sd * tau, sd, u3)
                return model.forces(wall, mode, sgn, theta + omega * tau, y)[2] / model.m

            tau = _chatter.summed(rebound, e, accel, _impact.chatter_period(omega))
            if tau is not None:
                # the phase starts where the series ends (``_end_chatter`` moves the
                # ball there when the run reaches that time)
                total, error = compensated_add(self._clock, self._clock_error, tau)
                self._mode = mode
                self._contact = (float(index), s, sd, sgn, total + error, total + error)
                return
        if not slow:
            return
        settle = t + 2.0 * rebound / (n_force / model.m * (1.0 - e))
        self._mode = mode
        self._contact = (float(index), s, sd, sgn, t, settle)

    def _end_chatter(self, until: float) -> bool:
        """A ball that landed at the end of a summed chatter series (its phase starts
        later than the impact it is at): move it there, at contact abscissa s with
        tangential speed sd and its spin, all as at the impact
        (:mod:`billiard.models.chatter`), the boundary moved on; samples in between show
        that state. False (the state unchanged, samples up to ``until`` reported) when
        the series ends after ``until``."""
        index, s, sd, _, t_start, _ = self._contact
        model = self.contact_model
        wall = self.boundary.surfaces[int(index)].wall
        mode = self._mode
        ball = self._ball
        omega = self.drive.omega
        samples = self._samples
        if self.on_sample is not None:
            sc = self.scene

            def at(ts: float) -> tuple:
                angle = ball.theta + omega * (ts - ball.t)
                q1, q2, u1, u2, _ = model.lab_state(wall, angle, (s, sd, ball.u3), mode)
                energy = _ball.energy(q2, u1, u2, ball.u3, sc.ball.mass, sc.ball.radius,
                                      sc.ball.inertia_factor, sc.run.gravity)  # fmt: skip
                return q1, q2, u1, u2, ball.u3, energy, "flight"

            self._emit_samples(ball.t, min(t_start, until), at)
        if t_start > until:
            # as the state, its sample count stays at the impact (see _cut)
            self._samples = samples
            return False
        tau = t_start - ball.t
        theta = (ball.theta + omega * tau) % (2.0 * math.pi)
        q1, q2, u1, u2, _ = model.lab_state(wall, theta, (s, sd, ball.u3), mode)
        self._ball = BallState(t_start, theta, q1, q2, u1, u2, ball.u3, ball.q3 + ball.u3 * tau)
        self._clock, self._clock_error = t_start, 0.0
        self.final_time = t_start
        return True

    def _leave_wall(self, wall: Any, s: float, theta: float) -> None:
        """A settling impact where the wall does not press the ball (N <= 0): it flies
        on. Leaving at a relative normal speed below LIFT_OFF_SPEED (after an impact with
        e = 0, or a grazing one), rounding could make the flight touch the wall again at
        once: an impact of zero duration, again and again at one instant. It leaves at
        LIFT_OFF_SPEED along the wall's normal, as at a lift-off."""
        fp = wall.df(s, wall.p)
        c = 1.0 / math.sqrt(1.0 + fp * fp)
        nx, ny = -fp * c, c
        vb1, vb2 = self.drive.boundary_velocity(theta)
        ball = self._ball
        vn = (ball.u1 - vb1) * nx + (ball.u2 - vb2) * ny
        if vn >= LIFT_OFF_SPEED:
            return
        dv = LIFT_OFF_SPEED - vn
        self._ball = BallState(
            ball.t, ball.theta, ball.q1, ball.q2, ball.u1 + dv * nx, ball.u2 + dv * ny,
            ball.u3, ball.q3,
        )  # fmt: skip

    def _start_in_contact(self) -> None:
        """A ball that starts lying on a wall (gap and relative normal speed zero to
        rounding, 1e-12 m and 1e-12 m/s) while the wall presses it starts in contact,
        without an impact."""
        ball = self._ball
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
        if len(touching) == 2:
            (a, za), (b, zb) = touching
            if self.vertex_hold.holds(za, zb, ball.theta, ball.u3):
                self._enter_hold(a, b, ball.t, ball.t)
                return
        for j, _ in touching:
            surface = self.boundary.offsets[j]
            s, _, _ = surface.contact(px, list(self.warm[j]))
            wall = surface.wall
            sd = model.s_dot(wall, ball.theta, s, ball.u1, ball.u2)
            mode, sgn = model.mode_for(wall, ball.theta, s, sd, ball.u3)
            if model.forces(wall, mode, sgn, ball.theta, (s, sd, ball.u3))[2] > 0.0:
                self._mode = mode
                self._contact = (float(j), s, sd, sgn, ball.t, ball.t)
                return

    def _watched(self, index: int) -> list[tuple[Any, list]]:
        """The surfaces a phase on surface ``index`` watches, each with its warm start,
        in the order of ``boundary.surfaces`` without ``index``: the other walls' offset
        curves, the lid and the escape level (a ball rolling or sliding up a wall
        reaches them too)."""
        return [
            (surface, self.warm[j])
            for j, surface in enumerate(self.boundary.surfaces)
            if j != index
        ]

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

    def _end_phase(self, mode: str, t_start: float, tau: float, total: float, error: float) -> None:
        """The clock and the tallies at the end of a contact phase of ``tau`` seconds (the
        new time is the compensated sum total + error); zero-length phases in a row are
        counted like zero flights, a collapse."""
        t = total + error
        self._clock, self._clock_error = total, error
        self._phase_time[mode] += t - t_start
        self.final_time = t
        self._zero_flights = self._zero_flights + 1 if tau == 0.0 else 0
        if self._zero_flights >= ZERO_FLIGHT_LIMIT:
            self._fault = SimulationError(
                f"contact phases of zero duration piled up at t = {t:.9g} s", Status.COLLAPSE
            )

    def _sample_times(self, t0: float, until: float) -> Iterator[float]:
        """The sample times k dt (from the run's start) in [t0, until], as offsets from
        t0 (s), from the next sample not yet reported."""
        k = self._samples
        while True:
            ts = self.initial.t + k * self.sample_dt
            if ts > until:
                return
            if ts >= t0:
                yield ts - t0
            k += 1

    def _report_sample(
        self, t: float, q1: float, q2: float, u1: float, u2: float, u3: float, mode: str
    ) -> None:
        """Report one sample (trajectory.csv) of a ball in contact, with its energy."""
        ball = self.scene.ball
        energy = _ball.energy(q2, u1, u2, u3, ball.mass, ball.radius, ball.inertia_factor,
                              self.scene.run.gravity)  # fmt: skip
        self.on_sample(t, q1, q2, u1, u2, u3, energy, mode)
        self._samples += 1

    def _contact_step(self, until: float) -> ImpactRecord | ContactRecord | None:
        """One contact phase, to its end (or to ``until``: None, state unchanged)."""
        if self._mode == HELD:
            return self._hold_step(until)
        if self._ball.t < self._contact[4] and not self._end_chatter(until):
            return None
        model = self.contact_model
        ball = self._ball
        index, s, sd, sgn, t_start, settle = self._contact
        index = int(index)
        surface = self.boundary.surfaces[index]
        wall = surface.wall
        mode = self._mode
        t0, theta0 = ball.t, ball.theta
        omega = self.drive.omega
        samples = self._samples

        def on_sample(tau: float, y: tuple) -> None:
            theta = theta0 + omega * tau
            self._report_sample(t0 + tau, *model.lab_state(wall, theta, y, mode), mode)

        deadline = self._contact_deadline(until)
        if t0 >= deadline:
            raise self._in_contact(t0)
        end = self._phase_end(
            t0,
            lambda: model.run_phase(
                wall, mode, sgn, theta0, (s, sd, ball.u3), until - t0, self._watched(index),
                self._sample_times(t0, until) if self.on_sample is not None else (),
                on_sample if self.on_sample is not None else None,
                pause=self._pause, stop_at=deadline - t0, interval=self._phase_interval(wall),
            ),
        )  # fmt: skip
        if end.reason is None:
            # the run ends inside the phase (its duration, the contact span, a stop
            # request): the phase so far is reported as cut, the state stays at its start
            t_cut = t0 + end.tau
            theta = (theta0 + omega * end.tau) % (2.0 * math.pi)
            self._cut(
                ContactRecord(
                    t_start,
                    t_cut,
                    surface.code,
                    mode,
                    CUT,
                    settle,
                    *model.lab_state(wall, theta0, (s, sd, ball.u3), mode),
                    *model.lab_state(wall, theta, end.y, mode)[:5],
                ),  # fmt: skip
                deadline,
                samples,
            )
            return None
        tau = end.tau
        total, error, t, theta = self._clock_after(theta0, tau)
        q1, q2, u1, u2, u3 = model.lab_state(wall, theta, end.y, mode)
        if not math.isfinite(q1 + q2 + u1 + u2 + u3):
            raise SimulationError(
                f"non-finite state at the end of a contact phase (t = {t:.9g} s)",
                Status.NON_FINITE,
            )
        q3 = ball.q3 + 0.5 * (ball.u3 + u3) * tau
        record = ContactRecord(
            t_start, t, surface.code, mode, end.reason, settle,
            *model.lab_state(wall, theta0, (s, sd, ball.u3), mode), q1, q2, u1, u2, u3,
        )  # fmt: skip
        self._ball = BallState(t, theta, q1, q2, u1, u2, u3, q3)
        self._end_phase(mode, t_start, tau, total, error)
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
        if reason == "wall-end":
            self._check_in_container(wall, s1, t)
        if reason == "impact":
            self._mode, self._contact = "flight", ()
            impact = self._impact_from_contact(end.other, index, t, tau, theta, q3)
            if impact is not None:
                return impact
        return record

    def _impact_from_contact(
        self, other: int, index: int, t: float, tau: float, theta: float, q3: float
    ) -> ImpactRecord | None:
        """The ball in contact with one wall reaches another (the wedge's vertex), the
        lid, or the escape level (which ends the run). None when the contact gives no
        impulse (see :func:`billiard.models.corner.is_impact`): no impact, neither
        recorded nor counted; the ball goes on from its state as after an impact."""
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
        # a ball that reaches a second wall or the lid lands, is held or reflects: under
        # contact phases the low-velocity rule never relaunches it (that adds energy)
        pressing = False
        res = self.impact.apply(ball, Contact(z, vb1, vb2, pressing))
        if not is_impact(res):
            if not self._hold_after(index, j, theta, res, t, impulse=False, instant=tau == 0.0):
                self._land(j, s_o, theta, res, t)
            return None
        sc = self.scene
        u4, un = _ball.frame_velocity(res.u1, res.u2, z)
        energy = _ball.energy(ball.q2, res.u1, res.u2, res.u3, sc.ball.mass, sc.ball.radius,
                              sc.ball.inertia_factor, sc.run.gravity)  # fmt: skip
        n = self._impacts + 1
        record = ImpactRecord(
            n, t, ball.q1, ball.q2, res.u1, res.u2, res.u3, u4, un, tau, res.regime, z,
            energy, surface.code, res.Rt, res.Rn, s_o, q3,
        )  # fmt: skip
        self._impacts = n
        self._last_impact = t
        self._ball = BallState(t, theta, ball.q1, ball.q2, res.u1, res.u2, res.u3, q3)
        self.counts[res.regime] = self.counts.get(res.regime, 0) + 1
        recent = self._recent
        recent.append(t)
        while t - recent[0] >= COLLAPSE_SPAN:
            recent.popleft()
        self._fault = self._collapse(n, t)
        if not self._hold_after(index, j, theta, res, t, instant=tau == 0.0):
            self._land(j, s_o, theta, res, t)
        return record

    # ------------------------------------------------------------------ two walls

    def _hold_after(
        self,
        index: int,
        j: int,
        theta: float,
        res: Any,
        t: float,
        impulse: bool = True,
        instant: bool = False,
    ) -> bool:
        """After a contact with wall j of a ball in contact with wall ``index`` (an
        impact, or with ``impulse`` False a contact that gave none; ``instant``: the
        phase on wall ``index`` lasted no time, it met wall j where it began): is it held
        by both? Yes when both walls press it and

        * the rebound speed is below the landing speed (as for landing on one wall), or
        * the phase lasted no time: the ball meets one wall and the other at one
          instant, a series of impacts at that instant that takes its velocity relative
          to the boundary to zero (e < 1: each impact shrinks its normal component
          towards one wall by e, and the two normals span the plane), or
        * the chattering between the two walls would end within ``CHATTER_TAIL`` of a
          drive period: v = e |wn| (|wn|, the speed at which the ball separates from
          wall j, after a contact without impulse) with 2 v <= CHATTER_TAIL P a (1 - e),
          a the smaller wall's normal force per unit mass, the bound of a series of
          rebounds each turned back by at least a (the time of a single wall's series,
          :mod:`billiard.models.chatter`; recorded as the phase's ``t_settle``).

        The last two hold whatever ``contact.elastic_below`` is. The chattering this
        skips would carry the ball's velocity relative to the boundary, at most v, to
        zero: it is dropped (never energy created), the spin is kept. Without them a
        ball pressed into a vertex with ``elastic_below = 0`` meets one wall and the
        other at one instant, again and again, until the collapse stop."""
        if self.boundary.surfaces[j].kind != "wall":
            return False  # the lid holds nothing
        slow = self._settles(res)
        e = self.contact_model.e
        if not slow and e >= 1.0:
            return False
        ball = self._ball
        px, _, _, _ = self.drive.to_boundary_frame(theta, ball.q1, ball.q2, ball.u1, ball.u2)
        offsets = self.boundary.offsets
        z_index = offsets[index].contact(px, list(self.warm[index]))[1]
        z_j = offsets[j].contact(px, list(self.warm[j]))[1]
        hold = self.vertex_hold
        spin = hold.held_spin(z_index, z_j, theta, res.u3)
        if math.isnan(spin):
            return False
        settle = t
        if not slow and not instant:
            n_a, n_b = hold.pressing(z_index, z_j, theta, spin)
            a = min(n_a, n_b) / self.contact_model.m
            v = e * abs(res.wn) if impulse else abs(res.wn)
            period = _impact.chatter_period(self.drive.omega)
            if not 2.0 * v <= _impact.CHATTER_TAIL * period * a * (1.0 - e):
                return False
            settle = t + 2.0 * v / (a * (1.0 - e))
        self._enter_hold(index, j, t, settle, spin)
        return True

    def _enter_hold(
        self, a: int, b: int, t: float, settle: float, spin: float | None = None
    ) -> None:
        """Hold the ball in walls a and b: its centre stays where it is relative to the
        boundary, and it moves with the boundary, with spin ``spin`` (rad/s; default
        its own, see ``VertexHold.held_spin``)."""
        ball = self._ball
        px, py, _, _ = self.drive.to_boundary_frame(ball.theta, ball.q1, ball.q2, ball.u1, ball.u2)
        u1, u2 = self.drive.boundary_velocity(ball.theta)
        u3 = ball.u3 if spin is None else spin
        self._ball = BallState(ball.t, ball.theta, ball.q1, ball.q2, u1, u2, u3, ball.q3)
        self._mode = HELD
        self._contact = (float(a), float(b), px, py, t, settle)

    def _phase_interval(self, wall: Any) -> tuple[float, float]:
        """Where a phase on ``wall`` ends with ``wall-end``: the wall's interval, within
        the container's range of x (where the curve reaches the lid or the escape
        height; +-1000 m where it never does, as a plane's low side)."""
        xl, xr = self.boundary.x_range
        return max(wall.lo, xl), min(wall.hi, xr)

    def _check_in_container(self, wall: Any, s: float, t: float) -> None:
        """A phase that ended at the container's end of x (not at its wall's end): the
        ball leaves the container sideways, which ends the run (ESCAPED)."""
        xl, xr = self.boundary.x_range
        lo, hi = self._phase_interval(wall)
        low_end = s <= 0.5 * (lo + hi)
        if (low_end and lo > wall.lo) or (not low_end and hi < wall.hi):
            raise SimulationError(
                f"the ball left the container's range x in [{xl:.6g}, {xr:.6g}] m at "
                f"x = {s:.6g} m, t = {t:.9g} s, after impact {self._impacts}",
                Status.ESCAPED,
            )

    def _contact_deadline(self, until: float) -> float:
        """The simulated time (s) at which a run without a time limit (``until`` = inf)
        ends in contact: ``run.contact_span`` after the last impact; else inf."""
        if math.isfinite(until):
            return math.inf
        return self._last_impact + self.scene.run.contact_span

    def _in_contact(self, t: float) -> SimulationError:
        """The end of a run whose ball stayed in contact without an impact for
        ``run.contact_span`` seconds, at t (a finished run, not a fault)."""
        self.final_time = t
        return SimulationError(
            f"no impact for run.contact_span = {self.scene.run.contact_span:g} s "
            f"(t = {t:.9g} s): the ball stays in contact",
            Status.IN_CONTACT,
        )

    def _cut(self, record: ContactRecord, deadline: float, samples: int) -> None:
        """A phase cut by the run's end (``end`` = ``cut``) at ``record.t_end``: reported
        (it is no event of the engine, whose state stays at the phase's start: a resumed
        run redoes the phase), then the contact span's end, a stop request
        (RunInterrupted), or the time limit (the caller returns None).

        ``samples``: the sample count at the phase's start. The samples the phase
        reported before the cut are not part of the engine's state either: its count
        goes back to that start (a checkpoint of this state, whose count disagreed with
        its time, was refused on resume; the resumed run reports them again)."""
        self._samples = samples
        if self.on_contact_cut is not None:
            self.on_contact_cut(record)
        t_cut = record.t_end
        request = self._request
        if request is not None and request.signum:
            self.final_time = t_cut
            raise RunInterrupted(request.signum)
        if t_cut >= deadline:
            raise self._in_contact(t_cut)

    def _phase_end(self, t0: float, run: Callable[[], Any]) -> Any:
        """The end of the phase or hold that ``run`` integrates from time ``t0``. A ball
        found at rest ends the run, complete: its clock stops where the rest began."""
        try:
            return run()
        except BallAtRest as rest:
            self.final_time = t0 + rest.tau
            raise

    def _clock_after(self, theta0: float, tau: float) -> tuple[float, float, float, float]:
        """(clock sum, its error, time t, drive angle) ``tau`` after the phase's start."""
        total, error = compensated_add(self._clock, self._clock_error, tau)
        theta = (theta0 + self.drive.omega * tau) % (2.0 * math.pi)
        return total, error, total + error, theta

    def _hold_step(self, until: float) -> ContactRecord | None:
        """The ball held by two walls, to the release of one (or to ``until``: None)."""
        hold = self.vertex_hold
        ball = self._ball
        ia, ib, px, py, t_start, settle = self._contact
        a, b = int(ia), int(ib)
        offsets = self.boundary.offsets
        za = offsets[a].contact(px, list(self.warm[a]))[1]
        zb = offsets[b].contact(px, list(self.warm[b]))[1]
        t0, theta0 = ball.t, ball.theta
        drive = self.drive

        def lab(theta: float, u3: float) -> tuple[float, float, float, float, float]:
            q1, q2 = drive.to_lab_frame(theta, px, py)
            u1, u2 = drive.boundary_velocity(theta)
            return q1, q2, u1, u2, u3

        def on_sample(tau: float, u3: float) -> None:
            self._report_sample(t0 + tau, *lab(theta0 + drive.omega * tau, u3), HELD)

        sampling = self.on_sample is not None
        samples = self._samples
        deadline = self._contact_deadline(until)
        if t0 >= deadline:
            raise self._in_contact(t0)
        end = self._phase_end(
            t0,
            lambda: hold.run_hold(
                za, zb, theta0, ball.u3, until - t0,
                self._sample_times(t0, until) if sampling else (),
                on_sample if sampling else None,
                self._pause if sampling else None,
            ),
        )  # fmt: skip
        if end.reason is None:
            t_cut = t0 + end.tau
            self._cut(
                ContactRecord(
                    t_start,
                    t_cut,
                    offsets[a].code,
                    HELD,
                    CUT,
                    settle,
                    *lab(theta0, ball.u3),
                    *lab(theta0 + drive.omega * end.tau, end.u3),
                    offsets[b].code,
                ),  # fmt: skip
                deadline,
                samples,
            )
            return None
        tau = end.tau
        total, error, t, theta = self._clock_after(theta0, tau)
        q1, q2, u1, u2, u3 = lab(theta, end.u3)
        # the spin decays linearly in time on a static boundary: the trapezoid is exact
        q3 = ball.q3 + 0.5 * (ball.u3 + u3) * tau
        record = ContactRecord(
            t_start, t, offsets[a].code, HELD, end.reason, settle,
            *lab(theta0, ball.u3), q1, q2, u1, u2, u3, offsets[b].code,
        )  # fmt: skip
        self._ball = BallState(t, theta, q1, q2, u1, u2, u3, q3)
        self._end_phase(HELD, t_start, tau, total, error)
        self._mode, self._contact = "flight", ()
        keeps = (a, b)[end.keeps] if end.keeps >= 0 else -1
        if keeps >= 0:
            self._continue_on(keeps, px, theta, u3, t)
        if self._mode == "flight":
            # leave both walls along the sum of their normals (see LIFT_OFF_SPEED)
            nx, ny = -math.sin(za) - math.sin(zb), math.cos(za) + math.cos(zb)
            norm = math.sqrt(nx * nx + ny * ny)
            self._ball = BallState(
                t, theta, q1, q2, u1 + LIFT_OFF_SPEED * nx / norm,
                u2 + LIFT_OFF_SPEED * ny / norm, u3, q3,
            )  # fmt: skip
        if self.on_contact is not None:
            self.on_contact(record)
        return record

    def _continue_on(self, j: int, px: float, theta: float, u3: float, t: float) -> None:
        """Released by the other wall: roll or slide on wall j from rest relative to the
        boundary, if it presses the ball (else the ball stays in flight)."""
        model = self.contact_model
        surface = self.boundary.offsets[j]
        s = surface.contact(px, list(self.warm[j]))[0]
        wall = surface.wall
        mode, sgn = model.mode_for(wall, theta, s, 0.0, u3)
        if model.forces(wall, mode, sgn, theta, (s, 0.0, u3))[2] > 0.0:
            self._mode = mode
            self._contact = (float(j), s, 0.0, sgn, t, t)
