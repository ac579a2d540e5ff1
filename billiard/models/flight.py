"""Flight of the ball between impacts, one small class per flight model.

State in flight: position (q1, q2) and velocity (u1, u2) of the centre in the lab frame;
the spin u3 is constant (no aerodynamic torque) and the rotation angle advances as u3 t.
Every model works in the time tau since the flight began and shares one interface:

``begin(q1, q2, u1, u2, u3)``
    start a flight at tau = 0.
``advance(tau_a, tau_target) -> tau_b``
    take one step of the model from tau_a towards tau_target; tau_b <= tau_target is where
    it ended (an error-controlled model may stop short). [tau_a, tau_b] becomes the
    *current segment*.
``state(tau) -> (q1, q2, u1, u2)``
    the state at any tau of the current segment (any tau at all for the exact parabola).
``acceleration(u1, u2) -> (a1, a2)`` and ``aero_bound(speed)``
    the ball's acceleration, and a bound on its non-gravitational part at a given speed.

Models:

* :class:`ExactFlight` - no air forces: the exact parabola (generated ``flight_exact``).
* :class:`AdaptiveFlight` - drag and/or Magnus force: Dormand-Prince 5(4) with error
  control. ``state(tau)`` inside a step re-integrates from the step start with one step of
  the exact length, so an impact state has the full accuracy of a step rather than that of
  an interpolant.
* :class:`RK4Flight` - the paper's fixed-step classical Runge-Kutta scheme (the baseline
  of ``method = "rk4"``), same right-hand side as the adaptive model; its ``step(y, h)``
  is what the paper's fixed-step locator drives, and inside a step ``state(tau)``
  re-integrates from the step start with a shorter step (Baraff's way).

Each is the kernels' flight (:mod:`billiard.kernels.flight`) of its ``kind``
(``FL_KIND``), run interpreted; ``write(ctx)`` puts its block into the engine's state
vector (:mod:`billiard.models.kinds`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, MutableSequence
from typing import Any

from billiard.kernels.interpreted import fixed_step as _fixed_step
from billiard.kernels.interpreted import flight as _flight
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import samples as _samples
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.names import copy, new_ctx, read, write, write_block

__all__ = [
    "FLIGHT_MODELS",
    "AdaptiveFlight",
    "ExactFlight",
    "FlightModel",
    "RK4Flight",
    "flight_model",
    "flight_model_name",
]

State = tuple[float, float, float, float]


def _air_of(scene: Any) -> tuple[float, float, float, float, float]:
    """(g (m/s^2), mass (kg), Fowles c_lin (N s/m), c_quad (N s^2/m^2), Magnus (kg)):
    the arguments a flight model with air forces is built from."""
    c_lin, c_quad = scene.air.coefficients
    return scene.run.gravity, scene.ball.mass, c_lin, c_quad, float(scene.air.magnus)


class FlightModel:
    """Common interface (see the module docstring)."""

    #: longest step the model wants to take (s); the locator never asks for more.
    max_step: float = math.inf

    @classmethod
    def from_scene(cls, scene: Any) -> FlightModel:
        """The model with a scene's coefficients (:data:`FLIGHT_MODELS` builds it so)."""
        raise NotImplementedError

    def begin(self, q1: float, q2: float, u1: float, u2: float, u3: float) -> None:
        raise NotImplementedError

    def advance(self, tau_a: float, tau_target: float) -> float:
        raise NotImplementedError

    def state(self, tau: float) -> State:
        raise NotImplementedError

    def acceleration(self, u1: float, u2: float) -> tuple[float, float]:
        raise NotImplementedError

    def aero_bound(self, speed: float) -> float:
        return 0.0

    def memory(self) -> dict[str, float]:
        """What the model carries from one flight to the next (none here), for a
        checkpoint: restored with :meth:`restore_memory`, a run continues bit for bit."""
        return {}

    def restore_memory(self, memory: Mapping[str, float]) -> None:
        """Set what :meth:`memory` returned (``ValueError`` if it does not fit)."""
        if dict(memory) != self.memory():
            raise ValueError(f"{type(self).__name__} carries no memory between flights")


class _KernelFlight(FlightModel):
    """A flight model whose steps are the kernels' (:mod:`billiard.kernels.flight`, run
    interpreted): its state lives in ``ctx``, a list of floats in the kernels' layout,
    which the event locator copies in and out around a search. ``kind``: its code in
    the kernels (``FL_KIND``), which each subclass names."""

    kind: float

    def __init__(self, gravity: float):
        self.g = float(gravity)
        self.ctx = new_ctx()
        write(self.ctx, "locator.gravity", self.g)
        write(self.ctx, "flight.kind", self.kind)

    def write(self, ctx: MutableSequence[float]) -> None:
        """Write the model's constants and step proposal (its kind first) into a state
        vector, as its own ``ctx`` holds them."""
        copy(ctx, self.ctx, "flight.kind", "flight.step")

    def _air(self, mass: float, c_lin: float, c_quad: float, c_magnus: float) -> None:
        """A model with air forces: its mass (kg), Fowles drag coefficients (N s/m,
        N s^2/m^2) and Magnus coefficient (kg), kept as attributes and in ``ctx``."""
        self.m = float(mass)
        self.c_lin, self.c_quad, self.c_magnus = float(c_lin), float(c_quad), float(c_magnus)
        write_block(
            self.ctx,
            "flight",
            mass=self.m,
            c_lin=self.c_lin,
            c_quad=self.c_quad,
            c_magnus=self.c_magnus,
        )

    def begin(self, q1: float, q2: float, u1: float, u2: float, u3: float) -> None:
        _flight.begin(self.ctx, q1, q2, u1, u2, u3)

    def advance(self, tau_a: float, tau_target: float) -> float:
        return _flight.advance(self.ctx, tau_a, tau_target)

    def state(self, tau: float) -> State:
        return _flight.state(self.ctx, tau)

    def acceleration(self, u1: float, u2: float) -> tuple[float, float]:
        return _flight.acceleration(self.ctx, u1, u2)

    def aero_bound(self, speed: float) -> float:
        return _flight.aero_bound(self.ctx, speed)


class ExactFlight(_KernelFlight):
    """Gravity only: the exact parabola, valid for any tau."""

    kind = _L.FLIGHT_EXACT

    @classmethod
    def from_scene(cls, scene: Any) -> ExactFlight:
        return cls(scene.run.gravity)


class AdaptiveFlight(_KernelFlight):
    """Flight with drag (and optionally the Magnus force): Dormand-Prince 5(4).

    The right-hand side depends on the velocity only, so the velocity stages are
    integrated and the position follows from the same weights applied to the stage
    velocities. Error control on (q1, q2, u1, u2) with ``atol = rtol * (1 m, 1 m/s)``.
    The last stage of an accepted step is the first of the next (FSAL), and the first
    stage of the current step is kept for re-integrations inside it. The step proposal
    (``step_proposal``) carries over from step to step and from flight to flight.
    """

    kind = _L.FLIGHT_ADAPTIVE

    def __init__(
        self,
        gravity: float,
        mass: float,
        c_lin: float,
        c_quad: float,
        c_magnus: float = 0.0,
        rtol: float = 1e-10,
    ):
        super().__init__(gravity)
        self._air(mass, c_lin, c_quad, c_magnus)
        self.rtol = float(rtol)
        write_block(self.ctx, "flight", rtol=self.rtol, step=1e-3)

    @classmethod
    def from_scene(cls, scene: Any) -> AdaptiveFlight:
        return cls(*_air_of(scene), rtol=scene.run.rtol)

    @property
    def step_proposal(self) -> float:
        """The step the next Dormand-Prince step tries (s)."""
        return read(self.ctx, "flight.step")

    @step_proposal.setter
    def step_proposal(self, value: float) -> None:
        write(self.ctx, "flight.step", value)

    def memory(self) -> dict[str, float]:
        # the step proposal outlives a flight: the next flight starts with it
        return {"step": self.step_proposal}

    def restore_memory(self, memory: Mapping[str, float]) -> None:
        step = memory.get("step") if set(memory) == {"step"} else None
        if not (isinstance(step, float) and math.isfinite(step) and step > 0.0):
            raise ValueError(f"AdaptiveFlight memory must be {{'step': h > 0}}, got {memory!r}")
        self.step_proposal = step

    def advance(self, tau_a: float, tau_target: float) -> float:
        ctx = self.ctx
        if tau_a != read(ctx, "flight.tb"):
            raise ValueError("AdaptiveFlight.advance must continue from the last step end")
        try:
            return _flight.advance(ctx, tau_a, tau_target)
        except _L.KernelError as exc:
            # a right-hand side that turned non-finite makes every error estimate fail
            raise _stop(exc, ctx) from None


class RK4Flight(_KernelFlight):
    """Classical fourth-order Runge-Kutta with a fixed step: the paper's scheme
    (:func:`billiard.kernels.fixed_step.rk4_step`, interpreted).

    Used by the fixed-step locator only (``method = "rk4"``); it integrates the same
    right-hand side as :class:`AdaptiveFlight` (gravity only when the air is off, still
    numerically, as the paper did).
    """

    kind = _L.FLIGHT_RK4

    def __init__(
        self,
        gravity: float,
        mass: float,
        c_lin: float,
        c_quad: float,
        c_magnus: float = 0.0,
        step: float = 1e-4,
    ):
        super().__init__(gravity)
        self._air(mass, c_lin, c_quad, c_magnus)
        self.max_step = float(step)
        write(self.ctx, "rk4.step", self.max_step)
        self.begin(0.0, 0.0, 0.0, 0.0, 0.0)

    @classmethod
    def from_scene(cls, scene: Any) -> RK4Flight:
        return cls(*_air_of(scene), step=scene.run.step)

    # the steps are the sample flight's (billiard.kernels.samples), which keeps the last
    # step in its SF_* slots: one copy of the fixed step's sequencing
    def begin(self, q1: float, q2: float, u1: float, u2: float, u3: float) -> None:
        _samples.flight_begin(self.ctx, q1, q2, u1, u2, u3)

    def advance(self, tau_a: float, tau_target: float) -> float:
        if tau_a != read(self.ctx, "samples.rk4_tb"):
            raise ValueError("RK4Flight.advance must continue from the last step end")
        return _samples.flight_advance(self.ctx, tau_a, tau_target)

    def state(self, tau: float) -> State:
        return _samples.flight_state(self.ctx, tau)

    def step(self, y: State, h: float) -> State:
        """One classical RK4 step of length h from y = (q1, q2, u1, u2)."""
        return _fixed_step.rk4_step(self.ctx, *y, h)


#: Flight models by name: classes built from a scene by their ``from_scene``.
FLIGHT_MODELS: dict[str, type[FlightModel]] = {
    "exact": ExactFlight,
    "adaptive": AdaptiveFlight,
    "rk4": RK4Flight,
}


def flight_model_name(scene: Any, method: str = "event") -> str:
    """The flight model a scene needs: the exact parabola when no air force is on, else
    the error-controlled integrator; the fixed-step RK4 for ``method = "rk4"``."""
    if method == "rk4":
        return "rk4"
    c_lin, c_quad = scene.air.coefficients
    if c_lin == 0.0 and c_quad == 0.0 and float(scene.air.magnus) == 0.0:
        return "exact"
    return "adaptive"


def flight_model(scene: Any, method: str = "event") -> FlightModel:
    """Build the flight model :func:`flight_model_name` chooses for a scene."""
    return FLIGHT_MODELS[flight_model_name(scene, method)].from_scene(scene)
