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

__all__ = ["arc_count", "arcs", "flight_from_state", "flight_label", "flight_positions"]

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


def arcs(columns: Columns, rows: np.ndarray, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Flight arcs (m) between consecutive impacts of ``rows``, separated by NaN.

    The arc after impact ``row`` lasts the next row's time of flight (``tof``).
    """
    tof = column(columns, "tof")
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    for row, nxt in zip(rows[:-1], rows[1:], strict=True):
        if nxt != row + 1:
            continue
        duration = max(float(tof[nxt]), 0.0)
        count = arc_count(duration)
        x, y = flight_positions(columns, int(row), np.linspace(0.0, duration, count), scene)
        xs += [x, np.array([np.nan])]
        ys += [y, np.array([np.nan])]
    if not xs:
        return np.array([]), np.array([])
    return np.concatenate(xs), np.concatenate(ys)
