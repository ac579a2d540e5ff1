"""Figures of a run: return map, times-of-flight map, phase plot, trajectory, animation.

Every function here reads the columns of a run's ``collisions.csv`` (see
:func:`billiard.camera.read_collisions`) and, where it needs them, the run's scene as the
plain dict that :mod:`tomllib` reads from ``scene.toml``. Lengths are stored in metres and
drawn in millimetres; times in seconds.

The figures follow Hartl, Miller and Mazzoleni, "Dynamic Modeling and Simulation of a Real
World Billiard": the return map of impact heights (q2,n vs q2,n+1), the map of times of
flight (t_n vs t_n+1), and the phase plot of the normalized impact height q2/q2max against
the normalized tangential velocity u4/u4max (their Figs. 2 and 3).

Drawing uses :class:`matplotlib.figure.Figure` with an Agg canvas and never pyplot, so no
figure is kept in a global registry; every figure made here is saved and dropped.

``billiard plot DIR`` is :func:`plot_run`; :func:`add_plot_arguments` and
:func:`run_plot_command` give the command-line interface.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import textwrap
import tomllib
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle
from matplotlib.ticker import MultipleLocator
from PIL import Image

from .camera import camera_filter
from .record import RunDataError, read_collisions

__all__ = [
    "FIGURE_NAMES",
    "RunDataError",
    "add_plot_arguments",
    "animate",
    "default_window",
    "drive_offset",
    "load_run",
    "paper_figure",
    "paper_phase_figure",
    "parse_window",
    "phase_coordinates",
    "phase_plot",
    "plot_run",
    "read_scene",
    "return_map",
    "run_plot_command",
    "scene_title",
    "time_map",
    "trajectory",
]

#: Files written by :func:`plot_run`, in order.
FIGURE_NAMES: tuple[str, ...] = (
    "return_map.png",
    "time_map.png",
    "phase.png",
    "trajectory.png",
    "animation.gif",
)

G_DEFAULT = 9.81  # m/s^2
MASS_DEFAULT = 1.3028e-4  # kg, the paper's steel ball
RADIUS_DEFAULT = 1.55e-3  # m
MM = 1e3  # mm per m

DPI = 100
SINGLE_SIZE = (6.0, 5.6)  # inches: 600 x 560 px at DPI
MODEL_COLOR = "tab:blue"
CAMERA_COLOR = "tab:orange"
REGIME_COLORS = {"stick": "tab:green", "slip": "tab:red", "elastic": "tab:purple"}

Window = tuple[int | None, int | None]
Columns = Mapping[str, np.ndarray]


# --- reading a run ---------------------------------------------------------------------


def read_scene(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a run's ``scene.toml`` into a plain dict.

    Raises:
        RunDataError: the file is missing, unreadable or not TOML (one line, naming it).
    """
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise RunDataError(
            f"{path}: file not found (the run's scene is needed "
            "for the ball's mass, the boundary and the titles)"
        ) from None
    except OSError as exc:
        raise RunDataError(f"{path}: cannot read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise RunDataError(f"{path}: not valid TOML: {' '.join(str(exc).split())}") from None


def load_run(run_dir: str | os.PathLike[str]) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Columns of ``run_dir/collisions.csv`` and the dict of ``run_dir/scene.toml``.

    Raises:
        RunDataError: a file is missing or malformed, or the CSV has no impacts.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise RunDataError(f"{run_dir}: not a directory")
    csv_path = run_dir / "collisions.csv"
    columns = read_collisions(csv_path)
    if columns["t"].size == 0:
        raise RunDataError(f"{csv_path}: no impacts to plot")
    scene = read_scene(run_dir / "scene.toml")
    return columns, scene


def _section(scene: Mapping[str, Any], name: str) -> Mapping[str, Any]:
    value = scene.get(name, {})
    return value if isinstance(value, Mapping) else {}


def _number(scene: Mapping[str, Any], section: str, key: str, default: float) -> float:
    value = _section(scene, section).get(key, default)
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise RunDataError(f"scene key '{section}.{key}' must be a number, got {value!r}") from None
    return value


def _mass(scene: Mapping[str, Any]) -> float:
    return _number(scene, "ball", "mass", MASS_DEFAULT)


def _radius(scene: Mapping[str, Any]) -> float:
    return _number(scene, "ball", "radius", RADIUS_DEFAULT)


def _gravity(scene: Mapping[str, Any]) -> float:
    return _number(scene, "run", "gravity", G_DEFAULT)


def _drive(scene: Mapping[str, Any]) -> tuple[float, float, float, str]:
    """Amplitude (m), frequency (Hz), phase (rad) and direction of the drive."""
    return (
        _number(scene, "drive", "amplitude", 0.0),
        _number(scene, "drive", "frequency", 0.0),
        _number(scene, "drive", "phase", 0.0),
        str(_section(scene, "drive").get("direction", "horizontal")),
    )


def drive_offset(scene: Mapping[str, Any], t: np.ndarray | float) -> np.ndarray:
    """The boundary's displacement D(t) = A sin(2 pi f t + phase) (m) at times t (s).

    It is along n1 for ``drive.direction = "horizontal"`` and along n2 for
    ``"vertical"``.
    """
    amplitude, frequency, phase, _ = _drive(scene)
    return amplitude * np.sin(2 * np.pi * frequency * np.asarray(t, dtype=float) + phase)


def _curve_parameters(scene: Mapping[str, Any]) -> dict[str, float]:
    params = _section(scene, "boundary").get("parameters", {})
    if isinstance(params, Mapping):
        return {str(k): float(v) for k, v in params.items()}
    return {str(k): float(v) for k, v in params}


def _curve_name(scene: Mapping[str, Any]) -> str:
    return str(_section(scene, "boundary").get("curve", "parabola"))


def _boundary_function(scene: Mapping[str, Any]) -> Callable[[np.ndarray], np.ndarray]:
    """f(x) (m) of the scene's boundary in its own frame, vectorized over x (m).

    An expression is evaluated directly (no derivation needed); a curve name is loaded
    with :func:`billiard.curves.load_curve`. Points where f is undefined give NaN.
    """
    curve = _curve_name(scene)
    params = _curve_parameters(scene)
    from .curves import is_expression, load_curve

    scalar: Callable[[float], float]
    try:
        if is_expression(curve):
            from .expr import parse_curve

            expression = parse_curve(curve)

            def scalar(x: float) -> float:
                return expression.evaluate(x, **params)
        else:
            scalar = load_curve(curve, params).f
    except ValueError as exc:
        raise RunDataError(
            f"boundary curve {curve!r} cannot be drawn: {' '.join(str(exc).split())}"
        ) from None

    def f(x: np.ndarray) -> np.ndarray:
        out = np.empty(np.shape(x))
        for i, xi in enumerate(np.ravel(x)):
            try:
                out.flat[i] = scalar(float(xi))
            except (ValueError, ArithmeticError):
                out.flat[i] = np.nan
        return out

    return f


# --- titles ----------------------------------------------------------------------------


def _fmt(value: float) -> str:
    return f"{value:.4g}"


def scene_title(scene: Mapping[str, Any], n_impacts: int | None = None, width: int = 90) -> str:
    """A figure title: the scene's name, then curve, drive, restitution and friction.

    The parts are joined with "; " on lines of at most ``width`` characters, e.g.::

        parabola-5.4hz, 25000 impacts
        curve parabola; drive 5.4 Hz, A = 5 mm horizontal; e = 0.393, mu_s = 0.61, mu_k = 0.47

    (mu_s and mu_k are drawn as Greek letters).
    """
    name = str(scene.get("name", "run"))
    head = name if n_impacts is None else f"{name}, {n_impacts} impacts"
    curve = _curve_name(scene)
    params = _curve_parameters(scene)
    from .curves import is_expression

    if is_expression(curve):
        curve_text = "f(x) = " + (curve if len(curve) <= 50 else curve[:47] + "...")
    else:
        curve_text = f"curve {curve}"
    if params:
        curve_text += " (" + ", ".join(f"{k}={_fmt(v)}" for k, v in params.items()) + ")"
    amplitude, frequency, _, direction = _drive(scene)
    drive_text = f"drive {_fmt(frequency)} Hz, A = {_fmt(amplitude * MM)} mm {direction}"
    contact = _section(scene, "contact")
    contact_text = ", ".join(
        f"{label} = {_fmt(float(contact[key]))}"
        for key, label in (
            ("restitution", "e"),
            ("mu_static", "$\\mu_s$"),
            ("mu_kinetic", "$\\mu_k$"),
        )
        if key in contact
    )
    # Break between the parts where possible; wrap a part only if it is too long alone.
    # Lengths are measured on plain text, so that the mathtext of mu counts as 4 characters.
    lines: list[str] = []
    for part in (curve_text, drive_text, contact_text):
        if not part:
            continue
        plain = _plain(part)
        current = lines[-1] if lines else None
        if current is not None and len(_plain(current)) + 2 + len(plain) <= width:
            lines[-1] = f"{current}; {part}"
        elif len(plain) <= width:
            lines.append(part)
        else:
            lines += textwrap.wrap(part, width=width)
    wrapped = "\n".join(lines)
    return f"{head}\n{wrapped}"


def _plain(text: str) -> str:
    return text.replace("$\\mu_s$", "mu_s").replace("$\\mu_k$", "mu_k")


def _short_label(scene: Mapping[str, Any]) -> str:
    """A panel title such as 'wedge, 6.6 Hz'."""
    curve = _curve_name(scene)
    from .curves import is_expression

    if is_expression(curve):
        curve = str(scene.get("name", "curve"))
    _, frequency, _, _ = _drive(scene)
    return f"{curve}, {_fmt(frequency)} Hz"


# --- small helpers ---------------------------------------------------------------------


def _marker_size(x: np.ndarray, y: np.ndarray, spans: tuple[float, float] | None = None) -> float:
    """Marker size (points) that keeps a cloud of points readable.

    It depends on how many distinct places the points occupy (cells of a 250 x 250 grid
    over ``spans``, the axes' data ranges, by default the data's own), not on how many
    points there are: 25,000 impacts on a period-one orbit still get visible markers.
    """
    good = np.isfinite(x) & np.isfinite(y)
    if not good.any():
        return 3.5
    x, y = x[good], y[good]
    sx, sy = spans if spans is not None else (float(np.ptp(x)), float(np.ptp(y)))
    sx = sx if sx > 0 else 1.0
    sy = sy if sy > 0 else 1.0
    ix = np.floor((x - x.min()) / sx * 250).astype(np.int64)
    iy = np.floor((y - y.min()) / sy * 250).astype(np.int64)
    cells = np.unique(ix * 1_000_003 + iy).size
    if cells <= 300:
        return 3.5
    if cells <= 3000:
        return 2.0
    return 1.0


def _uniform_legend_markers(legend: Any, size: float = 4.0) -> None:
    """Draw every marker of a legend at one readable size."""
    for handle in getattr(legend, "legend_handles", []):
        if isinstance(handle, Line2D) and handle.get_marker() not in (None, "None", ""):
            handle.set_markersize(size)


def _column(columns: Columns, name: str) -> np.ndarray:
    if name not in columns:
        raise RunDataError(f"collisions data have no column {name!r}")
    return np.asarray(columns[name], dtype=float)


def _camera_label(frame_interval: float, count: int) -> str:
    fps = 1.0 / frame_interval
    return f"camera, frame {frame_interval * 1e3:.3g} ms ({fps:.3g} fps): {count} impacts"


def _checked_interval(frame_interval: float | None) -> float | None:
    if frame_interval is None:
        return None
    value = float(frame_interval)
    if not (math.isfinite(value) and value > 0):
        raise RunDataError(
            f"camera frame interval must be a positive number of seconds, got {frame_interval!r}"
        )
    return value


def _pairs_axes(
    ax: Axes, x: np.ndarray, y: np.ndarray, label: str, color: str, size: float
) -> Line2D:
    (line,) = ax.plot(
        x,
        y,
        linestyle="none",
        marker="o",
        markersize=size,
        markeredgewidth=0,
        color=color,
        label=label,
    )
    return line


def _square_limits(ax: Axes, values: Sequence[np.ndarray]) -> tuple[float, float]:
    finite = np.concatenate([v[np.isfinite(v)] for v in values]) if values else np.array([])
    if finite.size == 0:
        lo, hi = 0.0, 1.0
    else:
        lo, hi = float(finite.min()), float(finite.max())
        if hi - lo < 1e-12 * max(1.0, abs(hi)):
            pad = max(abs(hi) * 0.05, 1e-3)
        else:
            pad = 0.04 * (hi - lo)
        lo, hi = lo - pad, hi + pad
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal", adjustable="box")
    return lo, hi


def _diagonal(ax: Axes, lo: float, hi: float, label: str) -> None:
    ax.plot([lo, hi], [lo, hi], color="0.35", linewidth=0.8, linestyle="--", label=label, zorder=0)


def _new_figure(size: tuple[float, float] = SINGLE_SIZE) -> Figure:
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: Path) -> Path:
    fig.savefig(path, dpi=DPI)
    fig.clear()
    return path


# --- the maps --------------------------------------------------------------------------


def return_map(columns: Columns, ax: Axes, *, frame_interval: float | None = None) -> list[Line2D]:
    """Return map of impact heights: q2,n (x) against q2,n+1 (y), both in mm.

    Each point is a pair of consecutive impacts (the centre's height q2 at impact n and at
    impact n + 1); the dashed line is the diagonal q2,n = q2,n+1, on which a period-one
    orbit sits. Points above it are impacts followed by a higher one.

    Args:
        columns: a run's columns (``q2`` in m, and ``t`` in s with ``frame_interval``).
        ax: the axes to draw in.
        frame_interval: if given (s), also draw, in a second colour, the return map of
            the impacts a camera with this frame interval would have recorded (see
            :func:`billiard.camera.camera_filter`).

    Returns:
        The data lines: the model's (x data ``q2[:-1]`` and y data ``q2[1:]`` in mm),
        then the camera's if ``frame_interval`` is given.
    """
    interval = _checked_interval(frame_interval)
    q2 = _column(columns, "q2") * MM
    sets = [(q2, f"model: all {q2.size} impacts", MODEL_COLOR)]
    if interval is not None:
        seen = _column(camera_filter(columns, interval), "q2") * MM
        sets.append((seen, _camera_label(interval, seen.size), CAMERA_COLOR))
    lines = [
        _pairs_axes(ax, h[:-1], h[1:], label, color, _marker_size(h[:-1], h[1:]))
        for h, label, color in sets
    ]
    lo, hi = _square_limits(ax, [h for h, _, _ in sets])
    _diagonal(ax, lo, hi, "$q_{2,n} = q_{2,n+1}$")
    ax.set_xlabel("impact height $q_{2,n}$ (mm)")
    ax.set_ylabel("next impact height $q_{2,n+1}$ (mm)")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    _uniform_legend_markers(ax.legend(loc="upper left", fontsize=8))
    return lines


def time_map(
    columns: Columns, ax: Axes, *, frame_interval: float | None = None, log: bool = False
) -> list[Line2D]:
    """Map of times of flight: t_n (x) against t_n+1 (y), in s.

    t_n is the time of flight before impact n (the ``tof`` column: time since the
    previous impact). The dashed line is the diagonal t_n = t_n+1.

    Args:
        columns: a run's columns (``tof`` in s, and ``t`` in s with ``frame_interval``).
        ax: the axes to draw in.
        frame_interval: if given (s), also draw the map of the camera-filtered impacts,
            whose times of flight are the times between recorded impacts.
        log: logarithmic axes (rapid-succession impacts have times of flight down to
            microseconds).

    Returns:
        The data lines (``tof[:-1]``, ``tof[1:]``): the model's, then the camera's.
    """
    interval = _checked_interval(frame_interval)
    tof = _column(columns, "tof")
    sets = [(tof, f"model: all {tof.size} impacts", MODEL_COLOR)]
    if interval is not None:
        seen = _column(camera_filter(columns, interval), "tof")
        sets.append((seen, _camera_label(interval, seen.size), CAMERA_COLOR))
    lines = [
        _pairs_axes(ax, s[:-1], s[1:], label, color, _marker_size(s[:-1], s[1:]))
        for s, label, color in sets
    ]
    if log:
        positive = [s[s > 0] for s, _, _ in sets]
        finite = np.concatenate(positive) if positive else np.array([])
        lo = float(finite.min()) / 1.5 if finite.size else 1e-4
        hi = float(finite.max()) * 1.5 if finite.size else 1.0
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_aspect("equal", adjustable="box")
    else:
        lo, hi = _square_limits(ax, [s for s, _, _ in sets])
        lo = max(lo, -0.02 * hi)
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
    _diagonal(ax, lo, hi, "$t_n = t_{n+1}$")
    ax.set_xlabel("time of flight $t_n$ (s)")
    ax.set_ylabel("next time of flight $t_{n+1}$ (s)")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    _uniform_legend_markers(ax.legend(loc="upper right", fontsize=8))
    return lines


def phase_coordinates(columns: Columns, scene: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Normalized tangential velocity and height after each impact.

    With E the mechanical energy after the impact (the ``energy`` column, J; kinetic
    energy of translation and spin plus m g q2, potential zero at q2 = 0), m the ball's
    mass (``ball.mass``, kg) and g the gravity (``run.gravity``, default 9.81 m/s^2):

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
    energy = _column(columns, "energy")
    q2 = _column(columns, "q2")
    u4 = _column(columns, "u4")
    m = _mass(scene)
    g = _gravity(scene)
    good = np.isfinite(energy) & (energy > 0)
    safe = np.where(good, energy, np.nan)
    q2max = safe / (m * g)
    u4max = np.sqrt(2.0 * safe / m)
    return u4 / u4max, q2 / q2max


def phase_plot(
    columns: Columns, scene: Mapping[str, Any], ax: Axes, *, frame_interval: float | None = None
) -> list[Line2D]:
    """Phase plot: normalized impact height q2/q2max (y) against normalized tangential
    velocity u4/u4max (x) after each impact (both dimensionless).

    q2max = E/(m g) is the height the ball would reach if all its mechanical energy E
    (the ``energy`` column, J) were potential, and u4max = sqrt(2 E / m) the speed it
    would have if all of it were kinetic; u4 is the centre's velocity along the contact
    tangent just after the impact (m/s). See :func:`phase_coordinates`. A period-one orbit
    is a single point (the paper's parabola at 5.4 Hz: (+-0.0372, 0.376)). The dashed curve
    is the energy bound (u4/u4max)^2 + q2/q2max = 1. The axes span x in [-1, 1] and
    y in [0, 1], widened if some points lie outside.

    Args:
        columns: a run's columns (``q2`` m, ``u4`` m/s, ``energy`` J).
        scene: the run's scene (``ball.mass``, ``run.gravity``).
        ax: the axes to draw in.
        frame_interval: if given (s), highlight the impacts a camera with this frame
            interval would have recorded (larger markers in a second colour, drawn
            underneath the model's).

    Returns:
        The data lines (x = u4/u4max, y = q2/q2max): the model's, then the camera's.
    """
    interval = _checked_interval(frame_interval)
    x, y = phase_coordinates(columns, scene)
    sets = [(x, y, f"model: all {x.size} impacts", MODEL_COLOR)]
    if interval is not None:
        seen = camera_filter(columns, interval)
        sx, sy = phase_coordinates(seen, scene)
        sets.append((sx, sy, _camera_label(interval, sx.size), CAMERA_COLOR))
    # The camera's impacts are a subset of the model's: draw them underneath, larger, so
    # that they show as halos around the model's points.
    lines = [
        _pairs_axes(
            ax, a, b, label, color, _marker_size(x, y, (2.0, 1.0)) * (1.0 if k == 0 else 2.2)
        )
        for k, (a, b, label, color) in enumerate(sets)
    ]
    for k, line in enumerate(lines):
        line.set_zorder(2.5 - k)
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
    xs = np.concatenate([a[np.isfinite(a)] for a, _, _, _ in sets])
    ys = np.concatenate([b[np.isfinite(b)] for _, b, _, _ in sets])
    xlo, xhi = -1.0, 1.0
    ylo, yhi = 0.0, 1.0
    if xs.size:  # widen only for points outside the usual ranges
        if xs.min() < xlo or xs.max() > xhi:
            xlo, xhi = min(xlo, float(xs.min()) - 0.02), max(xhi, float(xs.max()) + 0.02)
        if ys.min() < ylo or ys.max() > yhi:
            ylo, yhi = min(ylo, float(ys.min()) - 0.02), max(yhi, float(ys.max()) + 0.02)
    ax.set_xlim(xlo, xhi)
    ax.set_ylim(ylo, yhi)
    ax.xaxis.set_major_locator(MultipleLocator(0.5))
    ax.yaxis.set_major_locator(MultipleLocator(0.2))
    ax.set_xlabel("normalized tangential velocity $u_4/u_{4,max}$")
    ax.set_ylabel("normalized impact height $q_2/q_{2,max}$")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    _uniform_legend_markers(ax.legend(loc="upper right", fontsize=8))
    return lines


# --- trajectory ------------------------------------------------------------------------


def parse_window(text: str) -> Window:
    """Parse ``"N0:N1"`` (either side may be empty) into a window of impact numbers.

    Raises:
        ValueError: not of that form, or not whole numbers.
    """
    start, sep, stop = text.partition(":")
    if not sep:
        raise ValueError(
            f"window {text!r}: expected N0:N1 (impact numbers, N0 included, N1 excluded)"
        )
    try:
        n0 = int(start) if start.strip() else None
        n1 = int(stop) if stop.strip() else None
    except ValueError:
        raise ValueError(f"window {text!r}: N0 and N1 must be whole impact numbers") from None
    return n0, n1


def default_window(
    columns: Columns, scene: Mapping[str, Any], *, periods: float = 4.0, max_impacts: int = 400
) -> tuple[int, int]:
    """The impacts of the last ``periods`` drive periods of the run (the last second if
    the drive has no frequency), at most ``max_impacts`` and at least two of them.

    Returns:
        ``(n0, n1)``: impact numbers (the ``n`` column), n0 included, n1 excluded.
    """
    t = _column(columns, "t")
    n = _column(columns, "n").astype(int)
    _, frequency, _, _ = _drive(scene)
    span = periods / frequency if frequency > 0 else 1.0
    first = int(np.searchsorted(t, t[-1] - span, side="left"))
    first = max(0, min(first, t.size - 2), t.size - max_impacts)
    return int(n[first]), int(n[-1]) + 1


def _window_rows(columns: Columns, scene: Mapping[str, Any], window: Window | None) -> np.ndarray:
    """Row indices of the impacts n0 <= n < n1."""
    n = _column(columns, "n")
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


def _flight(columns: Columns, row: int, tau: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre position (m) a time tau (s) after impact ``row``: drag-free parabola."""
    q1 = float(columns["q1"][row])
    q2 = float(columns["q2"][row])
    v1 = float(columns["v1"][row])
    v2 = float(columns["v2"][row])
    return q1 + v1 * tau, q2 + v2 * tau - 0.5 * g * tau**2


def _arcs(columns: Columns, rows: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """Flight arcs between consecutive impacts of ``rows`` (m), NaN-separated."""
    tof = _column(columns, "tof")
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    for row, nxt in zip(rows[:-1], rows[1:], strict=True):
        if nxt != row + 1:
            continue
        duration = max(float(tof[nxt]), 0.0)
        count = int(min(200, max(8, duration * 2000)))
        x, y = _flight(columns, int(row), np.linspace(0.0, duration, count), g)
        xs += [x, [np.nan]]
        ys += [y, [np.nan]]
    if not xs:
        return np.array([]), np.array([])
    return np.concatenate(xs), np.concatenate(ys)


def _view(
    scene: Mapping[str, Any], xs: np.ndarray, ys: np.ndarray
) -> tuple[tuple[float, float], tuple[float, float], bool]:
    """Limits (m) around the ball's path, boundary included, and whether the lid shows."""
    amplitude, _, _, direction = _drive(scene)
    r = _radius(scene)
    f = _boundary_function(scene)
    x = xs[np.isfinite(xs)]
    y = ys[np.isfinite(ys)]
    x_lo, x_hi = float(x.min()), float(x.max())
    y_hi = float(y.max()) + r
    margin = max(0.15 * (x_hi - x_lo), 3 * r)
    x_lo, x_hi = x_lo - margin, x_hi + margin
    grid = np.linspace(x_lo, x_hi, 401)
    floor = np.nanmin(f(grid)) if np.any(np.isfinite(f(grid))) else float(y.min()) - r
    y_lo = min(float(floor), float(y.min()) - r)
    if direction == "vertical":
        y_lo -= amplitude
    ceiling = _section(scene, "boundary").get("ceiling")
    show_lid = ceiling is not None and y_hi > y_lo + 0.6 * (float(ceiling) - y_lo)
    if show_lid:
        y_hi = max(y_hi, float(ceiling))
    # Avoid a sliver: with equal aspect, neither side may be much shorter than the other.
    width, height = x_hi - x_lo, y_hi - y_lo
    if width < 0.6 * height:
        centre = 0.5 * (x_lo + x_hi)
        x_lo, x_hi = centre - 0.3 * height, centre + 0.3 * height
    elif height < 0.35 * width:
        y_hi = y_lo + 0.35 * width
    pad = 0.04 * max(x_hi - x_lo, y_hi - y_lo)
    return (x_lo, x_hi), (y_lo - pad, y_hi + pad), show_lid


def _boundary_positions(
    scene: Mapping[str, Any], x_lim: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """A grid of the boundary's own x (m) wide enough for any drive offset, and f there."""
    amplitude, _, _, _ = _drive(scene)
    grid = np.linspace(x_lim[0] - amplitude, x_lim[1] + amplitude, 801)
    return grid, _boundary_function(scene)(grid)


def trajectory(
    columns: Columns,
    scene: Mapping[str, Any],
    ax: Axes,
    window: Window | None = None,
    *,
    frame_interval: float | None = None,
) -> dict[str, Any]:
    """The ball's path over a window of impacts, in the lab frame, in mm (equal aspect).

    Drawn: the boundary y = f(x) at its mean position (solid), and at its extreme drive
    offsets +-A (dotted) since it moves; the lid at ``boundary.ceiling`` if the path gets
    near it; the centre of the ball at each impact (coloured by the impact's regime); and
    the flight arcs between consecutive impacts reconstructed from the post-impact
    velocities as drag-free parabolas, q1 + v1 t and q2 + v2 t - g t^2/2 for t from 0 to
    the next impact's time of flight (with air drag in the model, an arc can end a little
    off the next impact point). Impact points are ball centres, so they lie one radius
    inside the boundary.

    Args:
        columns: a run's columns.
        scene: the run's scene.
        ax: the axes to draw in.
        window: ``(n0, n1)``: impact numbers (the ``n`` column) n0 <= n < n1; either may
            be None for an open end. Default: :func:`default_window`.
        frame_interval: if given (s), ring the impacts the camera would have recorded.

    Returns:
        A dict with the row indices drawn (``rows``) and the artists (``impacts``,
        ``arcs``, ``boundary``).
    """
    interval = _checked_interval(frame_interval)
    rows = _window_rows(columns, scene, window)
    g = _gravity(scene)
    arc_x, arc_y = _arcs(columns, rows, g)
    q1 = _column(columns, "q1")[rows]
    q2 = _column(columns, "q2")[rows]
    path_x = np.concatenate([q1, arc_x])
    path_y = np.concatenate([q2, arc_y])
    x_lim, y_lim, show_lid = _view(scene, path_x, path_y)
    amplitude, _, _, direction = _drive(scene)

    grid, height = _boundary_positions(scene, x_lim)
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
                label=f"boundary at $\\pm A$ = $\\pm${_fmt(amplitude * MM)} mm"
                if sign > 0
                else None,
            )
    ceiling = _section(scene, "boundary").get("ceiling")
    if ceiling is not None and show_lid:
        ax.axhline(float(ceiling) * MM, color="0.3", linewidth=1.2, label="lid")
    (arcs,) = ax.plot(
        arc_x * MM,
        arc_y * MM,
        color=MODEL_COLOR,
        linewidth=0.8,
        label="flight (drag-free parabola)",
    )
    regime = np.asarray(columns["regime"])[rows] if "regime" in columns else None
    impacts = []
    if regime is None:
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
                )[0]
            )
    if interval is not None:
        seen = camera_filter(columns, interval)
        n = _column(columns, "n")[rows]
        mask = np.isin(n, _column(seen, "n"))
        ax.plot(
            q1[mask] * MM,
            q2[mask] * MM,
            "o",
            markersize=7,
            markerfacecolor="none",
            markeredgecolor=CAMERA_COLOR,
            markeredgewidth=1.0,
            label=f"seen by camera (frame {interval * 1e3:.3g} ms)",
        )
    ax.set_xlim(x_lim[0] * MM, x_lim[1] * MM)
    ax.set_ylim(y_lim[0] * MM, y_lim[1] * MM)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("$q_1$ (mm)")
    ax.set_ylabel("$q_2$ (mm)")
    t = _column(columns, "t")
    n_all = _column(columns, "n")
    ax.set_title(
        f"impacts {int(n_all[rows[0]])} to {int(n_all[rows[-1]])}, "
        f"t = {t[rows[0]]:.3f} to {t[rows[-1]]:.3f} s",
        fontsize=9,
    )
    ax.grid(True, linewidth=0.3, alpha=0.5)
    ax.legend(loc="upper right", fontsize=7, framealpha=0.85)
    return {"rows": rows, "impacts": impacts, "arcs": arcs, "boundary": boundary}


def animate(
    columns: Columns,
    scene: Mapping[str, Any],
    path: str | os.PathLike[str],
    window: Window | None = None,
    fps: int = 30,
    *,
    max_frames: int = 150,
    dpi: int = 80,
) -> Path:
    """Write an animated GIF of the ball inside the moving boundary.

    The still parts are drawn once; each frame redraws only the moving artists, and the
    frames are written with Pillow in one shared 64-colour palette.

    The ball is drawn as a circle of its true radius. Frames are spaced uniformly in time
    from the first to the last impact of the window; between impacts the centre follows
    the drag-free parabola from the previous impact's position and velocity, and the
    boundary is drawn shifted by the drive D(t) (see :func:`drive_offset`). The faint line
    is the whole reconstructed path in the window. The GIF plays at ``fps`` frames per
    second, so it is in slow or fast motion; the speed relative to real time is written
    in the frame.

    Args:
        columns: a run's columns.
        scene: the run's scene.
        path: the GIF to write.
        window: impact numbers ``(n0, n1)``, n0 <= n < n1 (default: :func:`default_window`).
        fps: playback frames per second.
        max_frames: number of frames (at most; fewer if the window has one impact).
        dpi: pixels per inch of the frame, 5 inches wide (400 px at 80 dpi), as high
            as the view needs.

    Returns:
        The path written.
    """
    rows = _window_rows(columns, scene, window)
    g = _gravity(scene)
    r = _radius(scene)
    t = _column(columns, "t")
    t0, t1 = float(t[rows[0]]), float(t[rows[-1]])
    count = max_frames if t1 > t0 else 1
    frame_times = np.linspace(t0, t1, count)
    arc_x, arc_y = _arcs(columns, rows, g)
    q1 = _column(columns, "q1")[rows]
    q2 = _column(columns, "q2")[rows]
    x_lim, y_lim, show_lid = _view(scene, np.concatenate([q1, arc_x]), np.concatenate([q2, arc_y]))
    grid, height = _boundary_positions(scene, x_lim)
    _, _, _, direction = _drive(scene)

    aspect = (y_lim[1] - y_lim[0]) / (x_lim[1] - x_lim[0])
    fig = Figure(
        figsize=(5.0, float(np.clip(4.2 * aspect + 0.9, 2.5, 6.5))), dpi=dpi, layout="constrained"
    )
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(arc_x * MM, arc_y * MM, color="0.8", linewidth=0.7, zorder=0)
    (boundary,) = ax.plot(grid * MM, height * MM, color="black", linewidth=1.5)
    ceiling = _section(scene, "boundary").get("ceiling")
    lid = None
    if ceiling is not None and show_lid:
        (lid,) = ax.plot(
            np.asarray(x_lim) * MM, [float(ceiling) * MM] * 2, color="0.3", linewidth=1.2
        )
    ball = Circle(
        (float(q1[0]) * MM, float(q2[0]) * MM),
        r * MM,
        facecolor="tab:blue",
        edgecolor="navy",
        linewidth=0.6,
        zorder=3,
    )
    ax.add_patch(ball)
    ax.set_xlim(x_lim[0] * MM, x_lim[1] * MM)
    ax.set_ylim(y_lim[0] * MM, y_lim[1] * MM)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("$q_1$ (mm)")
    ax.set_ylabel("$q_2$ (mm)")
    duration = (count / fps) if count > 1 else 1.0
    speed = (t1 - t0) / duration if t1 > t0 else 1.0
    fig.suptitle(f"{scene.get('name', 'run')}: {speed:.2g}x real time", fontsize=10)
    clock = ax.text(
        0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9, family="monospace"
    )

    moving = [boundary, ball, clock] + (
        [lid] if lid is not None and direction == "vertical" else []
    )
    for artist in moving:
        artist.set_animated(True)
    canvas = fig.canvas
    assert isinstance(canvas, FigureCanvasAgg)
    canvas.draw()
    fig.set_layout_engine("none")  # freeze the layout: the frames only move artists
    background = canvas.copy_from_bbox(fig.bbox)
    frames: list[Image.Image] = []
    for tf in frame_times:
        i = int(np.searchsorted(t[rows], tf, side="right")) - 1
        row = int(rows[max(i, 0)])
        x, y = _flight(columns, row, np.asarray(tf - t[row]), g)
        ball.center = (float(x) * MM, float(y) * MM)
        offset = float(drive_offset(scene, tf))
        if direction == "vertical":
            boundary.set_data(grid * MM, (height + offset) * MM)
            if lid is not None:
                lid.set_ydata([(float(ceiling) + offset) * MM] * 2)
        else:
            boundary.set_data((grid + offset) * MM, height * MM)
        clock.set_text(f"t = {tf:8.3f} s\nimpact {int(columns['n'][row])}")
        canvas.restore_region(background)
        for artist in moving:
            ax.draw_artist(artist)
        frames.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
    _save_gif(frames, Path(path), fps)
    fig.clear()
    return Path(path)


def _save_gif(frames: Sequence[Image.Image], path: Path, fps: int) -> None:
    """Save RGB frames as a looping GIF sharing one palette (small and fast to write;
    Pillow stores only the changed part of each frame)."""
    palette = frames[0].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    indexed = [palette] + [
        f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames[1:]
    ]
    indexed[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=indexed[1:],
        duration=max(1, round(1000 / fps)),
        loop=0,
    )


# --- whole runs ------------------------------------------------------------------------


def _legend_outside(fig: Figure, ax: Axes) -> None:
    """Move the axes' legend below the axes, so that it hides no data."""
    legend = ax.get_legend()
    if legend is None:
        return
    handles, labels = ax.get_legend_handles_labels()
    legend.remove()
    _uniform_legend_markers(
        fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    )


def _single(
    draw: Callable[[Axes], object], title: str, path: Path, *, fit_height: bool = False
) -> Path:
    """One-panel figure, 600 px wide, with the title on top and the legend below.

    With ``fit_height``, the height follows the shape of the (equal-aspect) view.
    """
    fig = _new_figure()
    ax = fig.add_subplot()
    draw(ax)
    if fit_height:
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        aspect = abs(y1 - y0) / max(abs(x1 - x0), 1e-300)
        fig.set_size_inches(SINGLE_SIZE[0], float(np.clip(4.6 * aspect + 2.0, 3.6, 8.0)))
    fig.suptitle(title, fontsize=9)
    _legend_outside(fig, ax)
    return _save(fig, path)


def plot_run(
    run_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    frame_interval: float | None = None,
    window: Window | None = None,
    gif: bool = True,
) -> list[Path]:
    """Draw every figure of a run.

    Reads ``run_dir/collisions.csv`` and ``run_dir/scene.toml`` and writes into
    ``out_dir`` (default ``run_dir``, created if missing): ``return_map.png``,
    ``time_map.png``, ``phase.png``, ``trajectory.png`` and, unless ``gif`` is False,
    ``animation.gif``. Each PNG is 600 px wide, titled with the scene's name and key
    parameters.

    With ``frame_interval`` (s), the maps also show, in a second colour, the data a camera
    with that frame interval would have recorded (the experiment missed impacts in rapid
    succession; see :func:`billiard.camera.camera_filter`), with the frame interval and
    impact counts in the legend, and the trajectory rings the impacts the camera would
    have seen. The files keep the same names.

    Args:
        run_dir: a directory written by ``billiard run``.
        out_dir: where to write the figures.
        frame_interval: the camera's frame interval (s), or None for the model data only.
        window: impact numbers ``(n0, n1)``, n0 <= n < n1, for the trajectory and the
            animation (default: :func:`default_window`, the last few drive periods).
        gif: write the animation (the slowest figure, a few seconds).

    Returns:
        The paths written, in the order of :data:`FIGURE_NAMES`.

    Raises:
        RunDataError: (a ValueError) a missing, empty or malformed file, a window with no
            impacts, or a bad frame interval; the message is one line.
    """
    interval = _checked_interval(frame_interval)
    columns, scene = load_run(run_dir)
    out = Path(out_dir) if out_dir is not None else Path(run_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = _window_rows(columns, scene, window)  # check the window before drawing
    chosen = (int(columns["n"][rows[0]]), int(columns["n"][rows[-1]]) + 1)
    title = scene_title(scene, int(columns["t"].size))
    written = [
        _single(
            lambda ax: return_map(columns, ax, frame_interval=interval),
            title,
            out / "return_map.png",
        ),
        _single(
            lambda ax: time_map(columns, ax, frame_interval=interval), title, out / "time_map.png"
        ),
        _single(
            lambda ax: phase_plot(columns, scene, ax, frame_interval=interval),
            title,
            out / "phase.png",
        ),
        _single(
            lambda ax: trajectory(columns, scene, ax, chosen, frame_interval=interval),
            title,
            out / "trajectory.png",
            fit_height=True,
        ),
    ]
    if gif:
        written.append(animate(columns, scene, out / "animation.gif", window=chosen))
    return written


def _paper_grid(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    panels: Sequence[Callable[[Columns, Mapping[str, Any], Axes], object]],
    title: str,
    frame_interval: float | None,
    guide: str,
) -> Path:
    """Panels in rows, one column per run; one shared legend at the bottom."""
    if not run_dirs:
        raise RunDataError("no run directories given")
    runs = [load_run(d) for d in run_dirs]
    cols = len(runs)
    fig = Figure(figsize=(3.3 * cols + 0.4, 3.3 * len(panels) + 1.0), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), cols, squeeze=False)
    for j, (columns, scene) in enumerate(runs):
        for i, draw in enumerate(panels):
            ax = axes[i, j]
            draw(columns, scene, ax)
            legend = ax.get_legend()
            if legend is not None:
                legend.remove()
            ax.xaxis.label.set_fontsize(9)
            ax.yaxis.label.set_fontsize(9)
            ax.tick_params(labelsize=8)
        count = f"{columns['t'].size} impacts"
        if frame_interval is not None:
            count += f", camera {camera_filter(columns, frame_interval)['t'].size}"
        axes[0, j].set_title(f"{_short_label(scene)}\n{count}", fontsize=9)
    handles = [
        Line2D(
            [],
            [],
            linestyle="none",
            marker="o",
            markersize=4,
            color=MODEL_COLOR,
            label="model: every impact",
        )
    ]
    if frame_interval is not None:
        handles.append(
            Line2D(
                [],
                [],
                linestyle="none",
                marker="o",
                markersize=4,
                color=CAMERA_COLOR,
                label=f"camera, frame {frame_interval * 1e3:.3g} ms",
            )
        )
    handles.append(Line2D([], [], color="0.35", linewidth=0.8, linestyle="--", label=guide))
    fig.legend(
        handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8, frameon=False
    )
    fig.suptitle(title, fontsize=10)
    return _save(fig, Path(path))


def paper_figure(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    *,
    frame_interval: float | None = None,
) -> Path:
    """One figure in the layout of the paper's Fig. 2: one column per run, the return map
    of impact heights (q2,n vs q2,n+1, mm) on the top row and the map of times of flight
    (t_n vs t_n+1, s) on the bottom row; each column titled with its curve and drive
    frequency. With ``frame_interval`` (s), the camera-filtered data are drawn too.

    Returns:
        The path written (PNG, or any format matplotlib infers from the suffix).
    """
    interval = _checked_interval(frame_interval)
    return _paper_grid(
        run_dirs,
        path,
        [
            lambda c, s, ax: return_map(c, ax, frame_interval=interval),
            lambda c, s, ax: time_map(c, ax, frame_interval=interval),
        ],
        "Impact heights (top) and times of flight (bottom)",
        interval,
        "diagonal $q_{2,n} = q_{2,n+1}$, $t_n = t_{n+1}$",
    )


def paper_phase_figure(
    run_dirs: Sequence[str | os.PathLike[str]],
    path: str | os.PathLike[str],
    *,
    frame_interval: float | None = None,
) -> Path:
    """One figure in the layout of the paper's Fig. 3: the phase plots (q2/q2max vs
    u4/u4max, see :func:`phase_plot`) of the runs side by side.

    Returns:
        The path written.
    """
    interval = _checked_interval(frame_interval)
    return _paper_grid(
        run_dirs,
        path,
        [lambda c, s, ax: phase_plot(c, s, ax, frame_interval=interval)],
        "Normalized impact height vs normalized tangential velocity after each impact",
        interval,
        "all energy in $q_2$ and $u_4$",
    )


# --- command line ----------------------------------------------------------------------


def _interval_argument(text: str) -> float:
    """A frame interval in seconds: a number or a fraction such as 1/30."""
    try:
        value = float(Fraction(text.strip())) if "/" in text else float(text)
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a number of seconds (e.g. 0.0333 or 1/30)"
        ) from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: the frame interval must be > 0 s")
    return value


def _window_argument(text: str) -> Window:
    try:
        return parse_window(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_plot_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the arguments of ``billiard plot`` to ``parser`` (a subparser)."""
    parser.add_argument("run_dir", help="a run directory (with collisions.csv and scene.toml)")
    parser.add_argument("--out", help="where to write the figures (default: RUN_DIR)")
    parser.add_argument(
        "--frame-interval",
        type=_interval_argument,
        metavar="S",
        help="also show what a camera with this frame interval (s, e.g. 1/30) would have recorded",
    )
    parser.add_argument(
        "--window",
        type=_window_argument,
        metavar="N0:N1",
        help="impacts N0 <= n < N1 for the trajectory and the animation "
        "(default: the last four drive periods)",
    )
    parser.add_argument(
        "--no-gif", dest="gif", action="store_false", help="do not write animation.gif"
    )


def run_plot_command(args: argparse.Namespace) -> int:
    """Run ``billiard plot`` with parsed arguments; print the files written.

    Returns:
        0 on success, 2 after printing a one-line error for bad input.
    """
    try:
        written = plot_run(
            args.run_dir,
            args.out,
            frame_interval=args.frame_interval,
            window=args.window,
            gif=args.gif,
        )
    except RunDataError as exc:
        print(f"billiard: error: {exc}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path}")
    return 0
