"""Orbits through a contact phase: the ball on the vertically shaken table that lies on
it between its flights (contact.model = "phases", e = 0.5, mu_s = 0.3, no air), against
references written here and in tests/validation (not the engine's): the lift-off where
sin(w t) = 1 / Gamma, the flight's landing (brentq on the ball's height over the
sinusoid, the gap of :func:`tests.validation.test_chatter.gap_over_tau`), the chatter
summed flight by flight, and the next lift-off after it (brentq,
:func:`tests.validation.test_liftoff.lift_off`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from billiard.orbits.continuation import continue_branch
from billiard.orbits.newton import NEWTON_TOL, find_orbit
from billiard.orbits.phases import PhaseMap
from billiard.orbits.returnmap import OrbitError
from billiard.runfile.record import ContactRecord, ImpactRecord
from billiard.scene.scene import load_scene, with_values
from tests.orbits import table
from tests.validation.test_chatter import gap_over_tau, relative_speed
from tests.validation.test_liftoff import lift_off

E = 0.5
LOCKED = ("t", "v2")


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def scene(gamma: float, **changes):
    return table.scene(gamma, E, **{"contact.model": "phases", **changes})


def landing(t0: float, v: float, amp: float) -> tuple[float, float]:
    """The flight from t0 (relative speed v, m/s) to its first landing: (its duration (s),
    the relative speed it arrives at). Its first root of y / tau by brentq, bracketed on
    a grid of T / 400 once past the first 1e-3 T (doubling before: a chatter's flights
    are short), fine enough not to step over a landing near the table's crest (at Gamma
    1.8 the third flight touches it after 21.0 ms, then would clear it to 41 ms)."""
    lo = 1e-6 * table.T if v == 0.0 else 1e-3 * v / table.G
    assert gap_over_tau(t0, v, lo, amp) > 0.0
    hi = lo
    while gap_over_tau(t0, v, hi, amp) > 0.0:
        lo, hi = hi, (2.0 * hi if hi < 1e-3 * table.T else hi + table.T / 400)
    tau = brentq(lambda s: gap_over_tau(t0, v, s, amp), lo, hi, xtol=1e-300, rtol=1e-15)
    return tau, relative_speed(t0, v, tau, amp)


def chatter_end(t0: float, v: float, amp: float, limit: float) -> float:
    """When the chatter from t0 (rebound v relative to the table, m/s) comes to rest: its
    flights summed until they fall below 1e-17 s; inf when it goes on past ``limit``."""
    t = t0
    while t < limit:
        tau, arrive = landing(t, v, amp)
        t, v = t + tau, -E * arrive
        if tau < 1e-17:
            return t
    return math.inf


def reference(gamma: float) -> dict[str, float]:
    """The locked orbit at ``gamma``: lift-off time (s, in the first period) and speed
    (m/s), the first landing's time and post-impact speed, the chatter's end, and n."""
    amp, w = table.amplitude(gamma), table.W
    lift = math.asin(1.0 / gamma) / w
    tau, arrive = landing(lift, 0.0, amp)
    t1 = lift + tau
    v1 = amp * w * math.cos(w * t1) - E * arrive  # the table's speed + e |relative speed|
    rest = chatter_end(t1, -E * arrive, amp, lift + 20 * table.T)
    assert table.G - amp * w * w * math.sin(w * rest) > 0.0  # the table presses it there
    n = round((lift_off(rest, amp) - lift) / table.T)
    return {"lift": lift, "speed": amp * w * math.cos(w * lift), "t1": t1, "v1": v1,
            "rest": rest, "n": n}  # fmt: skip


def phase(t: float, t0: float) -> float:
    """t - t0 folded into (-T/2, T/2] (s)."""
    return (t - t0 + table.T / 2) % table.T - table.T / 2


@pytest.mark.parametrize("gamma", [1.2, 1.5, 1.8])
def test_the_locked_orbit_is_the_references(gamma):
    """Found from the scene's own run: its lift-off at sin(w t) = 1 / Gamma, its landing,
    its chatter's end and n (1, 1 and 3 drive periods) are the references'; both
    multipliers are exactly 0 (superstable)."""
    ref = reference(gamma)
    orbit = find_orbit(scene(gamma), 1)
    assert orbit.free == LOCKED and orbit.residual <= NEWTON_TOL
    assert orbit.periods == ref["n"] == (3 if gamma == 1.8 else 1)
    assert orbit.multipliers.tolist() == [0.0, 0.0] and orbit.stable
    phases = [r for r in orbit.records if isinstance(r, ContactRecord)]
    lift = phases[-1]
    assert lift.end == "lift-off" and isinstance(orbit.records[-1], ImpactRecord)
    # located to 1e-13 s (EVENT_TOL); measured 1.9e-14, 1.1e-17, 3.3e-14 s
    assert abs(phase(lift.t_end, ref["lift"])) <= 1e-12
    # g times that: measured 1.9e-13, 9.7e-17, 3.2e-13 m/s
    assert lift.v2_end == pytest.approx(ref["speed"], abs=1e-12)
    # the section, the first impact after the lift-off: measured 1.7e-16 s, 6.2e-15 m/s
    assert abs(phase(orbit.x[0], ref["t1"])) <= 1e-13
    assert orbit.x[3] == pytest.approx(ref["v1"], abs=1e-13)
    assert orbit.x[[1, 2, 4]].tolist() == [0.0, 0.0, 0.0]
    # the chatter's end: the engine sums its tail (1e-8 of a period: 5e-10 s)
    landed = phases[0].t_start - orbit.x[0] + ref["t1"]
    assert landed == pytest.approx(ref["rest"], abs=1e-9)


def test_the_jacobian_is_zero_as_the_engines_map_differenced():
    """Central differences of the engine's map in t and v2 vanish to the lift-off's
    location (1e-13 s over steps of 1e-6 of a period and of the speed): the hold
    forgets the entering state. Off the orbit too, from a guess 3 ms early. The other
    entries are not derived: NaN."""
    rm = PhaseMap(scene(1.2))
    orbit = find_orbit(rm.scene, 1)
    size = np.array([table.T, 1.0, 1.0, abs(orbit.x[3]), 1.0])
    for x in (orbit.x, orbit.x - np.array([3e-3, 0.0, 0.0, 0.0, 0.0])):
        records = rm(x, 0)[1]
        jac = rm.jacobian(x, 0, records)
        assert np.isnan(jac[1]).all() and np.isnan(jac[:, 2]).all()
        for j in (0, 3):
            assert jac[0, j] == 0.0 and jac[3, j] == 0.0
            h = 1e-6 * size[j]
            up, down = x.copy(), x.copy()
            up[j] += h
            down[j] -= h
            diff = (rm(up, 0)[0].x - rm(down, 0)[0].x) / (2 * h) * size[j] / size
            # measured at most 2e-7 (the lift-off's 1e-13 s over 2 h = 1e-7 T)
            assert abs(diff[0]) <= 1e-6 and abs(diff[3]) <= 1e-6, (j, diff)


def test_the_map_is_the_engines_run():
    """From each first impact after a lift-off of the scene's run, the map lands on the
    next one."""
    rm = PhaseMap(scene(1.5))
    sim = rm.sim
    sim.reset()
    sections, lifted = [], False
    while len(sections) < 6:
        record = sim.step()
        if isinstance(record, ContactRecord):
            lifted = record.end == "lift-off"
        elif lifted:
            sections.append(record)
            lifted = False
    for before, after in zip(sections[-4:-1], sections[-3:], strict=True):
        x = np.array([before.t, before.s, before.v1, before.v2, before.omega])
        end = rm(x, int(before.wall))[0]
        expected = np.array([after.t, after.s, after.v1, after.v2, after.omega])
        assert end.x == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_the_orbit_nudged_stays_on_it_for_1000_periods():
    """Nudged by 1e-10 of its phase and speed and run 1,000 drive periods by the engine."""
    orbit = find_orbit(scene(1.2), 1)
    rm = PhaseMap(scene(1.2))
    nudged = orbit.x + np.array([1e-10 * table.T, 0.0, 0.0, 1e-10 * abs(orbit.x[3]), 0.0])
    records = rm.run(nudged, orbit.wall, impacts=1000)
    end = records[-1]
    assert round((end.t - orbit.x[0]) / table.T) == 1000
    # measured 6.8e-13 s (the clock's rounding at 50 s) and 0 m/s
    assert abs(phase(end.t, orbit.x[0])) < 1e-9 * table.T
    assert end.v2 == pytest.approx(orbit.x[3], abs=1e-12)


@pytest.fixture(scope="module")
def branch(billiard_home):
    start = find_orbit(scene(1.2), 1)
    span = (table.amplitude(1.1), table.amplitude(1.7))
    return continue_branch(scene(1.2), start, "drive.amplitude", span, points=400)


def excess(gamma: float) -> float:
    """How long (s) before the next lift-off phase the chatter ends (negative), or a
    quarter period where it does not end before it."""
    ref_lift = math.asin(1.0 / gamma) / table.W
    amp = table.amplitude(gamma)
    tau, arrive = landing(ref_lift, 0.0, amp)
    limit = ref_lift + 1.25 * table.T
    rest = min(chatter_end(ref_lift + tau, -E * arrive, amp, limit), limit)
    return rest - (ref_lift + table.T)


def test_the_branch_is_the_references_up_to_where_the_chatter_meets_the_lift_off(branch):
    """Continued in the drive amplitude from Gamma 1.2: every point is the reference's
    orbit, superstable; the branch ends, marked a grazing, where the chatter's end
    reaches the next lift-off phase (the reference's Gamma* by brentq: the ball no longer
    sticks above it)."""
    unit = table.amplitude(1.0)
    gammas = np.array(branch.values) / unit
    for g, o in zip(gammas, branch.orbits, strict=True):
        ref = reference(g)
        assert abs(phase(o.x[0], ref["t1"])) <= 1e-13
        assert o.x[3] == pytest.approx(ref["v1"], abs=1e-13)
        assert o.multipliers.tolist() == [0.0, 0.0] and o.periods == 1
    assert gammas.min() < 1.13
    grazings = [a / unit for a in branch.points("grazing")]
    star = brentq(excess, 1.59, 1.6, xtol=1e-15)  # 1.5973488311951525
    assert len(grazings) == 1 and grazings[0] == gammas.max()
    # the engine's branch ends 1.2e-5 short of it (measured 7.4e-6 relative): there the
    # chatter ends 3e-5 s before the lift-off, where the table's push has fallen to
    # 1e-3 g, and the engine can neither sum it within its error bound nor resolve it
    # impact by impact (it stops: no progress in simulated time)
    assert star - 2e-5 < grazings[0] <= star


def test_the_rerun_points_stay_on_their_orbits(branch):
    """Every 5th point of the branch, nudged by 1e-10, run 1,000 periods by the engine."""
    unit = table.amplitude(1.0)
    for value, o in list(zip(branch.values, branch.orbits, strict=True))[::5]:
        rm = PhaseMap(scene(value / unit))
        nudged = o.x + np.array([1e-10 * table.T, 0.0, 0.0, 1e-10 * abs(o.x[3]), 0.0])
        end = rm.run(nudged, o.wall, impacts=1000)[-1]
        assert abs(phase(end.t, o.x[0])) < 1e-9 * table.T
        assert end.v2 == pytest.approx(o.x[3], abs=1e-10)


def test_orbits_through_other_contact_phases_are_refused_in_one_line():
    with pytest.raises(OrbitError, match="only t and v2 can be free, not s, v1"):
        find_orbit(scene(1.2), 1, free=("t", "s", "v1", "v2"))
    with pytest.raises(OrbitError, match="need a vertical drive"):
        find_orbit(scene(1.2, **{"drive.direction": "horizontal"}), 1)
    # the parabola shaken vertically (Gamma 2.35, with air) started off its bottom: the
    # ball rolls to and fro and lifts off its sloped wall
    bowl = with_values(
        load_scene("parabola-5.4hz"),
        {"contact.model": "phases", "drive.direction": "vertical", "drive.amplitude": 0.02},
    )
    with pytest.raises(OrbitError, match="where it is not horizontal") as info:
        find_orbit(with_values(bowl, {"initial.q1": 0.05}), 1)
    assert "\n" not in str(info.value)
    # at its bottom, at rest along the wall, it lifts off at sin(w t) = 1 / Gamma (no air:
    # drag on the ball moving with the wall would add to N): found
    bowl = with_values(bowl, {"air.drag": "none"})
    orbit = find_orbit(bowl, 1)
    drive = PhaseMap(bowl).drive  # its frequency and phase
    lift = [r for r in orbit.records if isinstance(r, ContactRecord)][-1]
    gamma = drive.peak_acceleration / bowl.run.gravity
    assert drive.angle(lift.t_end) == pytest.approx(math.asin(1 / gamma), abs=1e-12 * drive.omega)
    assert orbit.multipliers.tolist() == [0.0, 0.0] and orbit.x[1] == 0.0
    # a ball that lifts off once and then bounces for ever (Gamma 1.6, elastic_below 0)
    with pytest.raises(OrbitError, match="no contact phase ended in a lift-off"):
        find_orbit(scene(1.65, **{"contact.restitution": 0.9}), 1)
