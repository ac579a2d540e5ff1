"""The return map of an orbit through contact phases (``contact.model = "phases"``): a
ball that lies on the shaken table between its flights, lifts off where the table's
downward acceleration reaches g, flies, lands, chatters (the engine sums the chatter's
tail) and lies on the table again until the next lift-off (Luck and Mehta, Phys. Rev. E
48 (1993) 3988: the "locked" orbits).

The section is the first impact after a lift-off, a post-impact state as the impacts'
map's (:data:`~billiard.orbits.returnmap.STATE`), and N counts lift-offs: P^N runs the
one engine (:class:`~billiard.engine.simulation.Simulation`, method ``event``, the
phases model) from there through N contact phases that end in a lift-off, to the first
impact after the N-th. Nothing of the flight, the chatter or the hold is computed here.

**The Jacobian.** A lift-off from a wall whose tangent is horizontal, under a vertical
drive, with the ball at rest along the wall (or the wall flat), is where the normal force
m (g + D''(t)) falls through zero: its time is fixed by the drive alone, the first
sin(w t) = g / (A w^2) after the landing, and the ball leaves with the wall's velocity
D'(t_L) from the wall's height. So the hold forgets the entering time and normal speed:
its leg of the Jacobian, in (t, v2), is exactly zero, and the Jacobian of P^N there, the
legs of the flights and impacts composed with it, is exactly zero too; the orbit is
superstable, both multipliers 0. That holds while each landing ends strictly inside
the span where the wall presses the ball, before the next lift-off phase: where the
chatter's end reaches that phase, the lift-off moves a whole drive period (the orbit's
drive periods n change) and the map jumps, a sequence change (a grazing of the
continuation). The tangential coordinates (s, v1, omega) are held, at rest (the ball
bouncing straight up: v1 = omega = 0, s neutral): their legs through the contact phase
would need the variational equations of the contact equations and the derivative of the
chatter's summed tail, which are not derived, so they cannot be freed, and a phase that
is not such a lift-off is refused (:meth:`PhaseMap.check_phase`), never given a wrong
Jacobian.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from billiard.errors import SimulationError
from billiard.orbits.returnmap import LID, STATE, OrbitError, ReturnMap, SequenceChange, landing
from billiard.runfile.record import NO_WALL, ContactRecord, ImpactRecord

__all__ = ["LIFT_OFF", "LOCKED", "PERIODS_PER_LIFT_OFF", "PhaseMap", "return_map"]

#: The end of a contact phase that the map goes through (contacts.csv's ``end``).
LIFT_OFF = "lift-off"
#: Ends of a phase that another phase on the same wall follows at once: rolling and
#: sliding take turns (at the lift-off of a ball at rest, rolling's friction limit
#: mu_s N - |F| reaches zero with N, and a sliding phase of no time may come between).
SWITCHES = ("slip", "roll")
#: The coordinates the hold locks: the only ones the map's Jacobian has.
LOCKED: tuple[str, ...] = ("t", "v2")
#: Drive periods the engine is given, per lift-off, to reach the next one; a run past
#: them has no contact phase ending in a lift-off (a bouncing orbit, a ball at rest).
PERIODS_PER_LIFT_OFF = 100
#: A wall's slope (tan z) and a tangential speed (m/s) that count as zero: rounding of
#: the centre's position on the wall (1e-12 m) over the ball's sizes.
HORIZONTAL = 1e-12


def return_map(scene: Any, period: int = 1) -> ReturnMap:
    """The return map for a scene: the impacts' (:class:`ReturnMap`, N impacts) under
    ``contact.model = "impacts"``, the map through contact phases (:class:`PhaseMap`,
    N lift-offs) under ``"phases"``."""
    if getattr(scene.contact, "model", "impacts") == "phases":
        return PhaseMap(scene, period)
    return ReturnMap(scene, period)


class PhaseMap(ReturnMap):
    """The map from the first impact after a lift-off to the first impact after the
    ``lifts``-th lift-off from there (module docstring).

    Args:
        scene: a scene with ``contact.model = "phases"`` and a vertical drive.
        lifts: N, the lift-offs of one period of the orbit.

    Raises:
        OrbitError: a horizontal drive (a lift-off there depends on the ball's motion
            along the wall), a boundary at rest, N < 1.
    """

    MODEL = "phases"
    UNIT = "lift-off"
    FREE = LOCKED
    HELD_HINT = (
        "the ball moves along the wall, and an orbit through a contact phase with "
        "tangential motion is out of scope (docs/orbits.md)"
    )

    def __init__(self, scene: Any, lifts: int = 1):
        super().__init__(scene, lifts)
        if self.drive.horizontal:
            raise OrbitError(
                "orbits through contact phases need a vertical drive: under a horizontal "
                "one a lift-off depends on the ball's motion along the wall, whose "
                "variational equations are not derived (docs/orbits.md, scope)"
            )

    # ------------------------------------------------------------------ the map

    def run(self, x: np.ndarray, wall: int, impacts: int | None = None) -> list[Any]:
        """The engine's records (impacts and contact phases) from ``x`` on ``wall`` to
        the first impact after the ``impacts``-th (default N) lift-off.

        Raises:
            OrbitError: a contact phase is out of scope (:meth:`check_phase`).
            SequenceChange: the engine stopped, or no lift-off came within
                :data:`PERIODS_PER_LIFT_OFF` drive periods: the ball no longer sticks
                (it bounces on, or its chatter ends so near the lift-off phase, where
                the wall's push vanishes, that the engine can neither sum it within its
                error bound nor resolve it impact by impact, and stops), which ends a
                branch of such orbits (a grazing).
        """
        sim = self.sim
        sim.reset(self.ball(x, wall))
        lifts = self.impacts if impacts is None else impacts
        until = float(x[0]) + PERIODS_PER_LIFT_OFF * lifts * self.period
        records: list[Any] = []
        lifted = 0
        while True:
            try:
                record = sim.step(until)
            except SimulationError as exc:
                raise SequenceChange(
                    f"the engine stopped on the way round the orbit: {exc}"
                ) from None
            if record is None:
                raise SequenceChange(
                    f"no contact phase ended in a lift-off within {PERIODS_PER_LIFT_OFF} "
                    "drive periods: an orbit of impacts alone is found under "
                    'contact.model = "impacts" (docs/orbits.md, scope)'
                )
            records.append(record)
            if isinstance(record, ContactRecord):
                self.check_phase(record)
                lifted += record.end == LIFT_OFF
            elif lifted == lifts:
                return records

    def check_phase(self, record: ContactRecord) -> None:
        """Refuse (OrbitError) a contact phase that does not lead to a lift-off fixed by
        the drive alone: one that ends otherwise than in a lift-off or a switch between
        rolling and sliding (:data:`SWITCHES`; at a wall's end, a hold's release), a
        hold by two walls, or a phase on a sloped wall or moving along a curved one,
        whose lift-off depends on the motion along the wall."""
        where = f"the orbit's contact phase at t = {record.t_start:.9g} s"
        if record.mode == "held" or record.wall_other != NO_WALL:
            raise OrbitError(f"{where} is held by two walls: out of scope (docs/orbits.md, scope)")
        if record.end != LIFT_OFF and record.end not in SWITCHES:
            raise OrbitError(
                f"{where} ends in {record.end!r}, not a lift-off: an orbit through a "
                "rolling or sliding phase is out of scope (docs/orbits.md, scope)"
            )
        ends = (
            (record.t_start, record.q1_start, record.q2_start, record.v1_start),
            (record.t_end, record.q1_end, record.q2_end, record.v1_end),
        )
        for t, q1, q2, v1 in ends:
            if not self._lies_level(int(record.wall), t, q1, q2, v1):
                raise OrbitError(
                    f"{where} lies on wall {record.wall} where it is not horizontal or moves "
                    "along it while curved: its lift-off depends on that motion, whose "
                    "variational equations are not derived (docs/orbits.md, scope)"
                )

    def _lies_level(self, wall: int, t: float, q1: float, q2: float, v1: float) -> bool:
        """Does the ball at lab (q1, q2) (m), lab v1 (m/s), on ``wall`` at t (s) touch it
        where its tangent is horizontal, and is the wall flat there or the ball at rest
        along it? Under a vertical drive the touching centre is then right above the
        contact point, at the abscissa px."""
        if wall == LID:
            return True  # flat and horizontal
        theta = self.drive.angle(t)
        px, py, vx, _ = self.drive.to_boundary_frame(theta, q1, q2, v1, 0.0)
        cx, cy, z, zs = self.wall_point(wall, px)
        size = 1.0 + abs(px) + abs(py)
        if abs(math.tan(z)) > HORIZONTAL or abs(cx - px) + abs(cy - py) > HORIZONTAL * size:
            return False
        return zs == 0.0 or abs(vx) <= HORIZONTAL

    # ------------------------------------------------------------------ the orbit's kind

    def enter(self, x: np.ndarray, wall: int) -> tuple[np.ndarray, int]:
        """A guess on the section: the first impact after the next lift-off from any
        post-impact state ``x`` on ``wall`` (a run's last impact, say)."""
        end = landing(self.run(x, wall, 1)[-1])
        return end.x, end.wall

    def check_free(self, idx: list[int]) -> None:
        """Only :data:`LOCKED` can be free: the hold's leg is derived there alone."""
        loose = [STATE[i] for i in idx if STATE[i] not in LOCKED]
        if loose:
            raise OrbitError(
                f"through a contact phase only {' and '.join(LOCKED)} can be free, not "
                f"{', '.join(loose)}: the motion along the wall through the phase has no "
                "derived variational equations (docs/orbits.md, scope)"
            )

    def sequence(self, x: np.ndarray, records: list[Any]) -> tuple[tuple[Any, ...], ...]:
        """(drive periods,) then per lift-off its wall and the drive periods since the
        first lift-off, and the first impact after it (wall, regime). The chatter's
        impacts and the phases' modes are left out: the hold forgets them, and their
        number (or a switch from rolling to sliding at the lift-off, rounding's choice)
        changes along a branch with no effect on the orbit."""
        out: list[tuple[Any, ...]] = [(round((records[-1].t - float(x[0])) / self.period),)]
        first: float | None = None
        after = False
        for r in records:
            if isinstance(r, ContactRecord) and r.end == LIFT_OFF:
                first = r.t_end if first is None else first
                out.append((int(r.wall), LIFT_OFF, round((r.t_end - first) / self.period)))
                after = True
            elif after and isinstance(r, ImpactRecord):
                out.append((int(r.wall), str(r.regime)))
                after = False
        return tuple(out)

    def route(self, x: np.ndarray, records: list[Any]) -> tuple[Any, ...]:
        """The whole :meth:`sequence`: a change of any of it moves the section."""
        return self.sequence(x, records)

    def jacobian(self, x: np.ndarray, wall: int, records: list[Any]) -> np.ndarray:
        """The Jacobian of P^N at ``x`` (5x5 over :data:`STATE`): in (t, v2) exactly
        zero, NaN elsewhere (not derived).

        The legs compose as J = L_N H_N C_N ... L_1 H_1 C_1 (C_k the chatter's impacts,
        H_k the hold to the k-th lift-off, L_k its flight and the impact after it). The
        hold's leg in (t, v2) is zero: the lift-off's time and speed are the drive's
        (module docstring; :meth:`check_phase` made sure of it for each of ``records``),
        so the product is zero in (t, v2) whatever the other legs are, and they are not
        computed (the chatter's summed tail has no derived derivative)."""
        if not any(isinstance(r, ContactRecord) for r in records):  # pragma: no cover
            raise OrbitError("the orbit has no contact phase to lock it")
        jac = np.full((len(STATE), len(STATE)), np.nan)
        locked = [STATE.index(name) for name in LOCKED]
        jac[np.ix_(locked, locked)] = 0.0
        return jac
