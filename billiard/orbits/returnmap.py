"""The return map of the impacts: the state just after an impact, to the state just after
the impact N impacts later, computed by the one engine.

A post-impact state is a point of the impact surface: the ball touches a wall, so its
centre is fixed by the wall's contact abscissa. Its coordinates (:data:`STATE`) are

* ``t`` the time of the impact (s; its drive phase is ``t`` modulo the drive period),
* ``s`` the contact point's abscissa on the wall, in the boundary's frame (m; the
  ``s`` column of collisions.csv),
* ``v1``, ``v2`` the centre's lab velocity (m/s) and ``omega`` the spin (rad/s), just
  after the impact,

and which wall was hit (an index, ``-1`` the lid), a discrete label. The map starts the
engine (:class:`billiard.engine.simulation.Simulation`, ``method = "event"``) from the
centre at that point of the wall and steps it N impacts: the orbit's map is the engine's,
with its event location and impact law, not a second implementation of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard.engine.simulation import Simulation
from billiard.engine.state import BallState
from billiard.errors import SimulationError
from billiard.orbits.errors import OrbitError, SequenceChange
from billiard.orbits.jacobian import map_jacobian
from billiard.runfile.record import ImpactRecord

__all__ = ["LID", "STATE", "Landing", "OrbitError", "ReturnMap", "SequenceChange", "landing"]

#: The coordinates of a post-impact state, in order (units: s, m, m/s, m/s, rad/s).
STATE: tuple[str, ...] = ("t", "s", "v1", "v2", "omega")
#: The wall index of the lid (collisions.csv's ``wall``).
LID = -1


@dataclass(frozen=True)
class Landing:
    """Where an impact put the ball: its post-impact coordinates ``x`` (:data:`STATE`),
    the wall hit and the impact's regime (``stick``, ``slip`` or ``elastic``)."""

    x: np.ndarray
    wall: int
    regime: str


class ReturnMap:
    """The map from one post-impact state to the one ``impacts`` impacts later.

    Args:
        scene: a scene with ``contact.model = "impacts"`` (under ``"phases"`` the map
            through contact phases is :class:`billiard.orbits.phases.PhaseMap`'s;
            :func:`billiard.orbits.phases.return_map` picks the one a scene needs).
        impacts: N, the number of impacts of one period of the orbit.

    Raises:
        OrbitError: a scene under contact phases, a boundary at rest, N < 1.
    """

    #: the scene's ``contact.model`` this map runs
    MODEL = "impacts"
    #: what N counts, for messages
    UNIT = "impact"
    #: the coordinates Newton varies when none are named (None: all of :data:`STATE`)
    FREE: tuple[str, ...] | None = None
    #: what to do when a held coordinate changes along the orbit
    HELD_HINT = "free them"

    def __init__(self, scene: Any, impacts: int = 1):
        if int(impacts) != impacts or impacts < 1:
            raise OrbitError(
                f"the period must be a whole number of {self.UNIT}s >= 1, not {impacts}"
            )
        if getattr(scene.contact, "model", "impacts") != self.MODEL:
            raise OrbitError(
                'periodic orbits need contact.model = "impacts": under "phases" an orbit may '
                "pass through a rolling or sliding phase, whose end is no impact "
                "(docs/orbits.md, scope)"
            )
        self.scene = scene
        self.impacts = int(impacts)
        self.sim = Simulation(scene, method="event")
        self.drive = self.sim.drive
        if self.drive.static:
            raise OrbitError(
                "the boundary is at rest (drive.amplitude or drive.frequency is 0): "
                "a periodic orbit needs a drive period"
            )
        #: the drive period (s)
        self.period = self.drive.period
        self.radius = self.sim.boundary.radius

    # ------------------------------------------------------------------ the wall

    def wall_point(self, wall: int, s: float) -> tuple[float, float, float, float]:
        """(px, py, z, z_s) at abscissa ``s`` (m) of wall ``wall``: the centre of a ball
        touching it, in the boundary's frame (m), the tangent angle z (rad) and
        dz/ds = f'' / (1 + f'^2) (1/m; 0 on the lid)."""
        r = self.radius
        if wall == LID:
            lid = self.sim.boundary.ceiling
            if lid is None:
                raise OrbitError("wall -1 (the lid) named, but the scene has no lid")
            return s, lid - r, math.pi, 0.0
        walls = self.sim.boundary.walls
        if not 0 <= wall < len(walls):
            raise OrbitError(f"wall {wall} named, but the curve has walls 0 to {len(walls) - 1}")
        w = walls[wall]
        f, fp, f2 = w.f(s, w.p), w.df(s, w.p), w.d2f(s, w.p)
        length = math.hypot(1.0, fp)
        return s - r * fp / length, f + r / length, math.atan(fp), f2 / (1.0 + fp * fp)

    def ball(self, x: np.ndarray, wall: int) -> BallState:
        """The engine's ball at post-impact coordinates ``x`` on ``wall``."""
        t, s, v1, v2, omega = (float(v) for v in x)
        theta = self.drive.angle(t)
        px, py, _, _ = self.wall_point(wall, s)
        q1, q2 = self.drive.to_lab_frame(theta, px, py)
        return BallState(t, theta, q1, q2, v1, v2, omega, 0.0)

    # ------------------------------------------------------------------ the map

    def run(self, x: np.ndarray, wall: int, impacts: int | None = None) -> list[ImpactRecord]:
        """The engine's records of the next ``impacts`` (default N) impacts from ``x``.

        Raises:
            OrbitError: the engine stopped (the ball escaped, a search failed, ...).
        """
        sim = self.sim
        sim.reset(self.ball(x, wall))
        records = []
        for _ in range(self.impacts if impacts is None else impacts):
            try:
                record = sim.step()
            except SimulationError as exc:
                raise OrbitError(f"the engine stopped on the way round the orbit: {exc}") from None
            if not isinstance(record, ImpactRecord):  # pragma: no cover (impacts model)
                raise OrbitError("the engine reported an event that is no impact")
            records.append(record)
        return records

    def run_scene(self, impacts: int) -> list[ImpactRecord]:
        """The engine's records of the scene's own run from its initial state, up to
        impact ``impacts`` (a guess for an orbit it settles on)."""
        sim = self.sim
        sim.reset()
        records = []
        for _ in range(impacts):
            try:
                record = sim.step()
            except SimulationError as exc:
                raise OrbitError(f"the scene's run stopped before settling: {exc}") from None
            if isinstance(record, ImpactRecord):
                records.append(record)
        if not records:
            raise OrbitError("the scene's run has no impact to start an orbit from")
        return records

    def __call__(self, x: np.ndarray, wall: int) -> tuple[Landing, list[Any]]:
        """P^N(x): where the N-th impact from ``x`` on ``wall`` lands, and the records of
        the N impacts."""
        records = self.run(x, wall)
        return landing(records[-1]), records

    # ------------------------------------------------------------------ the orbit's kind

    def enter(self, x: np.ndarray, wall: int) -> tuple[np.ndarray, int]:
        """A guess on the map's section: every post-impact state is one here."""
        return x, wall

    def check_free(self, idx: list[int]) -> None:
        """Refuse (OrbitError) free coordinates (positions in :data:`STATE`) whose
        derivatives the map's Jacobian does not have: none here."""

    def sequence(self, x: np.ndarray, records: list[Any]) -> tuple[tuple[Any, ...], ...]:
        """What a branch of orbits keeps between two points: (wall, regime) of each
        impact; where it changes the map is not smooth (a grazing). ``x`` is the start."""
        return tuple((int(r.wall), str(r.regime)) for r in records)

    def route(self, x: np.ndarray, records: list[Any]) -> tuple[Any, ...]:
        """The part of :meth:`sequence` without which no orbit of the branch exists: the
        walls hit in turn (a regime may change on the way, a bifurcation located)."""
        return tuple(int(r.wall) for r in records)

    def jacobian(self, x: np.ndarray, wall: int, records: list[Any]) -> np.ndarray:
        """The exact 5x5 Jacobian of P^N at ``x`` along ``records``
        (:func:`billiard.orbits.jacobian.map_jacobian`)."""
        return map_jacobian(self, x, wall, records)


def landing(record: ImpactRecord) -> Landing:
    """The post-impact coordinates of an engine record."""
    x = np.array([record.t, record.s, record.v1, record.v2, record.omega])
    return Landing(x, int(record.wall), str(record.regime))
