"""A ball rolling across smooth (C1) joins of a still curve, against an integration of
the rolling sphere on the true curve written here from its Lagrangian.

The curve is 10 x^2 for x < 0 and 30 x^2 for x > 0 (m): height and slope continuous at
0, f'' jumping from 20 to 60 1/m. A sphere of radius r rolling without slip on it has its
centre on the offset curve X(s) = s - r f'/sqrt(q), Y(s) = f + r/sqrt(q), q = 1 + f'^2,
s the contact's abscissa, and spins at |v|/r (the contact point at rest), so

    L = 1/2 m (1 + k) (X'^2 + Y'^2) s_dot^2 - m g Y(s),   X' = 1 - r f''/q^(3/2),
    Y' = f' X',

whose Euler-Lagrange equation is integrated with scipy's DOP853 on each piece, from
one join crossing to the next; at a crossing the centre's velocity X' s_dot is
continuous, so s_dot jumps with X'. Energy is conserved exactly, so the turning points are
the roots of Y(s) = Y(s0) on either side (brentq), independently of the integration.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from billiard.run.simulate import simulate
from tests.validation.test_contact import G, K, R, scene

M = 1.3028e-4  # kg, the default ball
CURVE = "Piecewise((10*x**2, x < 0), (30*x**2, True))"
S0 = 0.02  # m: the contact's abscissa at the start, at rest
DURATION = 1.0  # s


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def _a(s: float) -> float:
    return 10.0 if s < 0.0 else 30.0


def _geometry(s: float, a: float) -> tuple[float, float, float, float]:
    """(X, Y, M(s), dM/ds and dY/ds) of the centre for a contact at s on a x^2."""
    fp, f2 = 2.0 * a * s, 2.0 * a
    q = 1.0 + fp * fp
    xs = 1.0 - R * f2 / q**1.5
    # d/ds of X' = -r f'' d(q^-3/2)/ds = 3 r f''^2 f' / q^(5/2)  (f''' = 0)
    xss = 3.0 * R * f2 * f2 * fp / q**2.5
    mass = M * (1.0 + K) * q * xs * xs
    dmass = M * (1.0 + K) * (2.0 * fp * f2 * xs * xs + q * 2.0 * xs * xss)
    return mass, dmass, fp * xs, a * s * s + R / math.sqrt(q)


def _centre(s: float) -> tuple[float, float]:
    a = _a(s)
    fp = 2.0 * a * s
    q = 1.0 + fp * fp
    return s - R * fp / math.sqrt(q), a * s * s + R / math.sqrt(q)


def _energy(s: float, sd: float, a: float) -> float:
    mass, _, _, y = _geometry(s, a)
    return 0.5 * mass * sd * sd + M * G * y


def reference(duration: float, rtol: float = 1e-13) -> tuple[list[float], list[float], float]:
    """The crossing times of the join (s) and the turning points' centre abscissas (m) up
    to ``duration``, and the largest relative energy change at a crossing."""
    e0 = _energy(S0, 0.0, _a(S0))
    crossings: list[float] = []
    t, y = 0.0, [S0, 0.0]
    drift = 0.0
    while t < duration:
        # the piece the ball is on: from a crossing, the one it moves into
        a = (30.0 if y[1] > 0.0 else 10.0) if y[0] == 0.0 else _a(y[0])

        def rhs(_t, state, a=a):
            s, sd = state
            mass, dmass, dy, _ = _geometry(s, a)
            return [sd, -(0.5 * dmass * sd * sd + M * G * dy) / mass]

        def join(_t, state):
            return state[0]

        join.terminal = True
        # the next crossing, the way back (not the crossing it starts from)
        join.direction = -1.0 if (y[1] > 0.0 or (y[0] > 0.0 and y[1] == 0.0)) else 1.0
        sol = solve_ivp(
            rhs, (t, duration), y, method="DOP853", rtol=rtol, atol=1e-16, events=join,
            first_step=1e-6 if y[0] == 0.0 else None,
        )  # fmt: skip
        if sol.status == 1:
            t = float(sol.t_events[0][-1])
            sd = float(sol.y_events[0][-1][1])
            # the centre's velocity is continuous (the contact force stays finite), and
            # at s = 0 (f' = 0) it is X'(0) s_dot, X'(0) = 1 - r f'': s_dot jumps
            new = 10.0 if sd < 0.0 else 30.0
            y = [0.0, sd * (1.0 - R * 2.0 * a) / (1.0 - R * 2.0 * new)]
            crossings.append(t)
            drift = max(drift, abs(_energy(0.0, y[1], new) - e0) / e0)
        else:
            break
    # the turning points: Y(s) = Y(S0) on each side (energy conserved), centre X there
    y0 = _centre(S0)[1]
    left = brentq(lambda s: _centre(s)[1] - y0, -0.2, -1e-9, xtol=1e-16, rtol=1e-15)
    return crossings, [_centre(left)[0], _centre(S0)[0]], drift


def test_the_reference_conserves_energy_and_is_converged():
    """The reference is trustworthy before it judges: its energy is conserved at every
    crossing to 1e-12, and halving its tolerance moves no crossing by 1e-11 s."""
    crossings, _, drift = reference(DURATION)
    assert len(crossings) >= 4 and drift < 1e-12
    coarser, _, _ = reference(DURATION, rtol=2e-13)
    assert np.max(np.abs(np.subtract(crossings, coarser))) < 1e-11


def test_a_ball_rolls_across_a_smooth_join_as_on_the_true_curve():
    """Rolling without slip on the chain: no impact, every crossing a hand-over (the
    contact row's end is ``join``), at the reference's times to 1e-8 s; the turning points
    at the reference's to 1e-9 m; the energy changes by under 1e-10 of E per pass."""
    fp = 2.0 * 30.0 * S0
    q = 1.0 + fp * fp
    result = simulate(
        scene(
            CURVE,
            contact={"mu_static": 5.0, "mu_kinetic": 4.0},  # rolling all along
            initial={"q1": S0 - R * fp / math.sqrt(q), "q2": 30.0 * S0 * S0 + R / math.sqrt(q)},
            run={"rtol": 1e-13},
        ),
        duration=DURATION,
        sample=1e-5,
    )
    assert result.stop_reason is None
    assert len(result.columns["t"]) == 0  # no impact: no collisions.csv row
    contacts = result.contacts
    ends = list(contacts["end"])
    assert set(contacts["mode"]) == {"roll"}
    joins = [i for i, end in enumerate(ends) if end == "join"]
    assert ends[-1] == "cut" and len(joins) == len(ends) - 1
    # each row names the piece it rolled on: 30 x^2 (wall 1) first, then in turn
    assert list(contacts["wall"]) == [(i + 1) % 2 for i in range(len(ends))]
    crossings, turning, _ = reference(DURATION)
    times = np.asarray(contacts["t_end"])[joins]
    assert len(times) == len(crossings)
    assert np.max(np.abs(times - crossings)) < 1e-8
    # energy at each crossing, from the rows' end states (J)
    e0 = _energy(S0, 0.0, 30.0)
    energy = [
        0.5 * M * (contacts["v1_end"][i] ** 2 + contacts["v2_end"][i] ** 2)
        + 0.5 * K * M * R * R * contacts["omega_end"][i] ** 2
        + M * G * contacts["q2_end"][i]
        for i in joins
    ]
    steps = np.abs(np.diff([e0, *energy])) / e0
    print(f"\njoins: {len(times)} crossings, time error {np.max(np.abs(times - crossings)):.2g} s")
    print(f"joins: energy change per pass at most {np.max(steps):.2g} of E")
    assert np.max(steps) < 1e-10
    # the turning points: the extremes of the sampled centre, refined by the parabola
    # through the sample at the extreme and its neighbours
    q1 = np.asarray(result.trajectory["q1"])
    found = []
    for k in range(1, len(q1) - 1):
        if (q1[k] - q1[k - 1]) * (q1[k + 1] - q1[k]) < 0.0:
            a, b, c = q1[k - 1], q1[k], q1[k + 1]
            found.append(b - (c - a) ** 2 / (8.0 * (a - 2.0 * b + c)))
    assert len(found) >= 2
    for x in found:
        expected = turning[0] if x < 0 else turning[1]
        assert abs(x - expected) < 1e-9, (x, expected)
    worst = max(abs(x - (turning[0] if x < 0 else turning[1])) for x in found)
    print(f"joins: {len(found)} turning points, position error at most {worst:.2g} m")


@pytest.mark.parametrize("at", [0.05, 0.08, 0.02])
def test_a_flight_meets_the_chain_where_the_piece_holding_x_is(at):
    """Dropped from rest onto the curve 10 x^2 (x < 0.05) continued by its tangent line
    x - 0.025, without friction, at the join x = 0.05 (slope 1 both sides), on the line
    (x = 0.08, where the parabola's formula would lie 9 mm higher) and on the parabola: the
    first impact is at t = sqrt(2 h / g) on the piece holding x, with its tangent angle,
    and the ball leaves with v - (1 + e) (v . n) n, n that piece's normal (closed form;
    at the join, the pieces' common normal)."""
    e, h = 0.5, 0.02
    slope = 20.0 * at if at <= 0.05 else 1.0
    height = 10.0 * at * at if at <= 0.05 else at - 0.025
    c = 1.0 / math.sqrt(1.0 + slope * slope)
    n = (-slope * c, c)
    result = simulate(
        scene(
            "Piecewise((10*x**2, x < 0.05), (x - 0.025, True))",
            contact={"model": "impacts", "restitution": e, "mu_static": 0.0,
                     "mu_kinetic": 0.0, "elastic_below": 0.0},
            initial={"q1": at + R * n[0], "q2": height + R * n[1] + h},
        ),
        collisions=1,
    )  # fmt: skip
    row = {key: float(values[0]) for key, values in result.columns.items() if key != "regime"}
    assert row["t"] == pytest.approx(math.sqrt(2.0 * h / G), rel=1e-12)
    assert row["s"] == pytest.approx(at, abs=1e-12)
    assert row["z"] == pytest.approx(math.atan(slope), abs=1e-12)
    assert row["wall"] == (0 if at < 0.05 else 1) or at == 0.05
    v = -math.sqrt(2.0 * G * h)
    vn = v * n[1]
    expected = (-(1.0 + e) * vn * n[0], v - (1.0 + e) * vn * n[1])
    assert row["v1"] == pytest.approx(expected[0], abs=1e-12)
    assert row["v2"] == pytest.approx(expected[1], abs=1e-12)


def test_a_chain_runs_the_same_bits_compiled_and_interpreted():
    """A ball rolling and bouncing across the join of a shaken chain: the compiled engine
    and its source run as plain Python give the same records, bit for bit."""
    from billiard.engine.simulation import Simulation

    fp = 2.0 * 30.0 * S0
    q = 1.0 + fp * fp
    shaken = scene(
        CURVE,
        initial={"q1": S0 - R * fp / math.sqrt(q), "q2": 30.0 * S0 * S0 + R / math.sqrt(q)},
        drive={"amplitude": 0.004, "frequency": 12.0},
    )
    runs = []
    for interpreted in (False, True):
        sim = Simulation(shaken)
        sim.driver.interpreted = interpreted
        contacts: list = []
        sim.on_contact = contacts.append
        records: list = []
        sim.run(15, records)
        runs.append(([repr(tuple(r)) for r in records], [repr(tuple(c)) for c in contacts]))
    assert runs[0] == runs[1]
    records, contacts = runs[0]
    assert len(records) == 15 and any("'join'" in c for c in contacts)
