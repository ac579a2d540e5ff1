"""The engine's state: the ball at one instant, and everything the step carries from one
event to the next (what a checkpoint stores, so that a run continues bit for bit)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

from billiard.runfile.checkpoint import CheckpointError

__all__ = ["MOTION_STATES", "BallState", "EngineState"]

#: Motion states of the ball: free flight between impacts, and (``contact.model =
#: "phases"``) rolling and sliding on one wall, or held by two walls at once.
MOTION_STATES: tuple[str, ...] = ("flight", "roll", "slide", "held")


@dataclass(slots=True)
class BallState:
    """State of the ball at one instant: time t (s), drive angle theta (rad, reduced
    modulo 2 pi), centre position (m) and velocity (m/s) in the lab frame, spin u3
    (rad/s) and rotation angle q3 (rad)."""

    t: float
    theta: float
    q1: float
    q2: float
    u1: float
    u2: float
    u3: float
    q3: float = 0.0

    def copy(self) -> BallState:
        return BallState(self.t, self.theta, self.q1, self.q2, self.u1, self.u2, self.u3, self.q3)


@dataclass(slots=True)
class EngineState:
    """Everything the engine carries from one event to the next, after ``impacts``
    impacts: restored into a :class:`~billiard.engine.simulation.Simulation` built from the same
    scene, the run continues with exactly the floating-point operations of an
    uninterrupted one.

    Attributes:
        ball: the ball just after the last impact (or at the start).
        impacts: impacts done (rows recorded), counted from the scene's start.
        clock, clock_error: Neumaier's compensated sum of the flight times and its
            running error term (``ball.t == clock + clock_error``).
        zero_flights: consecutive impacts with zero time of flight so far.
        recent: times of the latest impacts that are still within the collapse
            detector's span of the last one (its window).
        counts: impacts per regime of the impact law, and resting relaunches.
        walls: per offset wall, the Newton warm start of its foot point and the slope
            there (both feed the next flight's search).
        flight: the flight model's memory (the adaptive integrator's step proposal).
        locator: the impact locator's memory (the fixed-step locator's warm starts).
        mode: the ball's motion state (one of :data:`MOTION_STATES`).
        contact: in contact (``roll`` or ``slide``): the wall's surface index, the contact
            abscissa s (m), ds/dt (m/s), the slip sign while sliding, the phase's start
            time and its settle time (s); on the lid, its surface index and, for s and
            ds/dt, the centre's x in the boundary's frame and its velocity along x
            relative to the boundary; held (``held``): the two walls' surface
            indices, the centre (m) in the boundary's frame, the start and settle
            times (s); empty in flight.
        samples: trajectory samples reported so far (``--sample``).
        phase_time: simulated time (s) spent in finished ``roll``, ``slide`` and ``held``
            phases.
        last_impact: contact phases: the time (s) of the last impact, or of the start
            (the contact-span rule, ``run.contact_span``, counts from it); None for the
            impacts model and in checkpoints written before it was kept.
    """

    ball: BallState
    impacts: int
    clock: float
    clock_error: float
    zero_flights: int
    recent: tuple[float, ...]
    counts: dict[str, int]
    walls: tuple[tuple[float, float], ...]
    flight: dict[str, float]
    locator: dict[str, list[float]]
    mode: str = "flight"
    contact: tuple[float, ...] = ()
    samples: int = 0
    phase_time: dict[str, float] = field(default_factory=dict)
    last_impact: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready data (floats stay floats; :mod:`json` writes them with
        :func:`repr`, which reads back to the same double)."""
        return {
            "ball": {f.name: getattr(self.ball, f.name) for f in fields(BallState)},
            "impacts": self.impacts,
            "clock": self.clock,
            "clock_error": self.clock_error,
            "zero_flights": self.zero_flights,
            "recent": list(self.recent),
            "counts": dict(self.counts),
            "walls": [list(pair) for pair in self.walls],
            "flight": dict(self.flight),
            "locator": {key: list(value) for key, value in self.locator.items()},
            "mode": self.mode,
            "contact": list(self.contact),
            "samples": self.samples,
            "phase_time": dict(self.phase_time),
            "last_impact": self.last_impact,
        }

    @classmethod
    def from_dict(cls, data: Any, window: int) -> EngineState:
        """Inverse of :meth:`to_dict`; raises :class:`CheckpointError` on malformed data
        (``window``: the longest collapse window the engine keeps)."""
        try:
            ball = data["ball"]
            names = [f.name for f in fields(BallState)]
            if set(ball) != set(names):
                raise CheckpointError("the engine state's ball has the wrong fields")
            mode = data["mode"]
            if mode not in MOTION_STATES:
                raise CheckpointError(f"its engine state has an unknown motion state {mode!r}")
            state = cls(
                ball=BallState(**{name: _finite(ball[name]) for name in names}),
                impacts=_count(data["impacts"]),
                clock=_finite(data["clock"]),
                clock_error=_finite(data["clock_error"]),
                zero_flights=_count(data["zero_flights"]),
                recent=tuple(_finite(t) for t in data["recent"]),
                counts={str(k): _count(v) for k, v in data["counts"].items()},
                walls=tuple((_finite(s), _finite(slope)) for s, slope in data["walls"]),
                flight={str(k): _finite(v) for k, v in data["flight"].items()},
                locator={str(k): [_finite(x) for x in v] for k, v in data["locator"].items()},
                mode=mode,
                contact=tuple(_finite(x) for x in data.get("contact", ())),
                samples=_count(data.get("samples", 0)),
                phase_time={str(k): _finite(v) for k, v in data.get("phase_time", {}).items()},
                last_impact=_optional(data.get("last_impact")),
            )
        except CheckpointError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise CheckpointError(f"its engine state is malformed ({exc!r})") from None
        if (mode == "flight") != (len(state.contact) == 0) or len(state.contact) not in (0, 6):
            raise CheckpointError("its engine state's contact does not match its motion state")
        if len(state.recent) > window:
            raise CheckpointError("its engine state is malformed (collapse window too long)")
        return state


def _finite(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CheckpointError(f"its engine state holds {value!r} where a number belongs")
    value = float(value)
    if not math.isfinite(value):
        raise CheckpointError("its engine state holds a non-finite number")
    return value


def _optional(value: Any) -> float | None:
    return None if value is None else _finite(value)


def _count(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise CheckpointError(f"its engine state holds {value!r} where a count belongs")
    return value
