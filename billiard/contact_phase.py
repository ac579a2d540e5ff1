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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from billiard.drive import Drive
from billiard.errors import BallAtRest, SimulationError
from billiard.generated import contact as _c
from billiard.status import Status

__all__ = ["CONTACT_MODES", "ContactModel", "PhaseEnd", "first_root", "skip_periods"]

#: the contact modes (motion states other than flight)
CONTACT_MODES = ("roll", "slide")

#: time resolution (s) of a phase's end
EVENT_TOL = 1e-13
#: A phase that starts touching another wall (its gap zero to rounding, possibly just
#: below zero, as in the wedge's vertex) ends with an impact there at once when the
#: centre then goes deeper into it than this (m; the impact locator's resolution).
CONTACT_GAP = 1e-12
#: absolute error allowed per step on s (m), s_dot (m/s) and u3 (rad/s), added to
#: rtol times the size of each
_ATOL = (1e-12, 1e-12, 1e-9)

# Dormand-Prince 5(4) (Dormand & Prince 1980) and its 4th-order continuous extension
# (Shampine 1986; the coefficients scipy's RK45 uses).
_C = (0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0)
_A = (
    (),
    (1 / 5,),
    (3 / 40, 9 / 40),
    (44 / 45, -56 / 15, 32 / 9),
    (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
    (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
)
_B = (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84)
_E = (-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40)
_P = (
    (1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432),
    (0.0, 0.0, 0.0, 0.0),
    (0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799),
    (0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072),
    (
        0.0,
        127303824393 / 49829197408,
        -318862633887 / 49829197408,
        701980252875 / 199316789632,
    ),
    (0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844),
    (0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423),
)

Vec = tuple[float, ...]


@dataclass(slots=True)
class PhaseEnd:
    """How a contact phase ended: after ``tau`` seconds, for ``reason`` (one of
    ``lift-off``, ``slip``, ``roll``, ``wall-end``, ``impact``, or ``None`` when the
    time limit came first), with the contact state ``y`` = (s, s_dot[, u3]) then; for
    ``impact`` the other wall's index in ``other``."""

    tau: float
    reason: str | None
    y: Vec
    other: int = -1


class ContactModel:
    """The contact equations of one scene: ball, gravity, drag, friction and drive.

    Args:
        scene: a :class:`billiard.scene.Scene`.
        drive: the boundary's drive.
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
        self.static = drive.amplitude == 0.0 or drive.omega == 0.0

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
        s, sd = y[0], y[1]
        _, fp, f2, f3 = self.geometry(wall, s)
        _, _, vb1, vb2, ab1, ab2 = self.boundary(theta)
        m, r, k, g = self.m, self.r, self.k, self.g
        if mode == "roll":
            sdd, n, f = _c.roll_rhs(sd, fp, f2, f3, ab1, ab2, vb1, vb2, m, r, k, g,
                                    self.c_lin, self.c_quad)  # fmt: skip
            return sdd, 0.0, n, f
        return _c.slide_rhs(sd, fp, f2, f3, ab1, ab2, vb1, vb2, m, r, k, g,
                            self.c_lin, self.c_quad, self.mu_k, sgn)  # fmt: skip

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
        gaps: Sequence[Callable[[float, float], float]] = (),
        samples: Iterable[float] = (),
        on_sample: Callable[[float, Vec], None] | None = None,
    ) -> PhaseEnd:
        """Integrate one contact phase from y0 at drive angle theta0 for at most
        ``limit`` seconds.

        Args:
            gaps: for each other surface (wall, lid, escape level), gap(px, py) (m)
                of the centre (relative to the boundary) from it (a wall's offset curve,
                the lid's level less r, the escape level); its zero is an ``impact``.
            samples: increasing times (s, from the phase's start; an iterable, read as
                far as the phase goes) at which to report the state to
                ``on_sample(tau, y)``.
        """
        omega = self.drive.omega
        lo, hi = wall.lo, wall.hi
        mu_s = self.mu_s
        frictionless = mu_s == 0.0
        n_y = 2 if mode == "roll" else 3
        y0 = tuple(y0[:n_y])

        def rhs(tau: float, y: Vec) -> Vec:
            sdd, u3d, _, _ = self.forces(wall, mode, sgn, theta0 + omega * tau, y)
            return (y[1], sdd) if n_y == 2 else (y[1], sdd, u3d)

        def conditions(tau: float, y: Vec) -> list[float]:
            """Functions positive while the phase lasts, by end reason."""
            theta = theta0 + omega * tau
            _, _, n, f = self.forces(wall, mode, sgn, theta, y)
            out = [n, y[0] - lo, hi - y[0]]
            if mode == "roll":
                out.append(mu_s * n - abs(f))
            elif frictionless:
                out.append(1.0)  # no friction: the slip's sign changes nothing
            else:
                out.append(sgn * self.slip(wall, y[0], y[1], y[2]))
            if gaps:
                s, sd = y[0], y[1]
                f0, fp, f2, _ = self.geometry(wall, s)
                px, py, _, _ = _c.centre_state(s, sd, f0, fp, f2, 0.0, 0.0, 0.0, 0.0, self.r)
                out.extend(gap(px, py) for gap in gaps)
            return out

        reasons = ["lift-off", "wall-end", "wall-end", "slip" if mode == "roll" else "roll"]
        reasons += ["impact"] * len(gaps)
        rtol = self.rtol
        atol = _ATOL[:n_y]

        tau, y = 0.0, y0
        k1 = rhs(0.0, y)
        scale = max(abs(k1[0]), abs(k1[1]), 1e-3)
        h = min(limit, 1e-3 / scale + 1e-4) if limit > 0.0 else 0.0
        c_prev = conditions(0.0, y)
        samples = iter(samples)
        next_sample = next(samples, math.inf)
        steps = 0
        # the step is at most 1/20 of the drive period, so that the conditions, which
        # the drive moves, cannot change sign twice unseen within a step
        h_max = math.inf if self.static else 0.1 * math.pi / abs(omega)
        rest_span = 0.0 if self.static else 2.0 * math.pi / abs(omega)
        rest_since = 0.0 if _at_rest(k1) else math.inf
        while tau < limit:
            h = min(h, limit - tau, h_max)
            for _ in range(60):
                ks = [k1]
                for i in range(1, 6):
                    a = _A[i]
                    yi = tuple(
                        y[j] + h * sum(a[q] * ks[q][j] for q in range(i)) for j in range(n_y)
                    )
                    ks.append(rhs(tau + _C[i] * h, yi))
                y_new = tuple(
                    y[j] + h * sum(_B[q] * ks[q][j] for q in range(6)) for j in range(n_y)
                )
                k7 = rhs(tau + h, y_new)
                ks.append(k7)
                err = 0.0
                for j in range(n_y):
                    e = h * sum(_E[q] * ks[q][j] for q in range(7))
                    sc = atol[j] + rtol * max(abs(y[j]), abs(y_new[j]))
                    err = max(err, abs(e) / sc)
                if err <= 1.0:
                    break
                h *= max(0.2, 0.9 * err**-0.2)
            else:
                raise SimulationError(
                    "the contact phase's step-size control failed (60 rejected steps)",
                    Status.SOLVER_FAILED,
                )
            steps += 1
            t_a, y_a, h_step = tau, y, h

            def dense(t: float, t_a: float = t_a, y_a: Vec = y_a, h_step: float = h_step,
                      ks: list = ks, y_b: Vec = y_new) -> Vec:  # fmt: skip
                x = (t - t_a) / h_step
                if x == 1.0:
                    return y_b
                w = [x * (p[0] + x * (p[1] + x * (p[2] + x * p[3]))) for p in _P]
                return tuple(
                    y_a[j] + h_step * sum(w[q] * ks[q][j] for q in range(7)) for j in range(n_y)
                )

            t_b = tau + h
            c_new = conditions(t_b, y_new)
            crossed = [
                i
                for i, (a, b) in enumerate(zip(c_prev, c_new, strict=True))
                if a > 0.0 >= b
                or (a == 0.0 and b < 0.0)
                # another wall touched at the start (the wedge's vertex: its gap is 0
                # to rounding, either sign) and then entered: an impact at the start
                or (i >= 4 and a < 0.0 and b < -CONTACT_GAP)
            ]
            end_t, end_y, end_i = t_b, y_new, -1
            if crossed:
                best = None
                for i in crossed:
                    t_root = first_root(
                        lambda t, i=i: conditions(t, dense(t))[i], t_a, t_b, c_prev[i]
                    )
                    if best is None or t_root < best[0]:
                        best = (t_root, i)
                end_t, end_i = best
                end_y = dense(end_t)
            if on_sample is not None:
                while next_sample <= end_t:
                    ts = next_sample
                    on_sample(ts, dense(ts) if ts > t_a else y_a)
                    next_sample = next(samples, math.inf)
            if end_i >= 0:
                other = end_i - 4 if reasons[end_i] == "impact" else -1
                return PhaseEnd(end_t, reasons[end_i], end_y, other)
            tau, y, k1, c_prev = t_b, y_new, k7, c_new
            factor = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err**-0.2))
            h *= factor
            if not _at_rest(k1):
                rest_since = math.inf
            elif rest_since == math.inf:
                rest_since = tau
            if math.isinf(limit) and steps > 4 and tau - rest_since >= rest_span:
                # at rest relative to the boundary, with every condition kept, for a
                # whole drive period (or, on a static boundary, a few steps): the drive
                # is periodic, so this repeats for ever
                raise BallAtRest(rest_since)
            if rest_span > 0.0 and steps > 4 and tau - rest_since >= rest_span:
                # the same argument with a time limit: whole drive periods repeat the one
                # just simulated exactly, so they are skipped (samples at the rest state)
                tau, next_sample = skip_periods(tau, limit, rest_span, y, next_sample,
                                                samples, on_sample)  # fmt: skip
                rest_since = tau
        return PhaseEnd(limit, None, y)


def skip_periods(
    tau: float,
    limit: float,
    period: float,
    y: Any,
    next_sample: float,
    samples: Iterator[float],
    on_sample: Callable[[float, Any], None] | None,
) -> tuple[float, float]:
    """Skip the whole drive periods (s) left before ``limit`` of a state at rest relative
    to the boundary; report the samples in the skipped span at that state. Returns the
    new time and the next sample time."""
    whole = math.floor((limit - tau) / period)
    if whole < 1:
        return tau, next_sample
    tau += whole * period
    while next_sample <= tau:
        if on_sample is not None:
            on_sample(next_sample, y)
        next_sample = next(samples, math.inf)
    return tau, next_sample


def _at_rest(k: Vec) -> bool:
    return all(abs(x) <= 1e-15 for x in k)


def first_root(fn: Callable[[float], float], a: float, b: float, fa: float) -> float:
    """The first time in (a, b] where fn, positive at a (or zero and falling), reaches
    zero or below: Illinois regula falsi, to EVENT_TOL."""
    fb = fn(b)
    if fa <= 0.0:
        return a
    side = 0
    for _ in range(200):
        if b - a <= EVENT_TOL:
            break
        m = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        if not a < m < b:
            m = 0.5 * (a + b)
        fm = fn(m)
        if fm > 0.0:
            a, fa = m, fm
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b, fb = m, fm
            if side == 1:
                fa *= 0.5
            side = 1
    return b
