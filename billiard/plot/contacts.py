"""The path of a run with contact phases (``contact.model = "phases"``): flights, and the
stretches along a wall where the ball rolled, slid or was held by two walls.

A run of the phases model records, besides its impacts (``collisions.csv``), one row per
finished contact phase (``contacts.csv``: its times, wall, mode, how it ended, and the
centre's state at both ends) and, with ``--sample DT``, exact states every DT seconds
(``trajectory.csv``). The path over a window of impacts is rebuilt from them:

* a **flight** starts at an impact (with the impact row's post-impact state) or at the end
  of a phase that the ball leaves flying (``lift-off``, ``wall-end``, ``release``: with
  the phase's end state, q and v at ``t_end``), and ends at the next impact or the next
  phase's start. It follows the scene's flight model (:mod:`billiard.plot.flights`) from
  that state, as the engine's flight does (no speed is added at a lift-off).
* a **contact stretch** is the centre's path over a phase, on the wall's offset curve. With
  samples, it joins the phase's start state, the samples inside the phase and its end
  state (all exact states). Without them, a rolling or sliding phase is integrated again
  from its start state with the engine's contact equations
  (:meth:`billiard.models.contact.ContactModel.run_phase`, no other wall watched, up to
  the phase's duration); the points are then on the offset curve by construction and the
  phase's recorded end state closes the stretch. Should that fail (or end more than
  :data:`AGREE` from the recorded end) the stretch is the path along the offset curve in
  the boundary's frame from the start's contact point to the end's, uniform in time,
  moved with the drive. If the curve cannot be loaded, or a recorded position is not on
  the wall's offset curve, the stretch is the straight segment between the start and end
  positions. A held phase keeps the centre fixed relative to the boundary: its stretch
  is that point moved with the drive D(t).

A phase is never interrupted by an impact, so the window's time span is that of its
impacts, extended to the end of the run's last recorded phase when the window holds the
run's last impact (a run that ends at rest or at its time limit in contact ends with
phases), and to the start of the run's first phase when it holds the first impact.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from billiard.plot.common import Columns, RunDataError, column
from billiard.plot.flights import arc_count, flight_from_state
from billiard.runfile.rows import NO_WALL
from billiard.scene.scene import Scene

__all__ = [
    "AGREE",
    "MODE_LABELS",
    "MODE_STYLES",
    "MODES",
    "PhasePath",
    "Piece",
    "phase_path",
]

#: the contact modes, in legend order
MODES = ("roll", "slide", "held")
#: legend names of the contact modes
MODE_LABELS = {"roll": "rolling", "slide": "sliding", "held": "held by two walls"}
#: how each contact mode's stretches are drawn (matplotlib line properties)
MODE_STYLES: dict[str, dict[str, object]] = {
    "roll": {"color": "tab:cyan", "linestyle": "-", "linewidth": 2.6},
    "slide": {"color": "tab:brown", "linestyle": (0, (3.0, 1.5)), "linewidth": 2.6},
    "held": {
        "color": "tab:pink",
        "linestyle": "-",
        "linewidth": 3.2,
        "marker": "s",
        "markersize": 4.5,
    },
}
#: times (s) closer than this are the same event (the run files hold them exactly)
SAME_TIME = 1e-12
#: a re-integrated phase must end this close (m) to the recorded end state
AGREE = 1e-6

Side = Mapping[str, np.ndarray]


@dataclass(frozen=True)
class Piece:
    """One piece of the path: a flight or a contact stretch.

    Attributes:
        kind: ``flight``, or the contact mode (``roll``, ``slide``, ``held``).
        t, x, y: times (s) and centre positions (m, lab frame) drawn along it; the first
            and last are the piece's start and end.
        source: how it was rebuilt: for a flight what it starts from (``impact N``, or the
            phase's end: ``lift-off``, ``wall-end``, ``release``); for a stretch
            ``samples``, ``integrated``, ``curve`` or ``segment`` (see the module's text),
            or ``ends`` for a phase of zero duration.
        wall: the wall of a contact stretch (``a+b`` when held), empty for a flight.
    """

    kind: str
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    source: str
    wall: str = ""
    at: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = field(
        default=None, repr=False, compare=False
    )

    def positions(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centre positions (m) at ``times`` (s) within the piece: a flight's and a held or
        integrated stretch's exactly (an integrated phase is integrated again to those
        times), the others interpolated between the piece's points."""
        times = np.asarray(times, dtype=float)
        if self.at is not None:
            return self.at(times)
        return np.interp(times, self.t, self.x), np.interp(times, self.t, self.y)


@dataclass(frozen=True)
class PhasePath:
    """The path over a window: its pieces in time order, and the span (s) it covers."""

    flights: list[Piece]
    stretches: list[Piece]
    t_lo: float
    t_hi: float

    @property
    def pieces(self) -> list[Piece]:
        return sorted(self.flights + self.stretches, key=lambda p: (p.t[0], p.t[-1]))

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """Every point drawn (m), for the view's limits."""
        pieces = self.flights + self.stretches
        if not pieces:
            return np.array([]), np.array([])
        return np.concatenate([p.x for p in pieces]), np.concatenate([p.y for p in pieces])


def joined(pieces: list[Piece]) -> tuple[np.ndarray, np.ndarray]:
    """The pieces' points (m) in one array each, the pieces separated by NaN."""
    if not pieces:
        return np.array([]), np.array([])
    gap = np.array([np.nan])
    xs = [a for p in pieces for a in (p.x, gap)]
    ys = [a for p in pieces for a in (p.y, gap)]
    return np.concatenate(xs), np.concatenate(ys)


def _text(values: np.ndarray) -> list[str]:
    return [str(v).strip() for v in np.asarray(values).tolist()]


def wall_labels(contacts: Side) -> list[str]:
    """Each phase's walls as a label: the wall's index, ``a+b`` for the two walls holding
    the ball (``wall`` and ``wall_other``)."""
    pairs = zip(
        np.asarray(contacts["wall"]).tolist(),
        np.asarray(contacts["wall_other"]).tolist(),
        strict=True,
    )
    return [str(int(a)) if int(b) == NO_WALL else f"{int(a)}+{int(b)}" for a, b in pairs]


def phase_path(
    columns: Columns,
    rows: np.ndarray,
    scene: Scene,
    contacts: Side,
    samples: Side | None = None,
) -> PhasePath:
    """The path over the impacts ``rows`` of a run with contact phases.

    Args:
        columns: the run's impacts (collisions.csv).
        rows: the row indices of the window's impacts (consecutive).
        scene: the run's scene.
        contacts: the run's contact phases (the columns of contacts.csv).
        samples: the run's samples (the columns of trajectory.csv), or None.

    Raises:
        RunDataError: a contacts or samples column is missing, or a flight cannot be
            integrated.
    """
    t = column(columns, "t")
    n = column(columns, "n")
    c_start = column(contacts, "t_start")
    c_end = column(contacts, "t_end")
    for name in ("mode", "end", "wall", "wall_other"):
        if name not in contacts:
            raise RunDataError(f"contacts data have no column {name!r}")
    modes, ends = (_text(contacts[k]) for k in ("mode", "end"))
    walls = wall_labels(contacts)
    t_lo, t_hi = float(t[rows[0]]), float(t[rows[-1]])
    if c_start.size and rows[-1] == t.size - 1:
        t_hi = max(t_hi, float(c_end.max()))
    if c_start.size and rows[0] == 0:
        t_lo = min(t_lo, float(c_start.min()))
    chosen = np.flatnonzero((c_start >= t_lo - SAME_TIME) & (c_end <= t_hi + SAME_TIME))
    starts = c_start[chosen]

    def phase_starts_at(time: float) -> bool:
        return bool(np.any(np.abs(starts - time) <= SAME_TIME))

    # departures: (time, state, what)
    departures: list[tuple[float, tuple[float, ...], str]] = []
    spin = column(columns, "omega") if "omega" in columns else np.zeros(t.size)
    for row in rows:
        if not phase_starts_at(float(t[row])):
            state = (*(float(columns[k][row]) for k in ("q1", "q2", "v1", "v2")), spin[row])
            departures.append((float(t[row]), state, f"impact {int(n[row])}"))
    for k in chosen:
        # a phase ending at an impact leaves from that impact's row (post-impact state)
        if ends[k] != "impact" and not phase_starts_at(float(c_end[k])):
            state = tuple(float(contacts[f"{q}_end"][k]) for q in ("q1", "q2", "v1", "v2"))
            departures.append((float(c_end[k]), (*state, float(contacts["omega_end"][k])), ends[k]))
    arrivals = np.sort(np.concatenate([t[rows], starts]))

    flights: list[Piece] = []
    for t0, state, what in sorted(departures, key=lambda d: d[0]):
        i = int(np.searchsorted(arrivals, t0 + SAME_TIME, side="right"))
        if i >= arrivals.size:
            continue  # no known end: the window's (or the run's) last flight
        t1 = float(arrivals[i])
        tau = np.linspace(0.0, t1 - t0, arc_count(t1 - t0))

        def at(times: np.ndarray, t0: float = t0, state: tuple = state, what: str = what):
            tau = np.clip(np.asarray(times, dtype=float) - t0, 0.0, None)
            return flight_from_state(state, tau, scene, f"the flight after the {what}")

        x, y = at(t0 + tau)
        flights.append(Piece("flight", t0 + tau, x, y, what, at=at))

    rebuild = _Rebuild(scene)
    stretches = [rebuild.stretch(contacts, int(k), modes[k], walls[k], samples) for k in chosen]
    return PhasePath(flights, stretches, t_lo, t_hi)


class _Rebuild:
    """Rebuilds contact stretches with the scene's contact equations and curve."""

    def __init__(self, scene: Scene):
        from billiard.geometry.drive import Drive
        from billiard.models.contact import ContactModel

        self.scene = scene
        self.drive = Drive.from_scene(scene.drive)
        self.model = ContactModel(scene, self.drive)
        self.r = float(scene.ball.radius)
        self._walls: tuple | None = None
        self._loaded = False

    def walls(self) -> tuple | None:
        if not self._loaded:
            from billiard.plot.outline import _curve

            self._loaded = True
            try:
                self._walls = _curve(self.scene).walls
            except RunDataError:
                self._walls = None
        return self._walls

    def _wall(self, label: str):
        walls = self.walls()
        if walls is None or not label.isdigit() or int(label) >= len(walls):
            return None
        return walls[int(label)]

    def stretch(
        self, contacts: Side, k: int, mode: str, wall_label: str, samples: Side | None
    ) -> Piece:
        t0, t1 = float(contacts["t_start"][k]), float(contacts["t_end"][k])
        start = tuple(float(contacts[f"{q}_start"][k]) for q in ("q1", "q2", "v1", "v2"))
        end = tuple(float(contacts[f"{q}_end"][k]) for q in ("q1", "q2", "v1", "v2"))
        omega0 = float(contacts["omega_start"][k])
        if not t1 > t0:  # a phase of zero duration: its one point
            times = np.array([t0, t1])
            x, y = np.array([start[0], end[0]]), np.array([start[1], end[1]])
            return Piece(mode, times, x, y, "ends", wall_label)
        if samples is not None and "t" in samples:
            ts = column(samples, "t")
            inside = np.flatnonzero((ts > t0) & (ts < t1))
            times = np.concatenate([[t0], ts[inside], [t1]])
            x = np.concatenate([[start[0]], column(samples, "q1")[inside], [end[0]]])
            y = np.concatenate([[start[1]], column(samples, "q2")[inside], [end[1]]])
            return Piece(mode, times, x, y, "samples", wall_label)
        times = np.linspace(t0, t1, arc_count(t1 - t0))
        if mode == "held":
            # fixed relative to the boundary: the start position moved with the drive
            px, py, _, _ = self.drive.to_boundary_frame(self.drive.angle(t0), *start)

            def held(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
                x = np.empty(np.shape(times))
                y = np.empty(np.shape(times))
                for i, ti in enumerate(np.ravel(times)):
                    x.flat[i], y.flat[i] = self.drive.to_lab_frame(
                        self.drive.angle(float(ti)), px, py
                    )
                return x, y

            x, y = held(times)
            x[-1], y[-1] = end[0], end[1]
            return Piece(mode, times, x, y, "integrated", wall_label, at=held)
        wall = self._wall(wall_label)
        s0 = self._abscissa(wall, t0, start[0], start[1]) if wall is not None else None
        s1 = self._abscissa(wall, t1, end[0], end[1]) if wall is not None else None
        if wall is None or s0 is None or s1 is None:
            # no curve to follow: the straight segment between the recorded ends (close to
            # the path for a short phase only)
            x = np.interp(times, [t0, t1], [start[0], end[0]])
            y = np.interp(times, [t0, t1], [start[1], end[1]])
            return Piece(mode, times, x, y, "segment", wall_label)
        path = self._integrate(wall, mode, t0, times, s0, start, omega0)
        if path is not None and math.hypot(path[0][-1] - end[0], path[1][-1] - end[1]) <= AGREE:
            x, y = path
            x[-1], y[-1] = end[0], end[1]

            def on_wall(
                times: np.ndarray, piece_t: np.ndarray = times, px: np.ndarray = x,
                py: np.ndarray = y,
            ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
                """The phase integrated again to the given times (exact positions)."""
                wanted = np.clip(np.asarray(times, dtype=float), t0, t1)
                order = np.argsort(np.ravel(wanted), kind="stable")
                full = np.concatenate([[t0], np.ravel(wanted)[order], [t1]])
                found = self._integrate(wall, mode, t0, full, s0, start, omega0)
                if found is None:
                    return np.interp(wanted, piece_t, px), np.interp(wanted, piece_t, py)
                qx = np.empty(order.size)
                qy = np.empty(order.size)
                qx[order], qy[order] = found[0][1:-1], found[1][1:-1]
                return qx.reshape(wanted.shape), qy.reshape(wanted.shape)

            return Piece(mode, times, x, y, "integrated", wall_label, at=on_wall)
        # along the offset curve from the start's contact point to the end's
        model = self.model
        x = np.empty(times.shape)
        y = np.empty(times.shape)
        for i, ti in enumerate(times):
            s = s0 + (s1 - s0) * (ti - t0) / (t1 - t0) if t1 > t0 else s1
            theta = self.drive.angle(float(ti))
            x[i], y[i] = model.lab_state(wall, theta, (s, 0.0, 0.0), "slide")[:2]
        return Piece(mode, times, x, y, "curve", wall_label)

    def _abscissa(self, wall, t: float, q1: float, q2: float) -> float | None:
        """The contact point's abscissa s (m) of a centre at (q1, q2) on the wall's
        offset curve at time t, or None if the centre is not on it (to 1e-9 m)."""
        px, py, _, _ = self.drive.to_boundary_frame(self.drive.angle(t), q1, q2, 0.0, 0.0)
        r = self.r
        s = px
        for _ in range(60):
            fp, f2 = wall.df(s, wall.p), wall.d2f(s, wall.p)
            c = 1.0 + fp * fp
            # the offset curve's abscissa X(s) = s - r f' / sqrt(1 + f'^2), increasing
            # while r is below the radius of curvature
            step = (s - r * fp / math.sqrt(c) - px) / (1.0 - r * f2 / c**1.5)
            s -= step
            if not math.isfinite(s):
                return None
            if abs(step) <= 1e-15 * (1.0 + abs(s)):
                break
        fp = wall.df(s, wall.p)
        height = wall.f(s, wall.p) + r / math.sqrt(1.0 + fp * fp)
        return s if abs(height - py) <= 1e-9 else None

    def _integrate(
        self,
        wall,
        mode: str,
        t0: float,
        times: np.ndarray,
        s0: float,
        start: tuple[float, ...],
        omega0: float,
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The phase integrated again from its start state, at ``times``; None if the
        integration fails or ends before the last time."""
        from billiard.errors import SimulationError

        model = self.model
        theta0 = self.drive.angle(t0)
        omega = self.drive.omega
        sd = model.s_dot(wall, theta0, s0, start[2], start[3])
        sgn = 0.0
        if mode == "slide":
            slip = model.slip(wall, s0, sd, omega0)
            if abs(slip) > 1e-12:
                sgn = 1.0 if slip > 0.0 else -1.0
            else:  # sliding starts where rolling was lost: the slip opposes F
                friction = model.forces(wall, "roll", 0.0, theta0, (s0, sd))[3]
                sgn = -1.0 if friction > 0.0 else 1.0
        points: list[tuple[float, float]] = []

        def on_sample(tau: float, y: tuple) -> None:
            points.append(model.lab_state(wall, theta0 + omega * tau, y, mode)[:2])

        taus = times - t0
        try:
            end = model.run_phase(wall, mode, sgn, theta0, (s0, sd, omega0), float(taus[-1]),
                                  (), taus.tolist(), on_sample)  # fmt: skip
        except (SimulationError, ArithmeticError, ValueError):
            return None
        if len(points) == taus.size - 1:
            # the phase's end located just before its recorded duration: end there
            points.append(model.lab_state(wall, theta0 + omega * end.tau, end.y, mode)[:2])
        if len(points) != taus.size:
            return None  # the phase ended early: not the recorded phase
        return np.array([p[0] for p in points]), np.array([p[1] for p in points])
