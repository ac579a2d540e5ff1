"""The peer a typical user would write: ``scipy.integrate.solve_ivp`` with event functions
for the flights, and the engine's impact law (``KaneLevinsonImpact``) at each event.

One ``solve_ivp`` call per flight, state (q1, q2, u1, u2), the generated right-hand side
(gravity and Fowles drag), one terminal event per surface (its offset-curve gap, falling
through zero), ``atol = rtol`` in SI units (the engine's error norm). The event functions
are the engine's own gap functions, the best geometry the peer could have: what is
compared is the flight integration and the event location. ``max_step`` left at its
default is what a typical user writes. The careful variant also sets ``max_step = T/20``
(T the drive period), so that a short excursion into a wall cannot fall between two steps,
and ``first_step = 1e-6 s``: a flight starts at G = 0 (the contact just resolved), and a
hop that ends within the first step shows no sign change of G.
"""

from __future__ import annotations

import math
import time

import numpy as np
from billiard.generated import ball as _ball
from scipy.integrate import solve_ivp

from billiard.errors import SimulationError
from billiard.models.impact import Contact
from billiard.run.simulate import BallState, Simulation
from billiard.scene.scene import Scene

#: A flight with no event within this time (s) has passed through a wall.
LONGEST_FLIGHT = 10.0
#: This many consecutive flights shorter than 1e-12 s end the run (inelastic collapse).
ZERO_FLIGHTS = 1000


class SolveIvpPeer:
    """Runs of a scene with ``solve_ivp`` flights (see the module docstring)."""

    def __init__(self, scene: Scene, rtol: float, method: str = "DOP853", careful: bool = False):
        self.sim = Simulation(scene)
        self.scene = scene
        self.rtol = rtol
        self.method = method
        drive = self.sim.drive
        self.max_step = drive.period / 20.0 if careful else math.inf
        self.first_step = 1e-6 if careful else None
        self.m, self.g = scene.ball.mass, scene.run.gravity
        self.c_lin, self.c_quad = scene.air.coefficients
        self.theta0 = 0.0
        self.events = [
            self._event(surface, warm)
            for surface, warm in zip(self.sim.boundary.surfaces, self.sim.warm, strict=True)
        ]

    def _rhs(self, t: float, y: np.ndarray) -> tuple[float, float, float, float]:
        a1, a2 = _ball.flight_rhs_drag(y[2], y[3], self.m, self.g, self.c_lin, self.c_quad)
        return y[2], y[3], a1, a2

    def _event(self, surface, warm):
        drive = self.sim.drive

        def gap(t: float, y: np.ndarray) -> float:
            theta = self.theta0 + drive.omega * t
            rel = drive.to_boundary_frame(theta, y[0], y[1], y[2], y[3])
            return surface.gap_rate(*rel, warm)[0]

        gap.terminal = True
        gap.direction = -1
        return gap

    def run(self, state: BallState, impacts: int) -> tuple[dict, float, str]:
        """Simulate from ``state``: (columns t, q1, q2, v1, v2, omega, tof, energy, wall,
        s; CPU s; stop reason or "")."""
        rows = []
        stop = ""
        start = time.process_time()
        try:
            rows = self._loop(state, impacts)
        except _Stop as exc:
            rows, stop = exc.rows, str(exc)
        except (ArithmeticError, ValueError, SimulationError) as exc:
            rows, stop = self._rows, f"{type(exc).__name__}: {exc}"
        cpu = time.process_time() - start
        names = ("t", "q1", "q2", "v1", "v2", "omega", "tof", "energy", "wall", "s")
        columns = {n: np.array([r[i] for r in rows]) for i, n in enumerate(names)}
        return columns, cpu, stop

    def _loop(self, state: BallState, impacts: int) -> list[tuple]:
        sim, drive, law = self.sim, self.sim.drive, self.sim.impact
        surfaces = sim.boundary.surfaces
        scene = self.scene
        m, r, k = scene.ball.mass, scene.ball.radius, scene.ball.inertia_factor
        y = (state.q1, state.q2, state.u1, state.u2)
        u3, t, self.theta0 = state.u3, state.t, state.theta
        rows: list[tuple] = []
        self._rows = rows
        short = 0
        while len(rows) < impacts:
            sol = solve_ivp(
                self._rhs,
                (0.0, LONGEST_FLIGHT),
                y,
                method=self.method,
                rtol=self.rtol,
                atol=self.rtol,
                events=self.events,
                max_step=self.max_step,
                first_step=self.first_step,
            )
            hits = [(te[0], j) for j, te in enumerate(sol.t_events) if len(te)]
            if not hits:
                raise _Stop(f"no impact within {LONGEST_FLIGHT:g} s of flight", rows)
            tau, j = min(hits)
            q1, q2, v1, v2 = sol.y_events[j][0]
            t += tau
            theta = (self.theta0 + drive.omega * tau) % (2.0 * math.pi)
            surface = surfaces[j]
            if surface.kind == "escape":
                raise _Stop("ball escaped", rows)
            px, py, vx, vy = drive.to_boundary_frame(theta, q1, q2, v1, v2)
            s, z, _ = surface.contact(px, sim.warm[j])
            a1, a2 = self._rhs(tau, (q1, q2, v1, v2))[2:]
            ab = drive.acceleration(theta)
            ax, ay = (a1 - ab, a2) if drive.horizontal else (a1, a2 - ab)
            pressing = surface.gap_accel(px, py, vx, vy, ax, ay, sim.warm[j]) < 0.0
            vb1, vb2 = drive.boundary_velocity(theta)
            before = BallState(t, theta, q1, q2, v1, v2, u3)
            res = law.apply(before, Contact(z, vb1, vb2, pressing))
            y, u3, self.theta0 = (q1, q2, res.u1, res.u2), res.u3, theta
            energy = _ball.energy(q2, res.u1, res.u2, res.u3, m, r, k, self.g)
            rows.append((t, q1, q2, res.u1, res.u2, res.u3, tau, energy, surface.label, s))
            short = short + 1 if tau < 1e-12 else 0
            if short >= ZERO_FLIGHTS:
                raise _Stop("inelastic collapse", rows)
        return rows


class _Stop(Exception):
    def __init__(self, reason: str, rows: list[tuple]):
        super().__init__(reason)
        self.rows = rows
