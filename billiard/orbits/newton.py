"""A periodic orbit as a fixed point of the return map: Newton's method on
P^N(x) - x - (m T, 0, 0, 0, 0) = 0, with m the whole number of drive periods T the N
impacts take (the drive phase is the time modulo T), and the orbit's Floquet multipliers.

The multipliers are the eigenvalues of the Jacobian of P^N in the coordinates
(t, s, v1, v2, omega) of the impact surface. In the six lab coordinates
(t, q1, q2, v1, v2, omega) of a post-impact state the Jacobian has one more eigenvalue,
the trivial 0: every image lies on the wall, so a perturbation across the wall is mapped
to nothing. Working on the wall (the contact abscissa s in place of q1, q2) removes it.
A multiplier 0 that remains is physical: a sticking impact leaves no slip, whatever the
slip before it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from billiard.orbits.phases import return_map
from billiard.orbits.returnmap import STATE, Landing, OrbitError, ReturnMap
from billiard.runfile.record import ImpactRecord

__all__ = ["NEWTON_TOL", "Orbit", "find_orbit", "free_indices", "newton", "stable"]

#: Newton converges when every coordinate's step is at most this, relative to
#: 1 + |coordinate| (s, m, m/s, rad/s): the orbit is then known to 1e-12 in its state.
NEWTON_TOL = 1e-12
#: Newton steps before giving up.
MAX_STEPS = 30
#: A multiplier counts as on the unit circle within this (rounding of the Jacobian).
UNIT_TOL = 1e-9


@dataclass
class Orbit:
    """A periodic orbit: its state just after its first impact, and its stability.

    Attributes:
        x: (t, s, v1, v2, omega) just after the first impact (s, m, m/s, m/s, rad/s),
            t reduced to [0, T).
        wall: the wall of the first impact (-1 the lid).
        impacts: N, impacts per period of the orbit (lift-offs for an orbit through
            contact phases: :class:`~billiard.orbits.phases.PhaseMap`).
        periods: m, drive periods per period of the orbit.
        jacobian: the Jacobian of P^N at x (the varied coordinates only).
        multipliers: its eigenvalues, the Floquet multipliers (largest modulus first).
        stable: all multipliers strictly inside the unit circle.
        sequence: (wall, regime) of each of the N impacts (the map's
            :meth:`~billiard.orbits.returnmap.ReturnMap.sequence`).
        records: the engine's records of the N impacts (and contact phases).
        lab: (q1, q2) (m) of the centre just after the first impact.
        residual: max |P^N(x) - x - m T e_t| relative to 1 + |x| at the end (NaN for
            a point of a continued branch, converged by its corrector's step instead).
        free: the coordinates Newton varied (the others held at the guess).
    """

    x: np.ndarray
    wall: int
    impacts: int
    periods: int
    jacobian: np.ndarray
    multipliers: np.ndarray
    stable: bool
    sequence: tuple[tuple[int, str], ...]
    records: list[Any] = field(repr=False)
    lab: tuple[float, float]
    residual: float
    free: tuple[str, ...]

    def as_dict(self) -> dict[str, Any]:
        """The state by name (``t_phase`` the time modulo the drive period)."""
        t, s, v1, v2, omega = (float(v) for v in self.x)
        return {
            "t_phase": t,
            "s": s,
            "q1": self.lab[0],
            "q2": self.lab[1],
            "v1": v1,
            "v2": v2,
            "omega": omega,
        }


def stable(multipliers: np.ndarray) -> bool:
    """Linearly stable: every multiplier strictly inside the unit circle."""
    return bool(np.all(np.abs(multipliers) < 1.0 - UNIT_TOL))


def free_indices(free: Sequence[str] | None) -> list[int]:
    """The positions in :data:`STATE` of the coordinates ``free`` (None: all)."""
    if free is None:
        return list(range(len(STATE)))
    unknown = [name for name in free if name not in STATE]
    if unknown or not free:
        raise OrbitError(
            f"free coordinates must be some of {', '.join(STATE)}; got {', '.join(free) or 'none'}"
        )
    return [STATE.index(name) for name in STATE if name in free]


def _residual(rm: ReturnMap, x: np.ndarray, landing: Landing, periods: int) -> np.ndarray:
    res = landing.x - x
    res[0] -= periods * rm.period
    return res


def newton(
    rm: ReturnMap,
    x0: Sequence[float],
    wall: int,
    free: Sequence[str] | None = None,
    periods: int | None = None,
) -> Orbit:
    """Newton's method for a fixed point of ``rm`` (P^N) from the guess ``x0`` on ``wall``.

    Args:
        free: the coordinates varied (default the map's ``FREE``: all of :data:`STATE`
            for impacts, t and v2 through contact phases); the others stay at the guess
            and must then be invariant (a ball on a flat table bouncing straight up:
            v1 = omega = 0 stays so).
        periods: drive periods per orbit (default: the guess's flight time, rounded).

    Raises:
        OrbitError: no convergence, the orbit leaves its wall sequence during the
            search, or a held coordinate is not invariant.
    """
    idx = free_indices(rm.FREE if free is None else free)
    rm.check_free(idx)
    x = np.array(x0, dtype=float)
    if x.shape != (len(STATE),) or not np.all(np.isfinite(x)):
        raise OrbitError(f"a guess is five finite numbers ({', '.join(STATE)}), not {x0!r}")
    x, wall = rm.enter(x, wall)
    x[0] %= rm.period
    landing, records = rm(x, wall)
    if periods is None:
        periods = int(round((landing.x[0] - x[0]) / rm.period))
    if periods < 1:
        raise OrbitError(
            f"the guess's {rm.impacts} {rm.UNIT}(s) take {landing.x[0] - x[0]:.6g} s, "
            f"less than half a drive period ({rm.period:.6g} s): no periodic orbit near it"
        )
    size = 1.0 + np.abs(x)
    for _ in range(MAX_STEPS):
        if landing.wall != wall:
            raise OrbitError(
                f"the guess does not return to its wall after {rm.impacts} {rm.UNIT}(s) "
                f"(wall {wall} to wall {landing.wall})"
            )
        res = _residual(rm, x, landing, periods)
        jac = rm.jacobian(x, wall, records)
        a = jac[np.ix_(idx, idx)] - np.eye(len(idx))
        step = -np.linalg.lstsq(a, res[idx], rcond=None)[0]
        x[idx] += step
        x[0] %= rm.period
        landing, records = rm(x, wall)
        res = _residual(rm, x, landing, periods)
        size = 1.0 + np.abs(x)
        if np.max(np.abs(step) / size[idx]) <= NEWTON_TOL or np.max(np.abs(res) / size) <= (
            NEWTON_TOL
        ):
            break
    else:
        raise OrbitError(
            f"Newton's method did not converge in {MAX_STEPS} steps (residual "
            f"{np.max(np.abs(res) / size):.3g}): start from a closer guess"
        )
    held = [i for i in range(len(STATE)) if i not in idx]
    residual = float(np.max(np.abs(res) / size))
    if held and np.max(np.abs(res[held]) / size[held]) > 1e3 * NEWTON_TOL:
        names = ", ".join(STATE[i] for i in held)
        raise OrbitError(f"the held coordinates ({names}) change along the orbit: {rm.HELD_HINT}")
    return _orbit(rm, x, wall, periods, records, idx, residual)


def _orbit(
    rm: ReturnMap,
    x: np.ndarray,
    wall: int,
    periods: int,
    records: list[Any],
    idx: list[int],
    residual: float,
) -> Orbit:
    jac = rm.jacobian(x, wall, records)[np.ix_(idx, idx)]
    mults = np.linalg.eigvals(jac)
    mults = mults[np.argsort(-np.abs(mults), kind="stable")]
    ball = rm.ball(x, wall)
    return Orbit(
        x=x.copy(),
        wall=wall,
        impacts=rm.impacts,
        periods=periods,
        jacobian=jac,
        multipliers=mults,
        stable=stable(mults),
        sequence=rm.sequence(x, records),
        records=records,
        lab=(ball.q1, ball.q2),
        residual=residual,
        free=tuple(STATE[i] for i in idx),
    )


def find_orbit(
    scene: Any,
    period: int = 1,
    guess: Sequence[float] | Any = None,
    wall: int = 0,
    free: Sequence[str] | None = None,
    settle: int = 2000,
) -> Orbit:
    """A period-``period`` orbit (``period`` impacts) of ``scene``, by Newton's method.

    Args:
        scene: a scene: under ``contact.model = "impacts"`` any; under ``"phases"`` one
            whose orbit lies on the table between its flights
            (:class:`~billiard.orbits.phases.PhaseMap`, docs/orbits.md).
        period: N, impacts per period (lift-offs per period under ``"phases"``).
        guess: (t, s, v1, v2, omega) just after an impact on ``wall``, a dict of them,
            an :class:`~billiard.runfile.record.ImpactRecord` (the wall is then the
            record's), or None: the state after ``settle`` impacts of the scene's run.
        free: coordinates Newton varies (default all; t and v2 under ``"phases"``).

    Returns:
        The :class:`Orbit`, converged to :data:`NEWTON_TOL` in its state.
    """
    rm = return_map(scene, period)
    if guess is None:
        records = rm.run_scene(settle)
        guess = records[-1]
    if isinstance(guess, ImpactRecord):
        wall = int(guess.wall)
        guess = (guess.t, guess.s, guess.v1, guess.v2, guess.omega)
    elif isinstance(guess, dict):
        missing = [k for k in STATE if k not in guess]
        if missing:
            raise OrbitError(f"the guess lacks {', '.join(missing)}")
        guess = [guess[k] for k in STATE]
    return newton(rm, guess, wall, free)
