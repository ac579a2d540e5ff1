"""Analyses of simulated trajectories: the largest Lyapunov exponent.

>>> from billiard.scene.scene import load_scene
>>> from billiard.analysis.lyapunov import lyapunov_exponent, format_lyapunov
>>> result = lyapunov_exponent(load_scene("wedge-6.6hz"), impacts=2000)  # doctest: +SKIP
>>> print(format_lyapunov(result))  # doctest: +SKIP

The exponent is estimated with two nearby trajectories (Benettin's method): a reference
and a perturbed copy that starts a distance ``d0`` away; every few impacts their
separation is measured, its logarithmic growth is accumulated, and the perturbed
trajectory is restarted at distance ``d0`` from the reference along the direction the
separation has taken. Both trajectories are run by the engine itself
(:class:`billiard.run.simulate.Simulation`), so the estimate includes every part of the
model: impacts with friction, the low-velocity rule, drag, the drive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard.engine.simulation import Simulation
from billiard.engine.state import BallState
from billiard.errors import BallAtRest, SimulationError
from billiard.status import Status

__all__ = [
    "LyapunovError",
    "LyapunovResult",
    "check_arguments",
    "format_lyapunov",
    "lyapunov_exponent",
]

#: Largest d0 as a fraction of the container's width (at its lid, or at the escape height).
D0_MAX_FRACTION = 1e-3
#: Smallest d0 (m): positions of ~0.1 m are rounded to ~1e-17 m and flights integrated
#: with drag to ~rtol x 1 m; a separation must stay well above both.
D0_MIN = 1e-13


class LyapunovError(ValueError):
    """Arguments of :func:`lyapunov_exponent` that cannot give an exponent; one line."""


@dataclass(frozen=True)
class LyapunovResult:
    """The largest Lyapunov exponent of a scene's trajectory.

    Attributes:
        per_impact: exponent per impact (dimensionless; natural log of the stretching
            factor per impact of the reference trajectory).
        per_second: exponent per unit of simulated time (1/s).
        impacts: impacts of the reference trajectory over which the exponent was
            averaged (the transient excluded).
        duration: simulated time over which it was averaged (s).
        renormalizations: number of separation measurements (and restarts).
        d0: separation (m, in the metric of :func:`lyapunov_exponent`) to which the
            perturbed trajectory is reset.
        largest_stretch: largest single-interval growth log(d / d0) met (dimensionless);
            a value far above the typical one flags a discontinuity between the two
            trajectories (one hit a surface the other missed).
        running: array of shape (renormalizations, 3): after each measurement, the
            reference's impact count, its simulated time (s) and the accumulated
            log-stretch, all counted from the end of the transient (for convergence
            plots: ``running[:, 2] / running[:, 0]`` is the running per-impact estimate).
        stop_reason: None, or why the reference or perturbed run ended early (the
            exponent is then averaged over what was simulated).
        undefined: None, or why the exponent is undefined (then ``per_impact`` and
            ``per_second`` are NaN): the reference trajectory never flies, e.g. a ball
            lying on the wall whose every impact is a relaunch of a resting ball.
    """

    per_impact: float
    per_second: float
    impacts: int
    duration: float
    renormalizations: int
    d0: float
    largest_stretch: float
    running: np.ndarray
    stop_reason: str | None = None
    undefined: str | None = None


class _Stopped(Exception):
    """A run ended early; the message is the engine's stop reason."""


class _NeverFlies(_Stopped):
    """The reference trajectory has no flight long enough to compare states in."""


class _AtRest(_Stopped):
    """The ball came to rest on the boundary (sustained contact): nothing more happens."""


class _InContact(_Stopped):
    """The ball stayed in contact without an impact for ``run.contact_span``."""


def _fly(sim: Simulation, state: BallState, tau: float) -> BallState:
    """State of the ball after flying for tau (s) from ``state`` with the simulation's own
    flight model (spin constant in flight)."""
    flight = sim.flight
    flight.begin(state.q1, state.q2, state.u1, state.u2, state.u3)
    done = 0.0
    while done < tau:
        done = flight.advance(done, tau)
    q1, q2, u1, u2 = flight.state(tau) if tau > 0.0 else (state.q1, state.q2, state.u1, state.u2)
    t = state.t + tau
    return BallState(t, sim.drive.angle(t), q1, q2, u1, u2, state.u3, 0.0)


def _advance(sim: Simulation, state: BallState, impacts: int) -> BallState:
    """Post-impact state after ``impacts`` engine steps from ``state``."""
    if impacts <= 0:
        return state
    sim.reset(state)
    try:
        for _ in range(impacts):
            sim.step()
        if sim.pending_stop is not None:
            raise sim.pending_stop
    except BallAtRest as exc:
        raise _AtRest(str(exc)) from None
    except SimulationError as exc:
        if exc.status is Status.IN_CONTACT:
            raise _InContact(str(exc)) from None
        raise _Stopped(str(exc)) from None
    b = sim.ball
    # the drive angle from the impact time, as for any state handed to the engine
    return BallState(b.t, sim.drive.angle(b.t), b.q1, b.q2, b.u1, b.u2, b.u3, 0.0)


def _next_impact(sim: Simulation, state: BallState) -> BallState:
    """Post-impact state of the next impact after ``state`` (one engine step)."""
    return _advance(sim, state, 1)


def lyapunov_exponent(
    scene: Any,
    *,
    impacts: int = 5000,
    renormalize_every: int = 10,
    d0: float = 1e-9,
    transient: int = 0,
    time_scale: float | None = None,
    min_flight: float = 1e-3,
    seed: int = 0,
    method: str | None = None,
) -> LyapunovResult:
    """Largest Lyapunov exponent of the trajectory of ``scene`` (two-trajectory method).

    Phase-space distance. Two states are compared *at the same time, both in flight*
    (never at impacts, where a pair of trajectories a hair apart may sit on either side
    of a bounce). The distance is Euclidean in the scaled state
    ``(q1, q2, T v1, T v2, T r omega)`` (all in metres): the centre position, the centre
    velocity times a time scale T, and the contact-point speed due to spin, r omega,
    times T. ``T = time_scale``, by default the free-fall time over 1 cm,
    sqrt(0.01 m / g) ~ 0.032 s. The drive phase is not a separate coordinate: both
    states are taken at the same instant, so they share it.

    Procedure. Let the reference state at time t* be X and the perturbed one X + d0 u
    (u a unit vector, random with ``seed`` at the start). Both are run by the engine
    for at least ``renormalize_every`` impacts of the reference, up to the middle of the
    reference's next flight that lasts at least ``min_flight`` (s) (so the comparison
    instant falls inside a real flight, not inside a burst of micro-bounces); there both
    are flown to the same instant t** with the scene's flight model, the distance d is
    measured and log(d / d0) accumulated. The perturbed trajectory is then restarted
    from X' + d0 (Y' - X') / d, X' and Y' the two states at t** (the engine restarts a
    run from any in-flight state: time, drive angle, position, velocity, spin). The
    reference is restarted from X' as well, so that both runs integrate their flights
    from the same instant with the same flight model.

    The exponent per impact is the accumulated log-stretch divided by the reference's
    impact count; per second, divided by the simulated time. Both exclude the first
    ``transient`` impacts (e.g. the ball lifting off from rest, or locking into an orbit).

    Args:
        scene: a :class:`billiard.scene.scene.Scene`.
        impacts: impacts of the reference trajectory to average over (after the
            transient).
        renormalize_every: impacts of the reference between two measurements (>= 1).
        d0: initial and reset separation (m, in the scaled metric above). It must be
            small against the scene's lengths yet well above the flight integrator's
            error (drag: ~rtol x 1 m).
        transient: impacts simulated before the measurement starts.
        time_scale: T of the metric (s); default sqrt(0.01 m / g).
        min_flight: shortest reference flight (s) whose middle may be a comparison
            instant.
        seed: seed of the random initial direction of the perturbation.
        method: ``"event"`` or ``"rk4"``; default the scene's.

    Returns:
        A :class:`LyapunovResult`. A run that ends early (escape, inelastic collapse)
        gives the estimate over what was simulated and the reason in ``stop_reason``.
    """
    ref = Simulation(scene, method)
    xl, xr = ref.boundary.x_range
    check_arguments(
        scene,
        impacts=impacts,
        transient=transient,
        d0=d0,
        renormalize_every=renormalize_every,
        min_flight=min_flight,
        time_scale=time_scale,
        width=xr - xl,
    )
    g = scene.run.gravity
    scale = math.sqrt(0.01 / g) if time_scale is None else float(time_scale)
    radius = scene.ball.radius
    weights = np.array([1.0, 1.0, scale, scale, scale * radius])

    pert = Simulation(scene, method)
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=5)
    direction /= np.linalg.norm(direction)

    def vector(s: BallState) -> np.ndarray:
        return np.array([s.q1, s.q2, s.u1, s.u2, s.u3]) * weights

    def from_vector(t: float, v: np.ndarray) -> BallState:
        q1, q2, u1, u2, u3 = (float(x) for x in v / weights)
        return BallState(t, ref.drive.angle(t), q1, q2, u1, u2, u3, 0.0)

    stop_reason: str | None = None
    running: list[tuple[float, float, float]] = []
    total = 0.0
    counted = 0
    largest = -math.inf
    t_start = math.nan
    undefined: str | None = None
    regimes = ref.impact.regimes
    impacts_before = resting_before = 0
    try:
        state = _advance(ref, ref.initial, transient)
        impacts_before = sum(ref.counts.get(r, 0) for r in regimes)
        resting_before = ref.counts.get("resting", 0)
        # first comparison instant: the middle of the next long enough flight
        x_state, _ = _comparison_state(ref, state, min_flight)
        t_start = x_state.t
        x = vector(x_state)
        y = x + d0 * direction
        while counted < impacts:
            # reference: renormalize_every impacts, then on to a long flight's middle
            after = _advance(ref, x_state, renormalize_every - 1)
            after = _next_impact(ref, after)
            x_next, n_extra = _comparison_state(ref, after, min_flight)
            n_ref = renormalize_every + n_extra
            # perturbed: impact by impact until its next impact falls after t**
            t_target = x_next.t
            y_state = from_vector(x_state.t, y)
            while True:
                nxt = _next_impact(pert, y_state)
                if nxt.t > t_target:
                    break
                y_state = nxt
            y_next = _fly(pert, y_state, t_target - y_state.t)
            xv, yv = vector(x_next), vector(y_next)
            d = float(np.linalg.norm(yv - xv))
            stretch = math.log(d / d0) if d > 0.0 else -math.inf
            if not math.isfinite(stretch):
                raise _Stopped("the perturbed trajectory merged with the reference")
            total += stretch
            largest = max(largest, stretch)
            counted += n_ref
            running.append((counted, x_next.t - t_start, total))
            x_state, x = x_next, xv
            y = xv + (yv - xv) * (d0 / d)
    except _NeverFlies as exc:
        undefined = f"the ball never flies: {exc}"
    except _AtRest:
        undefined = "the ball rests on the wall: it comes to rest in a contact phase"
    except _InContact as exc:
        undefined = f"the ball rolls, slides or is held without impacts ({exc})"
    except _Stopped as exc:
        stop_reason = str(exc)
    n_ref = sum(ref.counts.get(r, 0) for r in regimes) - impacts_before
    resting = ref.counts.get("resting", 0) - resting_before
    if undefined is None and n_ref > 0 and resting == n_ref:
        undefined = (
            f"the ball rests on the wall: each of the reference's {n_ref} impacts "
            "relaunched a resting ball (hops standing in for rolling contact)"
        )
    table = np.array(running, dtype=float).reshape(-1, 3)
    n = int(table[-1, 0]) if len(table) else 0
    duration = float(table[-1, 1]) if len(table) else 0.0
    if undefined is not None:
        total = math.nan
    return LyapunovResult(
        per_impact=total / n if n else math.nan,
        per_second=total / duration if duration > 0.0 else math.nan,
        impacts=n,
        duration=duration,
        renormalizations=len(table),
        d0=d0,
        largest_stretch=largest,
        running=table,
        stop_reason=stop_reason,
        undefined=undefined,
    )


def _comparison_state(
    sim: Simulation, state: BallState, min_flight: float
) -> tuple[BallState, int]:
    """From a post-impact (or in-flight) state, the state at the middle of the first
    flight lasting at least ``min_flight`` (s), and the number of impacts passed on the
    way (those whose flights were too short)."""
    extra = 0
    for _ in range(100_000):
        nxt = _next_impact(sim, state)
        tau = nxt.t - state.t
        if tau >= min_flight:
            return _fly(sim, state, 0.5 * tau), extra
        state = nxt
        extra += 1
    raise _NeverFlies(f"no flight lasts min_flight = {min_flight!r} s in 100000 impacts")


def format_lyapunov(result: LyapunovResult) -> str:
    """One line for humans: the exponent per impact and per second, and what it is
    averaged over; or why it is undefined."""
    if result.undefined is not None:
        return (
            f"largest Lyapunov exponent undefined: {result.undefined}; give the ball "
            "energy to fly (a stronger drive, or a start above the wall: initial.q2, m)"
        )
    text = (
        f"largest Lyapunov exponent {result.per_impact:+.4g} per impact "
        f"({result.per_second:+.4g} 1/s) over {result.impacts} impacts, "
        f"{result.duration:.4g} s, {result.renormalizations} renormalizations "
        f"(d0 = {result.d0:g} m)"
    )
    if result.stop_reason:
        text += f"; stopped early: {result.stop_reason}"
    return text


def _whole(name: str, value: Any, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise LyapunovError(f"{name} must be a whole number >= {low}, got {value!r}")
    return int(value)


def _seconds(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LyapunovError(f"{name} must be a number of seconds, got {value!r}")
    if not (math.isfinite(value) and value > 0.0):
        raise LyapunovError(f"{name} must be a positive number of seconds, got {value!r}")
    return float(value)


def check_arguments(
    scene: Any,
    *,
    impacts: int,
    transient: int = 0,
    d0: float = 1e-9,
    renormalize_every: int = 10,
    min_flight: float = 1e-3,
    time_scale: float | None = None,
    width: float | None = None,
) -> None:
    """Check the arguments of :func:`lyapunov_exponent` before any work.

    ``d0`` (m) must be small against the scene's lengths: at most :data:`D0_MAX_FRACTION`
    of the container's width ``width`` (m; default: measured on the scene's boundary at
    its lid, or at the escape height of an open container), and at least :data:`D0_MIN`.

    Raises:
        LyapunovError: (a ValueError) the first argument that is wrong, in one line.
    """
    _whole("impacts", impacts, 1)
    _whole("transient", transient, 0)
    _whole("renormalize_every", renormalize_every, 1)
    _seconds("min_flight", min_flight)
    if time_scale is not None:
        _seconds("time_scale", time_scale)
    if isinstance(d0, bool) or not isinstance(d0, (int, float)) or not math.isfinite(d0):
        raise LyapunovError(f"d0 must be a finite number of metres, got {d0!r}")
    if width is None:
        xl, xr = Simulation(scene).boundary.x_range
        width = xr - xl
    largest = D0_MAX_FRACTION * width
    if not D0_MIN <= d0 <= largest:
        raise LyapunovError(
            f"d0 = {d0!r} m must be small against the scene's lengths yet above rounding: "
            f"between {D0_MIN:g} m and {largest:.3g} m ({D0_MAX_FRACTION:g} of the "
            f"container's width {width:.4g} m)"
        )
