"""Sustained contact with one wall: rolling and sliding phases (``contact.model = "phases"``).

While the ball touches one wall its centre lies on the wall's offset curve (gap exactly
zero by construction): the state is the contact point's abscissa s (m) in the boundary's
frame, its rate s_dot (m/s) and, while sliding, the spin u3 (rad/s). The equations are the
generated ones of :mod:`billiard.generated.contact` (docs/derivation.md sections 9-14),
integrated by a Dormand-Prince 5(4) pair with step-size control (``run.rtol``) and its
fourth-order continuous extension, on which the phase's end is located:

* ``lift-off``: the normal force N falls through zero (the ball flies);
* ``slip``: rolling, |F| reaches mu_s N (the ball starts sliding);
* ``roll``: sliding, the slip velocity reaches zero (rolling starts if |F| <= mu_s N
  can hold, else the ball slides the other way);
* ``wall-end``: s leaves the wall's interval [lo, hi] (a kink, the end of the curve):
  the ball flies on from there;
* ``impact``: the centre reaches another wall's offset curve (the wedge's vertex) or
  the lid: the engine applies the impact law there (at the escape level of an open
  container the run ends). A phase that starts on the other wall's offset
  curve too (in the vertex, where that gap is zero to rounding and may be -1e-18 m)
  ends there at once when the centre moves into that wall (by more than 1e-12 m).

Each end is a root of a smooth function of time found by bisection-secant (Illinois) on
the dense output to 1e-13 s.

The numerics are the kernels of :mod:`billiard.kernels.contact`, run interpreted (the
twin :mod:`billiard.kernels_py`): :meth:`ContactModel.run_phase` fills the kernels' state
vector, runs the phase from one sample time to the next, and words the kernels' stops as
before.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.errors import BallAtRest, SimulationError
from billiard.geometry.drive import Drive
from billiard.kernels.interpreted import contact as _k
from billiard.kernels.interpreted import contact_equations as _c
from billiard.kernels.interpreted import contact_forces as _f
from billiard.kernels.interpreted import kernel_errors
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.interpreted import stop as _stop
from billiard.kernels.names import (
    new_ctx,
    put_surface_block,
    put_warm_s,
    read,
    read_slots,
    read_surface,
    write,
    write_block,
    write_slots,
)
from billiard.status import Status

__all__ = ["CONTACT_MODES", "ContactModel", "PhaseEnd", "Watched"]

#: the contact modes (motion states other than flight)
CONTACT_MODES = ("roll", "slide")

#: time resolution (s) of a phase's end
EVENT_TOL = _k.EVENT_TOL
#: see :data:`billiard.kernels.contact.CONTACT_GAP`
CONTACT_GAP = _k.CONTACT_GAP

Vec = tuple[float, ...]
#: a surface a phase watches, with the engine's warm start of it (updated in place)
Watched = tuple[Any, list]


_KERNEL_ERRORS = kernel_errors()
#: phases run by the compiled kernels (else by the twin, interpreted: the same bits)
COMPILED = _jit.ENABLED
#: the numbers of walls the compiled phase was called with in this process
_CALLED: set[int] = set()

#: accepted steps between two pauses of a phase (a stop request is looked at, progress
#: reported): some milliseconds compiled, a tenth of a second interpreted
PAUSE_STEPS = 1000.0

#: why a phase ends, by the kernels' condition index (3: friction; 4 and up: impact)
_REASONS = ("lift-off", "wall-end", "wall-end")


@dataclass(slots=True)
class PhaseEnd:
    """How a contact phase ended: after ``tau`` seconds, for ``reason`` (one of
    ``lift-off``, ``slip``, ``roll``, ``wall-end``, ``impact``, or ``None`` when the
    time limit came first or the caller stopped it, ``cut``), with the contact state
    ``y`` = (s, s_dot[, u3]) then; for ``impact`` the other wall's index in ``other``."""

    tau: float
    reason: str | None
    y: Vec
    other: int = -1
    #: stopped where it was by the caller (a pause's answer, or ``stop_at``)
    cut: bool = False


class ContactModel:
    """The contact equations of one scene: ball, gravity, drag, friction and drive.

    Args:
        scene: a :class:`billiard.scene.scene.Scene`.
        drive: the boundary's drive.

    Attributes:
        steps: accepted integration steps of all phases run so far (they bound a
            phase's accumulated error; the soak's energy audit reads them).
    """

    def __init__(self, scene: Any, drive: Drive):
        ball = scene.ball
        self.m = float(ball.mass)
        self.r = float(ball.radius)
        self.k = float(ball.inertia_factor)
        self.g = float(scene.run.gravity)
        self.c_lin, self.c_quad = (float(c) for c in scene.air.coefficients)
        self.mu_s = float(scene.contact.mu_static)
        self.mu_k = float(scene.contact.mu_kinetic)
        self.e = float(scene.contact.restitution)
        self.rtol = float(scene.run.rtol)
        self.drive = drive
        self.static = drive.static
        self.steps = 0
        # the kernels' state vector of a phase, and one for single force evaluations
        # (a query between two calls of a phase must not touch the phase's state)
        self.ctx = self.new_ctx()
        self._query = self.new_ctx()
        self._walls: dict[tuple[int, ...], tuple] = {}
        self._compiled: dict[tuple[int, ...], tuple] = {}

    def new_ctx(self) -> list[float]:
        """A state vector of the kernels (a list) with this scene's drive and contact
        constants set (a phase's, and a hold's in :mod:`billiard.models.hold`)."""
        ctx = new_ctx()
        self.drive.write(ctx)
        write_block(
            ctx,
            "phase",
            mass=self.m,
            radius=self.r,
            inertia_factor=self.k,
            gravity=self.g,
            c_lin=self.c_lin,
            c_quad=self.c_quad,
            mu_static=self.mu_s,
            mu_kinetic=self.mu_k,
            rtol=self.rtol,
            pause_steps=math.inf,
            pause_t=math.inf,
        )
        return ctx

    def wall_functions(self, wall: Any, others: Sequence[Watched] = ()) -> tuple:
        """(f, df, d2f, d3f) as the kernels take them: one entry per wall index of the
        curve, the phase's wall and the watched walls at their indices (an index that is
        neither, never called, holds the phase's wall)."""
        walls = [wall] + [s.wall for s, _ in others if s.kind == "wall"]
        key = tuple(id(w) for w in walls)
        functions = self._walls.get(key)
        if functions is None:
            by_index = {w.index: w for w in walls}
            row = [by_index.get(i, wall) for i in range(max(by_index) + 1)]
            functions = (
                tuple(w.f for w in row),
                tuple(w.df for w in row),
                tuple(w.d2f for w in row),
                tuple(w.d3f for w in row),
            )
            self._walls[key] = functions
        return functions

    # ------------------------------------------------------------------ kinematics

    def boundary(self, theta: float) -> tuple[float, float, float, float, float, float]:
        """(d1, d2, vb1, vb2, ab1, ab2): the boundary's displacement (m), velocity (m/s)
        and acceleration (m/s^2) in the lab frame at drive angle theta."""
        dr = self.drive
        d, v, a = dr.displacement(theta), dr.velocity(theta), dr.acceleration(theta)
        if dr.horizontal:
            return d, 0.0, v, 0.0, a, 0.0
        return 0.0, d, 0.0, v, 0.0, a

    def geometry(self, wall: Any, s: float) -> tuple[float, float, float, float]:
        """(f, f', f'', f''') of the wall at s (m, -, 1/m, 1/m^2)."""
        p = wall.p
        return wall.f(s, p), wall.df(s, p), wall.d2f(s, p), wall.d3f(s, p)

    def forces(self, wall: Any, mode: str, sgn: float, theta: float, y: Vec) -> tuple:
        """(s_ddot, u3_dot, N, F): u3_dot is that of the no-slip spin while rolling."""
        ctx = self._query
        write_block(
            ctx,
            "phase",
            wall=float(wall.index),
            mode=_L.ROLL if mode == "roll" else _L.SLIDE,
            slip_sign=sgn,
        )
        return _f.forces(ctx, wall.p, self.wall_functions(wall), theta, y[0], y[1])

    def spin(self, wall: Any, y: Vec, mode: str) -> float:
        """The spin u3 (rad/s): the no-slip value while rolling."""
        if mode == "roll":
            _, fp, f2, _ = self.geometry(wall, y[0])
            return _c.roll_spin(y[1], fp, f2, self.r)
        return y[2]

    def slip(self, wall: Any, s: float, sd: float, u3: float) -> float:
        _, fp, f2, _ = self.geometry(wall, s)
        return _c.slip_velocity(sd, u3, fp, f2, self.r)

    def lab_state(self, wall: Any, theta: float, y: Vec, mode: str) -> tuple[float, ...]:
        """(q1, q2, u1, u2, u3): the centre's lab state (m, m/s) and the spin (rad/s)."""
        s, sd = y[0], y[1]
        f0, fp, f2, _ = self.geometry(wall, s)
        d1, d2, vb1, vb2, _, _ = self.boundary(theta)
        q1, q2, u1, u2 = _c.centre_state(s, sd, f0, fp, f2, d1, d2, vb1, vb2, self.r)
        return q1, q2, u1, u2, self.spin(wall, y, mode)

    def s_dot(self, wall: Any, theta: float, s: float, u1: float, u2: float) -> float:
        """ds/dt (m/s) of a centre at s with the lab velocity (u1, u2)."""
        _, fp, f2, _ = self.geometry(wall, s)
        _, _, vb1, vb2, _, _ = self.boundary(theta)
        return _c.s_dot_of_velocity(u1, u2, fp, f2, vb1, vb2, self.r)

    def mode_for(
        self, wall: Any, theta: float, s: float, sd: float, u3: float
    ) -> tuple[str, float]:
        """The contact mode (and slip sign) of a ball at (s, s_dot, u3): rolling when the
        slip vanishes (to rounding) and static friction can hold it, else sliding."""
        _, fp, f2, _ = self.geometry(wall, s)
        w = _c.slip_velocity(sd, u3, fp, f2, self.r)
        scale = abs(sd) * math.sqrt(1.0 + fp * fp) + self.r * abs(u3)
        if abs(w) <= 1e-12 + 1e-9 * scale:
            _, _, n, f = self.forces(wall, "roll", 0.0, theta, (s, sd))
            if abs(f) <= self.mu_s * n:
                return "roll", 0.0
            return "slide", (-1.0 if f > 0.0 else 1.0)
        return "slide", (1.0 if w > 0.0 else -1.0)

    # ------------------------------------------------------------------ a phase

    def run_phase(
        self,
        wall: Any,
        mode: str,
        sgn: float,
        theta0: float,
        y0: Vec,
        limit: float,
        others: Sequence[Watched] = (),
        samples: Iterable[float] = (),
        on_sample: Callable[[float, Vec], None] | None = None,
        pause: Callable[[float], bool] | None = None,
        stop_at: float = math.inf,
        interval: tuple[float, float] | None = None,
    ) -> PhaseEnd:
        """Integrate one contact phase from y0 at drive angle theta0 for at most
        ``limit`` seconds (:func:`billiard.kernels.contact.advance`).

        Args:
            others: the other surfaces (walls, lid, escape level), each with the
                engine's warm start of it (a wall's ``[s, slope]``, whose s the phase
                moves as it evaluates that wall's offset height); the centre's reaching
                one (a wall's offset curve, the lid's level less r, the escape level)
                is an ``impact``.
            samples: increasing times (s, from the phase's start; an iterable, read as
                far as the phase goes) at which to report the state to
                ``on_sample(tau, y)``.
            pause: called as ``pause(tau)`` between two steps every
                :data:`PAUSE_STEPS` steps (tau: s from the phase's start); when it
                returns True the phase stops there (a ``cut`` end: reason None,
                ``cut`` True). The pauses leave the integration as it is: the phase's
                steps and end are those of a phase run without them.
            stop_at: the phase stops (a ``cut`` end) at the first step boundary at or
                after this time (s from the phase's start), without changing a step
                (a ball then at rest relative to the boundary goes on until the kernel
                finds it at rest for good, or moving again).
            interval: the abscissas (m) where the phase ends with ``wall-end``
                (default the wall's interval [lo, hi]).
        """
        ctx = self.ctx
        walls = self.wall_functions(wall, others)
        roll = mode == "roll"
        n_y = 2 if roll else 3
        lo, hi = (wall.lo, wall.hi) if interval is None else interval
        samples = iter(samples)
        # the phase's own wall is surface 0 (not watched), the others follow in order
        write_block(
            ctx,
            "phase",
            wall=float(wall.index),
            lo=lo,
            hi=hi,
            mode=_L.ROLL if roll else _L.SLIDE,
            slip_sign=sgn,
            theta0=theta0,
            limit=limit,
            surface=0.0,
            next_sample=next(samples, math.inf) if on_sample is not None else math.inf,
            steps=0.0,
            pause_steps=PAUSE_STEPS if pause is not None else math.inf,
            pause_t=stop_at,
        )
        write_slots(ctx, "phase.y", (y0[0], y0[1], 0.0 if roll else y0[2]))
        write(ctx, "locator.surfaces", float(1 + len(others)))
        curved = []
        for j, (surface, warm) in enumerate(others, 1):
            put_surface_block(ctx, j, surface.block())
            if read_surface(ctx, j, "kind") == _L.CURVED:
                put_warm_s(ctx, j, warm[0])
                curved.append((j, warm))
        p = wall.p
        cut = False
        try:
            if COMPILED:
                state, call = self._compiled_entry(wall, others)
            else:
                state = ctx

                def call(start: bool) -> int:
                    if start:
                        _k.begin(ctx, p, walls)
                    return _k.advance(ctx, p, walls)

            try:
                status = call(True)
                while status == _L.PHASE_SAMPLE or status == _L.PHASE_PAUSE:
                    if status == _L.PHASE_SAMPLE:
                        y = read_slots(state, "phase.sample_y", n_y)
                        on_sample(read(state, "phase.sample_t"), y)  # type: ignore[misc]
                        write(state, "phase.next_sample", next(samples, math.inf))
                    else:
                        tau = read(state, "phase.tau")
                        if pause is not None and pause(tau):
                            cut = True
                            break
                        steps = read(state, "phase.steps")
                        if tau < stop_at:
                            write(state, "phase.pause_steps", steps + PAUSE_STEPS)
                        elif read(state, "phase.rest_since") == math.inf:
                            cut = True  # moving at stop_at
                            break
                        else:
                            # at rest relative to the boundary: on to the kernel's at-rest
                            # stop (within a drive period), looked at after every step
                            write_block(state, "phase", pause_t=math.inf, pause_steps=steps + 1.0)
                    status = call(False)
            finally:
                if state is not ctx:
                    ctx[:] = state.tolist()
        except _KERNEL_ERRORS as exc:
            raise self._stop(exc) from None
        finally:
            for j, warm in curved:
                warm[0] = read_surface(ctx, j, "warm_s")
            self.steps += int(read(ctx, "phase.steps"))
        if cut:
            return PhaseEnd(read(ctx, "phase.tau"), None, read_slots(ctx, "phase.y", n_y), cut=True)
        if status == _L.PHASE_LIMIT:
            return PhaseEnd(limit, None, read_slots(ctx, "phase.y", n_y))
        i = int(read(ctx, "phase.end_condition"))
        if i < 3:
            reason = _REASONS[i]
        elif i == 3:
            reason = "slip" if roll else "roll"
        else:
            reason = "impact"
        end_y = read_slots(ctx, "phase.end_y", n_y)
        return PhaseEnd(read(ctx, "phase.end_t"), reason, end_y, i - 4 if i >= 4 else -1)

    def _compiled_entry(
        self, wall: Any, others: Sequence[Watched]
    ) -> tuple[np.ndarray, Callable[[bool], int]]:
        """The phase set up in ``self.ctx`` as a float64 copy, and the compiled kernels'
        call on it (:func:`billiard.kernels.contact.run_phase`; ``call(start)``): the
        caller copies the array back into ``self.ctx`` (also after a stop), so that the
        rest reads Python floats as before."""
        from billiard.kernels.contact import run_phase

        walls, first = self._compiled_walls(wall, others)
        state = np.array(self.ctx, dtype=np.float64)
        p = np.array(wall.p, dtype=np.float64)

        def call(start: bool) -> int:
            nonlocal first
            if first:
                first = False
                with _jit.compiling(run_phase):
                    return run_phase(state, p, walls, start)
            return run_phase(state, p, walls, start)

        return state, call

    def _compiled_walls(self, wall: Any, others: Sequence[Watched]) -> tuple[tuple, bool]:
        """The phase's wall functions as compiled function values, and whether this is
        the process's first phase with their number of walls (whose first call of the
        compiled kernel may compile it: with the compile notices)."""
        from billiard.geometry.wall_functions import WallFunction, WallTable

        functions = self.wall_functions(wall, others)
        key = tuple(id(f) for f in functions[0])
        walls = self._compiled.get(key)
        if walls is None:
            walls = WallTable(tuple(WallFunction(f) for f in row) for row in functions)
            self._compiled[key] = walls
        # the wall functions are typed by their signature alone: one compile per count
        first = len(walls[0]) not in _CALLED
        _CALLED.add(len(walls[0]))
        return walls, first

    def _stop(self, exc: Exception) -> SimulationError:
        """The error a kernel's stop stands for, worded as before."""
        code = exc.args[0]
        if code == _L.E_AT_REST:
            return BallAtRest(read(self.ctx, "phase.rest_since"))
        if code == _L.E_PHASE_STEPS:
            return SimulationError(
                "the contact phase's step-size control failed (60 rejected steps)",
                Status.SOLVER_FAILED,
            )
        return _stop(exc, self.ctx)
