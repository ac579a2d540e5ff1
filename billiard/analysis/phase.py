"""The paper's normalized phase point: the one place q2max and u4max are defined.

The paper plots, after each impact, the height q2 over q2max against the tangential
velocity u4 over u4max, where q2max and u4max are the height and the speed the ball would
have if all its energy were potential or kinetic. It states neither where the potential
energy is zero nor whether the spin's kinetic energy counts. Each combination is a named
candidate in :data:`PHASE_REFERENCES`. With

    h0    the height (m) where the potential energy is zero (the candidate's *zero*),
    E     the ball's mechanical energy just after the impact (J; translation, spin and
          m g q2, the ``energy`` column of a run),
    Es    = I omega^2 / 2, the spin's kinetic energy (J), I = k m r^2,
    E0    = E - m g h0 - (0 if the spin counts else Es), the energy the point shares out,

every candidate normalizes the same way:

    q2max = E0 / (m g)        the height (m) above h0 the ball would reach with all of E0
                              potential;
    u4max = sqrt(2 E0 / m)    the speed (m/s) it would have with all of E0 kinetic
                              (translation);
    point = ((q2 - h0) / q2max, u4 / u4max).

Height and energy are measured from the same zero, so a ball at rest above h0 is the
point (1, 0) under every candidate, and a ball passing through h0 without spin is
(0, +-1). The zeros (:data:`PHASE_ZEROS`):

``lab-origin``
    h0 = 0, the lab frame's q2 = 0 (for the paper's curves 6.3 mm below the parabola's
    vertex, the constant c of f(x) = a x^2 + c).
``vertex``
    h0 = the lowest point of the boundary curve (the curve's vertex).
``lowest-centre``
    h0 = the lowest position of the ball's centre: the centre of a ball at rest touching
    the bottom (the vertex plus r for a smooth bottom, plus r / cos of the half-angle in
    a wedge), where the ball's potential energy is least.

For a vertical drive the zeros are taken with the boundary at its mid position (D = 0).
A candidate's name is its zero for translation only (``lowest-centre``) and the zero with
``+spin`` when the spin's energy counts (``lowest-centre+spin``).

:data:`DEFAULT_PHASE_REFERENCE` is ``lowest-centre`` (translation only): it is the
candidate that puts the calibrated period-one orbit of the parabola at 5.4 Hz where the
paper reports it, and the one a camera can measure (the reasoning and the numbers of
every candidate are in docs/paper-reproduction.md, computed by ``billiard reproduce``).

:func:`phase_scales` and :func:`phase_point` work on floats and numpy arrays alike;
without a ``reference`` they take E as it is (the ``lab-origin+spin`` candidate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "DEFAULT_PHASE_REFERENCE",
    "PAPER_PHASE_POINT",
    "PHASE_REFERENCES",
    "PHASE_ZEROS",
    "PhaseFrame",
    "PhaseReference",
    "candidate_points",
    "normalized_points",
    "paper_distance",
    "phase_frame",
    "phase_point",
    "phase_scales",
    "zero_height",
]

#: Where the potential energy is zero, the candidates (see the module's docstring).
PHASE_ZEROS: tuple[str, ...] = ("lab-origin", "vertex", "lowest-centre")

#: The paper's normalized point of the parabola's period-one orbit at 5.4 Hz,
#: (q2/q2max, |u4/u4max|).
PAPER_PHASE_POINT: tuple[float, float] = (0.376, 0.0372)


@dataclass(frozen=True)
class PhaseReference:
    """One candidate definition of q2max and u4max.

    Attributes:
        name: the registry key, e.g. ``"lowest-centre"`` or ``"vertex+spin"``.
        zero: one of :data:`PHASE_ZEROS`, where the potential energy is zero.
        spin: the spin's kinetic energy I omega^2 / 2 is part of the energy shared out.
        formula: q2max and u4max written out.
    """

    name: str
    zero: str
    spin: bool
    formula: str


_ZERO_SYMBOL = {"lab-origin": "0", "vertex": "h_v", "lowest-centre": "h_c"}


def _reference(zero: str, spin: bool) -> PhaseReference:
    h0 = _ZERO_SYMBOL[zero]
    energy = f"E - m g {h0}" if h0 != "0" else "E"
    if not spin:
        energy += " - I w^2/2"
    return PhaseReference(
        name=zero + ("+spin" if spin else ""),
        zero=zero,
        spin=spin,
        formula=(
            f"E0 = {energy}; q2max = E0/(m g), u4max = sqrt(2 E0/m); "
            f"point ({'q2' if h0 == '0' else f'(q2 - {h0})'}/q2max, u4/u4max)"
        ),
    )


#: The candidates by name: every zero of :data:`PHASE_ZEROS`, translation only and with
#: the spin's energy (``+spin``).
PHASE_REFERENCES: dict[str, PhaseReference] = {
    r.name: r for r in (_reference(z, s) for z in PHASE_ZEROS for s in (False, True))
}

#: The definition the phase plots, the calibration and the reproduction use.
DEFAULT_PHASE_REFERENCE = "lowest-centre"


def _lookup(reference: str) -> PhaseReference:
    try:
        return PHASE_REFERENCES[reference]
    except KeyError:
        raise ValueError(
            f"unknown phase reference {reference!r}: choose from {', '.join(PHASE_REFERENCES)}"
        ) from None


@dataclass(frozen=True)
class PhaseFrame:
    """A candidate resolved for one scene: its zero height and the ball's inertia.

    Attributes:
        reference: the candidate.
        zero_height: h0 (m), the height where the potential energy is zero.
        inertia: I = k m r^2 (kg m^2), for the spin's energy.
    """

    reference: PhaseReference
    zero_height: float
    inertia: float

    def removed_energy(self, mass: float, gravity: float, omega: Any) -> Any:
        """The energy (J) that E minus this is E0: m g h0, plus I omega^2 / 2 when the
        spin does not count."""
        out = mass * gravity * self.zero_height
        if not self.reference.spin:
            out = out + 0.5 * self.inertia * np.square(omega)
        return out


def phase_scales(
    energy: Any,
    mass: float,
    gravity: float,
    *,
    reference: PhaseFrame | None = None,
    omega: Any = 0.0,
) -> tuple[Any, Any]:
    """(q2max in m, u4max in m/s) for the energy E (J) after an impact of a ball of mass
    m (kg) under gravity g (m/s^2).

    With ``reference`` (from :func:`phase_frame`), E0 = E - m g h0 (and minus
    I omega^2 / 2 if the candidate leaves the spin out; ``omega`` in rad/s) is shared out;
    without one, E itself (the ``lab-origin+spin`` candidate). q2max = E0 / (m g) is the
    height above h0.
    """
    e0 = energy if reference is None else energy - reference.removed_energy(mass, gravity, omega)
    return e0 / (mass * gravity), np.sqrt(2.0 * e0 / mass)


def phase_point(
    q2: Any,
    u4: Any,
    energy: Any,
    mass: float,
    gravity: float,
    *,
    reference: PhaseFrame | None = None,
    omega: Any = 0.0,
) -> tuple[Any, Any]:
    """The normalized point ((q2 - h0) / q2max, u4 / u4max), both dimensionless; h0 = 0
    without a ``reference`` (see :func:`phase_scales`)."""
    q2max, u4max = phase_scales(energy, mass, gravity, reference=reference, omega=omega)
    h0 = 0.0 if reference is None else reference.zero_height
    return (q2 - h0) / q2max, u4 / u4max


def zero_height(scene: Any, zero: str) -> float:
    """The height h0 (m, lab frame, boundary at D = 0) of a zero of :data:`PHASE_ZEROS`
    for a scene: 0, the lowest point of the boundary curve, or the centre of a ball at
    rest touching the bottom.

    Raises:
        ValueError: an unknown zero.
        GeometryError: the curve has no bottom (from the boundary's rest position).
    """
    if zero not in PHASE_ZEROS:
        raise ValueError(f"unknown phase zero {zero!r}: choose from {', '.join(PHASE_ZEROS)}")
    if zero == "lab-origin":
        return 0.0
    from billiard.geometry.boundary import Boundary
    from billiard.geometry.curves import load_curve

    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    boundary = Boundary.from_scene(scene, curve.walls)
    if zero == "lowest-centre":
        return float(boundary.resting_position()[1])
    return _curve_minimum(boundary)


def _curve_minimum(boundary: Any, samples: int = 4001) -> float:
    """Lowest point of the boundary curve (the maximum of its walls) over the container:
    the least of a grid, refined by a bounded scalar minimization between its neighbours
    (a kink is a minimum the refinement finds too: the curve is unimodal there)."""
    from scipy.optimize import minimize_scalar

    xl, xr = boundary.x_range
    xs = np.linspace(xl, xr, samples)
    heights = np.array([boundary.curve_height(float(x)) for x in xs])
    k = int(np.argmin(heights))
    a, b = float(xs[max(k - 1, 0)]), float(xs[min(k + 1, samples - 1)])
    best = float(heights[k])
    if b > a:
        found = minimize_scalar(
            boundary.curve_height, bounds=(a, b), method="bounded", options={"xatol": 1e-12}
        )
        best = min(best, float(found.fun))
    return best


def phase_frame(scene: Any, reference: str = DEFAULT_PHASE_REFERENCE) -> PhaseFrame:
    """The candidate ``reference`` (a key of :data:`PHASE_REFERENCES`) resolved for a
    scene: its zero height (:func:`zero_height`) and the ball's moment of inertia.

    Raises:
        ValueError: an unknown reference.
    """
    ref = _lookup(reference)
    ball = scene.ball
    return PhaseFrame(
        ref, zero_height(scene, ref.zero), ball.inertia_factor * ball.mass * ball.radius**2
    )


def normalized_points(
    columns: Any, scene: Any, reference: str | PhaseFrame = DEFAULT_PHASE_REFERENCE
) -> tuple[np.ndarray, np.ndarray]:
    """(q2 normalized, u4 normalized) after each impact of a run's columns (``q2`` m,
    ``u4`` m/s, ``energy`` J, ``omega`` rad/s; ``omega`` may be missing when the spin
    counts). Rows whose E0 is not positive and finite give NaN."""
    frame = reference if isinstance(reference, PhaseFrame) else phase_frame(scene, reference)
    m, g = scene.ball.mass, scene.run.gravity
    q2 = np.asarray(columns["q2"], dtype=float)
    u4 = np.asarray(columns["u4"], dtype=float)
    energy = np.asarray(columns["energy"], dtype=float)
    if "omega" in columns:
        omega = np.asarray(columns["omega"], dtype=float)
    elif frame.reference.spin:
        omega = np.zeros_like(energy)
    else:
        raise ValueError(
            f"phase reference {frame.reference.name!r} leaves the spin out: the columns "
            "need 'omega'"
        )
    e0 = energy - frame.removed_energy(m, g, omega)
    good = np.isfinite(e0) & (e0 > 0)
    safe = np.where(good, energy, np.nan)
    q2n, u4n = phase_point(q2, u4, safe, m, g, reference=frame, omega=omega)
    return np.asarray(q2n, dtype=float), np.asarray(u4n, dtype=float)


def candidate_points(
    q2: float, u4: float, energy: float, omega: float, scene: Any
) -> dict[str, tuple[float, float]]:
    """The normalized point of one impact (q2 m, u4 m/s, E J, omega rad/s) under every
    candidate of :data:`PHASE_REFERENCES`: name -> (q2 normalized, u4 normalized)."""
    m, g = scene.ball.mass, scene.run.gravity
    heights = {z: zero_height(scene, z) for z in PHASE_ZEROS}
    ball = scene.ball
    inertia = ball.inertia_factor * ball.mass * ball.radius**2
    out = {}
    for name, ref in PHASE_REFERENCES.items():
        frame = PhaseFrame(ref, heights[ref.zero], inertia)
        a, b = phase_point(q2, u4, energy, m, g, reference=frame, omega=omega)
        out[name] = (float(a), float(b))
    return out


def paper_distance(point: tuple[float, float]) -> float:
    """How far a normalized point (q2n, u4n) is from the paper's :data:`PAPER_PHASE_POINT`:
    the root mean square of the two relative differences (u4 by magnitude)."""
    q, u = PAPER_PHASE_POINT
    return math.hypot(point[0] / q - 1, abs(point[1]) / u - 1) / math.sqrt(2)
