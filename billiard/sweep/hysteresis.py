"""Up/down (hysteresis) sweeps: one scene key goes up through its values and back down,
every trajectory continuing from its own final state at the previous value.

At each value the trajectories run ``transient`` impacts, then ``impacts`` measured
ones, measured as a sweep point is (the ensemble kernel's statistics: attractor class,
period, mean and spread of the impact height). The next value's set-up
(:func:`billiard.engine.ensemble.prepare`, once per value: the way down reuses the way
up's) then takes each trajectory's ball as it is after its last impact: time, drive
angle, position, velocity, spin, rotation angle and the compensated clock.

The drive angle is carried, not recomputed. The kernel advances the drive angle theta
from impact to impact by omega tau (tau the flight's duration), so the container's
position A sin(theta) is continuous through every flight; recomputing theta as
omega_new t + phase at the switch would move the container by up to twice its
amplitude in no time (a kick no slow change of the frequency makes) and would make the
result depend on the absolute time at which the switch happens. After a switch the
drive angle is theta(t) = theta_switch + omega_new (t - t_switch): the period test's
drive phase (which it computes from the time) is set per trajectory to theta_switch -
omega_new t_switch, so that it reads the drive angle the ball really sees.

A trajectory that fails, or whose ball the next value's container would overlap (a
varied geometry key), is not continued: it is ``failed`` (or ``invalid``) from there on.
"""

from __future__ import annotations

import csv
import math
import textwrap
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from billiard.kernels import layout as _L

__all__ = [
    "DIRECTIONS",
    "REFUSED",
    "HysteresisResult",
    "check_size",
    "continue_states",
    "drive_phases",
    "estimate_size",
    "hysteresis_figure",
    "run_hysteresis",
    "start_grid",
    "write_csv",
]

#: the two branches, in the order they are run
DIRECTIONS = ("up", "down")
#: keys an up/down sweep refuses, and why: each value continues the last one's state
REFUSED = {
    "drive.phase": "the drive angle is carried from value to value, so the phase has no effect",
    "run.collisions": "the impacts per value are --impacts and --transient",
    "run.duration": "each value runs --transient + --impacts impacts, not a duration",
}
#: the ball as :func:`billiard.kernels.ensemble.start` takes it (t, theta, q1, q2, u1,
#: u2, u3), and the slots a continuation carries besides: what is kept between values
_BALL = tuple(f"engine.{name}" for name in ("t", "theta", "q1", "q2", "u1", "u2", "u3"))
_CARRIED = ("engine.q3", "engine.clock", "engine.clock_error", "flight.step")
_STATE = _BALL + _CARRIED
#: trajectories per call of the kernel: bounds the memory of the state vectors (about
#: 11 kB each) and rings (about 14 kB each); between values only _STATE is kept
CHUNK = 4096

# Memory of an up/down sweep, for :func:`estimate_size` (measured with tracemalloc on
# hyperbola-4.5hz, 5 impacts per value: 300 starts x 3 values peak at 15.2 MB, 4,096 x 2
# at 203 MB, 8,192 x 2 at 206 MB, 16,384 x 2 at 210 MB, 4 x 64 at 4.9 MB).
#: bytes per trajectory of a chunk while the kernel runs (state vector, ring, statistics):
#: two copies of the state vector (``billiard.kernels.layout.SIZE`` floats) and 40 kB for
#: the rest; with 1,367-slot state vectors (walls as chains) 300 starts x 3 values peak at
#: 15.8 MB
TRAJECTORY_BYTES = 40_000 + 2 * 8 * _L.SIZE
#: bytes per value: its scene and set-up, kept for the way down
VALUE_BYTES = 75_000
#: bytes per start kept from value to value (carried state, start, flags, its grid)
START_BYTES = 300
#: bytes per (direction, value, start): the measured columns
CELL_BYTES = 64
#: bytes per row of hysteresis.csv (measured: 139 to 152)
CSV_ROW_BYTES = 150


@dataclass
class HysteresisResult:
    """An up/down sweep's measurements, indexed [direction, value, start].

    Attributes:
        scene: the base scene (the swept key at its values, every other key as given).
        key: the swept scene key; ``values`` its values in increasing sweep order.
        q1_start, q2_start: the starts (m), one per trajectory.
        columns: name -> array (2, values, starts): ``attractor`` (class names),
            ``period`` (impacts), ``height_mean``, ``height_std`` (m), ``tof_mean`` (s),
            ``run_status``. ``down`` rows are stored in value order (index i is
            ``values[i]``), though they are run from the top value down.
        impacts, transient: impacts measured and simulated first at each value.
        seconds: wall-clock time (s).
    """

    scene: Any
    key: str
    values: np.ndarray
    q1_start: np.ndarray
    q2_start: np.ndarray
    columns: dict[str, np.ndarray]
    impacts: int
    transient: int
    seconds: float = 0.0


def continue_states(setup: Any, ctxs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """State vectors of ``setup``'s parameter set holding the balls of ``ctxs`` (one row
    per trajectory, after its last impact): time, drive angle, position, velocity and
    spin as they are (not recomputed from the new drive), plus the rotation angle, the
    compensated clock and the flight's step proposal; the event count starts afresh.

    Returns:
        (ctxs, ok) as :func:`billiard.engine.ensemble.start` returns them (ok False: the
        ball overlaps a wall or the lid of the new set-up, or is above its escape height).
    """
    from billiard.kernels.names import columns

    return _resume(setup, columns(ctxs, _STATE))


def _resume(setup: Any, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`continue_states` from the carried slots alone (``_STATE``, one row per
    trajectory): what an up/down sweep keeps between two values."""
    from billiard.engine.ensemble import _OVERLAP
    from billiard.kernels.ensemble import start_batch
    from billiard.kernels.names import set_columns

    n = state.shape[0]
    balls = np.ascontiguousarray(state[:, : len(_BALL)])
    theta = balls[:, 1]
    d = setup.drive.amplitude * np.sin(theta)
    q1, q2 = balls[:, 2], balls[:, 3]
    px, py = (q1 - d, q2) if setup.drive.horizontal else (q1, q2 - d)
    px = np.ascontiguousarray(px, dtype=np.float64)
    py = np.ascontiguousarray(py, dtype=np.float64)
    out = np.empty((n, setup.template.size))
    gaps = np.empty(n)
    params = np.tile(setup.params, (n, 1))  # writable, C-contiguous
    if n:
        start_batch(out, params, setup.walls, setup.template, balls, px, py, setup.offsets, gaps)
    set_columns(out, _CARRIED, state[:, len(_BALL) :])
    set_columns(out, ("engine.until",), math.inf)
    with np.errstate(invalid="ignore"):
        ok = (py <= setup.lid_level + _OVERLAP) & (py < setup.escape_level)
        ok &= gaps >= -_OVERLAP  # NaN (no gap computed: a row not carried) is refused
    return out, ok


def drive_phases(ctxs: np.ndarray, frequency: float) -> np.ndarray:
    """Per trajectory the drive phase (rad, in [0, 2 pi)) that makes omega t + phase the
    drive angle the ball sees from its state on (frequency in Hz): theta - omega t."""
    from billiard.kernels.names import column

    omega = 2.0 * math.pi * frequency
    return np.mod(column(ctxs, "engine.theta") - omega * column(ctxs, "engine.t"), 2.0 * math.pi)


def start_grid(scene: Any, setup: Any, count: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` starting positions (m) of the ball (which starts with the scene's
    initial velocity and spin: at rest in the built-in scenes).

    One start: the scene's own (initial.q1, initial.q2), or the ball at rest on the
    bottom where the scene gives none. More: a square grid over the container, q1
    across the wall's width at the top of the region and q2 from 2 radii above the
    resting height to halfway between it and the lid (0.1 m above it without a lid);
    of the grid's starts the set-up accepts, ``count`` are taken evenly spread in grid
    order (row by row, from the bottom), the grid refined until there are enough.
    """
    from billiard.kernels.names import read
    from billiard.sweep.container import wall_outline

    if count < 1:
        raise ValueError(f"starts must be >= 1, got {count}")
    initial = scene.initial
    if count == 1:
        q1 = read(setup.template, "engine.q1") if initial.q1 is None else initial.q1
        q2 = read(setup.template, "engine.q2") if initial.q2 is None else initial.q2
        return np.array([float(q1)]), np.array([float(q2)])
    rest = setup.rest_height
    radius = scene.ball.radius
    lid = setup.lid_level
    top = rest + (0.5 * (lid - rest) if math.isfinite(lid) else 0.1)
    bottom = rest + 2.0 * radius
    x, y = wall_outline(scene, -10.0, 10.0, 20001)
    inside = np.isfinite(y) & (y <= top)
    if not inside.any():
        raise ValueError("no part of the container lies below the starts' top height")
    lo, hi = float(x[inside].min()), float(x[inside].max())
    side = max(2, math.ceil(math.sqrt(2 * count)))
    from billiard.engine.ensemble import start_verdicts

    for _ in range(8):
        q1, q2 = np.meshgrid(np.linspace(lo, hi, side), np.linspace(bottom, top, side))
        q1, q2 = q1.ravel(), q2.ravel()
        # checked in blocks: a state vector per grid point (11 kB) is not kept
        valid = np.nonzero(start_verdicts(setup, q1, q2, t=initial.t) == 0)[0]
        if valid.size >= count:
            pick = valid[np.rint(np.linspace(0, valid.size - 1, count)).astype(np.int64)]
            return q1[pick], q2[pick]
        side *= 2
    raise ValueError(f"found no {count} valid starts in the container")


def estimate_size(values: int, starts: int) -> tuple[float, float]:
    """Bytes of memory an up/down sweep of ``values`` values and ``starts`` trajectories
    takes at most, about, and bytes of the ``hysteresis.csv`` it writes (one row per
    direction, value and start). Floats: they may exceed every integer type."""
    values, starts = float(values), float(starts)
    cells = 2.0 * values * starts
    memory = (
        TRAJECTORY_BYTES * min(starts, CHUNK)
        + VALUE_BYTES * values
        + START_BYTES * starts
        + CELL_BYTES * cells
    )
    return memory, CSV_ROW_BYTES * (cells + 1)


def check_size(values: int, starts: int, allow: str = "allow_large=True") -> None:
    """Refuse, before anything is allocated, an up/down sweep whose memory or
    ``hysteresis.csv`` (:func:`estimate_size`) is over the limit of
    :data:`billiard.run.output_size.MAX_BYTES`, unless confirmed.

    Raises:
        OutputSizeError: one line naming the estimate, the values and the starts, and
            ``allow`` as the way to go ahead.
    """
    from billiard.run.output_size import check_size as check

    memory, table = estimate_size(values, starts)
    plural = "" if starts == 1 else "s"
    check(
        {"memory": memory, "hysteresis.csv": table},
        what=f"an up/down sweep of {values:,} values x {starts:,} start{plural}",
        fewer="give fewer values (--vary ...:N) or starts (--starts)",
        allow=allow,
    )


def run_hysteresis(
    scene: Any,
    key: str,
    values: Sequence[float],
    *,
    starts: int = 1,
    impacts: int = 300,
    transient: int = 300,
    tolerance: float = 1e-5,
    max_period: int = 64,
    rest_band: float = 0.01,
    threads: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    allow_large: bool = False,
) -> HysteresisResult:
    """Sweep ``key`` (a numeric scene key, not ``initial.*``) of ``scene`` (a scene or
    a built-in name) up through ``values`` (increasing order) and back down, ``starts``
    trajectories continued from value to value (see the module's text).
    ``progress(direction, step, steps)`` is called before each value. ``tolerance``
    (m), ``max_period`` (impacts) and ``rest_band`` (m) are the sweep's period test and
    resting band. ``allow_large``: go ahead when the sweep's memory or CSV file would be
    over 1 GB (:func:`check_size`).

    Raises:
        ValueError: fewer than 2 values, a value that is not a number, a key of the
            ball's start or one of :data:`REFUSED`, impacts < 1 or transient < 0, or a
            scene the ensemble kernel does not take (method rk4), one under contact
            phases (the state carried between values is the ball's in flight), or
            that cannot be simulated.
        OutputSizeError: (a ``SceneError``) the sweep would take more than 1 GB of
            memory or of CSV file and ``allow_large`` is False; checked first.
    """
    from billiard.engine import ensemble as EN
    from billiard.kernels import ensemble as E
    from billiard.kernels.names import columns as read_columns
    from billiard.scene.scene import with_values
    from billiard.sweep.attractor import PERIOD_WINDOW
    from billiard.sweep.ensemble import as_scene, measured_columns

    if starts < 1:
        raise ValueError(f"starts must be >= 1, got {starts}")
    if not allow_large:  # first: nothing of the values or starts is made before
        check_size(len(values), starts)
    scene = as_scene(scene)
    began = time.perf_counter()
    if key.startswith("initial."):
        raise ValueError(f"{key}: a key of the ball's start cannot be swept up and down")
    if key in REFUSED:
        raise ValueError(f"{key} cannot be swept up and down: {REFUSED[key]}")
    if len(values) < 2:
        raise ValueError(f"{key}: an up/down sweep needs at least 2 values, got {len(values)}")
    for value in values:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{key}: {value!r} is not a number")
        if not math.isfinite(value):
            raise ValueError(f"{key}: {value!r} is not a finite number")
    if impacts < 1 or transient < 0:
        raise ValueError("impacts must be >= 1 and transient >= 0")
    why = EN.supports(scene)
    if getattr(scene.contact, "model", "impacts") == "phases":
        # the state carried from one value to the next is the ball's in flight
        why = "contact.model = 'phases' (an up/down sweep carries the flight state only)"
    if why is not None:
        raise ValueError(f"the ensemble kernel does not take this scene: {why}")
    values = np.sort(np.asarray(values, dtype=np.float64))
    scenes: dict[int, Any] = {}
    setups: dict[int, Any] = {}

    def setup_of(i: int) -> Any:
        if i not in setups:  # once per value: the way down reuses the way up's
            scenes[i] = with_values(scene, {key: float(values[i])})
            setups[i] = EN.prepare(scenes[i])
        return setups[i]

    first = setup_of(0)
    q1, q2 = start_grid(scene, first, starts)
    ini = scene.initial
    n, count = q1.size, values.size
    alive = np.ones(n, dtype=bool)  # still continued
    invalid = np.zeros(n, dtype=bool)  # refused by a set-up (the first, or a later one)
    state = np.full((n, len(_STATE)), np.nan)
    shape = (len(DIRECTIONS), count, n)
    columns: dict[str, np.ndarray] = {
        "attractor": np.full(shape, "invalid", dtype=object),
        "period": np.zeros(shape, dtype=np.int64),
        "height_mean": np.full(shape, np.nan),
        "height_std": np.full(shape, np.nan),
        "tof_mean": np.full(shape, np.nan),
        "run_status": np.full(shape, "", dtype=object),
    }
    window = PERIOD_WINDOW
    order = [(0, i) for i in range(count)] + [(1, i) for i in reversed(range(count))]
    for step, (direction, i) in enumerate(order):
        if progress is not None:
            progress(DIRECTIONS[direction], step, len(order))
        setup = setup_of(i)
        base = EN.constants(scenes[i], tolerance, max_period, window)
        for lo in range(0, n, CHUNK):
            part = slice(lo, min(n, lo + CHUNK))
            if step == 0:
                ctxs, ok = EN.start(first, q1[part], q2[part], ini.v1, ini.v2, ini.omega, t=ini.t)
            else:
                ctxs, ok = _resume(setup, state[part])
            invalid[part] |= alive[part] & ~ok
            alive[part] &= ok
            consts = np.tile(base, (ctxs.shape[0], 1))
            consts[:, E.C_PHASE] = drive_phases(ctxs, scenes[i].drive.frequency)
            stats = np.zeros((ctxs.shape[0], E.NSTAT))
            stats[:, E.ST_STATUS] = E.RUN_FAILED
            run = np.nonzero(alive[part])[0]
            if run.size:
                sub = np.ascontiguousarray(ctxs[run])
                s, _ = EN.advance(
                    sub, setup.params, setup.walls, consts[run], transient=transient,
                    impacts=impacts, width=window, threads=threads,
                )  # fmt: skip
                stats[run], ctxs[run] = s, sub
            valid = ~invalid[part]
            measured = measured_columns(stats, valid, setup.rest_height, rest_band, scenes[i])
            for name in columns:
                columns[name][direction, i, part] = measured[name]
            # a run that stopped is not continued
            alive[part] &= stats[:, E.ST_STATUS] == E.RUN_COMPLETE
            state[part] = read_columns(ctxs, _STATE)
    return HysteresisResult(
        scene=scene,
        key=key,
        values=values,
        q1_start=q1,
        q2_start=q2,
        columns=columns,
        impacts=impacts,
        transient=transient,
        seconds=time.perf_counter() - began,
    )


#: the CSV's columns, with their units
CSV_COLUMNS = (
    "direction",
    "step",
    "value",
    "start",
    "q1_start_m",
    "q2_start_m",
    "attractor",
    "period",
    "height_mean_m",
    "height_std_m",
    "tof_mean_s",
    "run_status",
)


def write_csv(result: HysteresisResult, path: Path) -> Path:
    """One row per value, direction and start, in the order they were run (``step``
    counts the values run so far: up 0 .. V-1, down V .. 2V-1); ``value`` is in the
    swept key's unit; floats written with ``repr`` (they read back exactly)."""
    count = result.values.size
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(CSV_COLUMNS)
        order = [(0, i) for i in range(count)] + [(1, i) for i in reversed(range(count))]
        for step, (direction, i) in enumerate(order):
            c = {name: column[direction, i] for name, column in result.columns.items()}
            for j in range(result.q1_start.size):
                writer.writerow(
                    (
                        DIRECTIONS[direction],
                        step,
                        repr(float(result.values[i])),
                        j,
                        repr(float(result.q1_start[j])),
                        repr(float(result.q2_start[j])),
                        c["attractor"][j],
                        int(c["period"][j]),
                        repr(float(c["height_mean"][j])),
                        repr(float(c["height_std"][j])),
                        repr(float(c["tof_mean"][j])),
                        c["run_status"][j],
                    )
                )
    return path


def hysteresis_figure(result: HysteresisResult, path: Path, title: str | None = None) -> Path:
    """Mean impact height (m) against the swept value, the up branch and the down branch
    in two colours and markers; one marker per start and value, small and translucent
    when there are many starts, joined by lines when there is one."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from billiard.sweep.units import axis_label

    n = result.q1_start.size
    fig, ax = plt.subplots(figsize=(8, 5))
    size = 16.0 if n <= 10 else max(1.0, 160.0 / n)
    alpha = 1.0 if n <= 10 else max(0.08, min(0.8, 10.0 / math.sqrt(n)))
    # up: triangles pointing up, a little left; down: pointing down, a little right, so
    # that where the branches agree both stay visible
    styles = (("up", "tab:blue", "^", -1), ("down", "tab:orange", "v", 1))
    step = np.diff(result.values).min() if result.values.size > 1 else 0.0
    for direction, (name, colour, marker, side) in enumerate(styles):
        heights = result.columns["height_mean"][direction]  # values x starts
        x = np.repeat(result.values + side * 0.2 * step, n).reshape(heights.shape)
        if n == 1:
            ax.plot(x[:, 0], heights[:, 0], "-", color=colour, lw=0.8, alpha=0.6)
        label = f"{name} ({'increasing' if name == 'up' else 'decreasing'} {result.key})"
        ax.scatter(x.ravel(), heights.ravel(), s=size, color=colour, alpha=alpha, lw=0,
                   marker=marker, label=label)  # fmt: skip
    ax.set_xlabel(axis_label(result.key))
    ax.set_ylabel("mean impact height q2 (m)")
    starts = "the scene's start" if n == 1 else f"{n} starts"
    text = title or (
        f"{result.scene.name}: up/down sweep of {result.key}, {starts}, "
        f"{result.transient} impacts of transient + {result.impacts} measured per value"
    )
    ax.set_title("\n".join(textwrap.wrap(text, 80)), fontsize=10)
    # below the axes, where it hides no branch
    legend = ax.legend(
        loc="upper center",
        bbox_to_anchor=(0.5, -0.13),
        ncol=2,
        frameon=False,
        markerscale=max(1.0, 4.0 / math.sqrt(size)),
    )
    for handle in legend.legend_handles:
        handle.set_alpha(1.0)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
