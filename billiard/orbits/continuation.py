"""Pseudo-arclength continuation of a branch of periodic orbits through a scene key, with
step control, and the exact location of the bifurcations met on the way
(:mod:`billiard.orbits.bifurcation`).

The unknowns are the orbit's varied coordinates x and the key's value lam, both scaled
to order one. Each step predicts along the branch's unit tangent (the null vector of
[d F/dx, dF/dlam], F = P^N(x; lam) - x - m T(lam) e_t) and corrects by Newton's method on
F = 0 together with the hyperplane through the prediction orthogonal to the tangent.
dF/dx is the exact Jacobian (:mod:`billiard.orbits.jacobian`); dF/dlam, one column that
only steers the steps, is a central difference of the engine's map in lam (the scene
rebuilt at lam +- h). A step whose corrector needs many iterations or fails is halved; an
easy one lengthens the next.

Between two points a test function that changes sign, or an impact sequence that differs,
is located by bisection along the chord between them, each trial point corrected back
onto the branch on the hyperplane orthogonal to the chord, to 1e-12 of the chord.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from billiard.orbits.bifurcation import (
    BIFURCATIONS,
    GRAZING,
    NONE,
    SMOOTH,
    neimark_sacker_pair,
    test_functions,
)
from billiard.orbits.jacobian import map_jacobian
from billiard.orbits.newton import NEWTON_TOL, Orbit, free_indices, stable
from billiard.orbits.returnmap import STATE, OrbitError, ReturnMap
from billiard.scene.scene import SceneError, with_values

__all__ = ["Branch", "continue_branch", "continue_orbit", "variable_name"]

#: Corrector iterations before a step counts as failed (and is halved).
MAX_CORRECTOR = 10
#: Bisection steps locating a bifurcation: 2^-42 of the chord, ~2e-13.
BISECTIONS = 42
#: Relative step of the central difference dF/dlam.
LAMBDA_STEP = 1e-6


@dataclass
class Branch:
    """A continued branch: one entry per point, in the order along the branch.

    ``key`` the scene key varied, ``values`` its values, ``orbits`` the orbits,
    ``bifurcation`` a code of :data:`~billiard.orbits.bifurcation.BIFURCATIONS` per point
    (``none`` for a regular point), ``period`` N impacts."""

    key: str
    period: int
    values: list[float] = field(default_factory=list)
    orbits: list[Orbit] = field(default_factory=list)
    bifurcation: list[int] = field(default_factory=list)

    def points(self, code: str) -> list[float]:
        """The key's values at the points of bifurcation ``code``."""
        want = BIFURCATIONS.index(code)
        return [v for v, b in zip(self.values, self.bifurcation, strict=True) if b == want]

    def arrays(self) -> dict[str, np.ndarray]:
        """The branch as arrays by the names of branch.nc (docs/orbits.md)."""
        rows = [o.as_dict() for o in self.orbits]
        width = max((len(o.multipliers) for o in self.orbits), default=0)
        mults = np.full((len(rows), width), np.nan, dtype=complex)
        for i, o in enumerate(self.orbits):
            mults[i, : len(o.multipliers)] = o.multipliers
        out = {variable_name(self.key): np.array(self.values, dtype=float)}
        for name in ("t_phase", "s", "q1", "q2", "v1", "v2", "omega"):
            out[name] = np.array([r[name] for r in rows], dtype=float)
        out["multipliers_real"] = mults.real
        out["multipliers_imag"] = mults.imag
        out["stable"] = np.array([o.stable for o in self.orbits], dtype=np.int8)
        out["bifurcation"] = np.array(self.bifurcation, dtype=np.int8)
        return out

    def to_xarray(self) -> Any:
        """The branch as an ``xarray.Dataset`` (needs xarray: the ``data`` extra)."""
        import xarray as xr

        from billiard.orbits.netcdf import attributes

        arrays = self.arrays()
        attrs = attributes(self.key)
        data = {}
        for name, values in arrays.items():
            dims = ("point", "multiplier") if values.ndim == 2 else ("point",)
            data[name] = (dims, values, attrs.get(name, {}))
        ds = xr.Dataset(data)
        ds.attrs.update({"key": self.key, "period_impacts": self.period})
        return ds


def variable_name(key: str) -> str:
    """A scene key as a variable name: ``drive.amplitude`` -> ``drive_amplitude``."""
    return key.replace(".", "_")


class _Problem:
    """The branch's equations F(x, lam) = 0 over the varied coordinates ``idx``."""

    def __init__(self, scene, period, key, idx, wall, periods, scale):
        self.scene, self.period, self.key = scene, period, key
        self.idx, self.wall, self.periods = idx, wall, periods
        self.scale = scale  # of (x[idx], lam)
        self.x_full: np.ndarray | None = None
        self._maps: dict[float, ReturnMap] = {}

    def rmap(self, lam: float) -> ReturnMap:
        rm = self._maps.get(lam)
        if rm is None:
            try:
                scene = with_values(self.scene, {self.key: lam})
            except SceneError as exc:
                raise OrbitError(f"{self.key} = {lam:.10g}: {exc}") from None
            rm = ReturnMap(scene, self.period)
            if len(self._maps) > 8:
                self._maps.clear()
            self._maps[lam] = rm
        return rm

    def full(self, z: np.ndarray) -> tuple[np.ndarray, float]:
        y = z * self.scale
        x = self.x_full.copy()
        x[self.idx] = y[:-1]
        return x, float(y[-1])

    def residual(self, x: np.ndarray, lam: float) -> tuple[np.ndarray, Any, ReturnMap]:
        rm = self.rmap(lam)
        landing, records = rm(x, self.wall)
        if landing.wall != self.wall:
            raise OrbitError("the orbit left its wall sequence")
        res = landing.x - x
        res[0] -= self.periods * rm.period
        return res, records, rm

    def system(self, z: np.ndarray):
        """(F scaled, [dF/dz] scaled, records, rm) at z."""
        x, lam = self.full(z)
        res, records, rm = self.residual(x, lam)
        jac = map_jacobian(rm, x, self.wall, records)
        n = len(self.idx)
        sx = self.scale[:-1]
        dfx = jac[np.ix_(self.idx, self.idx)] - np.eye(n)
        h = LAMBDA_STEP * max(abs(lam), self.scale[-1])
        up, _, _ = self.residual(x, lam + h)
        down, _, _ = self.residual(x, lam - h)
        dfl = (up - down)[self.idx] / (2 * h)
        big = np.hstack([dfx * sx[None, :], (dfl * self.scale[-1])[:, None]]) / sx[:, None]
        return res[self.idx] / sx, big, records, rm, jac

    def correct(self, z0: np.ndarray, normal: np.ndarray):
        """Newton's method on F = 0 and normal . (z - z0) = 0; returns (z, iterations,
        records, jac) or raises OrbitError."""
        z = z0.copy()
        for it in range(1, MAX_CORRECTOR + 1):
            f, big, records, rm, jac = self.system(z)
            a = np.vstack([big, normal])
            b = np.concatenate([f, [normal @ (z - z0)]])
            try:
                dz = -np.linalg.solve(a, b)
            except np.linalg.LinAlgError:
                raise OrbitError("the corrector's system is singular") from None
            z = z + dz
            y = z * self.scale
            if np.max(np.abs(dz * self.scale) / (1.0 + np.abs(y))) <= NEWTON_TOL:
                x, lam = self.full(z)
                res, records, rm = self.residual(x, lam)
                jac = map_jacobian(rm, x, self.wall, records)
                return z, it, records, jac, rm
        raise OrbitError("the corrector did not converge")

    def tangent(self, z: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
        _, big, _, _, _ = self.system(z)
        if previous is None:
            tau = np.linalg.svd(big)[2][-1]
        else:
            a = np.vstack([big, previous])
            rhs = np.zeros(len(z))
            rhs[-1] = 1.0
            tau = np.linalg.solve(a, rhs)
        tau /= np.linalg.norm(tau)
        if previous is not None and tau @ previous < 0:
            tau = -tau
        return tau


@dataclass
class _Point:
    z: np.ndarray
    records: list
    jac: np.ndarray
    rm: ReturnMap

    def sequence(self):
        return tuple((int(r.wall), str(r.regime)) for r in self.records)


def _orbit(problem: _Problem, p: _Point) -> tuple[float, Orbit]:
    x, lam = problem.full(p.z)
    x[0] %= p.rm.period
    jac = p.jac[np.ix_(problem.idx, problem.idx)]
    mults = np.linalg.eigvals(jac)
    mults = mults[np.argsort(-np.abs(mults), kind="stable")]
    ball = p.rm.ball(x, problem.wall)
    orbit = Orbit(
        x=x,
        wall=problem.wall,
        impacts=problem.period,
        periods=problem.periods,
        jacobian=jac,
        multipliers=mults,
        stable=stable(mults),
        sequence=p.sequence(),
        records=p.records,
        lab=(ball.q1, ball.q2),
        residual=0.0,
        free=tuple(STATE[i] for i in problem.idx),
    )
    return lam, orbit


def _locate(problem: _Problem, a: _Point, b: _Point, side: Callable[[_Point], bool]) -> _Point:
    """Bisect the chord a-b for where ``side`` (True at a, False at b) changes."""
    lo, hi = 0.0, 1.0
    chord = b.z - a.z
    normal = chord / np.linalg.norm(chord)
    best = a
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        try:
            z, _, records, jac, rm = problem.correct(a.z + mid * chord, normal)
        except OrbitError:
            hi = mid  # no smooth orbit there: beyond the change
            continue
        point = _Point(z, records, jac, rm)
        if side(point):
            lo, best = mid, point
        else:
            hi = mid
    return best


def continue_branch(
    scene: Any,
    start: Orbit,
    key: str,
    span: tuple[float, float],
    points: int = 200,
    step: float | None = None,
    progress: Callable[[int], None] | None = None,
) -> Branch:
    """Continue ``start`` (an orbit of ``scene``) through scene key ``key`` over ``span``,
    in both directions from the scene's value, at most ``points`` points in all."""
    lo, hi = float(span[0]), float(span[1])
    lam0 = float(_scene_value(scene, key))
    if not lo < hi or not lo <= lam0 <= hi:
        raise OrbitError(
            f"{key} = {lam0:.10g} (the starting orbit's) must lie in the span {lo:g}:{hi:g}"
        )
    idx = [STATE.index(n) for n in start.free]
    floor = np.array([start_period(scene), 1e-3, 1e-2, 1e-2, 1.0])
    scale = np.append(np.maximum(np.abs(start.x), floor)[idx], max(abs(lam0), hi - lo))
    problem = _Problem(scene, start.impacts, key, idx, start.wall, start.periods, scale)
    problem.x_full = start.x.copy()
    z0 = np.append(start.x[idx], lam0) / scale
    res = problem.correct(z0, np.eye(len(z0))[-1])
    first = _Point(res[0], res[2], res[3], res[4])
    width = (hi - lo) / scale[-1]
    h0 = width / 40.0 if step is None else step / scale[-1]
    tau0 = problem.tangent(first.z, None)
    halves: list[tuple[_Point, int]] = []
    for sign in (1.0, -1.0):
        limit = max(points // 2, 1) if sign > 0 else max(points - len(halves), 1)
        tau = sign * tau0
        if tau[-1] == 0.0:
            tau[-1] = sign * 1e-300
        points_here = [(first, NONE)] if sign > 0 else []
        current = first
        h = h0
        while len(points_here) < limit:
            if h < h0 * 1e-7:
                break
            try:
                z, iterations, records, jac, rm = problem.correct(current.z + h * tau, tau)
                nxt = _Point(z, records, jac, rm)
                if np.linalg.norm(z - current.z) > 3 * h:
                    raise OrbitError("the step jumped to another branch")
            except OrbitError:
                h /= 2
                continue
            lam = z[-1] * scale[-1]
            events = _events(problem, current, nxt)
            for code, point in events:
                points_here.append((point, code))
            if not lo <= lam <= hi:
                break
            points_here.append((nxt, NONE))
            if progress is not None:
                progress(len(halves) + len(points_here))
            tau = problem.tangent(z, tau)
            current = nxt
            h = min(h * (1.5 if iterations <= 3 else 1.0), 4 * h0)
        if sign > 0:
            halves = points_here
        else:
            halves = points_here[::-1] + halves
    branch = Branch(key, start.impacts)
    for point, code in halves:
        lam, orbit = _orbit(problem, point)
        if lo <= lam <= hi:
            branch.values.append(lam)
            branch.orbits.append(orbit)
            branch.bifurcation.append(code)
    return branch


def _events(problem: _Problem, a: _Point, b: _Point) -> list[tuple[int, _Point]]:
    """The bifurcations between consecutive points a and b, located, in order."""
    found = []
    if a.sequence() != b.sequence():
        seq = a.sequence()
        point = _locate(problem, a, b, lambda p: p.sequence() == seq)
        found.append((GRAZING, point))
        return found  # the map is not smooth across it: the test functions do not compare
    idx = problem.idx
    fa = test_functions(a.jac[np.ix_(idx, idx)])
    fb = test_functions(b.jac[np.ix_(idx, idx)])
    for k, name in enumerate(SMOOTH):
        if np.sign(fa[k]) == np.sign(fb[k]) or fa[k] == 0.0:
            continue
        sign = np.sign(fa[k])

        def side(p: _Point, k: int = k, sign: float = sign) -> bool:
            return np.sign(test_functions(p.jac[np.ix_(idx, idx)])[k]) == sign

        point = _locate(problem, a, b, side)
        if name == "neimark_sacker":
            mults = np.linalg.eigvals(point.jac[np.ix_(idx, idx)])
            if not neimark_sacker_pair(mults):
                continue  # a neutral saddle: two real multipliers with product 1
        found.append((BIFURCATIONS.index(name), point))
    found.sort(key=lambda cp: float(np.linalg.norm(cp[1].z - a.z)))
    return found


def start_period(scene: Any) -> float:
    """The drive period (s) of a scene, for scaling the time coordinate."""
    f = float(scene.drive.frequency)
    return 1.0 / f if f > 0 else 1.0


def _scene_value(scene: Any, key: str) -> float:
    section, _, name = key.partition(".")
    try:
        value = getattr(getattr(scene, section), name)
    except AttributeError:
        raise OrbitError(f"unknown scene key {key!r}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise OrbitError(f"scene key {key!r} is not a number, and cannot be continued")
    return float(value)


def continue_orbit(
    scene: Any,
    period: int = 1,
    vary: str = "drive.amplitude",
    span: tuple[float, float] = (0.0, 1.0),
    guess: Sequence[float] | Any = None,
    free: Sequence[str] | None = None,
    points: int = 200,
    step: float | None = None,
) -> Any:
    """Continue the period-``period`` orbit of ``scene`` through scene key ``vary`` over
    ``span``: an ``xarray.Dataset`` over dimension ``point`` (docs/orbits.md).

    The starting orbit is found by :func:`billiard.orbits.newton.find_orbit` from ``guess``
    at the scene's own value of ``vary``, which must lie in ``span``."""
    from billiard.orbits.newton import find_orbit

    free_indices(free)
    start = find_orbit(scene, period, guess=guess, free=free)
    return continue_branch(scene, start, vary, span, points, step).to_xarray()
