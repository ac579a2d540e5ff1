"""Calibrate a scene parameter against the height of a period-one orbit.

This repeats the paper's procedure: the ball mode-locks into a period-one orbit (on the
driven parabola it hits the two walls alternately, once every half drive period, at one
height), and a parameter is tuned until that height matches the experiment's. The paper
fitted the restitution e = 0.393 to an orbit height of about 0.075 m at 5.4 Hz; it does
not state the drive amplitude A, which we infer the same way with e fixed.

Normalized point of the orbit (the paper's phase plot): q2max and u4max are defined in
:mod:`billiard.analysis.phase` (the candidates for the energy's zero and the spin, and the
default, :data:`billiard.analysis.phase.DEFAULT_PHASE_REFERENCE`); the point is
((q2 - h0) / q2max, u4 / u4max), u4 the velocity along the wall's tangent.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from billiard.analysis.dissipation import impact_dissipation, relative_energy
from billiard.analysis.phase import PhaseFrame, phase_frame, phase_point
from billiard.errors import GeometryError
from billiard.models.impact import IMPACT_LAWS, with_law
from billiard.run.simulate import simulate
from billiard.scene.scene import Scene, SceneError, key_number, key_value, with_values


class CalibrationError(ValueError):
    """The calibration could not be done; the message says why in one line."""


@dataclass(frozen=True)
class Orbit:
    """A period-one orbit found at the end of a run."""

    height: float  # q2 at the impacts (m)
    time_of_flight: float  # s
    u4: float  # tangential velocity after the impact (m/s), sign alternates wall to wall
    energy: float  # J
    q2_normalized: float  # (q2 - h0) / q2max under ``reference``
    u4_normalized: float
    impacts_to_lock: int  # impacts before the orbit was reached
    omega: float = 0.0  # spin after the impact (rad/s)
    reference: str = "lab-origin+spin"  # the phase reference of the normalized point
    #: kinetic energy (J) the impact law removes at an impact of the orbit, in the
    #: boundary's frame (:mod:`billiard.analysis.dissipation`), and the ball's kinetic
    #: energy relative to the boundary before it (nan: not computed)
    dissipated: float = math.nan
    relative_energy: float = math.nan


def find_period_one(
    columns: dict[str, np.ndarray],
    mass: float,
    gravity: float,
    *,
    window: int = 40,
    tol: float = 1e-6,
    reference: PhaseFrame | None = None,
) -> Orbit | None:
    """The period-one orbit at the end of a run, or None if the run did not lock.

    Locked means the last ``window`` impacts have one height and one time of flight, to
    within ``tol`` (m and s). The orbit's normalized point is taken under ``reference``
    (:func:`billiard.analysis.phase.phase_frame` of the run's scene; None: E as it is, the
    ``lab-origin+spin`` candidate).
    """
    q2, tof = columns["q2"], columns["tof"]
    if len(q2) < window + 1:
        return None
    tail_q2, tail_tof = q2[-window:], tof[-window:]
    if np.ptp(tail_q2) > tol or np.ptp(tail_tof) > tol:
        return None
    ref_q2, ref_tof = tail_q2.mean(), tail_tof.mean()
    # First impact from which every later one is on the orbit.
    off = (np.abs(q2 - ref_q2) > tol) | (np.abs(tof - ref_tof) > tol)
    lock = int(np.nonzero(off)[0][-1]) + 1 if off.any() else 0
    energy = float(columns["energy"][-1])
    u4 = float(columns["u4"][-1])
    omega = float(columns["omega"][-1]) if "omega" in columns else 0.0
    q2n, u4n = phase_point(
        float(ref_q2), u4, energy, mass, gravity, reference=reference, omega=omega
    )
    return Orbit(
        height=float(ref_q2),
        time_of_flight=float(ref_tof),
        u4=u4,
        energy=energy,
        q2_normalized=float(q2n),
        u4_normalized=float(u4n),
        impacts_to_lock=lock,
        omega=omega,
        reference="lab-origin+spin" if reference is None else reference.reference.name,
    )


def orbit_for(scene: Scene, parameter: str, value: float, impacts: int) -> Orbit | None:
    """Run the scene with ``parameter = value`` and return its period-one orbit, if any."""
    try:
        trial = with_values(scene, {parameter: value})
        result = simulate(trial, collisions=impacts)
    except (SceneError, GeometryError):  # e.g. a restitution above 1 in the scan: no orbit
        return None
    if result.stop_reason:
        return None
    try:
        frame = phase_frame(trial)
    except GeometryError:  # no bottom, so no lowest centre: E as it is (orbit.reference)
        frame = None
    orbit = find_period_one(result.columns, trial.ball.mass, trial.run.gravity, reference=frame)
    if orbit is None:
        return None
    last = {key: np.asarray(result.columns[key])[-1:] for key in result.columns}
    return dataclasses.replace(
        orbit,
        dissipated=float(impact_dissipation(last, trial)[0]),
        relative_energy=float(relative_energy(last, trial)[0]),
    )


@dataclass(frozen=True)
class Calibration:
    parameter: str
    value: float
    target_height: float
    orbit: Orbit
    evaluations: int
    scan: tuple[tuple[float, float | None], ...]  # (value, orbit height or None)

    def as_dict(self) -> dict:
        o = self.orbit
        return {
            "parameter": self.parameter,
            "value": self.value,
            "target_height": self.target_height,
            "orbit_height": o.height,
            "time_of_flight": o.time_of_flight,
            "q2_normalized": o.q2_normalized,
            "u4_normalized": abs(o.u4_normalized),
            "phase_reference": o.reference,
            "impacts_to_lock": o.impacts_to_lock,
            "dissipated_per_impact": o.dissipated,
            "relative_energy": o.relative_energy,
            "evaluations": self.evaluations,
        }


def calibrate(
    scene: Scene,
    parameter: str,
    target_height: float,
    *,
    low: float | None = None,
    high: float | None = None,
    points: int = 9,
    impacts: int = 1500,
    xtol: float = 1e-7,
) -> Calibration:
    """Value of ``parameter`` for which the ball locks into a period-one orbit at
    ``target_height`` (m), starting from the scene's initial state.

    The parameter is scanned over [low, high] (default: a quarter to four times its
    value in the scene), the first pair of neighbouring values whose locked orbits
    straddle the target is refined with Brent's method.
    """
    if not (math.isfinite(target_height) and target_height > 0):
        raise CalibrationError(f"target height {target_height!r} m must be a positive number")
    current = _current_value(scene, parameter)
    low = low if low is not None else current / 4
    high = high if high is not None else current * 4
    if not (0 < low < high):
        raise CalibrationError(f"scan range [{low}, {high}] for {parameter} is empty")
    values = np.geomspace(low, high, points)
    scan = []
    evaluations = 0
    for v in values:
        orbit = orbit_for(scene, parameter, float(v), impacts)
        evaluations += 1
        scan.append((float(v), orbit.height if orbit else None))
    bracket = None
    for (a, ha), (b, hb) in zip(scan, scan[1:], strict=False):
        if ha is not None and hb is not None and (ha - target_height) * (hb - target_height) <= 0:
            bracket = (a, b)
            break
    if bracket is None:
        heights = ", ".join(f"{v:.4g}: {'none' if h is None else f'{h:.4f} m'}" for v, h in scan)
        raise CalibrationError(
            f"no period-one orbit at {target_height} m for {parameter} in [{low:.4g}, "
            f"{high:.4g}] (orbit heights: {heights})"
        )

    def miss(v: float) -> float:
        nonlocal evaluations
        evaluations += 1
        orbit = orbit_for(scene, parameter, v, impacts)
        if orbit is None:
            raise CalibrationError(
                f"{parameter} = {v:.6g}: the ball did not lock into a "
                f"period-one orbit within {impacts} impacts"
            )
        return orbit.height - target_height

    from scipy.optimize import brentq  # here: scipy costs 0.4 s to import

    value = float(brentq(miss, *bracket, xtol=xtol))
    orbit = orbit_for(scene, parameter, value, impacts)
    assert orbit is not None
    return Calibration(parameter, value, target_height, orbit, evaluations + 1, tuple(scan))


#: scan points of a law's main parameter (:func:`calibrate_law`): a period-one orbit
#: exists only in windows of it (Walton's law locks at e = 0.532 and not at 0.47)
LAW_POINTS = 33


def calibrate_law(
    scene: Scene,
    target_height: float,
    *,
    law: str | None = None,
    parameter: str | None = None,
    low: float | None = None,
    high: float | None = None,
    impacts: int = 1500,
) -> tuple[Scene, Calibration]:
    """:func:`calibrate` under the impact law ``law`` (the scene's by default; its other
    parameters at the law's defaults where the scene has none,
    :func:`billiard.models.impact.with_law`): of ``parameter``, by default the law's main
    parameter scanned over the law's range in :data:`LAW_POINTS` points.

    Returns:
        The scene under the law (before the fit) and the calibration.

    Raises:
        SceneError: ``law`` is no impact law (one line naming the choices).
        CalibrationError: no orbit at the target height in the range.
    """
    scene = with_law(scene, law if law is not None else scene.contact.law)
    points = 9
    if parameter is None:
        model = IMPACT_LAWS[scene.contact.law]
        parameter = f"contact.{model.main}"
        low = model.main_range[0] if low is None else low
        high = model.main_range[1] if high is None else high
        points = LAW_POINTS
    fit = calibrate(
        scene, parameter, target_height, low=low, high=high, points=points, impacts=impacts
    )
    return scene, fit


def _current_value(scene: Scene, parameter: str) -> float:
    try:
        value = key_number(scene, parameter)
    except KeyError:
        raise CalibrationError(f"unknown scene parameter {parameter!r}") from None
    if value is None or value <= 0:
        raise CalibrationError(
            f"scene parameter {parameter!r} = {key_value(scene, parameter)!r} is not a "
            "positive number to calibrate"
        )
    return value
