"""The paper's normalized phase point: the one place q2max and u4max are defined.

With E the ball's mechanical energy just after an impact (J; translation, rotation and
gravity, potential zero at q2 = 0 in the lab frame, the ``energy`` column):

    q2max = E / (m g)        the height (m) the ball would have if all of E were potential;
    u4max = sqrt(2 E / m)    the speed (m/s) it would have if all of E were kinetic.

The phase plot shows (u4 / u4max, q2 / q2max) after each impact; the calibration reports
the point of a period-one orbit. Works on floats and on numpy arrays alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["phase_point", "phase_scales"]


def phase_scales(energy: Any, mass: float, gravity: float) -> tuple[Any, Any]:
    """(q2max in m, u4max in m/s) for the energy E (J) of a ball of mass m (kg) under
    gravity g (m/s^2)."""
    return energy / (mass * gravity), np.sqrt(2.0 * energy / mass)


def phase_point(q2: Any, u4: Any, energy: Any, mass: float, gravity: float) -> tuple[Any, Any]:
    """The normalized point (q2 / q2max, u4 / u4max), both dimensionless."""
    q2max, u4max = phase_scales(energy, mass, gravity)
    return q2 / q2max, u4 / u4max
