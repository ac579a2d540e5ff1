"""The energy an impact law removes at each impact, from a run's collision record.

On a moving boundary the ball's energy changes at an impact by what the law dissipates
and by the work the boundary does; the first is the change of the ball's kinetic energy
in the frame moving with the boundary at the impact (the boundary's velocity is
constant during the instantaneous impact). For an impulse (Rt, Rn) at the contact point
that change is the impulse times the mean of the contact point's velocity before and
after (Kane and Levinson's impulse-energy relation):

    dT = Rt (wt- + wt+) / 2 + Rn (wn- + wn+) / 2,

with wt+ - wt- = Rt (1 + 1/k) / m and wn+ - wn- = Rn / m (the impulse-momentum equations,
derivation/ball.py). The dissipation is -dT >= 0 for every law (tests/models/
test_impact_laws.py checks that no law gains energy on a still boundary).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from billiard.geometry.drive import Drive

__all__ = ["impact_dissipation", "relative_energy"]


def _boundary_velocity(columns: Mapping[str, np.ndarray], scene: Any) -> np.ndarray:
    """The boundary's velocity (vb1, vb2) at each impact (m/s), one row each."""
    drive = Drive.from_scene(scene.drive)
    t = np.asarray(columns["t"], dtype=float)
    return np.array([drive.boundary_velocity(drive.angle(float(x))) for x in t]).reshape(-1, 2)


def _after(columns: Mapping[str, np.ndarray], scene: Any) -> tuple[np.ndarray, np.ndarray]:
    """The contact point's velocity (wt+, wn+) relative to the boundary just after each
    impact (m/s)."""
    vb = _boundary_velocity(columns, scene)
    z = np.asarray(columns["z"], dtype=float)
    c, s = np.cos(z), np.sin(z)
    d1 = np.asarray(columns["v1"], dtype=float) - vb[:, 0]
    d2 = np.asarray(columns["v2"], dtype=float) - vb[:, 1]
    wt = c * d1 + s * d2 + scene.ball.radius * np.asarray(columns["omega"], dtype=float)
    wn = c * d2 - s * d1
    return wt, wn


def impact_dissipation(columns: Mapping[str, np.ndarray], scene: Any) -> np.ndarray:
    """The kinetic energy (J) each impact of a run's record removed, in the frame of the
    boundary at the impact: -(Rt (wt- + wt+) + Rn (wn- + wn+)) / 2."""
    m, k = scene.ball.mass, scene.ball.inertia_factor
    rt = np.asarray(columns["Rt"], dtype=float)
    rn = np.asarray(columns["Rn"], dtype=float)
    wt, wn = _after(columns, scene)
    wt_before = wt - rt * (1.0 + 1.0 / k) / m
    wn_before = wn - rn / m
    return -0.5 * (rt * (wt_before + wt) + rn * (wn_before + wn))


def relative_energy(columns: Mapping[str, np.ndarray], scene: Any) -> np.ndarray:
    """The ball's kinetic energy (J) relative to the boundary just before each impact:
    what the impact could at most remove."""
    m, r, k = scene.ball.mass, scene.ball.radius, scene.ball.inertia_factor
    rt = np.asarray(columns["Rt"], dtype=float)
    rn = np.asarray(columns["Rn"], dtype=float)
    z = np.asarray(columns["z"], dtype=float)
    vb = _boundary_velocity(columns, scene)
    c, s = np.cos(z), np.sin(z)
    # the centre's velocity and the spin before the impact, from those after
    d1 = np.asarray(columns["v1"], dtype=float) - (c * rt - s * rn) / m - vb[:, 0]
    d2 = np.asarray(columns["v2"], dtype=float) - (s * rt + c * rn) / m - vb[:, 1]
    omega = np.asarray(columns["omega"], dtype=float) - rt / (k * m * r)
    return 0.5 * m * (d1 * d1 + d2 * d2) + 0.5 * k * m * r * r * omega * omega
