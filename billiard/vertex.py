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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from billiard.contact_phase import ContactModel, first_root, skip_periods
from billiard.errors import BallAtRest

__all__ = ["HELD", "HoldEnd", "VertexHold"]

#: the motion state of a ball held by two walls
HELD = "held"


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
        model: the scene's :class:`~billiard.contact_phase.ContactModel` (ball, gravity,
            drag, friction and drive: the same constants as rolling and sliding).
    """

    def __init__(self, model: ContactModel):
        self.m, self.r, self.k, self.g = model.m, model.r, model.k, model.g
        self.c_lin, self.c_quad = model.c_lin, model.c_quad
        self.mu_k = model.mu_k
        self.drive = model.drive
        self.static = model.static

    def forces(self, za: float, zb: float, theta: float, sigma: float) -> tuple[float, float]:
        """(N_a, N_b): the normal forces (N) of the two walls, tangent angles za and zb
        (rad) at their contact points, at drive angle theta, spin sign sigma."""
        dr = self.drive
        a, v = dr.acceleration(theta), dr.velocity(theta)
        ab1, ab2, vb1, vb2 = (a, 0.0, v, 0.0) if dr.horizontal else (0.0, a, 0.0, v)
        drag = self.c_lin + self.c_quad * math.sqrt(vb1 * vb1 + vb2 * vb2)
        # the centre moves with the boundary: m a_b = m g + D + contact forces
        rx = self.m * ab1 + drag * vb1
        ry = self.m * (ab2 + self.g) + drag * vb2
        mu = self.mu_k * sigma
        ca, sa, cb, sb = math.cos(za), math.sin(za), math.cos(zb), math.sin(zb)
        # columns: n - mu sigma t for each wall, n = (-sin z, cos z), t = (cos z, sin z)
        a11, a21 = -sa - mu * ca, ca - mu * sa
        a12, a22 = -sb - mu * cb, cb - mu * sb
        det = a11 * a22 - a12 * a21
        if det == 0.0:
            return -math.inf, -math.inf  # parallel walls cannot hold the ball together
        return (rx * a22 - ry * a12) / det, (a11 * ry - a21 * rx) / det

    def holds(self, za: float, zb: float, theta: float, u3: float) -> bool:
        """Do both walls press a ball with spin u3 (rad/s) at drive angle theta?"""
        n_a, n_b = self.forces(za, zb, theta, _sign(u3))
        return n_a > 0.0 and n_b > 0.0

    def spin_rate(self, n_a: float, n_b: float, sigma: float) -> float:
        """du3/dt (rad/s^2) from the kinetic friction of both walls."""
        return -self.mu_k * sigma * (n_a + n_b) / (self.k * self.m * self.r)

    def run_hold(
        self,
        za: float,
        zb: float,
        theta0: float,
        u3: float,
        limit: float,
        samples: Iterable[float] = (),
        on_sample: Callable[[float, float], None] | None = None,
    ) -> HoldEnd:
        """Hold the ball from drive angle theta0 with spin u3 for at most ``limit``
        seconds; report ``on_sample(tau, u3)`` at the sample times (s from the start).

        Raises:
            BallAtRest: no time limit, the spin is zero and no release comes within a
                drive period (or at all, on a static boundary).
        """
        omega = self.drive.omega
        sigma = _sign(u3)

        def normal(tau: float, sigma: float) -> tuple[float, float]:
            return self.forces(za, zb, theta0 + omega * tau, sigma)

        def rate(tau: float, sigma: float) -> float:
            n_a, n_b = normal(tau, sigma)
            return self.spin_rate(n_a, n_b, sigma)

        def spin_at(tau_a: float, w_a: float, tau: float, sigma: float) -> float:
            # Simpson's rule on [tau_a, tau]; a spin that would change sign has stopped
            if sigma == 0.0:
                return 0.0
            h = tau - tau_a
            mid = 0.5 * (tau_a + tau)
            w = w_a + h / 6.0 * (rate(tau_a, sigma) + 4.0 * rate(mid, sigma) + rate(tau, sigma))
            return w if w * sigma > 0.0 else 0.0

        h = math.inf if self.static else 2.0 * math.pi / abs(omega) / 64.0
        samples = iter(samples)
        next_sample = next(samples, math.inf)
        tau, w = 0.0, u3
        rest_since = 0.0 if sigma == 0.0 else math.inf
        rest_span = 0.0 if self.static else 2.0 * math.pi / abs(omega)
        while True:
            if math.isinf(limit) and tau - rest_since >= rest_span:
                raise BallAtRest(rest_since)
            if rest_span > 0.0 and tau - rest_since >= rest_span:
                # at rest through a whole period: the next ones repeat it exactly
                tau, next_sample = skip_periods(tau, limit, rest_span, 0.0, next_sample,
                                                samples, on_sample)  # fmt: skip
                rest_since = tau
            t_b = min(tau + h, limit)
            stops = math.inf
            if sigma != 0.0 and self.static:
                # static boundary: constant forces, the spin stops at a known time
                stops = tau + abs(w / rate(tau, sigma))
                t_b = min(stops, limit)
            n_prev = normal(tau, sigma)
            n_new = normal(t_b, sigma) if math.isfinite(t_b) else n_prev
            end_t, keeps = t_b, -2
            for i in (0, 1):
                if n_new[i] <= 0.0 < n_prev[i] or n_prev[i] <= 0.0:
                    t_i = first_root(lambda x, i=i, sg=sigma: normal(x, sg)[i], tau, t_b, n_prev[i])
                    if keeps == -2 or t_i < end_t:
                        end_t, keeps = t_i, 1 - i
                    elif t_i == end_t:
                        keeps = -1  # both walls release at once
            w_end = spin_at(tau, w, end_t, sigma) if math.isfinite(end_t) else w
            if end_t == stops:
                w_end = 0.0
            if on_sample is not None:
                while next_sample <= end_t:
                    on_sample(next_sample, spin_at(tau, w, next_sample, sigma))
                    next_sample = next(samples, math.inf)
            if keeps != -2:
                return HoldEnd(end_t, "release", w_end, keeps)
            if end_t >= limit:
                return HoldEnd(limit, None, w_end)
            if end_t == stops:
                tau, w, sigma, rest_since = stops, 0.0, 0.0, stops
                continue
            if sigma != 0.0 and w_end == 0.0:
                # the spin stopped within this step: find when, then hold without friction
                lo, hi = tau, end_t
                for _ in range(200):
                    if hi - lo <= 1e-13:
                        break
                    mid = 0.5 * (lo + hi)
                    if spin_at(tau, w, mid, sigma) == 0.0:
                        hi = mid
                    else:
                        lo = mid
                tau, w, sigma, rest_since = hi, 0.0, 0.0, hi
                continue
            tau, w = end_t, w_end


def _sign(x: float) -> float:
    return 0.0 if x == 0.0 else math.copysign(1.0, x)
