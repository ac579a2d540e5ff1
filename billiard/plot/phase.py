"""The paper's phase plot (Hartl, Miller and Mazzoleni, Fig. 3): the normalized impact
height q2/q2max against the normalized tangential velocity u4/u4max after each impact."""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.ticker import MultipleLocator

from billiard.analysis.phase import (
    DEFAULT_PHASE_REFERENCE,
    PHASE_REFERENCES,
    normalized_points,
    phase_frame,
)
from billiard.errors import GeometryError
from billiard.plot.common import (
    MODEL_COLOR,
    Columns,
    RunDataError,
    camera_filter,
    column,
    dots,
    marker_size,
    rings,
    uniform_legend_markers,
)
from billiard.plot.density import density_handle, density_image, rasterize_if_large, use_density
from billiard.plot.inputs import checked_interval
from billiard.plot.titles import camera_label
from billiard.scene.scene import Scene

__all__ = [
    "PHASE_CAPTION",
    "PHASE_XLABEL",
    "PHASE_YLABEL",
    "phase_caption",
    "phase_coordinates",
    "phase_plot",
]

#: Axis labels of the phase plot: the normalizations, with their units (h0 and E0 are
#: defined in :mod:`billiard.analysis.phase`, and for a caption by :func:`phase_caption`).
PHASE_XLABEL = (
    "normalized tangential velocity $u_4/u_{4,max}$\n"
    "$u_4$ (m/s) over $u_{4,max} = \\sqrt{2E_0/m}$ (m/s)"
)
PHASE_YLABEL = (
    "normalized impact height $(q_2 - h_0)/q_{2,max}$\n"
    "$q_2 - h_0$ (m) over $q_{2,max} = E_0/(m\\,g)$ (m)"
)

_ZERO_TEXT = {
    "lab-origin": "$h_0$ = 0, the lab frame's $q_2$ = 0",
    "vertex": "$h_0$ (m): the boundary's vertex",
    "lowest-centre": "$h_0$ (m): the ball's centre at rest at the bottom",
}


def phase_caption(reference: str = DEFAULT_PHASE_REFERENCE) -> str:
    """What E0 and h0 are under a phase reference (a key of
    :data:`billiard.analysis.phase.PHASE_REFERENCES`), for a caption under the phase plot."""
    ref = PHASE_REFERENCES[reference]
    kinds = "translation and spin" if ref.spin else "translation (spin left out)"
    return (
        f"$E_0$ (J): kinetic energy of {kinds} after each impact plus m g ($q_2 - h_0$);\n"
        f"{_ZERO_TEXT[ref.zero]} (phase reference {ref.name!r}); "
        "m (kg): ball mass; g (m/s$^2$): gravity"
    )


#: What E0 and h0 are under the default reference, for a caption under the phase plot.
PHASE_CAPTION = phase_caption()


def phase_coordinates(
    columns: Columns, scene: Scene, reference: str = DEFAULT_PHASE_REFERENCE
) -> tuple[np.ndarray, np.ndarray]:
    """Normalized tangential velocity and height after each impact.

    Under a phase reference of :data:`billiard.analysis.phase.PHASE_REFERENCES` (default
    :data:`billiard.analysis.phase.DEFAULT_PHASE_REFERENCE`), with h0 its zero of potential energy
    (m) and E0 the energy it shares out (J; from the ``energy`` column, the height h0 and,
    when the spin is left out, the ``omega`` column), m the ball's mass
    (``scene.ball.mass``, kg) and g the gravity (``scene.run.gravity``, m/s^2):

    - q2max = E0 / (m g), the height (m) above h0 the ball would reach if all of E0 were
      potential energy, and
    - u4max = sqrt(2 E0 / m), the speed (m/s) it would have if all of it were kinetic
      energy of translation.

    So a ball at rest at a height above h0 is the point (0, 1); every point with
    q2 >= h0 lies in the half disc (u4/u4max)^2 + (q2 - h0)/q2max <= 1 (the normal
    velocity, and the spin when it counts, move points further inside).

    Returns:
        ``(u4 / u4max, (q2 - h0) / q2max)``, both dimensionless, one entry per impact.
        Rows whose E0 is not positive and finite give NaN (they cannot be normalized).
    """
    for name in ("energy", "q2", "u4"):
        column(columns, name)  # a missing column is a RunDataError
    try:
        frame = phase_frame(scene, reference)
    except (ValueError, ArithmeticError, GeometryError) as exc:
        raise RunDataError(
            f"phase reference {reference!r} for boundary curve {scene.boundary.curve!r}: "
            + " ".join(str(exc).split())
        ) from None
    if "omega" not in columns and not frame.reference.spin:
        raise RunDataError(
            f"collisions data have no column 'omega' (phase reference {reference!r})"
        )
    q2n, u4n = normalized_points(columns, scene, frame)
    return u4n, q2n


def phase_plot(
    columns: Columns,
    scene: Scene,
    ax: Axes,
    *,
    frame_interval: float | None = None,
    reference: str = DEFAULT_PHASE_REFERENCE,
    density: bool | None = None,
) -> list[Artist]:
    """Phase plot: normalized impact height q2/q2max (y) against normalized tangential
    velocity u4/u4max (x) after each impact (both dimensionless).

    q2max = E0/(m g) (m) is the height above h0 the ball would reach if all the energy E0
    of ``reference`` (J) were potential, and u4max = sqrt(2 E0 / m) (m/s) the speed it
    would have if all of it were kinetic; u4 is the centre's velocity along the contact
    tangent just after the impact (m/s). See :func:`phase_coordinates`. The axis labels
    state both definitions with their units (:func:`phase_caption` defines E0 and h0, for
    a caption). A period-one orbit is a single point (the paper's parabola at 5.4 Hz:
    (+-0.0372, 0.376)). The dashed curve is the energy bound
    (u4/u4max)^2 + (q2 - h0)/q2max = 1.
    The axes span x in [-1, 1] and y in [0, 1], widened if some points lie outside.
    The model's impacts are dots, or a density image when more than
    :data:`billiard.plot.density.DENSITY_THRESHOLD` of them can be normalized (see
    :mod:`billiard.plot.density`).

    Args:
        columns: a run's columns (``q2`` m, ``u4`` m/s, ``energy`` J).
        scene: the run's scene (``ball.mass``, ``run.gravity``).
        ax: the axes to draw in.
        frame_interval: if given (s), ring the impacts a camera with this frame interval
            would have recorded (hollow rings in a second colour beneath the model's dots).
        density: True for a density image, False for dots, None (default) to choose by
            the number of points drawn (impacts with E0 > 0).

    Returns:
        The data artists (x = u4/u4max, y = q2/q2max): the model's (dots, or the density
        image whose ``get_array()`` holds the impacts per bin), then the camera's.
    """
    interval = checked_interval(frame_interval)
    x, y = phase_coordinates(columns, scene, reference)
    xs, ys = [x], [y]
    if interval is not None:
        sx, sy = phase_coordinates(camera_filter(columns, interval), scene, reference)
        xs.append(sx)
        ys.append(sy)
    all_x = np.concatenate([a[np.isfinite(a)] for a in xs])
    all_y = np.concatenate([b[np.isfinite(b)] for b in ys])
    xlo, xhi = -1.0, 1.0
    ylo, yhi = 0.0, 1.0
    if all_x.size:  # widen only for points outside the usual ranges
        if all_x.min() < xlo or all_x.max() > xhi:
            xlo, xhi = min(xlo, float(all_x.min()) - 0.02), max(xhi, float(all_x.max()) + 0.02)
        if all_y.min() < ylo or all_y.max() > yhi:
            ylo, yhi = min(ylo, float(all_y.min()) - 0.02), max(yhi, float(all_y.max()) + 0.02)
    label = f"model: all {x.size} impacts"
    lines: list[Artist]
    drawn = int(np.count_nonzero(np.isfinite(x) & np.isfinite(y)))  # E0 > 0 only
    if use_density(drawn, density):
        lines = [density_image(ax, x, y, (xlo, xhi), (ylo, yhi))]
        density_handle(ax, f"{label} (density)")
        size = 1.5
    else:
        size = marker_size(x, y, (2.0, 1.0))
        lines = [dots(ax, x, y, label, MODEL_COLOR, size)]
    if interval is not None:
        lines.append(rings(ax, xs[1], ys[1], camera_label(interval, xs[1].size), size))
        rasterize_if_large(lines[-1], xs[1].size)
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
    ax.set_xlim(xlo, xhi)
    ax.set_ylim(ylo, yhi)
    ax.xaxis.set_major_locator(MultipleLocator(0.5))
    ax.yaxis.set_major_locator(MultipleLocator(0.2))
    ax.set_xlabel(PHASE_XLABEL)
    ax.set_ylabel(PHASE_YLABEL)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    uniform_legend_markers(ax.legend(loc="upper right", fontsize=8))
    return lines
