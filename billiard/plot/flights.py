"""Flight arcs between impacts, rebuilt from the post-impact states in the CSV.

With air drag and the Magnus force off (``air.drag = "none"``, ``air.magnus = 0``) the
flight is the exact parabola q1 + v1 t, q2 + v2 t - g t^2/2. Otherwise it is integrated
from the post-impact state (``q1, q2, v1, v2`` and the spin ``omega``, constant in
flight) with the derivation's accelerations (:func:`billiard.generated.ball.flight_rhs_drag`
or ``flight_rhs_magnus``) by :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-9), so
that an arc ends at the next impact's position, as the model's flight did.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from billiard.generated import ball as _ball
from billiard.plot.common import Columns, RunDataError, column
from billiard.scene.scene import Scene

__all__ = [
    "ARC_POINT_BUDGET",
    "arc_count",
    "arc_counts",
    "arcs",
    "flight_from_state",
    "flight_label",
    "flight_positions",
    "positions_at",
]

RTOL = 1e-9
ATOL = 1e-12  # m and m/s


def _rhs(scene: Scene, spin: float) -> Callable[[float, np.ndarray], list[float]] | None:
    """Right-hand side d(q1, q2, u1, u2)/dt of the scene's flight, or None for the exact
    parabola."""
    c_lin, c_quad = scene.air.coefficients
    c_magnus = float(scene.air.magnus)
    m, g = scene.ball.mass, scene.run.gravity
    if c_lin == 0.0 and c_quad == 0.0 and c_magnus == 0.0:
        return None

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        u1, u2 = float(y[2]), float(y[3])
        if c_magnus != 0.0:
            du1, du2 = _ball.flight_rhs_magnus(u1, u2, spin, m, g, c_lin, c_quad, c_magnus)
        else:
            du1, du2 = _ball.flight_rhs_drag(u1, u2, m, g, c_lin, c_quad)
        return [u1, u2, du1, du2]

    return rhs


def flight_label(scene: Scene) -> str:
    """A legend label naming the flight model the arcs follow."""
    c_lin, c_quad = scene.air.coefficients
    if scene.air.magnus != 0.0:
        return "flight (drag and Magnus force)"
    if c_lin != 0.0 or c_quad != 0.0:
        return "flight (with air drag)"
    return "flight (parabola, no drag)"


def flight_positions(
    columns: Columns, row: int, tau: np.ndarray, scene: Scene
) -> tuple[np.ndarray, np.ndarray]:
    """Centre position (m) at times ``tau`` (s, >= 0, non-decreasing) after impact ``row``.

    Args:
        columns: a run's columns (``q1, q2`` m, ``v1, v2`` m/s, ``omega`` rad/s).
        row: the row index of the impact the flight starts from.
        tau: times since that impact (s).
        scene: the run's scene (gravity, mass, air).

    Returns:
        ``(q1, q2)`` arrays shaped like ``tau``.
    """
    spin = float(columns["omega"][row]) if "omega" in columns else 0.0
    state = tuple(float(columns[name][row]) for name in ("q1", "q2", "v1", "v2"))
    name = f"impact {int(columns['n'][row])}" if "n" in columns else f"row {row}"
    return flight_from_state((*state, spin), tau, scene, f"the flight after {name}")


def flight_from_state(
    state: tuple[float, float, float, float, float],
    tau: np.ndarray,
    scene: Scene,
    what: str = "the flight",
) -> tuple[np.ndarray, np.ndarray]:
    """Centre position (m) at times ``tau`` (s, >= 0, non-decreasing) of a flight that
    starts from ``state`` = ``(q1, q2, v1, v2, omega)`` (m, m/s, rad/s).

    ``what`` names the flight in the error raised when it cannot be integrated.

    Returns:
        ``(q1, q2)`` arrays shaped like ``tau``.
    """
    tau = np.asarray(tau, dtype=float)
    q1, q2, v1, v2, spin = (float(v) for v in state)
    rhs = _rhs(scene, spin)
    if rhs is None:
        g = scene.run.gravity
        return q1 + v1 * tau, q2 + v2 * tau - 0.5 * g * tau**2
    flat = np.ravel(tau)
    end = float(flat.max()) if flat.size else 0.0
    if end <= 0.0:
        return np.full(tau.shape, q1), np.full(tau.shape, q2)
    from scipy.integrate import solve_ivp  # scipy on first use: a drag flight

    solution = solve_ivp(
        rhs,
        (0.0, end),
        [q1, q2, v1, v2],
        method="DOP853",
        rtol=RTOL,
        atol=ATOL,
        dense_output=True,
    )
    if not solution.success:
        raise RunDataError(f"{what} cannot be integrated: {solution.message}")
    x, y = solution.sol(flat)[:2]
    # the dense output matches the steps' ends; use the exact end point there
    x[flat == end], y[flat == end] = solution.y[0, -1], solution.y[1, -1]
    return x.reshape(tau.shape), y.reshape(tau.shape)


def arc_count(duration: float) -> int:
    """Points drawn along a flight (or a contact stretch) of ``duration`` seconds."""
    return int(min(200, max(8, duration * 2000)))


def positions_at(
    columns: Columns, rows: np.ndarray, times: np.ndarray, scene: Scene
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The centre (m) at each of ``times`` (s, within the impacts ``rows``' span), on the
    flight from the last impact of ``rows`` at or before it, and that impact's row.

    Exact parabolas are computed for all times at once; a flight with drag is integrated
    once per impact that starts one of the times' flights.

    Returns:
        ``(x, y, starts)``, each shaped like ``times``.
    """
    rows = np.asarray(rows, dtype=np.intp)
    times = np.asarray(times, dtype=float)
    t = column(columns, "t")
    index = np.searchsorted(t[rows], times, side="right") - 1
    starts = rows[np.maximum(index, 0)]
    if _rhs(scene, 0.0) is None:  # the exact parabola, as flight_from_state draws it
        tau = times - t[starts]
        q1, q2, v1, v2 = (column(columns, k)[starts] for k in ("q1", "q2", "v1", "v2"))
        g = scene.run.gravity
        return q1 + v1 * tau, q2 + v2 * tau - 0.5 * g * tau**2, starts
    x = np.empty(times.shape)
    y = np.empty(times.shape)
    for row in np.unique(starts):
        mask = starts == row
        x[mask], y[mask] = flight_positions(columns, int(row), times[mask] - t[row], scene)
    return x, y, starts


#: Points drawn along all the arcs of a trajectory, at most (about the pixels of the
#: figure). A longer window (thousands of impacts) covers the view with overlapping
#: arcs; its arcs get proportionally fewer points each (at least :data:`MIN_ARC_POINTS`),
#: so that drawing it takes seconds, not minutes, and shows the same picture.
ARC_POINT_BUDGET = 1_000_000
MIN_ARC_POINTS = 3


def arc_counts(durations: np.ndarray, budget: int | None = ARC_POINT_BUDGET) -> np.ndarray:
    """Points along flights of the given durations (s): :func:`arc_count` each, scaled
    down together where their sum exceeds ``budget`` (None: no limit)."""
    counts = np.clip(np.asarray(durations, dtype=float) * 2000, 8, 200).astype(np.intp)
    total = int(counts.sum())
    if budget is not None and total > budget:
        counts = np.maximum(MIN_ARC_POINTS, (counts * (budget / total)).astype(np.intp))
    return counts


def arcs(
    columns: Columns, rows: np.ndarray, scene: Scene, *, budget: int | None = ARC_POINT_BUDGET
) -> tuple[np.ndarray, np.ndarray]:
    """Flight arcs (m) between consecutive impacts of ``rows``, separated by NaN.

    The arc after impact ``row`` lasts the next row's time of flight (``tof``), drawn on
    :func:`arc_count` points, fewer where all the arcs' points would exceed ``budget``
    (see :func:`arc_counts`). Exact parabolas (no air drag, no Magnus force) are computed
    for all arcs at once, as whole arrays; a flight with drag is integrated arc by arc.
    """
    rows = np.asarray(rows, dtype=np.intp)
    tof = column(columns, "tof")
    starts = rows[:-1][np.diff(rows) == 1]  # an arc needs the next impact's time of flight
    if starts.size == 0:
        return np.array([]), np.array([])
    durations = np.maximum(tof[starts + 1], 0.0)
    counts = arc_counts(durations, budget)
    if _rhs(scene, 0.0) is None:  # no drag, no Magnus force: the exact parabola
        return _parabolas(columns, starts, durations, counts, scene)
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    for row, duration, count in zip(starts, durations, counts, strict=True):
        tau = np.linspace(0.0, float(duration), int(count))
        x, y = flight_positions(columns, int(row), tau, scene)
        xs += [x, np.array([np.nan])]
        ys += [y, np.array([np.nan])]
    return np.concatenate(xs), np.concatenate(ys)


def _parabolas(
    columns: Columns,
    starts: np.ndarray,
    durations: np.ndarray,
    counts: np.ndarray,
    scene: Scene,
) -> tuple[np.ndarray, np.ndarray]:
    """The exact parabolas after the impacts ``starts`` (row indices), of the given
    durations (s) and numbers of points, each followed by NaN: the points
    :func:`flight_positions` gives one arc at a time, to the last bit (times spaced as
    :func:`numpy.linspace` spaces them)."""
    steps = durations / np.maximum(counts - 1, 1)
    lengths = counts + 1  # each arc's points and the NaN after it
    arc = np.repeat(np.arange(starts.size), lengths)
    first = np.cumsum(lengths) - lengths
    j = np.arange(arc.size) - first[arc]  # the point's index along its arc
    tau = j * steps[arc]
    tau[first + counts - 1] = durations  # linspace ends exactly at its stop
    rows = starts[arc]
    q1, q2, v1, v2 = (column(columns, k)[rows] for k in ("q1", "q2", "v1", "v2"))
    g = scene.run.gravity
    x = q1 + v1 * tau
    y = q2 + v2 * tau - 0.5 * g * tau**2
    gap = first + counts
    x[gap] = np.nan
    y[gap] = np.nan
    return x, y
