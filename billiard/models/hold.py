"""Held in a vertex: the ball touching two walls at once (``contact.model = "phases"``).

In the wedge's vertex (or any kink of a curve whose two walls the ball touches together)
the centre sits where the two offset curves meet, a point P fixed in the boundary's frame:
the ball moves with the boundary and only its spin u3 is free. Two holonomic constraints
fix the centre, so the contact forces follow from the centre's equation of motion alone
(Newton-Euler; two walls with two unknown normal forces, statically determinate):

    N_a (n_a - mu_k sigma t_a) + N_b (n_b - mu_k sigma t_b) = m (a_b - g) - D(v_b)

with n, t the unit normal (into the ball) and tangent (c2, c1) of each wall at its
contact point, a_b and v_b the boundary's acceleration and velocity, g = (0, -g), D the
Fowles drag on the centre (moving at v_b), and sigma = sign(u3). Each contact point then
slips at r u3 along its tangent, so kinetic friction -mu_k N sigma acts at both, and the
spin obeys I du3/dt = r (F_a + F_b) = -r mu_k sigma (N_a + N_b): it decays to zero and
then stays zero (static friction, which then needs no force: F_a = F_b = 0 is the
choice of the statically indeterminate split; any other split with F_a = -F_b moves
nothing). The hold ends (``release``) when a normal force falls through zero: the ball
goes on on the other wall, or flies if both release together.

The forces are exact functions of the drive angle, so a release is located by root
refinement on them (to ``EVENT_TOL``); the spin's decay integrates the forces with
Simpson's rule over steps of at most 1/64 drive period (exact on a static boundary,
where the forces are constant).

The numerics are the kernels of :mod:`billiard.kernels.vertex`, compiled when numba is
there (one call of ``run_hold`` per hold and per sample, on a float64 copy of the state
vector) and otherwise interpreted (the twin :mod:`billiard.kernels_py`), as a contact
phase's: :meth:`VertexHold.run_hold` fills the kernels' state vector, runs the hold from
one sample time to the next, and words the kernels' stop as before. The force queries
(``forces``, ``holds``) call the twin: a compiled call costs more than they do.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from billiard import jit as _jit
from billiard.errors import BallAtRest
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import vertex as _k
from billiard.kernels.names import read, write, write_block
from billiard.models import contact as _phase
from billiard.models.contact import _KERNEL_ERRORS, ContactModel

__all__ = ["EVENT_TOL", "HELD", "HoldEnd", "VertexHold"]

#: the motion state of a ball held by two walls
HELD = "held"
#: time resolution (s) of a release
EVENT_TOL = _k.EVENT_TOL
#: the compiled hold was called in this process (its first call may compile it)
_CALLED = False


@dataclass(slots=True)
class HoldEnd:
    """How a hold ended: after ``tau`` seconds, ``reason`` ``"release"`` (or None when
    the time limit came first), the spin ``u3`` (rad/s) then, and which walls still
    press: ``keeps`` = 0 (the first), 1 (the second) or -1 (neither: the ball flies)."""

    tau: float
    reason: str | None
    u3: float
    keeps: int = -1


class VertexHold:
    """The forces and the spin of a ball held by two walls of one scene.

    Args:
        model: the scene's :class:`~billiard.models.contact.ContactModel` (ball, gravity,
            drag, friction and drive: the same constants as rolling and sliding).
    """

    def __init__(self, model: ContactModel):
        self.m, self.r, self.k, self.g = model.m, model.r, model.k, model.g
        self.c_lin, self.c_quad = model.c_lin, model.c_quad
        self.mu_k = model.mu_k
        self.drive = model.drive
        self.static = model.static
        # the kernels' state vector: the phase's constants and the hold's slots (the
        # force queries read only the constants, so they share it)
        self.ctx = model.new_ctx()

    def forces(self, za: float, zb: float, theta: float, sigma: float) -> tuple[float, float]:
        """(N_a, N_b): the normal forces (N) of the two walls, tangent angles za and zb
        (rad) at their contact points, at drive angle theta, spin sign sigma."""
        return _k.forces(self.ctx, za, zb, theta, sigma)

    def holds(self, za: float, zb: float, theta: float, u3: float) -> bool:
        """Do both walls press a ball with spin u3 (rad/s) at drive angle theta?"""
        return _k.holds(self.ctx, za, zb, theta, u3)

    def held_spin(self, za: float, zb: float, theta: float, u3: float) -> float:
        """The spin (rad/s) with which both walls hold a ball arriving with spin u3, or
        NaN where they cannot (:func:`billiard.kernels.vertex.held_spin`)."""
        return _k.held_spin(self.ctx, za, zb, theta, u3)

    def pressing(self, za: float, zb: float, theta: float, u3: float) -> tuple[float, float]:
        """(N_a, N_b) on a ball with spin u3 (rad/s): the forces :meth:`holds` looks at."""
        return _k.forces(self.ctx, za, zb, theta, _k.sign(u3))

    def spin_rate(self, n_a: float, n_b: float, sigma: float) -> float:
        """du3/dt (rad/s^2) from the kinetic friction of both walls."""
        return _k.spin_rate(self.ctx, n_a, n_b, sigma)

    def run_hold(
        self,
        za: float,
        zb: float,
        theta0: float,
        u3: float,
        limit: float,
        samples: Iterable[float] = (),
        on_sample: Callable[[float, float], None] | None = None,
        pause: Callable[[float], bool] | None = None,
    ) -> HoldEnd:
        """Hold the ball from drive angle theta0 with spin u3 for at most ``limit``
        seconds (:func:`billiard.kernels.vertex.advance`); report ``on_sample(tau, u3)``
        at the sample times (s from the start; an iterable, read as far as the hold
        goes). ``pause(tau)`` is called after each sample: True stops the hold there
        (reason None, as at the time limit; a stop request of a sampled run).

        Raises:
            BallAtRest: no time limit, the spin is zero and no release comes within a
                drive period (or at all, on a static boundary).
        """
        ctx = self.ctx
        samples = iter(samples)
        first = next(samples, math.inf) if on_sample is not None else math.inf
        write_block(
            ctx, "hold", za=za, zb=zb, theta0=theta0, limit=limit, spin=u3, next_sample=first
        )
        try:
            if _phase.COMPILED:  # compiled as the phases are
                status = self._run_compiled(samples, on_sample, pause)
            else:
                _k.begin(ctx)
                status = _k.advance(ctx)
                while status == _L.PHASE_SAMPLE:
                    tau = read(ctx, "hold.sample_t")
                    on_sample(tau, read(ctx, "hold.sample_spin"))  # type: ignore[misc]
                    if pause is not None and pause(tau):
                        break
                    write(ctx, "hold.next_sample", next(samples, math.inf))
                    status = _k.advance(ctx)
        except _KERNEL_ERRORS as exc:
            if exc.args[0] == _L.E_AT_REST:
                raise BallAtRest(read(ctx, "hold.rest_since")) from None
            raise
        if status == _L.PHASE_SAMPLE:  # paused at the sample
            return HoldEnd(read(ctx, "hold.sample_t"), None, read(ctx, "hold.sample_spin"))
        end_spin = read(ctx, "hold.end_spin")
        if status == _L.PHASE_LIMIT:
            return HoldEnd(limit, None, end_spin)
        return HoldEnd(read(ctx, "hold.end_t"), "release", end_spin, int(read(ctx, "hold.keeps")))

    def _run_compiled(
        self,
        samples: Iterator[float],
        on_sample: Callable[[float, float], None] | None,
        pause: Callable[[float], bool] | None,
    ) -> int:
        """The hold set up in ``self.ctx``, run by the compiled kernels
        (:func:`billiard.kernels.vertex.run_hold`) on a float64 copy of it, copied back
        (also after a stop) so that the rest reads Python floats as before."""
        global _CALLED
        from billiard.kernels.vertex import run_hold

        ctx = self.ctx
        state = np.array(ctx, dtype=np.float64)
        try:
            if _CALLED:
                status = run_hold(state, True)
            else:
                _CALLED = True
                with _jit.compiling(run_hold):
                    status = run_hold(state, True)
            while status == _L.PHASE_SAMPLE:
                tau = read(state, "hold.sample_t")
                on_sample(tau, read(state, "hold.sample_spin"))  # type: ignore[misc]
                if pause is not None and pause(tau):
                    break
                write(state, "hold.next_sample", next(samples, math.inf))
                status = run_hold(state, False)
        finally:
            ctx[:] = state.tolist()
        return status
