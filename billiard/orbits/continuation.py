"""Pseudo-arclength continuation of a branch of periodic orbits through a scene key, with
step control, and the exact location of the bifurcations met on the way
(:mod:`billiard.orbits.bifurcation`).

The unknowns are the orbit's varied coordinates x and the key's value lam, both scaled
to order one. Each step predicts along the branch's unit tangent (the null vector of
[d F/dx, dF/dlam], F = P^N(x; lam) - x - m T(lam) e_t) and corrects by Newton's method on
F = 0 together with the hyperplane through the prediction orthogonal to the tangent.
dF/dx is the exact Jacobian (:mod:`billiard.orbits.jacobian`); dF/dlam, one column that
only steers the corrector and the tangent, is a one-sided difference of the engine's map in
lam (the scene rebuilt at lam + h), renewed every few steps. Away from a fold the
corrector holds lam at its predicted value (the hyperplane lam = const crosses the branch
steeply there, and every iteration runs one engine); near a fold it corrects on the
pseudo-arclength hyperplane. A step whose corrector fails is halved; an easy one lengthens
the next.

Between two points a test function that changes sign, or an impact sequence that differs,
is located by bisection along the chord between them, each trial point corrected back
onto the branch: a test function's zero by the Illinois method, a change of sequence by
bisection, to about 1e-13 of the chord. At a branch point (two branches crossing) the
corrector's system is singular; :func:`_zero` says how a symmetric orbit's is located
all the same (to 2e-10 of the key, measured on the parabola).

At a period doubling the branch of period 2N born there can be switched onto
(``switch``; :func:`_switch` says how) and continued in turn.
"""

from __future__ import annotations

import math
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
from billiard.orbits.newton import NEWTON_TOL, Orbit, free_indices, stable
from billiard.orbits.phases import return_map
from billiard.orbits.returnmap import STATE, OrbitError, ReturnMap, SequenceChange, landing
from billiard.scene.scene import SceneError, key_number, with_values

__all__ = [
    "Branch",
    "check_span",
    "continue_branch",
    "continue_orbit",
    "scene_value",
    "variable_name",
]

#: Corrector iterations before a step counts as failed (and is halved).
MAX_CORRECTOR = 10
#: Bisection steps locating a bifurcation: 2^-42 of the chord, ~2e-13.
BISECTIONS = 42
#: Relative step of the difference dF/dlam.
LAMBDA_STEP = 1e-6
#: Steps a dF/dlam column is used for before it is taken afresh (it only steers the
#: corrector and the tangent; a step that needed more than 3 iterations renews it).
COLUMN_AGE = 5
#: The key's part of the unit tangent (scaled) below which the corrector leaves the key
#: free, on the pseudo-arclength hyperplane (near a fold), rather than holding it.
STEEP = 0.05
#: Shortest step, relative to the first, before a direction is given up.
MIN_STEP = 1e-6
#: The residual |F| (relative to 1 + |x|, as NEWTON_TOL) at which a point beside a branch
#: point counts as on the branch: the engine's map repeats itself to about 1e-15, and
#: there the corrector's steps stall at that noise over the vanishing singular value of
#: its system while F stays at it (measured on the parabola: 3e-16 to 7e-14).
RESIDUAL_FLOOR = 1e-13
#: Offsets along the doubling's eigenvector (halved each time) tried for the first point
#: of the period-2N branch.
SWITCH_TRIES = 8


@dataclass
class Branch:
    """A continued branch: one entry per point, in the order along the branch.

    ``key`` the scene key varied, ``values`` its values, ``orbits`` the orbits,
    ``bifurcation`` a code of :data:`~billiard.orbits.bifurcation.BIFURCATIONS` per point
    (``none`` for a regular point), ``period`` N impacts of the branch continued,
    ``segment`` per point the branch it lies on: 0 the one continued, k >= 1 the k-th
    period-2N branch switched onto at a period doubling (its points, from the doubling
    outwards, follow the continued branch's)."""

    key: str
    period: int
    values: list[float] = field(default_factory=list)
    orbits: list[Orbit] = field(default_factory=list)
    bifurcation: list[int] = field(default_factory=list)
    segment: list[int] = field(default_factory=list)

    def add(self, lam: float, orbit: Orbit, code: int, segment: int = 0) -> None:
        """Append a point."""
        self.values.append(lam)
        self.orbits.append(orbit)
        self.bifurcation.append(code)
        self.segment.append(segment)

    def points(self, code: str, segment: int = 0) -> list[float]:
        """The key's values at the points of bifurcation ``code`` on branch ``segment``
        (0 the one continued)."""
        want = BIFURCATIONS.index(code)
        rows = zip(self.values, self.bifurcation, self.segment, strict=True)
        return [v for v, b, k in rows if b == want and k == segment]

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
        # which branch a point lies on, and its period: a switched branch's are 2N
        out["period"] = np.array([o.impacts for o in self.orbits], dtype=np.int32)
        out["drive_periods"] = np.array([o.periods for o in self.orbits], dtype=np.int32)
        out["branch"] = np.array(self.segment, dtype=np.int32)
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
    """The branch's equations F(x, lam) = 0 over the varied coordinates ``idx``, the
    impacts hitting the walls ``walls`` in turn (the map's
    :meth:`~billiard.orbits.returnmap.ReturnMap.route`)."""

    def __init__(self, scene, period, key, idx, wall, periods, scale, walls):
        self.scene, self.period, self.key = scene, period, key
        self.idx, self.wall, self.periods = idx, wall, periods
        self.scale = scale  # of (x[idx], lam)
        self.walls = walls
        self.x_full: np.ndarray | None = None
        self._maps: dict[float, ReturnMap] = {}

    def rmap(self, lam: float) -> ReturnMap:
        rm = self._maps.get(lam)
        if rm is None:
            try:
                scene = with_values(self.scene, {self.key: lam})
            except SceneError as exc:
                raise OrbitError(f"{self.key} = {lam:.10g}: {exc}") from None
            rm = return_map(scene, self.period)
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
        if rm.route(x, records) != self.walls:
            raise SequenceChange("the orbit left its wall sequence")
        res = landing.x - x
        res[0] -= self.periods * rm.period
        return res, records, rm

    def lambda_column(self, z: np.ndarray) -> np.ndarray:
        """dF/dlam (scaled) at z, a difference of the engine's map."""
        x, lam = self.full(z)
        h = LAMBDA_STEP * max(abs(lam), self.scale[-1])
        # one-sided: the value at lam is the current point's, whose engine is built
        # already; a difference to 1e-6 steers as well as a central one
        ends = []
        for offset in (0.0, h, -h):
            try:
                ends.append((offset, self.residual(x, lam + offset)[0]))
            except SequenceChange:
                continue
            if len(ends) == 2:
                break
        if len(ends) < 2:
            raise SequenceChange("the orbit leaves its wall sequence within the key's step")
        (a, fa), (b, fb) = ends
        return (fa - fb)[self.idx] / (a - b) * self.scale[-1] / self.scale[:-1]

    def system(self, z: np.ndarray, column: np.ndarray):
        """(F scaled, [dF/dx dF/dlam] scaled, the point at z but its z, full Jacobian)
        at z, with the lam column given."""
        x, lam = self.full(z)
        res, records, rm = self.residual(x, lam)
        jac = rm.jacobian(x, self.wall, records)
        sx = self.scale[:-1]
        dfx = (jac[np.ix_(self.idx, self.idx)] - np.eye(len(self.idx))) * sx[None, :]
        big = np.hstack([dfx / sx[:, None], column[:, None]])
        return res[self.idx] / sx, big, _Point(z, records, jac, rm, big, rm.sequence(x, records))

    def correct(
        self,
        z0: np.ndarray,
        normal: np.ndarray,
        column: np.ndarray | None = None,
        floor: bool = False,
    ):
        """Newton's method on F = 0 and normal . (z - z0) = 0; returns (point,
        iterations) or raises OrbitError. The lam column (taken at z0 unless given) is
        held through the iterations: it only steers them, and each costs two engines.
        A normal along lam alone holds lam at z0's, bit for bit: every iteration then
        runs the one engine built for that value. With ``floor``, an iterate whose
        residual is down to :data:`RESIDUAL_FLOOR` is taken too, its step unfinished:
        beside a branch point (see :func:`_zero`)."""
        z = z0.copy()
        held = bool(np.all(normal[:-1] == 0.0))
        if column is None:
            column = self.lambda_column(z)
        for it in range(1, MAX_CORRECTOR + 1):
            f, big, here = self.system(z, column)
            if floor and it > 1:
                y = z[:-1] * self.scale[:-1]
                if np.max(np.abs(f * self.scale[:-1]) / (1.0 + np.abs(y))) <= RESIDUAL_FLOOR:
                    return here, it
            a = np.vstack([big, normal])
            b = np.concatenate([f, [normal @ (z - z0)]])
            try:
                dz = -(_solve_to_floor(a, b) if floor else np.linalg.solve(a, b))
            except np.linalg.LinAlgError:
                raise OrbitError("the corrector's system is singular") from None
            z = z + dz
            if held:
                z[-1] = z0[-1]
            y = z * self.scale
            if np.max(np.abs(dz * self.scale) / (1.0 + np.abs(y))) <= NEWTON_TOL:
                # the last step moved z by 1e-12 of itself: the records and Jacobian of
                # the point before it stand for it (the Jacobian to 1e-12, the impact
                # sequence exactly) without another engine
                here.z = z
                return here, it
        raise OrbitError("the corrector did not converge")


def _solve_to_floor(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The solution of a x = b without the parts of b (along a's left singular vectors)
    already at :data:`RESIDUAL_FLOOR`: beside a branch point such a part, over a
    vanishing singular value, would throw x off the branch (a symmetric orbit off its
    symmetry) by rounding alone; elsewhere it is a step below rounding."""
    u, sv, vt = np.linalg.svd(a)
    c = u.T @ b
    keep = np.abs(c) > RESIDUAL_FLOOR
    return vt.T[:, keep] @ (c[keep] / sv[keep])


def _tangent(big: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """The branch's unit tangent: the null vector of ``big``, oriented along
    ``previous``."""
    if previous is None:
        tau = np.linalg.svd(big)[2][-1]
    else:
        a = np.vstack([big, previous])
        rhs = np.zeros(big.shape[1])
        rhs[-1] = 1.0
        tau = np.linalg.solve(a, rhs)
    tau = tau / np.linalg.norm(tau)
    if previous is not None and tau @ previous < 0:
        tau = -tau
    return tau


@dataclass
class _Point:
    z: np.ndarray
    records: list
    jac: np.ndarray
    rm: ReturnMap
    big: np.ndarray
    seq: tuple  # the map's sequence of the records

    def sequence(self):
        return self.seq


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
        residual=math.nan,  # converged by the corrector: its step, not its residual
        free=tuple(STATE[i] for i in problem.idx),
    )
    return lam, orbit


def _on_chord(
    problem: _Problem, a: _Point, chord: np.ndarray, sigma: float, floor: bool = False
) -> _Point | None:
    """The branch's point on the hyperplane orthogonal to ``chord`` at a + sigma chord,
    or None where the corrector finds no orbit of the branch's wall sequence. ``floor``:
    as :meth:`_Problem.correct`'s."""
    normal = chord / np.linalg.norm(chord)
    if abs(normal[-1]) >= STEEP:  # as the steps: the key held where the chord is steep
        normal = np.eye(len(normal))[-1]
    try:
        return problem.correct(a.z + sigma * chord, normal, floor=floor)[0]
    except OrbitError:
        return None


def _bisect(problem: _Problem, a: _Point, b: _Point, side: Callable[[_Point], bool]) -> _Point:
    """Bisect the chord a-b for where ``side`` (True at a, False at b) changes: the last
    point on a's side, within 2^-42 of the chord."""
    lo, hi = 0.0, 1.0
    chord = b.z - a.z
    best = a
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        point = _on_chord(problem, a, chord, mid)
        if point is not None and side(point):
            lo, best = mid, point
        else:
            hi = mid  # no smooth orbit of the branch there: beyond the change
    return best


def _zero(problem: _Problem, a: _Point, b: _Point, k: int) -> _Point:
    """The zero of test function ``k`` on the chord a-b (its signs differ at a and b):
    the Illinois variant of regula falsi, which keeps the zero bracketed and converges
    superlinearly, to 1e-13 of the chord (or until its estimate stops moving, or the test
    function is exactly zero); where a trial point has no orbit it bisects.

    A multiplier +1 (``k`` 0) may be a branch point, where two branches cross and the
    corrector's system, on either hyperplane, is singular. Beside it the residual's part
    along the vanishing singular direction is the map's rounding (about 1e-15), and
    Newton's steps, that rounding over the singular value, stall at 1e-10 to 1e-7
    (measured at 1e-9 of the key from the parabola's) and never pass the step test. So
    for k 0 the corrector leaves out of its steps the parts of the residual already at
    rounding (:func:`_solve_to_floor`), and takes a point once its residual is there
    (``floor``): a symmetric orbit stays symmetric, and the parabola's two branch points
    come out within 5e-13 to 2e-10 (relative) of the period doublings of its half-period
    map, where Newton's method is regular (5e-5 without). Where the crossing is not
    forced by a symmetry (a transcritical crossing) the chord's own error along that
    direction is no rounding, is kept, and the zero is located less sharply."""
    idx = problem.idx
    floor = k == 0

    def value(p: _Point) -> float:
        return float(test_functions(p.jac[np.ix_(idx, idx)])[k])

    chord = b.z - a.z
    lo, hi, f_lo, f_hi = 0.0, 1.0, value(a), value(b)
    best, best_f, side, previous = a, abs(f_lo), 0, -1.0
    for _ in range(BISECTIONS):
        if hi - lo <= 1e-13:
            break
        sigma = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not lo < sigma < hi:
            sigma = 0.5 * (lo + hi)
        if abs(sigma - previous) <= 1e-14:
            break  # the estimate has settled to rounding
        previous = sigma
        point = _on_chord(problem, a, chord, sigma, floor)
        if point is None:
            sigma = 0.5 * (lo + hi)
            point = _on_chord(problem, a, chord, sigma, floor)
            if point is None:
                break
        f = value(point)
        if abs(f) <= best_f:  # the point nearest the zero, should a trial point fail
            best, best_f = point, abs(f)
        if f == 0.0:
            break
        if np.sign(f) == np.sign(f_lo):
            lo, f_lo = sigma, f
            if side == -1:
                f_hi /= 2  # Illinois: halve the end that stayed, so that it moves too
            side = -1
        else:
            hi, f_hi = sigma, f
            if side == 1:
                f_lo /= 2
            side = 1
    return best


def continue_branch(
    scene: Any,
    start: Orbit,
    key: str,
    span: tuple[float, float],
    points: int = 200,
    step: float | None = None,
    progress: Callable[[int], None] | None = None,
    switch: bool = False,
) -> Branch:
    """Continue ``start`` (an orbit of ``scene``) through scene key ``key`` over ``span``,
    in both directions from the scene's value, at most ``points`` points in all.

    With ``switch``, at each period doubling located on it the branch of period 2N born
    there is continued too (:func:`_switch`, at most ``points // 2`` points each), its
    points appended as segments 1, 2, ... of the :class:`Branch`."""
    lo, hi = float(span[0]), float(span[1])
    lam0 = check_span(scene, key, (lo, hi))
    idx = [STATE.index(n) for n in start.free]
    floor = np.array([start_period(scene), 1e-3, 1e-2, 1e-2, 1.0])
    scale = np.append(np.maximum(np.abs(start.x), floor)[idx], max(abs(lam0), hi - lo))
    problem = _Problem(scene, start.impacts, key, idx, start.wall, start.periods, scale, None)
    problem.walls = problem.rmap(lam0).route(start.x, start.records)
    problem.x_full = start.x.copy()
    z0 = np.append(start.x[idx], lam0) / scale
    first = problem.correct(z0, np.eye(len(z0))[-1])[0]
    h0 = (hi - lo) / scale[-1] / 40.0 if step is None else step / scale[-1]
    tau0 = _tangent(first.big, None)
    ahead = _walk(problem, first, tau0, h0, (lo, hi), max(points // 2, 1), progress)
    counted = None if progress is None else (lambda n: progress(len(ahead) + n - 1))
    behind = _walk(problem, first, -tau0, h0, (lo, hi), max(points - len(ahead), 1) + 1, counted)
    # the starting point is both walks' first: a grazing either walk met at once marks it
    code = max(ahead[0][1], behind[0][1])
    halves = behind[:0:-1] + [(first, code)] + ahead[1:]
    branch = Branch(key, start.impacts)
    _append(branch, problem, halves, (lo, hi), 0)
    if switch:
        doublings = [p for p, code in halves if code == BIFURCATIONS.index("period_doubling")]
        for point in doublings:
            done = len(branch.values)
            counted = None if progress is None else (lambda n, done=done: progress(done + n))
            doubled, found = _switch(problem, point, h0, (lo, hi), max(points // 2, 2), counted)
            _append(branch, doubled, found, (lo, hi), max(branch.segment) + 1)
    return branch


def _append(
    branch: Branch,
    problem: _Problem,
    found: list[tuple[_Point, int]],
    span: tuple[float, float],
    segment: int,
) -> None:
    """Append the points ``found`` of ``problem``'s branch inside ``span`` to ``branch``."""
    for point, code in found:
        lam, orbit = _orbit(problem, point)
        if span[0] <= lam <= span[1]:
            branch.add(lam, orbit, code, segment)


def _switch(
    problem: _Problem,
    doubling: _Point,
    h0: float,
    span: tuple[float, float],
    limit: int,
    progress: Callable[[int], None] | None = None,
) -> tuple[_Problem, list[tuple[_Point, int]]]:
    """The branch of period 2N born at the period doubling ``doubling`` of ``problem``'s
    branch (period N), from the doubling outwards: (its problem, its points).

    At the doubling x* the Jacobian has the multiplier -1 with eigenvector v; the period-N
    orbit is a fixed point of P^2N too, where P^2N has the multiplier +1 along v, and the
    doubled branch leaves it along v, orthogonally to the key (a pitchfork of P^2N, the
    key going as the square of the offset). So the first point is corrected on the
    hyperplane through x* + h v orthogonal to v, the key free: it lands on the side of the
    doubling where the doubled orbit exists (beyond it for a supercritical doubling,
    before it for a subcritical one) without having to know which. h starts at the
    branch's first step and is halved while the corrector fails or finds the period-N
    orbit again. The doubling itself is the doubled branch's first point."""
    idx = problem.idx
    mults, vectors = np.linalg.eig(doubling.jac[np.ix_(idx, idx)])
    k = int(np.argmin(np.abs(mults + 1.0)))
    v = np.append(vectors[:, k].real / problem.scale[:-1], 0.0)  # scaled, the key held
    v /= np.linalg.norm(v)
    doubled = _Problem(
        problem.scene,
        2 * problem.period,
        problem.key,
        idx,
        problem.wall,
        2 * problem.periods,
        problem.scale,
        None,
    )
    doubled.x_full = problem.x_full
    x, lam = doubled.full(doubling.z)
    rm = doubled.rmap(lam)
    doubled.walls = rm.route(x, rm(x, problem.wall)[1])  # the period-N route, twice
    found: list[tuple[_Point, int]] = [(doubled.system(doubling.z, np.zeros(len(idx)))[2], NONE)]
    h = h0
    for _ in range(SWITCH_TRIES):
        try:
            point = doubled.correct(doubling.z + h * v, v)[0]
        except OrbitError:
            point = None
        # the doubled orbit's two halves lie about 2 h apart; the period-N orbit's coincide
        if point is not None and _split(problem, doubled, point) > h / 4:
            break
        h /= 2
    else:
        return doubled, found  # no doubled orbit beside it (a grazing there, say)
    return doubled, found + _walk(doubled, point, _tangent(point.big, v), h0, span, limit, progress)


def _split(problem: _Problem, doubled: _Problem, point: _Point) -> float:
    """How far (scaled) the state N impacts after ``point``, an orbit of period 2N, lies
    from its own: 0 for an orbit of period N."""
    x, _ = doubled.full(point.z)
    gap = landing(point.records[problem.period - 1]).x - x
    gap[0] -= problem.periods * point.rm.period
    return float(np.linalg.norm(gap[problem.idx] / problem.scale[:-1]))


def _walk(
    problem: _Problem,
    first: _Point,
    tau: np.ndarray,
    h0: float,
    span: tuple[float, float],
    limit: int,
    progress: Callable[[int], None] | None = None,
) -> list[tuple[_Point, int]]:
    """Follow the branch from ``first`` along ``tau`` with step control (first step
    ``h0``, scaled) until the key leaves ``span``, the branch ends or ``limit`` points
    are taken; returns ``first`` and the points after it, each with its bifurcation
    code."""
    lo, hi = span
    scale = problem.scale
    here: list[tuple[_Point, int]] = [(first, NONE)]
    current, h, grazed, column, age = first, h0, False, None, 0
    while len(here) < limit:
        if h < h0 * MIN_STEP:
            if grazed:
                # the wall sequence ends here: a flight touches a wall (grazing)
                here[-1] = (here[-1][0], GRAZING)
            break
        try:
            if column is None or age >= COLUMN_AGE:
                column, age = problem.lambda_column(current.z), 0
            # away from a fold the corrector holds the key at the predicted value (on the
            # hyperplane lam = const, which the branch crosses steeply there): one engine
            # per step instead of one per iteration; near a fold (the key's part of the
            # tangent under STEEP) it corrects on the pseudo-arclength hyperplane
            normal = tau if abs(tau[-1]) < STEEP else np.eye(len(tau))[-1]
            nxt, iterations = problem.correct(current.z + h * tau, normal, column)
            if np.linalg.norm(nxt.z - current.z) > 3 * h:
                raise OrbitError("the step jumped to another branch")
        except SequenceChange:
            h, grazed, column = h / 2, True, None
            continue
        except OrbitError:
            h, grazed, column = h / 2, False, None
            continue
        age += 1
        if iterations > 4:
            column = None  # a stale column slows the corrector: a fresh one next step
        if _through_one(problem, current, nxt):
            # a multiplier passed +1: beside a branch point dF/dx is near singular and the
            # tangent, -(dF/dx)^-1 dF/dlam, takes any error of a column taken elsewhere
            # over that vanishing singular value (the parabola's second branch point:
            # a fold, the walk turned back); so the tangent here gets its own column
            column, age = problem.lambda_column(nxt.z), 0
            nxt.big[:, -1] = column
        new_tau = _tangent(nxt.big, tau)
        for code, point in _events(problem, current, nxt, tau, new_tau):
            here.append((point, code))
        if not lo <= nxt.z[-1] * scale[-1] <= hi:
            break
        here.append((nxt, NONE))
        if progress is not None:
            progress(len(here))
        tau, current = new_tau, nxt
        h = min(h * (1.5 if iterations <= 3 else 1.0), 4 * h0)
    return here


def _through_one(problem: _Problem, a: _Point, b: _Point) -> bool:
    """Has a multiplier passed +1 between a and b (det(J - I) changed sign)?"""
    idx = problem.idx
    fa, fb = (test_functions(p.jac[np.ix_(idx, idx)])[0] for p in (a, b))
    return bool(np.sign(fa) != np.sign(fb))


def _events(
    problem: _Problem, a: _Point, b: _Point, tau_a: np.ndarray, tau_b: np.ndarray
) -> list[tuple[int, _Point]]:
    """The bifurcations between consecutive points a and b (tangents tau_a, tau_b),
    located, in order along the branch."""
    if a.sequence() != b.sequence():
        seq = a.sequence()
        # the map is not smooth across it: the test functions do not compare
        return [(GRAZING, _bisect(problem, a, b, lambda p: p.sequence() == seq))]
    idx = problem.idx
    fa = test_functions(a.jac[np.ix_(idx, idx)])
    fb = test_functions(b.jac[np.ix_(idx, idx)])
    found = []
    for k, name in enumerate(SMOOTH):
        if fa[k] == 0.0 or np.sign(fa[k]) == np.sign(fb[k]):
            continue
        point = _zero(problem, a, b, k)
        if name == "neimark_sacker":
            mults = np.linalg.eigvals(point.jac[np.ix_(idx, idx)])
            if not neimark_sacker_pair(mults):
                continue  # a neutral saddle: two real multipliers with product 1
        if name == "fold" and np.sign(tau_a[-1]) == np.sign(tau_b[-1]):
            # a multiplier through +1 where the key goes on: no turning point but a
            # branch point (a symmetric orbit's pitchfork, a transcritical crossing)
            name = "branch_point"
        found.append((BIFURCATIONS.index(name), point))
    found.sort(key=lambda cp: float(np.linalg.norm(cp[1].z - a.z)))
    return found


def check_span(scene: Any, key: str, span: tuple[float, float]) -> float:
    """The scene's value of ``key``, refused (OrbitError) outside ``span``."""
    lo, hi = float(span[0]), float(span[1])
    lam0 = scene_value(scene, key)
    if not lo < hi or not lo <= lam0 <= hi:
        raise OrbitError(
            f"{key} = {lam0:.10g} (the starting orbit's) must lie in the span {lo:g}:{hi:g}"
        )
    return lam0


def start_period(scene: Any) -> float:
    """The drive period (s) of a scene, for scaling the time coordinate."""
    f = float(scene.drive.frequency)
    return 1.0 / f if f > 0 else 1.0


def scene_value(scene: Any, key: str) -> float:
    """The value of numeric scene key ``key`` (OrbitError for another)."""
    try:
        value = key_number(scene, key)
    except KeyError:
        raise OrbitError(f"unknown scene key {key!r}") from None
    if value is None:
        raise OrbitError(f"scene key {key!r} is not a number, and cannot be continued")
    return value


def continue_orbit(
    scene: Any,
    period: int = 1,
    vary: str = "drive.amplitude",
    span: tuple[float, float] = (0.0, 1.0),
    guess: Sequence[float] | Any = None,
    free: Sequence[str] | None = None,
    points: int = 200,
    step: float | None = None,
    switch: bool = False,
) -> Any:
    """Continue the period-``period`` orbit of ``scene`` through scene key ``vary`` over
    ``span``: an ``xarray.Dataset`` over dimension ``point`` (docs/orbits.md).

    The starting orbit is found by :func:`billiard.orbits.newton.find_orbit` from ``guess``
    at the scene's own value of ``vary``, which must lie in ``span``. With ``switch`` the
    branches of period 2N born at its period doublings are continued too (the
    Dataset's ``period`` and ``branch`` tell them apart)."""
    from billiard.orbits.newton import find_orbit

    free_indices(free)
    start = find_orbit(scene, period, guess=guess, free=free)
    return continue_branch(scene, start, vary, span, points, step, switch=switch).to_xarray()
