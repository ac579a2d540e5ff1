"""The ball's path over a window of impacts, in the lab frame: impacts, flight arcs, the
boundary at its mean and extreme positions, and the lid."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes

from billiard.plot.common import (
    CAMERA_COLOR,
    MM,
    MODEL_COLOR,
    REGIME_COLORS,
    Columns,
    RunDataError,
    Window,
    camera_filter,
    column,
)
from billiard.plot.contacts import MODE_LABELS, MODE_STYLES, MODES, Side, joined, phase_path
from billiard.plot.density import density_handle, density_image, use_density
from billiard.plot.flights import arcs, flight_label, positions_at
from billiard.plot.inputs import checked_interval
from billiard.plot.outline import boundary_function, boundary_outline
from billiard.plot.titles import fmt
from billiard.scene.scene import Scene

__all__ = [
    "FLIGHT_TIME_LABEL",
    "PATH_SAMPLES",
    "default_window",
    "path_samples",
    "trajectory",
    "view",
    "window_rows",
]

#: Times at which a long window's path is sampled for its density image.
PATH_SAMPLES = 1_000_000
#: The colour bar's label of a long window's density image (the bin's size follows it).
FLIGHT_TIME_LABEL = "flight time per bin (s)"


def default_window(
    columns: Columns, scene: Scene, *, periods: float = 4.0, max_impacts: int = 400
) -> tuple[int, int]:
    """The impacts of the last ``periods`` drive periods of the run (the last second if
    the drive has no frequency), at most ``max_impacts`` and at least two of them.

    Returns:
        ``(n0, n1)``: impact numbers (the ``n`` column), n0 included, n1 excluded.
    """
    t = column(columns, "t")
    n = column(columns, "n").astype(int)
    frequency = scene.drive.frequency
    span = periods / frequency if frequency > 0 else 1.0
    first = int(np.searchsorted(t, t[-1] - span, side="left"))
    first = max(0, min(first, t.size - 2), t.size - max_impacts)
    return int(n[first]), int(n[-1]) + 1


def window_rows(columns: Columns, scene: Scene, window: Window | None) -> np.ndarray:
    """Row indices of the impacts n0 <= n < n1 (default: :func:`default_window`).

    Raises:
        RunDataError: the window holds no impacts.
    """
    n = column(columns, "n")
    if window is None:
        window = default_window(columns, scene)
    n0, n1 = window
    lo = -math.inf if n0 is None else n0
    hi = math.inf if n1 is None else n1
    rows = np.flatnonzero((n >= lo) & (n < hi))
    if rows.size == 0:
        shown = f"{'' if n0 is None else n0}:{'' if n1 is None else n1}"
        raise RunDataError(
            f"window {shown} holds no impacts (the run has impacts "
            f"{int(n[0])} to {int(n[-1])}; N1 is excluded)"
        )
    return rows


def path_samples(
    columns: Columns, rows: np.ndarray, scene: Scene, count: int = 0
) -> tuple[np.ndarray, np.ndarray, float]:
    """The centre (m) at ``count`` times (default :data:`PATH_SAMPLES`) spaced evenly
    from the first to the last impact of ``rows``, each on its flight (see
    :func:`billiard.plot.flights.positions_at`), and the time step (s) between them:
    binned, they give the time spent per bin."""
    t = column(columns, "t")
    t0, t1 = float(t[rows[0]]), float(t[rows[-1]])
    times, step = np.linspace(t0, t1, count or PATH_SAMPLES, retstep=True)
    x, y, _ = positions_at(columns, rows, times, scene)
    return x, y, float(step)


def view(
    scene: Scene, xs: np.ndarray, ys: np.ndarray
) -> tuple[tuple[float, float], tuple[float, float], bool]:
    """Limits (m) around the ball's path, boundary included, and whether the lid shows."""
    drive = scene.drive
    r = scene.ball.radius
    f = boundary_function(scene)
    x = xs[np.isfinite(xs)]
    y = ys[np.isfinite(ys)]
    x_lo, x_hi = float(x.min()), float(x.max())
    y_hi = float(y.max()) + r
    margin = max(0.15 * (x_hi - x_lo), 3 * r)
    x_lo, x_hi = x_lo - margin, x_hi + margin
    heights = f(np.linspace(x_lo, x_hi, 401))
    floor = np.nanmin(heights) if np.any(np.isfinite(heights)) else float(y.min()) - r
    y_lo = min(float(floor), float(y.min()) - r)
    if drive.direction == "vertical":
        y_lo -= drive.amplitude
    ceiling = scene.boundary.ceiling
    show_lid = ceiling is not None and y_hi > y_lo + 0.6 * (ceiling - y_lo)
    if ceiling is not None and show_lid:
        y_hi = max(y_hi, ceiling)
    # Avoid a sliver: with equal aspect, neither side may be much shorter than the other.
    width, height = x_hi - x_lo, y_hi - y_lo
    if width < 0.6 * height:
        centre = 0.5 * (x_lo + x_hi)
        x_lo, x_hi = centre - 0.3 * height, centre + 0.3 * height
    elif height < 0.35 * width:
        y_hi = y_lo + 0.35 * width
    pad = 0.04 * max(x_hi - x_lo, y_hi - y_lo)
    return (x_lo, x_hi), (y_lo - pad, y_hi + pad), show_lid


def boundary_positions(scene: Scene, x_lim: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """A grid of the boundary's own x (m) wide enough for any drive offset, and f there."""
    amplitude = scene.drive.amplitude
    return boundary_outline(scene, x_lim[0] - amplitude, x_lim[1] + amplitude)


def trajectory(
    columns: Columns,
    scene: Scene,
    ax: Axes,
    window: Window | None = None,
    *,
    frame_interval: float | None = None,
    contacts: Side | None = None,
    samples: Side | None = None,
    title: bool = True,
    density: bool | None = None,
) -> dict[str, Any]:
    """The ball's path over a window of impacts, in the lab frame, in mm (equal aspect).

    Drawn: the boundary y = f(x) at its mean position (solid), and at its extreme drive
    offsets +-A (dotted) since it moves; the lid at ``boundary.ceiling`` if the path gets
    near it; the centre of the ball at each impact (coloured by the impact's regime); and
    the flight arcs between consecutive impacts, rebuilt from each impact's position and
    velocity over the next impact's time of flight with the scene's flight model (the
    exact parabola without air drag, the integrated drag flight with it; see
    :mod:`billiard.plot.flights`), so that each arc ends at the next impact. Impact points
    are ball centres, so they lie one radius inside the boundary.

    With ``contacts`` (a run of ``contact.model = "phases"``) the flights are drawn only
    where the ball flew (from an impact or a phase's lift-off, wall end or release, to the
    next impact or phase), and the contact phases as stretches along the wall, one line
    style per mode (rolling, sliding, held), from ``samples`` when given, else rebuilt
    (see :mod:`billiard.plot.contacts`).

    Args:
        columns: a run's columns.
        scene: the run's scene.
        ax: the axes to draw in.
        window: ``(n0, n1)``: impact numbers (the ``n`` column) n0 <= n < n1; either may
            be None for an open end. Default: :func:`default_window`.
        frame_interval: if given (s), ring the impacts the camera would have recorded.
        contacts: the run's contact phases (the columns of contacts.csv,
            ``Result.contacts``), or None.
        samples: the run's samples (the columns of trajectory.csv,
            ``Result.trajectory``), used with ``contacts``; or None.
        title: write the window's first and last impacts and times (and the number of
            contact phases) above the axes; False leaves them to a caption.
        density: draw the flights as a density image (see below): True, False, or None
            (default) when the window holds more than
            :data:`billiard.plot.density.DENSITY_THRESHOLD` impacts. Not for a run with
            ``contacts``.

    A window of more than :data:`billiard.plot.density.DENSITY_THRESHOLD` impacts would
    be a tangle of arcs that takes minutes to draw: its flights are drawn instead as a
    density image of the time the centre spent in each bin (s, the path sampled at
    :data:`PATH_SAMPLES` times spaced evenly over the window), with a colour bar, and
    neither the impacts nor the camera's rings are marked.

    Returns:
        A dict with the row indices drawn (``rows``) and the artists (``impacts``,
        ``arcs``: the line, or the density image, ``boundary``, and ``camera`` with
        ``frame_interval`` unless the flights are a density image); with ``contacts``
        also the :class:`~billiard.plot.contacts.PhasePath` drawn (``path``) and the contact
        stretches' lines by mode (``stretches``).
    """
    interval = checked_interval(frame_interval)
    rows = window_rows(columns, scene, window)
    path = None
    extra_x, extra_y = np.array([]), np.array([])
    dense = contacts is None and use_density(rows.size, density)
    step = 0.0
    if dense:
        arc_x, arc_y, step = path_samples(columns, rows, scene)
    elif contacts is None:
        arc_x, arc_y = arcs(columns, rows, scene)
    else:
        path = phase_path(columns, rows, scene, contacts, samples)
        arc_x, arc_y = joined(path.flights)
        extra_x, extra_y = joined(path.stretches)
    q1 = column(columns, "q1")[rows]
    q2 = column(columns, "q2")[rows]
    x_lim, y_lim, show_lid = view(
        scene, np.concatenate([q1, arc_x, extra_x]), np.concatenate([q2, arc_y, extra_y])
    )
    amplitude, direction = scene.drive.amplitude, scene.drive.direction

    grid, height = boundary_positions(scene, x_lim)
    (boundary,) = ax.plot(
        grid * MM, height * MM, color="black", linewidth=1.4, label="boundary, mean position"
    )
    if amplitude > 0:
        for sign in (-1.0, 1.0):
            if direction == "vertical":
                bx, by = grid, height + sign * amplitude
            else:
                bx, by = grid + sign * amplitude, height
            ax.plot(
                bx * MM,
                by * MM,
                color="0.55",
                linewidth=0.7,
                linestyle=":",
                label=f"boundary at $\\pm A$ = $\\pm${fmt(amplitude * MM)} mm"
                if sign > 0
                else None,
            )
    ceiling = scene.boundary.ceiling
    if ceiling is not None and show_lid:
        ax.axhline(ceiling * MM, color="0.3", linewidth=1.2, label="lid")
    arc_line: Any
    if dense:
        arc_line = density_image(
            ax,
            arc_x * MM,
            arc_y * MM,
            (x_lim[0] * MM, x_lim[1] * MM),
            (y_lim[0] * MM, y_lim[1] * MM),
            unit="mm",
            weight=step,
            label=FLIGHT_TIME_LABEL,
        )
        density_handle(ax, f"{flight_label(scene)}, {rows.size} impacts (density)")
    else:
        (arc_line,) = ax.plot(
            arc_x * MM, arc_y * MM, color=MODEL_COLOR, linewidth=0.8, label=flight_label(scene)
        )
    stretches = {} if path is None else _draw_stretches(ax, path)
    regime = np.asarray(columns["regime"])[rows] if "regime" in columns else None
    impacts = []
    if dense:
        pass  # thousands of impacts would hide the path: the density shows where they are
    elif regime is None:
        impacts.append(
            ax.plot(
                q1 * MM, q2 * MM, "o", markersize=3.5, color="tab:red", label="impact (ball centre)"
            )[0]
        )
    else:
        for name in sorted(set(regime.tolist())):
            mask = regime == name
            impacts.append(
                ax.plot(
                    q1[mask] * MM,
                    q2[mask] * MM,
                    "o",
                    markersize=3.5,
                    color=REGIME_COLORS.get(name, "0.4"),
                    label=f"{name} impact ({int(mask.sum())})",
                    zorder=2.5,
                )[0]
            )
    drawn: dict[str, Any] = {
        "rows": rows,
        "impacts": impacts,
        "arcs": arc_line,
        "boundary": boundary,
    }
    if path is not None:
        drawn["path"] = path
        drawn["stretches"] = stretches
    if interval is not None and not dense:
        seen = camera_filter(columns, interval)
        mask = np.isin(column(columns, "n")[rows], column(seen, "n"))
        (drawn["camera"],) = ax.plot(
            q1[mask] * MM,
            q2[mask] * MM,
            "o",
            markersize=7,
            markerfacecolor="none",
            markeredgecolor=CAMERA_COLOR,
            markeredgewidth=1.0,
            label=f"seen by camera (frame {interval * 1e3:.3g} ms)",
            zorder=2.0,
        )
    ax.set_xlim(x_lim[0] * MM, x_lim[1] * MM)
    ax.set_ylim(y_lim[0] * MM, y_lim[1] * MM)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("horizontal position of the centre $q_1$ (mm)")
    ax.set_ylabel("height of the centre $q_2$ (mm)")
    t = column(columns, "t")
    n_all = column(columns, "n")
    t_lo, t_hi = (t[rows[0]], t[rows[-1]]) if path is None else (path.t_lo, path.t_hi)
    phases = "" if path is None else f", {len(path.stretches)} contact phases"
    if title:
        ax.set_title(
            f"impacts {int(n_all[rows[0]])} to {int(n_all[rows[-1]])}{phases}, "
            f"t = {t_lo:.3f} to {t_hi:.3f} s",
            fontsize=9,
        )
    ax.grid(True, linewidth=0.3, alpha=0.5)
    ax.legend(loc="upper right", fontsize=7, framealpha=0.85)
    return drawn


def _draw_stretches(ax: Axes, path: Any) -> dict[str, Any]:
    """One line per contact mode through its stretches, in the mode's style, labelled
    with the mode and the number of phases and the time spent in it."""
    lines: dict[str, Any] = {}
    for mode in MODES:
        pieces = [p for p in path.stretches if p.kind == mode]
        if not pieces:
            continue
        x, y = joined(pieces)
        style = dict(MODE_STYLES[mode])
        if "marker" in style:
            # mark where each stretch starts: a held ball on a still boundary is one point
            starts = np.concatenate([[0], np.flatnonzero(np.isnan(x[:-1])) + 1])
            style["markevery"] = starts.tolist()
        spent = sum(float(p.t[-1] - p.t[0]) for p in pieces)
        (lines[mode],) = ax.plot(
            x * MM,
            y * MM,
            label=f"{MODE_LABELS[mode]} ({_count(len(pieces))}, {spent:.3g} s)",
            zorder=2.2,
            solid_capstyle="round",
            **style,
        )
    return lines


def _count(phases: int) -> str:
    return f"{phases} phase" if phases == 1 else f"{phases} phases"
