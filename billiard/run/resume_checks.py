"""Is a checkpoint's engine state one that a run of its scene can have reached? Checked
before a run is resumed from it (:func:`billiard.run.persist.resume`), so that a checkpoint
edited by hand or forged (a checkpoint's own checksum is no protection: anyone can
recompute it) is refused in one line instead of continuing a run that never was: a
speed of 10^6 m/s, a ball outside its container, a clock that disagrees with the ball's
time, counters that disagree with each other or with the rows in the files.

The bounds are generous: a run of the scene could never come near them, but an edit
that changes a state's meaning does.
"""

from __future__ import annotations

import math
from typing import Any

from billiard.engine.simulation import ZERO_FLIGHT_LIMIT
from billiard.engine.state import EngineState
from billiard.kernels.interpreted import impact as _impact
from billiard.models.chatter import CHATTER_TAIL
from billiard.run.output_size import vertical_range
from billiard.runfile.checkpoint import CheckpointError

__all__ = ["check_state", "speed_limit"]

#: Speed (m/s) no ball of a scene's plausible range reaches by itself: the checks of
#: billiard.scene.checks allow starting velocities up to 100 m/s.
BASE_SPEED = 100.0
#: Spin (rad/s) allowed at the start (billiard.scene.checks: initial.omega).
BASE_SPIN = 1e5


def speed_limit(scene: Any, boundary: Any) -> float:
    """The largest plausible speed (m/s) of the ball's centre in a run of ``scene``: the
    starting range, plus ten times the boundary's largest speed (each impact adds at
    most (1 + e) times it), plus the speed of a fall through the container's height."""
    drive = scene.drive
    bottom, top = vertical_range(scene, boundary)
    fall = math.sqrt(2.0 * scene.run.gravity * max(top - bottom, 0.0))
    return BASE_SPEED + 10.0 * drive.amplitude * drive.omega + fall


def _fail(message: str) -> CheckpointError:
    return CheckpointError(f"its engine state is implausible: {message}")


def check_state(
    state: EngineState, sim: Any, *, rows: int, sample: float | None, regimes: tuple[str, ...]
) -> None:
    """Refuse an engine state that a run of ``sim``'s scene cannot have reached after
    ``rows`` impacts (sampling every ``sample`` s, or not at all).

    Raises:
        CheckpointError: the first implausible value, named with its unit and bound.
    """
    scene = sim.scene
    ball = state.ball
    t0 = sim.initial.t
    # time: from the start, within the run's duration, kept by the compensated clock
    if ball.t < t0:
        raise _fail(f"the ball's time t = {ball.t!r} s is before the start ({t0!r} s)")
    if scene.run.duration is not None and ball.t > t0 + scene.run.duration * (1 + 1e-12):
        raise _fail(
            f"the ball's time t = {ball.t!r} s is past the run's end "
            f"({t0 + scene.run.duration!r} s)"
        )
    if not math.isclose(state.clock + state.clock_error, ball.t, rel_tol=1e-12, abs_tol=1e-12):
        raise _fail(
            f"its clock ({state.clock!r} + {state.clock_error!r} s) is not the ball's time "
            f"t = {ball.t!r} s"
        )
    if not 0.0 <= ball.theta <= 2.0 * math.pi:
        raise _fail(f"the drive angle {ball.theta!r} rad is not in [0, 2 pi]")
    # motion: within what the scene's start and drive allow
    limit = speed_limit(scene, sim.boundary)
    speed = math.hypot(ball.u1, ball.u2)
    if speed > limit:
        raise _fail(f"the ball's speed {speed:.6g} m/s is over {limit:.6g} m/s")
    spin = (
        BASE_SPIN
        + abs(scene.initial.omega)
        + 10.0 * limit / (scene.ball.inertia_factor * scene.ball.radius)
    )
    if abs(ball.u3) > spin:
        raise _fail(f"the ball's spin {ball.u3:.6g} rad/s is over {spin:.6g} rad/s")
    boundary = sim.boundary
    xl, xr = boundary.x_range
    bottom, top = vertical_range(scene, boundary)
    margin = 1.0 + scene.drive.amplitude  # m: the boundary moves, a wall may end
    if not (xl - margin <= ball.q1 <= xr + margin and bottom - margin <= ball.q2 <= top + margin):
        raise _fail(
            f"the ball's centre ({ball.q1:.6g}, {ball.q2:.6g}) m is outside its container "
            f"(x in [{xl:.4g}, {xr:.4g}] m, y in [{bottom:.4g}, {top:.4g}] m, 1 m aside)"
        )
    # counters: impacts, regimes, the collapse detector, the samples
    if state.impacts != rows:
        raise _fail(f"{state.impacts} impacts for {rows} rows")
    counted = sum(state.counts.get(name, 0) for name in regimes)
    if counted != state.impacts:
        raise _fail(f"its regime counters add up to {counted}, not {state.impacts} impacts")
    if state.counts.get("resting", 0) > state.impacts:
        raise _fail(f"{state.counts['resting']} relaunches in {state.impacts} impacts")
    recent = state.recent
    if any(b < a for a, b in zip(recent, recent[1:], strict=False)) or any(
        not t0 <= t <= ball.t for t in recent
    ):
        raise _fail("the collapse detector's impact times are not in order before t")
    if state.zero_flights > ZERO_FLIGHT_LIMIT:
        raise _fail(f"{state.zero_flights} zero flights in a row, over {ZERO_FLIGHT_LIMIT}")
    _check_samples(state, t0, sample)
    _check_phases(state, sim, t0)


def _check_samples(state: EngineState, t0: float, sample: float | None) -> None:
    t = state.ball.t
    if sample is None:
        if state.samples:
            raise _fail(f"{state.samples} samples in a run that samples nothing")
        return
    # the samples made are those at t0 + k dt <= t (the step reports them up to its end)
    expected = math.floor((t - t0) / sample) + 1
    if abs(state.samples - expected) > 1 and not (state.samples == 0 and t == t0):
        raise _fail(
            f"{state.samples} samples at t = {t!r} s, every {sample!r} s from {t0!r} s "
            f"makes {expected}"
        )


def _check_phases(state: EngineState, sim: Any, t0: float) -> None:
    t = state.ball.t
    span = t - t0
    for mode, seconds in state.phase_time.items():
        if mode not in ("roll", "slide", "held"):
            raise _fail(f"unknown contact mode {mode!r} in its phase times")
        if not 0.0 <= seconds <= span * (1 + 1e-9) + 1e-9:
            raise _fail(f"{seconds!r} s {mode} in {span!r} s of run")
    if state.mode == "flight":
        return
    if not sim.phases:
        raise _fail(f"the ball is in contact ({state.mode}) in a scene without contact phases")
    walls = len(sim.boundary.offsets)
    first, second, _, third, start, _settle = state.contact
    if state.mode == "held":
        indices = (first, second)
    else:
        indices = (first,)
        if third not in (-1.0, 0.0, 1.0):
            raise _fail(f"the slip sign {third!r} is not -1, 0 or 1")
    if any(not (i == int(i) and 0 <= i < walls) for i in indices):
        raise _fail(f"the contact's wall {indices!r} is not one of the {walls} walls")
    # a landing at the end of a summed chatter series starts its phase up to
    # CHATTER_TAIL of the drive period after the impact the ball is at
    latest = t + CHATTER_TAIL * _impact.chatter_period(sim.drive.omega) * (1.0 + 1e-9)
    if not t0 <= start <= latest:
        raise _fail(f"the contact phase starts at {start!r} s, not in [{t0!r}, {latest!r}] s")
