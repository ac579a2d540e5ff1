"""How large a run's trajectory samples get (``--sample DT``, ``simulate(..., sample=DT)``),
estimated before the run starts and enforced while it runs.

A sampled run writes one row every DT seconds of simulated time, to ``trajectory.csv`` or
to memory. With ``run.duration`` the number of rows is known exactly; without it, the
simulated time is bounded by the impacts asked for times the longest flight the
container allows (:func:`longest_flight`: a ball cannot fly longer than it takes to rise
and fall through the container's whole height). A run whose estimate is larger than
:data:`MAX_BYTES` is refused (:class:`OutputSizeError`, one line naming the estimate)
unless the caller confirms it (``billiard run --yes``, ``simulate(..., allow_large=True)``);
the bound of a run without a duration is loose (some 25 times what the paper's scenes
make), so such a run is refused only beyond :data:`BOUND_FACTOR` times the limit, and
otherwise stopped when it reaches the limit.

The same limit holds for what other commands make from the user's numbers (an up/down
sweep's trajectories, the uncertainty exponent's starts): each estimates its memory and
files before it allocates anything and refuses through :func:`check_size`.

While the run goes on, :func:`guard_samples` stops it with :class:`OutputSizeError` before
it writes more rows than the larger of the estimate and the limit: the time a ball spends
rolling, sliding or held (``contact.model = "phases"``) is not in the bound, and the
estimate must never be exceeded silently.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from billiard.scene.checks import SceneError

__all__ = [
    "BOUND_FACTOR",
    "FILE_ROW_BYTES",
    "MAX_BYTES",
    "MEMORY_ROW_BYTES",
    "OutputSizeError",
    "SampleEstimate",
    "check_samples",
    "check_size",
    "estimate_samples",
    "guard_samples",
    "longest_flight",
    "vertical_range",
]

#: Largest trajectory a run writes (trajectory.csv) or keeps (in memory) without the
#: caller's confirmation, in bytes: 1 GB, some 7 million rows on disk.
MAX_BYTES = 10**9
#: A run without ``run.duration`` is refused before it starts only when the bound on its
#: trajectory is over this many times :data:`MAX_BYTES` (see :func:`check_samples`).
BOUND_FACTOR = 100
#: Bytes of one row of trajectory.csv (measured: 137 on average, 156 at most, over runs of
#: the paper's scenes with impacts and with contact phases).
FILE_ROW_BYTES = 140
#: Bytes of memory one sample takes in ``result.trajectory`` while the run goes on: eight
#: list entries, seven of them float objects (8 + 7 x 32).
MEMORY_ROW_BYTES = 232


class OutputSizeError(SceneError):
    """A sampled run would write (or keep) more rows than allowed; the message is one line
    naming the estimate and how to go on.

    Attributes:
        confirm: the words in the message that say how to confirm the run (e.g.
            ``allow_large=True``; a command line puts its own option in their place), or
            None when confirming does not help.
    """

    def __init__(self, message: str, confirm: str | None = None):
        super().__init__(message)
        self.confirm = confirm

    def confirmed_by(self, option: str) -> str:
        """The message with ``option`` as the way to confirm the run."""
        text = str(self)
        return text if self.confirm is None else text.replace(self.confirm, option)


@dataclass(frozen=True)
class SampleEstimate:
    """The samples a run makes, at most.

    Attributes:
        rows: samples (float: it may exceed every integer type; ``inf`` for no bound).
        span: simulated time (s) sampled, at most.
        why: how the span is bounded, in words (for messages).
        row_bytes: bytes per row (:data:`FILE_ROW_BYTES` or :data:`MEMORY_ROW_BYTES`).
    """

    rows: float
    span: float
    why: str
    row_bytes: int
    #: True when ``run.duration`` bounds the span (then ``rows`` is exact), False when the
    #: impacts do (then ``rows`` is a bound, far above what most runs make)
    exact: bool = False
    #: set by :func:`check_samples`: the run goes ahead unconfirmed and stops at the limit
    #: (how to confirm a larger run, e.g. ``allow_large=True``), else None
    limited_by: str | None = None

    @property
    def bytes(self) -> float:
        return self.rows * self.row_bytes

    @property
    def cap(self) -> float:
        """Rows a run may make before :func:`guard_samples` stops it: the estimate, and
        never fewer than the limit allows."""
        return max(self.rows, MAX_BYTES // self.row_bytes)


def _gravity_fall(height: float, g: float, terminal: float) -> float:
    """Time (s) to fall ``height`` (m) from rest under gravity ``g`` with a drag that is at
    least linear with terminal speed ``terminal`` (m/s; inf: no drag): a convex drag
    force c1 v + c2 v^2 equal to m g at the terminal speed is at most m g v / terminal
    below it, so the linear law falls slowest."""
    if math.isinf(terminal):
        return math.sqrt(2.0 * height / g)
    tau = terminal / g

    def fallen(t: float) -> float:  # the linear law's distance after t
        return terminal * t - terminal * tau * -math.expm1(-t / tau)

    lo, hi = 0.0, math.sqrt(2.0 * height / g) + height / terminal + tau
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if fallen(mid) < height:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * hi:
            break
    return hi


def vertical_range(scene: Any, boundary: Any) -> tuple[float, float]:
    """Lowest and highest height (m, lab frame) of the ball's centre in the container:
    the lowest point of the curve (on a grid of 2001 abscissas, less a ball radius for
    what lies between them) and the top (the lid, or the escape height), both moved by
    a vertical drive's amplitude."""
    lo, hi = boundary.x_range
    xs = [lo + (hi - lo) * k / 2000 for k in range(2001)]
    bottom = min(boundary.curve_height(x) for x in xs) - scene.ball.radius
    sway = scene.drive.amplitude if scene.drive.direction == "vertical" else 0.0
    return bottom - sway, boundary.top + sway


def longest_flight(scene: Any, boundary: Any) -> float:
    """An upper bound (s) on one flight of the ball in the container.

    A flight stays between the lowest point of the curve and the top (the lid, or the
    escape height, above which the run ends), both moving with a vertical drive. Rising,
    gravity and drag both slow the ball, so it spends at most sqrt(2 H / g) rising through
    the height H; falling, at most the time of a fall through H from rest against drag
    (:func:`_gravity_fall`). Left out, and covered by the run-time guard instead: the
    Magnus force, which can lift a spinning ball, and a fast sideways motion, which adds
    to the quadratic drag on a falling ball.
    """
    bottom, top = vertical_range(scene, boundary)
    height = max(top - bottom, 1e-9)
    g = scene.run.gravity
    c_lin, c_quad = scene.air.coefficients
    weight = scene.ball.mass * g
    if c_lin == 0.0 and c_quad == 0.0:
        terminal = math.inf
    elif c_quad == 0.0:
        terminal = weight / c_lin
    else:  # c_quad v^2 + c_lin v = m g
        terminal = 2.0 * weight / (c_lin + math.sqrt(c_lin * c_lin + 4.0 * c_quad * weight))
    return math.sqrt(2.0 * height / g) + _gravity_fall(height, g, terminal)


def estimate_samples(
    sim: Any, total: int, *, start_time: float, start_impacts: int, in_memory: bool
) -> SampleEstimate:
    """The samples a run of ``sim`` (``sim.sample_dt`` set) makes from ``start_time`` (s)
    and impact ``start_impacts`` up to impact ``total`` or ``run.duration``."""
    dt = sim.sample_dt
    scene = sim.scene
    row_bytes = MEMORY_ROW_BYTES if in_memory else FILE_ROW_BYTES
    flight = longest_flight(scene, sim.boundary)
    by_impacts = (total - start_impacts) * flight
    duration = scene.run.duration
    if duration is not None:
        left = sim.initial.t + duration - start_time
        if left <= by_impacts:
            span, why = left, f"{_seconds(duration)} s of simulated time (run.duration)"
            return SampleEstimate(_rows(span, dt), span, why, row_bytes, exact=True)
    span = by_impacts
    why = (
        f"{total - start_impacts:,} impacts of at most {_seconds(flight)} s each (the longest "
        f"flight this container allows)"
    )
    return SampleEstimate(_rows(span, dt), span, why, row_bytes)


def _rows(span: float, dt: float) -> float:
    rows = math.floor(span / dt) + 1.0 if math.isfinite(span / dt) else math.inf
    return max(rows, 1.0)


def _seconds(value: float) -> str:
    return f"{value:.4g}"


def _count(rows: float) -> str:
    return f"{rows:,.0f}" if rows < 1e15 else f"{rows:.3g}"


def _bytes(size: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size:,.0f} bytes"


def check_samples(estimate: SampleEstimate, *, sample: float, allow: str) -> SampleEstimate:
    """Refuse an estimate over :data:`MAX_BYTES`; returns the estimate the run goes on with.

    Without ``run.duration`` the estimate is a bound (every impact after the longest flight
    the container allows), some 25 times what the paper's scenes make: such a run is
    refused only when its bound is over :data:`BOUND_FACTOR` times the limit; under that it
    goes ahead, and :func:`guard_samples` stops it at the limit itself (the estimate
    returned then says so).

    Args:
        estimate: from :func:`estimate_samples`.
        sample: the sampling interval (s), for the message.
        allow: how the caller confirms a larger run (``--yes``, ``allow_large=True``).

    Raises:
        OutputSizeError: over the limit; the message names the rows, the bytes, the
            bound on the simulated time and the ways to go on.
    """
    if estimate.bytes <= MAX_BYTES:
        return estimate
    if not estimate.exact and estimate.bytes <= BOUND_FACTOR * MAX_BYTES:
        rows = float(MAX_BYTES // estimate.row_bytes)
        return SampleEstimate(rows, estimate.span, estimate.why, estimate.row_bytes, False, allow)
    where = "in memory" if estimate.row_bytes == MEMORY_ROW_BYTES else "of trajectory.csv"
    raise OutputSizeError(
        f"sampling every {sample:g} s over at most {estimate.why} makes up to "
        f"{_count(estimate.rows)} rows ({_bytes(estimate.bytes)} {where}), over the limit "
        f"of {_bytes(MAX_BYTES)}; give a larger sampling interval or a shorter duration "
        f"(run.duration, s), or {allow} to go ahead",
        allow,
    )


def check_size(sizes: dict[str, float], *, what: str, fewer: str, allow: str) -> None:
    """Refuse a piece of work whose estimated sizes (bytes; ``sizes`` maps ``memory`` or
    a file's name to its estimate) are any of them over :data:`MAX_BYTES`.

    Args:
        sizes: the estimates, named as the message names them ("X of memory").
        what: the work and the numbers that size it, e.g. "an up/down sweep of 71
            values x 32 starts".
        fewer: how to make it smaller (the options to lower).
        allow: how the caller confirms it (``allow_large=True``; a command line puts its
            own option in its place with :meth:`OutputSizeError.confirmed_by`).

    Raises:
        OutputSizeError: one line naming ``what``, the estimates and the limit.
    """
    if all(size <= MAX_BYTES for size in sizes.values()):
        return
    estimates = " and ".join(f"{_bytes(size)} of {name}" for name, size in sizes.items())
    raise OutputSizeError(
        f"{what} would take about {estimates}, over the limit of {_bytes(MAX_BYTES)}; "
        f"{fewer}, or {allow} to go ahead",
        allow,
    )


def guard_samples(
    append: Callable[[tuple], None], estimate: SampleEstimate, done: int, sample: float
) -> Callable[..., None]:
    """An ``on_sample`` callback that hands each sample's row to ``append`` and raises
    :class:`OutputSizeError` instead of passing :attr:`SampleEstimate.cap` rows since the
    run (re)started (``done``: the samples made before it)."""
    cap = estimate.cap
    made = [0]

    def on_sample(*row: Any) -> None:
        if made[0] >= cap and estimate.limited_by is not None:
            raise OutputSizeError(
                f"the trajectory reached the limit of {_bytes(MAX_BYTES)} "
                f"({_count(done + made[0])} samples, every {sample:g} s) at t = {row[0]:.6g} s: "
                f"give a larger sampling interval or a duration (run.duration, s), or "
                f"{estimate.limited_by} to go beyond the limit",
                estimate.limited_by,
            )
        if made[0] >= cap:
            raise OutputSizeError(
                f"the trajectory reached {_count(done + made[0])} samples at t = "
                f"{row[0]:.6g} s, more than estimated ({_count(cap)} from {estimate.why}, "
                f"every {sample:g} s); the time spent rolling, sliding or held is not in "
                f"the estimate: give a duration (run.duration, s) to bound the run"
            )
        made[0] += 1
        append(row)

    return on_sample
