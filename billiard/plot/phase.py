"""The paper's phase plot (Hartl, Miller and Mazzoleni, Fig. 3): the normalized impact
height q2/q2max against the normalized tangential velocity u4/u4max after each impact."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.ticker import MultipleLocator

from ..phase import phase_point
from ..scene import Scene
from .common import (
    MODEL_COLOR,
    Columns,
    camera_filter,
    column,
    dots,
    marker_size,
    rings,
    uniform_legend_markers,
)
from .inputs import checked_interval
from .titles import camera_label

__all__ = [
    "PHASE_CAPTION",
    "PHASE_XLABEL",
    "PHASE_YLABEL",
    "phase_coordinates",
    "phase_plot",
]

#: Axis labels of the phase plot: the normalizations, with their units.
PHASE_XLABEL = (
    "normalized tangential velocity $u_4/u_{4,max}$\n"
    "$u_4$ (m/s) over $u_{4,max} = \\sqrt{2E/m}$ (m/s)"
)
PHASE_YLABEL = (
    "normalized impact height $q_2/q_{2,max}$\n$q_2$ (m) over $q_{2,max} = E/(m\\,g)$ (m)"
)
#: What E is, for a caption under the phase plot.
PHASE_CAPTION = (
    "E (J): mechanical energy after each impact (translation, spin and m g $q_2$,\n"
    "potential zero at $q_2$ = 0 in the lab frame); m (kg): ball mass; g (m/s$^2$): gravity"
)


def phase_coordinates(columns: Columns, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Normalized tangential velocity and height after each impact.

    With E the mechanical energy after the impact (the ``energy`` column, J; kinetic
    energy of translation and spin plus m g q2, potential zero at q2 = 0), m the ball's
    mass (``scene.ball.mass``, kg) and g the gravity (``scene.run.gravity``, m/s^2):

    - q2max = E / (m g), the height (m) the ball would reach if all of E were potential
      energy, and
    - u4max = sqrt(2 E / m), the speed (m/s) it would have if all of E were kinetic
      energy of translation.

    So a ball at rest at height h has E = m g h and the point (0, 1); the ball's energy
    bounds every point to the half disc (u4/u4max)^2 + q2/q2max <= 1 when q2 >= 0 and the
    spin is zero (spin energy moves points further inside).

    Returns:
        ``(u4 / u4max, q2 / q2max)``, both dimensionless, one entry per impact. Rows whose
        energy is not positive and finite give NaN (they cannot be normalized).
    """
    energy = column(columns, "energy")
    q2 = column(columns, "q2")
    u4 = column(columns, "u4")
    m = scene.ball.mass
    g = scene.run.gravity
    good = np.isfinite(energy) & (energy > 0)
    safe = np.where(good, energy, np.nan)
    q2n, u4n = phase_point(q2, u4, safe, m, g)
    return u4n, q2n


def phase_plot(
    columns: Columns, scene: Scene, ax: Axes, *, frame_interval: float | None = None
) -> list[Line2D]:
    """Phase plot: normalized impact height q2/q2max (y) against normalized tangential
    velocity u4/u4max (x) after each impact (both dimensionless).

    q2max = E/(m g) (m) is the height the ball would reach if all its mechanical energy E
    (the ``energy`` column, J) were potential, and u4max = sqrt(2 E / m) (m/s) the speed it
    would have if all of it were kinetic; u4 is the centre's velocity along the contact
    tangent just after the impact (m/s). See :func:`phase_coordinates`. The axis labels
    state both definitions with their units (:data:`PHASE_CAPTION` defines E, for a
    caption). A period-one orbit is a single point (the paper's parabola at 5.4 Hz:
    (+-0.0372, 0.376)). The dashed curve is the energy bound (u4/u4max)^2 + q2/q2max = 1.
    The axes span x in [-1, 1] and y in [0, 1], widened if some points lie outside.

    Args:
        columns: a run's columns (``q2`` m, ``u4`` m/s, ``energy`` J).
        scene: the run's scene (``ball.mass``, ``run.gravity``).
        ax: the axes to draw in.
        frame_interval: if given (s), ring the impacts a camera with this frame interval
            would have recorded (hollow rings in a second colour beneath the model's dots).

    Returns:
        The data lines (x = u4/u4max, y = q2/q2max): the model's, then the camera's.
    """
    interval = checked_interval(frame_interval)
    x, y = phase_coordinates(columns, scene)
    size = marker_size(x, y, (2.0, 1.0))
    lines = [dots(ax, x, y, f"model: all {x.size} impacts", MODEL_COLOR, size)]
    xs, ys = [x], [y]
    if interval is not None:
        sx, sy = phase_coordinates(camera_filter(columns, interval), scene)
        lines.append(rings(ax, sx, sy, camera_label(interval, sx.size), size))
        xs.append(sx)
        ys.append(sy)
    s = np.linspace(-1, 1, 201)
    ax.plot(
        s,
        1 - s**2,
        color="0.35",
        linewidth=0.8,
        linestyle="--",
        label="all energy in $q_2$ and $u_4$",
        zorder=0,
    )
    ax.axvline(0.0, color="0.6", linewidth=0.5, zorder=0)
    all_x = np.concatenate([a[np.isfinite(a)] for a in xs])
    all_y = np.concatenate([b[np.isfinite(b)] for b in ys])
    xlo, xhi = -1.0, 1.0
    ylo, yhi = 0.0, 1.0
    if all_x.size:  # widen only for points outside the usual ranges
        if all_x.min() < xlo or all_x.max() > xhi:
            xlo, xhi = min(xlo, float(all_x.min()) - 0.02), max(xhi, float(all_x.max()) + 0.02)
        if all_y.min() < ylo or all_y.max() > yhi:
            ylo, yhi = min(ylo, float(all_y.min()) - 0.02), max(yhi, float(all_y.max()) + 0.02)
    ax.set_xlim(xlo, xhi)
    ax.set_ylim(ylo, yhi)
    ax.xaxis.set_major_locator(MultipleLocator(0.5))
    ax.yaxis.set_major_locator(MultipleLocator(0.2))
    ax.set_xlabel(PHASE_XLABEL)
    ax.set_ylabel(PHASE_YLABEL)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    uniform_legend_markers(ax.legend(loc="upper right", fontsize=8))
    return lines
