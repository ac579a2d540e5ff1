"""The engine state in the state vector ``ctx``, and back.

:func:`state_vector` builds ``ctx`` for a :class:`billiard.engine.simulation.Simulation` (the
scene's constants, the surfaces, the warm starts and the engine state);
:func:`write_state` puts an :class:`~billiard.engine.state.EngineState` into an existing
``ctx`` and :func:`engine_state` reads it back, so a checkpoint written by either engine
continues bit for bit. Plain Python (not compiled): these run once per run or step.

Slots (``layout.py``): the ball at ``EN_T`` .. ``EN_Q3``; the collapse window as a ring
of ``RING`` slots at ``RECENT`` (oldest at ``EN_RHEAD``, ``EN_RCOUNT`` of them); the
regime counters at ``COUNTS`` (stick, slip, elastic, resting); the warm start of
surface ``j`` in its block (``S_WS``, ``S_WSLOPE``); the flight's step proposal at
``FL_H``. The locator carries nothing from one flight to the next.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from billiard.engine.state import BallState, EngineState
from billiard.geometry.surfaces import FlatLid, OffsetWall
from billiard.kernels import layout as L
from billiard.kernels.rules import COLLAPSE_COUNT
from billiard.models.kinds import require_kernel

__all__ = [
    "COUNT_KEYS",
    "RING",
    "constants_vector",
    "engine_state",
    "read_ball",
    "put_motion",
    "read_motion",
    "state_vector",
    "write_ball",
    "write_motion",
    "write_state",
]

#: slots of the collapse window's ring
RING = COLLAPSE_COUNT + 1
#: the counters at COUNTS, in order
COUNT_KEYS = ("stick", "slip", "elastic", "resting")
_BALL = (L.EN_T, L.EN_THETA, L.EN_Q1, L.EN_Q2, L.EN_U1, L.EN_U2, L.EN_U3, L.EN_Q3)


def _ball_values(ball: BallState) -> tuple[float, ...]:
    return (ball.t, ball.theta, ball.q1, ball.q2, ball.u1, ball.u2, ball.u3, ball.q3)


def _surface_constants(ctx: list[float], j: int, surface: Any) -> None:
    if not isinstance(surface, (OffsetWall, FlatLid)):
        raise ValueError(f"the kernels have no surface {type(surface).__name__}")
    base = L.SURF + j * L.SURF_STRIDE
    ctx[base : base + L.S_WS] = surface.block()


def state_vector(sim: Any) -> list[float]:
    """The kernels' ``ctx`` (a list of floats) for ``sim`` in its current engine state:
    the locator (with the drive), the flight model and the impact law each write their
    block, their kind first.

    Raises:
        SceneError: a locator, flight model or impact law without a compiled kernel.
        ValueError: a surface the kernels do not have.
    """
    ctx = constants_vector(sim)
    write_state(ctx, sim.state)
    if sim.phases:
        write_motion(ctx, sim.state)
    return ctx


def constants_vector(sim: Any) -> list[float]:
    """The kernels' ``ctx`` (a list of floats) for ``sim``: the scene's constants and
    the warm starts its objects hold; no engine state.

    Raises:
        ValueError: a flight model or surface the kernels do not have.
    """
    ctx = [0.0] * L.SIZE
    for model, what in (
        (sim.locator, "locator"),
        (sim.flight, "flight model"),
        (sim.impact, "impact law"),
    ):
        require_kernel(model, what)
        model.write(ctx)
    surfaces = sim.boundary.surfaces
    ctx[L.NSURF] = float(len(surfaces))
    for j, surface in enumerate(surfaces):
        _surface_constants(ctx, j, surface)
        base = L.SURF + j * L.SURF_STRIDE
        warm = sim.warm[j]
        ctx[base + L.S_WS] = float(warm[0])
        ctx[base + L.S_WSLOPE] = float(warm[1])
    ctx[L.EN_UNTIL] = sim.end_time
    # samples count from the run's start (billiard run --sample)
    ctx[L.SM_T0] = sim.initial.t
    if sim.phases:
        _machine_constants(ctx, sim)
    return ctx


def _machine_constants(ctx: list[float], sim: Any) -> None:
    """Contact phases: the phases' constants (as the contact model's own ``ctx`` holds
    them), the contact span, the container's range of x and the walls' intervals; the
    flights end after an impact that settles (the landing test reads the law's
    restitution and elastic_below, IM_E and IM_EB)."""
    phase = sim.contact_model.new_ctx()
    ctx[L.PH_M : L.PH_RTOL + 1] = phase[L.PH_M : L.PH_RTOL + 1]
    ctx[L.MC_SPAN] = float(sim.scene.run.contact_span)
    ctx[L.MC_X_LO], ctx[L.MC_X_HI] = (float(x) for x in sim.boundary.x_range)
    for wall in sim.boundary.walls:
        ctx[L.MC_WALL_LO + wall.index] = float(wall.lo)
        ctx[L.MC_WALL_HI + wall.index] = float(wall.hi)
    ctx[L.EN_LAND_ON] = 1.0


def write_ball(ctx: Any, ball: BallState) -> None:
    """Start the event count afresh from ``ball`` (as ``Simulation.reset``): the
    regime counters, warm starts and the flight's step proposal are kept."""
    for slot, value in zip(_BALL, _ball_values(ball), strict=True):
        ctx[slot] = value
    ctx[L.EN_IMPACTS] = 0.0
    ctx[L.EN_CLOCK] = ball.t
    ctx[L.EN_CLOCK_ERR] = 0.0
    ctx[L.EN_ZERO] = 0.0
    ctx[L.EN_RCOUNT] = 0.0
    ctx[L.EN_RHEAD] = 0.0
    ctx[L.EN_FAULT] = 0.0


def write_state(ctx: Any, state: EngineState) -> None:
    """Put ``state`` into ``ctx`` (the collapse window written oldest first from slot 0;
    no pending stop). The state's walls are the warm starts of the first surfaces."""
    for slot, value in zip(_BALL, _ball_values(state.ball), strict=True):
        ctx[slot] = value
    ctx[L.EN_IMPACTS] = float(state.impacts)
    ctx[L.EN_CLOCK] = state.clock
    ctx[L.EN_CLOCK_ERR] = state.clock_error
    ctx[L.EN_ZERO] = float(state.zero_flights)
    recent = tuple(state.recent)
    if len(recent) > RING:
        raise ValueError(f"a collapse window of {len(recent)} impacts (at most {RING})")
    for i, t in enumerate(recent):
        ctx[L.RECENT + i] = t
    ctx[L.EN_RCOUNT] = float(len(recent))
    ctx[L.EN_RHEAD] = 0.0
    ctx[L.EN_FAULT] = 0.0
    for i, key in enumerate(COUNT_KEYS):
        ctx[L.COUNTS + i] = float(state.counts.get(key, 0))
    for j, (s, slope) in enumerate(state.walls):
        base = L.SURF + j * L.SURF_STRIDE
        ctx[base + L.S_WS] = s
        ctx[base + L.S_WSLOPE] = slope
    if ctx[L.FL_KIND] == L.FLIGHT_ADAPTIVE and "step" in state.flight:
        ctx[L.FL_H] = state.flight["step"]


def read_ball(ctx: Any) -> BallState:
    """The ball in ``ctx`` (EN_T .. EN_Q3)."""
    return BallState(*(float(ctx[slot]) for slot in _BALL))


def engine_state(ctx: Any, regimes: Sequence[str], walls: int) -> EngineState:
    """The :class:`EngineState` held by ``ctx`` (flight mode: the impacts model):
    ``regimes`` name the counters (then ``resting``), ``walls`` is how many surfaces
    carry a warm start (the offset walls, which come first)."""
    ball = read_ball(ctx)
    head, count = int(ctx[L.EN_RHEAD]), int(ctx[L.EN_RCOUNT])
    recent = tuple(float(ctx[L.RECENT + (head + i) % RING]) for i in range(count))
    counts = {key: int(ctx[L.COUNTS + COUNT_KEYS.index(key)]) for key in (*regimes, "resting")}
    warm = []
    for j in range(walls):
        base = L.SURF + j * L.SURF_STRIDE
        warm.append((float(ctx[base + L.S_WS]), float(ctx[base + L.S_WSLOPE])))
    adaptive = ctx[L.FL_KIND] == L.FLIGHT_ADAPTIVE
    return EngineState(
        ball=ball,
        impacts=int(ctx[L.EN_IMPACTS]),
        clock=float(ctx[L.EN_CLOCK]),
        clock_error=float(ctx[L.EN_CLOCK_ERR]),
        zero_flights=int(ctx[L.EN_ZERO]),
        recent=recent,
        counts=counts,
        walls=tuple(warm),
        flight={"step": float(ctx[L.FL_H])} if adaptive else {},
        locator={},
        phase_time={"roll": 0.0, "slide": 0.0, "held": 0.0},
    )


def write_motion(ctx: Any, state: EngineState) -> None:
    """Put the motion state of ``state`` (contact phases: the mode, the contact, the
    time in finished phases, the last impact) into ``ctx``'s machine slots, no phase
    under way (:mod:`billiard.kernels.machine`)."""
    last = state.ball.t if state.last_impact is None else state.last_impact
    put_motion(ctx, state.mode, state.contact, state.phase_time, last)


def put_motion(
    ctx: Any, mode: str, contact: Sequence[float], phase_time: dict[str, float], last: float
) -> None:
    """:func:`write_motion` of its parts (the last impact's time ``last``, s)."""
    ctx[L.MC_MODE] = float(L.MOTION_NAMES.index(mode))
    contact = tuple(contact) + (0.0,) * (6 - len(contact))
    for i, value in enumerate(contact):
        ctx[L.MC_CONTACT + i] = float(value)
    for i, key in enumerate(L.MOTION_NAMES[1:]):
        ctx[L.MC_PHASE_TIME + i] = float(phase_time.get(key, 0.0))
    ctx[L.MC_LAST_IMPACT] = float(last)
    ctx[L.MC_PHASE_ON] = 0.0
    ctx[L.MC_HOLD_ON] = 0.0
    ctx[L.MC_FLYING] = 0.0


def read_motion(ctx: Any) -> dict[str, Any]:
    """The motion state in ``ctx``'s machine slots, as the fields of an
    :class:`EngineState` (``mode``, ``contact``, ``phase_time``, ``last_impact``)."""
    mode = L.MOTION_NAMES[int(ctx[L.MC_MODE])]
    contact = () if mode == "flight" else tuple(float(ctx[L.MC_CONTACT + i]) for i in range(6))
    phase_time = {key: float(ctx[L.MC_PHASE_TIME + i]) for i, key in enumerate(L.MOTION_NAMES[1:])}
    return {
        "mode": mode,
        "contact": contact,
        "phase_time": phase_time,
        "last_impact": float(ctx[L.MC_LAST_IMPACT]),
    }
