"""The flights between contact phases on the kernels.

Under ``contact.model = "phases"`` the engine (:class:`billiard.engine.simulation.Simulation`) owns
its state in Python: contact phases, holds, landings and lift-offs are its own. The
flights between them are impacts of the impact-only engine, and run on the compiled loop
(:func:`billiard.kernels.loop.run_chunk`) as they do there: :func:`fly` hands the state
to the kernels, runs them until an impact settles on a wall (or the run ends), takes the
state back and lands the ball as the one-event step does (``ContactPhases._land``). The
same operations in the same order as :meth:`billiard.engine.event_step.EventStep._step`: the
same records to the last bit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

from billiard.engine.interrupt import StopRequest
from billiard.kernels import layout as L
from billiard.status import Status

__all__ = ["fly"]


class Settled(NamedTuple):
    """What landing needs of the impact that settles (``ImpactResult``'s fields)."""

    u1: float
    u2: float
    u3: float
    regime: str
    wn: float


def fly(
    sim: Any,
    flights: Any,
    collisions: int,
    recorder: Any,
    progress: Callable[[int, int], None] | None,
    checkpoint: Callable[[Any], None] | None,
    request: StopRequest,
    until: float,
    on_record: Callable[[int], None] | None,
    next_save: float,
) -> tuple[Status, str | None] | None:
    """Fly ``sim`` (in flight, no pending stop) on its kernels ``flights`` (a
    :class:`billiard.engine.kernel_engine.KernelEngine`) until an impact settles or the run
    ends; the arguments are :meth:`Simulation.run`'s. Returns None when the run goes on
    (the ball landed, or flies on when the wall does not press it), else the run's
    (status, stop reason). The next checkpoint's time is left in ``flights.next_save``.
    """
    flights.restore(sim._python_state())
    ctx = flights.ctx
    ctx[L.EN_SETTLES] = 0.0
    # while the kernels fly, the engine's state is theirs (hooks and checkpoints see it)
    sim._kernel = flights
    impacts = sim._impacts
    try:
        status, reason = flights.run(
            collisions, recorder, progress, checkpoint, request, until, on_record,
            next_save=next_save, final_progress=False,
        )  # fmt: skip
    finally:
        sim._kernel = None
        state = dataclasses.replace(flights.state(), **sim._held_state())
        fault, final_time = flights.pending_stop(), sim.final_time
        sim.restore(state)
        sim._fault, sim.final_time = fault, final_time
        if sim._impacts > impacts:
            # the kernels stop after an impact (or leave the state at the last one)
            sim._last_impact = sim._ball.t
    if ctx[L.EN_SETTLES] != 0.0:
        ball = sim._ball
        settled = Settled(
            ball.u1, ball.u2, ball.u3, L.REGIMES[int(ctx[L.EN_LAST_REGIME])],
            float(ctx[L.EN_LAST_WN]),
        )  # fmt: skip
        sim._land(int(ctx[L.EN_LAST_J]), float(ctx[L.EN_LAST_S]), ball.theta, settled, ball.t)
    return None if status is None else (status, reason)
