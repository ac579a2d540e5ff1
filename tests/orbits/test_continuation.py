"""continue_orbit: the bouncing ball's branch of period-one orbits through the drive
amplitude, its fold and period doubling located against the closed forms
(tests/orbits/table.py), and its points re-run by brute force."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from billiard.orbits.bifurcation import BIFURCATIONS
from billiard.orbits.continuation import continue_branch, continue_orbit
from billiard.orbits.jacobian import map_jacobian
from billiard.orbits.newton import find_orbit
from billiard.orbits.returnmap import OrbitError, ReturnMap
from billiard.scene.scene import load_scene, with_values
from tests.orbits import table


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


VERTICAL = ("t", "v2")
E = 0.5


@pytest.fixture(scope="module")
def branch(billiard_home):
    scene = table.scene(1.3, E)
    t, v = table.orbit(1.3, E)
    start = find_orbit(scene, 1, guess=(t, 0.0, 0.0, v, 0.0), free=VERTICAL)
    span = (table.amplitude(1.0), table.amplitude(1.7))
    return scene, continue_branch(scene, start, "drive.amplitude", span, points=100)


def test_the_fold_and_the_period_doubling_are_located_to_1e_8(branch):
    _, br = branch
    unit = table.amplitude(1.0)  # A at Gamma = 1
    folds = [a / unit for a in br.points("fold")]
    doublings = [a / unit for a in br.points("period_doubling")]
    assert len(folds) == 1 and len(doublings) == 1
    assert folds[0] == pytest.approx(table.onset(E), rel=1e-8)
    assert doublings[0] == pytest.approx(table.period_doubling(E), rel=1e-8)
    assert br.points("neimark_sacker") == [] and br.points("grazing") == []


def test_the_branch_is_stable_between_the_fold_and_the_period_doubling(branch):
    _, br = branch
    gamma = np.array(br.values) / table.amplitude(1.0)
    stable = np.array([o.stable for o in br.orbits])
    # the stable half: decelerating table at the impact, sin(theta) > 0
    theta = np.array([o.x[0] for o in br.orbits]) * table.W
    upper = np.sin(theta) > 0
    inside = (gamma > table.onset(E) * (1 + 1e-6)) & (gamma < table.period_doubling(E) * (1 - 1e-6))
    regular = np.array(br.bifurcation) == 0
    assert np.array_equal(stable[regular], (upper & inside)[regular])
    # both halves met: the fold joins them
    assert upper.any() and (~upper).any()
    # every point is the closed form's orbit at its Gamma
    for g, o, up in zip(gamma, br.orbits, upper, strict=True):
        t, v = table.orbit(g, E, 1, bool(up))
        assert o.x[3] == pytest.approx(v, abs=1e-12)
        phase = (o.x[0] - t + table.T / 2) % table.T - table.T / 2
        assert abs(phase) < 1e-9  # s; the fold's phase is a square root of Gamma - Gamma_1


def test_points_rerun_by_the_engine_stay_where_stable_and_leave_where_not(branch):
    """Each point, nudged by 1e-10 of its phase and speed, run 1,000 periods. Unnudged,
    even a saddle stays: its state is a fixed point of the engine's floating-point map,
    bit for bit, so rounding never starts the departure."""
    _, br = branch
    checked = {True: 0, False: 0}
    for value, o in zip(br.values, br.orbits, strict=True):
        largest = np.max(np.abs(o.multipliers))
        if 0.95 < largest < 1.05:
            continue  # too close to a bifurcation for 1,000 periods to tell
        rm = ReturnMap(table.scene(value / table.amplitude(1.0), E), 1)
        try:
            nudged = o.x + np.array([1e-10 * table.T, 0.0, 0.0, 1e-10 * o.x[3], 0.0])
            end = rm.run(nudged, o.wall, impacts=1000)[-1]
            # the phase too: a saddle's ball may settle on the stable orbit at the same
            # Gamma, whose take-off speed is the same g T / 2
            phase = (end.t - o.x[0] + table.T / 2) % table.T - table.T / 2
            drift = max(abs(end.v2 - o.x[3]) / o.x[3], abs(phase) / table.T)
        except OrbitError:
            drift = np.inf  # it left so far that the run stopped
        if o.stable:
            assert drift < 1e-9
        else:
            assert drift > 1e-3
        checked[bool(o.stable)] += 1
    assert checked[True] >= 3 and checked[False] >= 3


def test_continue_orbit_returns_the_dataset_of_the_issue():
    scene = table.scene(1.3, E)
    t, v = table.orbit(1.3, E)
    ds = continue_orbit(
        scene,
        period=1,
        vary="drive.amplitude",
        span=(table.amplitude(1.2), table.amplitude(1.4)),
        guess=(t, 0.0, 0.0, v, 0.0),
        free=VERTICAL,
        points=10,
    )
    assert set(ds.dims) == {"point", "multiplier"}
    for name in ("drive_amplitude", "t_phase", "q1", "q2", "v1", "v2", "omega", "stable"):
        assert ds[name].dims == ("point",)
    assert ds["multipliers_real"].dims == ("point", "multiplier")
    assert ds["bifurcation"].attrs["flag_meanings"] == " ".join(BIFURCATIONS)
    assert ds["bifurcation"].attrs["flag_meanings"] == (
        "none fold period_doubling neimark_sacker grazing branch_point"
    )
    assert ds["stable"].values.tolist() == [1] * ds.sizes["point"]
    a = ds["drive_amplitude"].values
    assert a.min() >= table.amplitude(1.2) and a.max() <= table.amplitude(1.4)
    # the orbit's take-off speed is g T / 2 all along (the table returns to its height)
    assert ds["v2"].values == pytest.approx(table.G * table.T / 2, abs=1e-12)


def test_a_span_without_the_starting_value_is_refused():
    scene = table.scene(1.3, E)
    t, v = table.orbit(1.3, E)
    start = find_orbit(scene, 1, guess=(t, 0.0, 0.0, v, 0.0), free=VERTICAL)
    with pytest.raises(OrbitError, match="must lie in the span"):
        continue_branch(scene, start, "drive.amplitude", (1.0, 2.0))
    with pytest.raises(OrbitError, match="unknown scene key"):
        continue_branch(scene, start, "drive.nothing", (0.0, 1.0))


@pytest.fixture(scope="module")
def switched(billiard_home):
    """The period-one branch with the period-two branch switched onto at its doubling."""
    scene = table.scene(1.3, E)
    t, v = table.orbit(1.3, E)
    start = find_orbit(scene, 1, guess=(t, 0.0, 0.0, v, 0.0), free=VERTICAL)
    span = (table.amplitude(1.0), table.amplitude(1.7))
    return continue_branch(scene, start, "drive.amplitude", span, points=100, switch=True)


def _doubled(br):
    """(Gamma, orbit, code) of the points of the first switched branch."""
    unit = table.amplitude(1.0)
    return [
        (value / unit, o, code)
        for value, o, code, segment in zip(
            br.values, br.orbits, br.bifurcation, br.segment, strict=True
        )
        if segment == 1
    ]


def test_the_period_two_branch_starts_at_the_doubling_and_is_the_maps_orbit(switched):
    """The switched branch starts at the period-one orbit's doubling and every point is the
    period-two orbit of the 2-D map (tests/orbits/table.py), solved independently: its
    two impacts' phases and speeds to 1e-9 s and m/s, its multipliers to 1e-8."""
    assert set(switched.segment) == {0, 1}
    doubled = _doubled(switched)
    assert all(o.impacts == 2 and o.periods == 2 for _, o, _ in doubled)
    assert len(doubled) >= 20
    gamma0, origin, _ = doubled[0]
    assert gamma0 == pytest.approx(table.period_doubling(E), rel=1e-8)
    assert switched.points("period_doubling")[0] == pytest.approx(
        table.amplitude(table.period_doubling(E)), rel=1e-8
    )
    assert origin.x[3] == pytest.approx(table.G * table.T / 2, abs=1e-12)  # period one there
    assert all(g > table.period_doubling(E) for g, _, _ in doubled[1:])  # supercritical
    checked = 0
    for gamma, o, code in doubled[1:]:
        if code != 0 or gamma < table.period_doubling(E) + 1e-3:
            continue  # a root of Gamma(tau1) this close to the doubling is ill-conditioned
        states, mults = table.period_two_at(gamma, E)
        # the first impact is either of the two: match the state, then its partner
        first = int(np.argmin(np.abs(states[:, 1] - o.x[3])))
        phase = (o.x[0] - states[first, 0] + table.T / 2) % table.T - table.T / 2
        assert abs(phase) < 1e-9 and o.x[3] == pytest.approx(states[first, 1], abs=1e-9)
        assert o.records[0].v2 == pytest.approx(states[1 - first, 1], abs=1e-9)
        assert abs(states[0, 1] - states[1, 1]) > 1e-3  # truly of period two
        got = np.sort_complex(o.multipliers)
        assert got == pytest.approx(np.sort_complex(mults), abs=1e-8)
        assert o.stable == bool(np.all(np.abs(mults) < 1))
        checked += 1
    assert checked >= 10


def test_the_period_two_orbits_own_doubling_is_located_to_1e_8(switched):
    doublings = [g for g, _, code in _doubled(switched) if code == 2]
    assert len(doublings) == 1
    assert doublings[0] == pytest.approx(table.period_two_doubling(E), rel=1e-8)
    unit = table.amplitude(1.0)
    assert [a / unit for a in switched.points("period_doubling", 1)] == doublings
    assert len(switched.points("period_doubling")) == 1  # the continued branch's own


def test_the_stable_period_two_orbits_hold_for_1000_periods_in_the_engine(switched):
    """Points of the period-two branch, nudged by 1e-10, run 1,000 of their periods
    (2,000 impacts): they stay where stable, and leave where not."""
    checked = {True: 0, False: 0}
    for gamma, o, _ in _doubled(switched)[1::3]:
        largest = np.max(np.abs(o.multipliers))
        if 0.95 < largest < 1.05:
            continue
        rm = ReturnMap(table.scene(gamma, E), 2)
        nudged = o.x + np.array([1e-10 * table.T, 0.0, 0.0, 1e-10 * o.x[3], 0.0])
        try:
            records = rm.run(nudged, o.wall, impacts=2000)
            end = records[-1]
            phase = (end.t - o.x[0] + table.T / 2) % table.T - table.T / 2
            drift = max(abs(end.v2 - o.x[3]) / o.x[3], abs(phase) / table.T)
        except OrbitError:
            drift = np.inf
        if o.stable:
            assert drift < 1e-9
        else:
            assert drift > 1e-3
        checked[bool(o.stable)] += 1
    assert checked[True] >= 3 and checked[False] >= 1


def test_continue_orbit_switch_gives_each_point_its_period():
    scene = table.scene(1.6, E)
    t, v = table.orbit(1.6, E)
    ds = continue_orbit(
        scene,
        period=1,
        vary="drive.amplitude",
        span=(table.amplitude(1.5), table.amplitude(1.6)),
        guess=(t, 0.0, 0.0, v, 0.0),
        free=VERTICAL,
        points=20,
        switch=True,
    )
    period, branch = ds["period"].values, ds["branch"].values
    assert period.dtype.kind == "i" and set(period.tolist()) == {1, 2}
    assert np.array_equal(period, np.where(branch == 0, 1, 2))
    gamma = ds["drive_amplitude"].values / table.amplitude(1.0)
    assert gamma[branch == 1].min() == pytest.approx(table.period_doubling(E), rel=1e-8)


@pytest.fixture(scope="module")
def parabola():
    """The parabola's period-one orbit (two impacts) continued from 5.4 Hz down to 4.75."""
    scene = load_scene("parabola-5.4hz")
    start = find_orbit(scene, 2)
    return scene, start, continue_branch(scene, start, "drive.frequency", (4.75, 5.4), points=200)


def test_the_parabolas_branch_goes_on_through_both_branch_points(parabola):
    """The mirror-symmetric orbit loses its stability through a multiplier +1 near 5.146 Hz
    and regains it near 4.793 Hz, the branch going on downwards through both (branch
    points, not folds), to the span's end."""
    _, _, br = parabola
    assert [round(f, 3) for f in br.points("branch_point")] == [5.146, 4.793]
    assert br.points("fold") == []
    assert min(br.values) < 4.76
    steps = np.diff(br.values)
    assert np.all(steps < 0) or np.all(steps > 0)  # it never turned back in the key


#: (t, s, v1, v2, omega) mirrored in the parabola's axis
MIRROR = np.diag([1.0, -1.0, -1.0, 1.0, -1.0])


def _half_period_orbit(scene, x: np.ndarray) -> tuple[np.ndarray, float]:
    """The parabola's mirror-symmetric orbit as a fixed point of its half-period map, by
    Newton's method from ``x``: (its state, det(J_H + I)).

    Driven horizontally, the parabola is symmetric under the mirror M (q1 -> -q1) with
    half a drive period's shift (D(t + T/2) = -D(t)): H(x) = M P(x) - (T/2) e_t maps the
    symmetric orbit's first impact onto itself, P^2 = (M H)^2 = H^2 there, and P^2's
    multipliers are the squares of H's. A multiplier +1 of P^2 with the branch going on
    is a multiplier -1 of H: a period doubling of H, where det(J_H + I) has a simple
    zero and Newton's method on H(x) = x stays regular."""
    rm = ReturnMap(scene, 1)
    for _ in range(30):
        landing, records = rm(x, 0)
        image = landing.x.copy()
        image[0] -= rm.period / 2
        jac = MIRROR @ map_jacobian(rm, x, 0, records)
        step = -np.linalg.solve(jac - np.eye(5), MIRROR @ image - x)
        x = x + step
        if np.max(np.abs(step) / (1 + np.abs(x))) < 1e-14:
            break
    landing, records = rm(x, 0)
    jac = MIRROR @ map_jacobian(rm, x, 0, records)
    return x, float(np.linalg.det(jac + np.eye(5)))


def _half_period_doubling(scene, x: np.ndarray, lo: float, hi: float) -> float:
    """The drive frequency in (lo, hi) (Hz) where H has the multiplier -1, its orbit
    walked there from ``x`` (at ``hi``) in steps of 0.01 Hz."""
    for f in np.arange(hi, lo, -0.01):
        x, _ = _half_period_orbit(with_values(scene, {"drive.frequency": f}), x)
    walked = {"x": x}

    def det(f: float) -> float:
        walked["x"], value = _half_period_orbit(
            with_values(scene, {"drive.frequency": f}), walked["x"]
        )
        return value

    return brentq(det, lo, lo + 0.02, xtol=1e-14, rtol=1e-15)


def test_the_parabolas_branch_points_are_located_to_1e_8(parabola):
    """The two branch points, where the corrector's system is singular, against the
    period doublings of the half-period map (regular there), and their multiplier 1."""
    scene, start, br = parabola
    found = br.points("branch_point")
    assert len(found) == 2
    for f in found:
        assert f == pytest.approx(
            _half_period_doubling(scene, start.x, round(f, 2) - 0.01, 5.4), rel=1e-8
        )
    for o, code in zip(br.orbits, br.bifurcation, strict=True):
        if code == BIFURCATIONS.index("branch_point"):
            assert np.min(np.abs(o.multipliers - 1.0)) < 1e-8
