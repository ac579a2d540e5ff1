"""The exact Jacobian of the return map: the flight's variational equations and the
saltation matrix of each impact, composed along the orbit.

One leg of the map goes from the post-impact coordinates x_k = (t, s, v1, v2, omega)
(:data:`~billiard.orbits.returnmap.STATE`) to x_k+1. Its derivative, for a perturbation
(dt_k, ds_k, du_k, domega):

1. the centre's lab position moves along the wall and with the boundary,
   dq_k = T_s ds_k + vb(t_k) dt_k, T_s = dq/ds = (L - r z_s) c1 the offset curve's tangent;
2. the flight (lab frame, autonomous) carries (dq, du) by its state-transition matrix
   Phi(tof) (generated ``flight_exact_jacobian`` without air forces; with them Phi solves
   the variational equations dPhi/dtau = A(u(tau)) Phi, A from the generated
   ``flight_jacobian``), and a later start shifts the arrival by -f^- dt_k;
3. the impact time moves so that the centre stays on the moving offset curve
   G(t, q) = c2 . (q - D(t) - p_wall) = 0:  dt* = -(dG/dx) / (dG/dt) along the flow,
   dt_k+1 = -c2 . dq_A / (c2 . (u^- - vb)), the event-time correction;
4. the contact abscissa follows, ds = c1 . (dq^- - vb dt_k+1) / (c1 . T_s), and with it the
   tangent angle dz = z_s ds; the boundary's velocity changes by ab dt_k+1;
5. the impact law's derivative (generated ``impact_stick_jacobian`` or
   ``impact_slip_jacobian``, in the regime the impact had) maps (du^-, domega, dz, dvb)
   to the post-impact speeds.

Steps 3 to 5 are the saltation matrix of the impact; the product of the legs' matrices
is the Jacobian of P^N. Nothing here differentiates numerically: finite differences of the
engine's map are the test (tests/orbits/test_jacobian.py), not the method.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from billiard.generated import ball as gball
from billiard.generated import orbit as gorbit
from billiard.orbits.errors import OrbitError
from billiard.runfile.record import ImpactRecord

__all__ = ["FLIGHT_RTOL", "flight_transition", "map_jacobian"]

#: Relative tolerance of the variational equations' integration under air forces: the
#: Jacobian enters Newton's steps and the multipliers, where 1e-11 of it is far below
#: what either resolves (the fixed point itself comes from the engine's map).
FLIGHT_RTOL = 1e-11


class _Air:
    """The flight's constants: gravity (m/s^2), mass (kg), Fowles c_lin (N s/m) and
    c_quad (N s^2/m^2), Magnus (kg); ``still`` when there are no air forces."""

    def __init__(self, scene):
        c_lin, c_quad = scene.air.coefficients
        self.g = float(scene.run.gravity)
        self.m = float(scene.ball.mass)
        self.c_lin, self.c_quad = float(c_lin), float(c_quad)
        self.c_magnus = float(scene.air.magnus)
        self.still = self.c_lin == 0.0 and self.c_quad == 0.0 and self.c_magnus == 0.0

    def acceleration(self, u1: float, u2: float, u3: float) -> tuple[float, float]:
        if self.still:
            return 0.0, -self.g
        return gball.flight_rhs_magnus(
            u1, u2, u3, self.m, self.g, self.c_lin, self.c_quad, self.c_magnus
        )


def flight_transition(
    air: _Air, tof: float, q: Sequence[float], u: Sequence[float], omega: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The flight of duration ``tof`` (s) from centre ``q`` (m), velocity ``u`` (m/s), spin
    ``omega`` (rad/s): (arrival (q1, q2, u1, u2), its 4x4 derivative in (q, u) at the
    start, its derivative in omega (4,))."""
    q1, q2 = float(q[0]), float(q[1])
    u1, u2 = float(u[0]), float(u[1])
    if air.still:
        end = np.array(gball.flight_exact(tof, q1, q2, u1, u2, air.g))
        phi = np.array(gorbit.flight_exact_jacobian(tof, q1, q2, u1, u2, air.g))
        return end, phi, np.zeros(4)
    m, g, cl, cq, cm = air.m, air.g, air.c_lin, air.c_quad, air.c_magnus

    def rhs(_tau: float, y: np.ndarray) -> np.ndarray:
        a1, a2 = gball.flight_rhs_magnus(y[2], y[3], omega, m, g, cl, cq, cm)
        jac = np.array(gorbit.flight_jacobian(y[2], y[3], omega, m, g, cl, cq, cm))
        sens = y[4:].reshape(4, 5)
        out = np.empty(24)
        out[:4] = (y[2], y[3], a1, a2)
        dsens = np.zeros((4, 5))
        dsens[0:2] = sens[2:4]
        dsens[2:4] = jac[:, :2] @ sens[2:4]
        dsens[2:4, 4] += jac[:, 2]
        out[4:] = dsens.ravel()
        return out

    y0 = np.zeros(24)
    y0[:4] = (q1, q2, u1, u2)
    y0[4:] = np.hstack([np.eye(4), np.zeros((4, 1))]).ravel()
    sol = solve_ivp(rhs, (0.0, tof), y0, method="DOP853", rtol=FLIGHT_RTOL, atol=1e-15)
    if not sol.success:  # pragma: no cover (a smooth, short flight)
        raise OrbitError(f"the flight's variational equations failed: {sol.message}")
    y = sol.y[:, -1]
    sens = y[4:].reshape(4, 5)
    return y[:4], sens[:, :4], sens[:, 4]


def _impact_jacobian(rm: Any, u: np.ndarray, omega: float, z: float, vb) -> np.ndarray:
    """d(u1+, u2+, u3+)/d(u1, u2, u3, z, vb1, vb2) of the impact law in the regime the
    engine's law takes for these pre-impact speeds (the low-velocity rule's e = 1
    included). A ball lying on the wall (the rule's shifted approach) is no smooth impact:
    refused."""
    law = rm.sim.impact
    m, r, k, e = law.m, law.r, law.k, law.e
    wt, wn = gball.contact_velocity(u[0], u[1], omega, z, vb[0], vb[1], r)
    if abs(wn) < law.elastic_below:
        e = 1.0
    if wn >= 0.0:
        raise OrbitError("an impact of the orbit has no approach speed (a grazing flight)")
    args = (u[0], u[1], omega, z, vb[0], vb[1], m, r, k, e)
    _, _, _, rt, rn = gball.impact_stick(*args)
    if abs(rt) > law.mu_s * rn:
        sgn = math.copysign(1.0, wt)
        return np.array(gorbit.impact_slip_jacobian(*args, law.mu_k, sgn))
    return np.array(gorbit.impact_stick_jacobian(*args))


def leg_jacobian(rm: Any, air: _Air, x: np.ndarray, wall: int, record: ImpactRecord) -> np.ndarray:
    """d x_k+1 / d x_k (5x5) of one leg: from post-impact ``x`` on ``wall`` to the impact
    the engine recorded as ``record``."""
    drive = rm.drive
    t0, s0, v1, v2, omega = (float(v) for v in x)
    _, _, z0, zs0 = rm.wall_point(wall, s0)
    tangent0 = _tangent(rm, wall, z0, zs0)
    vb0 = np.array(drive.boundary_velocity(drive.angle(t0)))
    ball = rm.ball(x, wall)
    tof = float(record.t) - t0
    end, phi, dphi_w = flight_transition(air, tof, (ball.q1, ball.q2), (v1, v2), omega)
    u_pre = end[2:]
    a_pre = np.array(air.acceleration(u_pre[0], u_pre[1], omega))
    f_pre = np.concatenate([u_pre, a_pre])
    # columns: perturbations of (t, s, v1, v2, omega); rows of dy: (q1, q2, u1, u2)
    dy0 = np.zeros((4, 5))
    dy0[0:2, 0] = vb0
    dy0[0:2, 1] = tangent0
    dy0[2, 2] = 1.0
    dy0[3, 3] = 1.0
    dy = phi @ dy0
    dy[:, 4] += dphi_w
    dy[:, 0] -= f_pre  # a later start arrives later
    theta1 = drive.angle(float(record.t))
    vb1 = np.array(drive.boundary_velocity(theta1))
    ab = drive.acceleration(theta1)
    ab1 = np.array([ab, 0.0]) if drive.horizontal else np.array([0.0, ab])
    wall1 = int(record.wall)
    _, _, z1, zs1 = rm.wall_point(wall1, float(record.s))
    c1 = np.array([math.cos(z1), math.sin(z1)])
    c2 = np.array([-math.sin(z1), math.cos(z1)])
    approach = float(c2 @ (u_pre - vb1))
    if approach == 0.0:
        raise OrbitError("an impact of the orbit is tangential to the wall (grazing)")
    dt1 = -(c2 @ dy[0:2]) / approach
    dq = dy[0:2] + np.outer(u_pre, dt1)
    du = dy[2:4] + np.outer(a_pre, dt1)
    tangent1 = _tangent(rm, wall1, z1, zs1)
    ds1 = (c1 @ (dq - np.outer(vb1, dt1))) / float(c1 @ tangent1)
    dz = zs1 * ds1
    dvb = np.outer(ab1, dt1)
    jac_law = _impact_jacobian(rm, u_pre, omega, z1, vb1)
    dw = np.zeros(5)
    dw[4] = 1.0
    inputs = np.vstack([du, dw, dz, dvb])  # (u1, u2, u3, z, vb1, vb2) x 5
    dpost = jac_law @ inputs
    out = np.empty((5, 5))
    out[0] = dt1
    out[1] = ds1
    out[2:5] = dpost
    return out


def _tangent(rm: Any, wall: int, z: float, zs: float) -> np.ndarray:
    """dq/ds (dimensionless): how the touching ball's centre moves with the contact
    abscissa, (L - r z_s) c1 on a curve wall (L = 1 / cos z), (1, 0) on the lid."""
    if wall < 0:
        return np.array([1.0, 0.0])
    c = math.cos(z)
    return (1.0 / c - rm.radius * zs) * np.array([c, math.sin(z)])


def map_jacobian(rm: Any, x: np.ndarray, wall: int, records: Sequence[ImpactRecord]) -> np.ndarray:
    """The 5x5 Jacobian of P^N at ``x`` on ``wall``, along the engine's ``records`` of the
    N impacts from there (:meth:`ReturnMap.__call__`). ``rm`` is the
    :class:`~billiard.orbits.returnmap.ReturnMap` (its wall geometry, drive and scene;
    not imported here: the map's ``jacobian`` calls this function)."""
    air = _Air(rm.scene)
    jac = np.eye(5)
    xk, wk = np.asarray(x, float), wall
    for record in records:
        jac = leg_jacobian(rm, air, xk, wk, record) @ jac
        xk = np.array([record.t, record.s, record.v1, record.v2, record.omega])
        wk = int(record.wall)
    return jac
