"""Property-based tests over valid scenes: the paper's curves and two expressions, any
drive, restitution, friction (mu_k <= mu_s), ball radius within the curvature limit,
initial position inside the container, any velocities and spin.

* Every run completes, or stops with one of the documented one-line reasons (escape,
  inelastic collapse, non-finite numbers, a failed root or step-size solve), or is
  refused before it starts with a geometry error; never another exception.
* With the drive off, no impact creates energy (the low-velocity rule's lift of a
  lying ball adds exactly its designed amount), and with drag off the mechanical energy
  recorded after each impact never exceeds the one before by more than that.
* Both contact models are drawn (``contact.model`` "impacts" or "phases"); with
  "phases" the contact phases and the transitions into them are audited too
  (:class:`bench.soak.PhaseAudit`: no energy created in the boundary's frame, no jump),
  and a phases scene runs for at most ``PHASES_TEST_DURATION`` of simulated time.

The default runs take well under a minute (fixed examples, ``derandomize``); the
``slow`` variants explore many more random examples with longer runs.
"""

from __future__ import annotations

import math
import re
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from bench.soak import CURVES, MODELS, AuditedSimulation, scene_from_draw, stop_kind
from billiard.errors import GeometryError
from billiard.geometry.curves import load_curve
from billiard.run.simulate import CHECKPOINT_NAME, Simulation, simulate
from billiard.runfile.checkpoint import read_checkpoint
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import with_values
from billiard.status import Status

DOCUMENTED_STOPS = [
    re.compile(p)
    for p in (
        r"ball escaped above escape_height = \S+ m at t = \S+ s after impact \d+",
        r"inelastic collapse: 200 impacts within 1e-06 s of simulated time, "
        r"at impact \d+ \(t = \S+ s\)",
        r"inelastic collapse: 1000 consecutive impacts with zero time of flight, "
        r"at impact \d+ \(t = \S+ s\)",
        r"non-finite state at impact \d+ \(t = \S+ s\): \w+ = \S+",
        r"numerical failure after impact \d+ \(t = \S+ s\): \w+: .+",
        r"(no impact found within 1000 s of flight|the impact time did not converge"
        r"|the gap's extremum did not converge"
        r"|offset-curve inversion did not converge at x = \S+ m"
        r"|the flight's step-size control failed \(.+\)) (after|at) impact \d+ \(t = \S+ s\)",
        r"run.step = \S+ s is too coarse for this scene \(use run.step <= \S+ s\): 3 impacts "
        r"in a row were found within \S+ s of the previous one, where the ball had just left "
        r"the wall \(it comes back within one step\) after impact \d+ \(t = \S+ s\)",
        # contact.model = "phases"
        r"the ball rests on the boundary, moving with it: nothing more happens",
        r"contact phases of zero duration piled up at t = \S+ s",
        r"the contact phase's step-size control failed \(60 rejected steps\)",
        r"non-finite state at the end of a contact phase \(t = \S+ s\)",
        r"no progress in simulated time: the ball is pressed against (the lid \(which cannot "
        r"hold a ball\)|a wall) and meets it without impulse again and again \(200 contacts "
        r"within 1e-06 s or 1000 at one time\) after impact \d+ \(t = \S+ s\)",
    )
]
#: Simulated time (s) a phases scene of the property tests runs at most (the soak's
#: scenes run for bench.soak.PHASES_DURATION).
PHASES_TEST_DURATION = 2.0
DOCUMENTED_GEOMETRY = re.compile(
    r"(ball radius .* exceeds the boundary's radius of curvature .*"
    r"|initial position .* puts the ball .* into the (wall|lid).*"
    r"|initial position .* is above escape_height .*"
    r"|the boundary curve has no bottom to rest on: .*)"
)


def draws(elastic_below=(0.0, 1e-3, 1e-2, 3e-2), amplitude=None, models=MODELS):
    """The primitive choices of :func:`bench.soak.scene_from_draw`."""
    two_pi = 2.0 * math.pi
    unit = st.floats(0.0, 1.0)
    return st.fixed_dictionaries(
        {
            "curve": st.sampled_from(CURVES),
            "lid": st.booleans(),
            "top": unit,
            "amplitude": amplitude
            if amplitude is not None
            else st.one_of(st.just(0.0), st.floats(0.0, 0.03)),
            "frequency": st.floats(1.0, 12.0),
            "direction": st.sampled_from(("horizontal", "vertical")),
            "phase": st.floats(0.0, two_pi),
            "restitution": unit,
            "mu_static": st.floats(0.0, 1.2),
            "mu_kinetic_fraction": unit,
            "elastic_below": st.sampled_from(elastic_below),
            "radius_fraction": st.floats(0.05, 0.97),
            "log_mass": st.floats(-5.0, -2.0),
            "inertia_factor": st.floats(0.1, 1.0),
            "drag": st.sampled_from(("fowles", "none")),
            "magnus": st.one_of(st.just(0.0), st.floats(0.0, 1e-8)),
            "start": st.sampled_from(("rest", "inside")),
            "x_fraction": unit,
            "y_fraction": st.one_of(st.just(0.0), st.floats(0.0, 0.95)),
            "v1": st.floats(-2.0, 2.0),
            "v2": st.floats(-2.0, 2.0),
            "omega": st.floats(-300.0, 300.0),
            "t0": st.floats(0.0, 50.0),
            "model": st.sampled_from(models),
        }
    )


methods = st.sampled_from(("event",) * 7 + ("rk4",))


@pytest.fixture(scope="module", autouse=True)
def curve_cache(tmp_path_factory):
    """Derive the expression curves once, into a private cache."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard-home")))
        for curve in CURVES:
            load_curve(curve)
        yield


def scene_for_test(draw: dict):
    """The soak's scene of a draw; a phases scene with the tests' shorter time limit."""
    scene = scene_from_draw(draw)
    assert scene.contact.model == draw["model"]
    if draw["model"] == "phases":
        scene = with_values(scene, {"run.duration": PHASES_TEST_DURATION})
    return scene


def check_run(draw: dict, method: str, impacts: int) -> None:
    n = impacts if method == "event" else max(1, impacts // 25)  # rk4: ~1 ms per step
    try:
        scene = scene_for_test(draw)
        with tempfile.TemporaryDirectory() as out:
            result = simulate(scene, collisions=n, method=method, out_dir=out)
            status = read_checkpoint(f"{out}/{CHECKPOINT_NAME}")["status"]
            c = result.columns
    except GeometryError as exc:
        assert DOCUMENTED_GEOMETRY.fullmatch(str(exc)), str(exc)
        event("geometry error")
        return
    reason = result.stop_reason
    event(f"{method} {draw['model']}: {stop_kind(result.status)}")
    if reason is None and result.status == Status.TIME_LIMIT:
        assert draw["model"] == "phases" and len(result) <= n and status == "complete"
    elif reason is None:
        assert len(result) == n and status == "complete"
    else:
        assert "\n" not in reason
        assert any(p.fullmatch(reason) for p in DOCUMENTED_STOPS), reason
        assert status == "stopped"
    assert c["n"].tolist() == list(range(1, len(result) + 1))
    for name, values in c.items():
        if values.dtype.kind == "f":
            assert np.all(np.isfinite(values)), name
    assert np.all(c["tof"] >= 0.0) and np.all(np.diff(c["t"]) >= 0.0)
    # the run in memory is the same run
    again = Simulation(scene, method)
    rows = MemoryRecorder()
    assert again.run(n, rows) == reason
    assert np.array_equal(rows.columns()["t"], c["t"])


def check_energy(draw: dict, method: str, impacts: int) -> None:
    try:
        simulation = AuditedSimulation(scene_for_test(draw), method, history=[])
    except GeometryError:
        return
    scene = simulation.scene
    audit = simulation.impact_audit
    rows = MemoryRecorder()
    simulation.run(impacts, rows)
    assert audit.created == 0, audit.examples
    phases = simulation.phase_audit
    if phases is not None:
        event(f"phases: {'some' if phases.phases else 'no'} contact phases")
        assert phases.transitions + phases.unlinked == phases.phases
        for count in ("transition_energy_created", "transition_jumps", "unlinked"):
            assert getattr(phases, count) == 0, (count, phases.examples)
        assert phases.phase_energy_created == 0, phases.examples
        if phases.static:
            assert phases.static_phases == phases.phases
    c = rows.columns()
    drag_free = scene.air.coefficients == (0.0, 0.0) and not scene.air.magnus
    if len(c["n"]) < 2 or not drag_free or scene.drive.amplitude != 0.0 or phases is not None:
        # (with phases, the contact phases between impacts are audited above instead)
        return
    # a fixed boundary and drag-free flights conserve energy: each impact's record can
    # exceed the previous one only by a lift's allowance (and rounding)
    m, g = scene.ball.mass, scene.run.gravity
    energy = c["energy"]
    allowance = np.array([entry[2] for entry in audit.history])[: len(energy)]
    scale = np.abs(energy[:-1]) + m * g * 0.3 + allowance[1:]
    growth = energy[1:] - energy[:-1] - allowance[1:]
    assert np.all(growth <= 1e-11 * scale), float(np.max(growth / scale))


# 120 examples in the default suite (the slow suite draws 1500 longer runs below)
@settings(
    max_examples=120, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(draw=draws(), method=methods)
def test_every_run_completes_or_stops_with_a_documented_reason(draw, method):
    check_run(draw, method, 250)


@settings(
    max_examples=100, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(draw=draws(elastic_below=(1e-3, 1e-2, 3e-2), amplitude=st.just(0.0)))
# a ball that lands after a summed chatter series and is still in that phase when the
# run ends: the landing is audited, but is not a transition of a finished phase
@example(
    draw={
        "curve": "parabola",
        "lid": False,
        "top": 0.0,
        "amplitude": 0.0,
        "frequency": 1.0,
        "direction": "horizontal",
        "phase": 0.0,
        "restitution": 0.001953125,
        "mu_static": 0.0,
        "mu_kinetic_fraction": 0.0,
        "elastic_below": 0.001,
        "radius_fraction": 0.5,
        "log_mass": -2.0,
        "inertia_factor": 1.0,
        "drag": "fowles",
        "magnus": 0.0,
        "start": "inside",
        "x_fraction": 0.75,
        "y_fraction": 0.0,
        "v1": 1.0,
        "v2": 0.0,
        "omega": 0.0,
        "t0": 0.0,
        "model": "phases",
    }  # fmt: skip
)
def test_impacts_never_create_energy_with_the_drive_off(draw):
    check_energy(draw, "event", 300)


@pytest.mark.slow  # 5 s; the drive-off property above runs by default
@settings(
    max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(draw=draws(elastic_below=(1e-3, 1e-2, 3e-2)))
def test_impacts_never_create_energy_in_the_boundary_frame(draw):
    """With the drive on too: energy relative to the moving boundary never grows."""
    check_energy(draw, "event", 300)


@pytest.mark.slow
@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(draw=draws(), method=methods)
def test_every_long_run_completes_or_stops_with_a_documented_reason(draw, method):
    check_run(draw, method, 2000)


@pytest.mark.slow
@settings(max_examples=800, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(draw=draws(elastic_below=(1e-3, 1e-2, 3e-2)))
def test_long_runs_never_create_energy_in_the_boundary_frame(draw):
    check_energy(draw, "event", 2000)


# ---------------------------------------------------------------------------------
# Known issues found by the soak: impacts applied at a contact that is separating.
# They fail today; ``strict`` makes them pass loudly once the engine is fixed.

RULE_OFF = {  # a drive-off scene with the low-velocity rule disabled
    "curve": "sqrt(0.0001 + 2*x**2) + 0.005",
    "lid": True,
    "top": 0.42226583358982994,
    "amplitude": 0.0,
    "frequency": 1.5884622345274966,
    "direction": "horizontal",
    "phase": 2.0634997170978937,
    "restitution": 0.04414612813616248,
    "mu_static": 0.42346847853307096,
    "mu_kinetic_fraction": 0.2678715311135216,
    "elastic_below": 0.0,
    "radius_fraction": 0.8027116114451683,
    "log_mass": -3.616924509598804,
    "inertia_factor": 0.6091231859581618,
    "drag": "none",
    "magnus": 0.0,
    "start": "inside",
    "x_fraction": 0.4977144959203087,
    "y_fraction": 0.6905718713945812,
    "v1": 1.1855213919540915,
    "v2": 0.722504758897192,
    "omega": 211.17248570827564,
    "t0": 6.962526447157391,
    "model": "impacts",
}
RK4_DEPARTURE = {  # rk4, rule on, a vertical drive
    "curve": "parabola",
    "lid": True,
    "top": 0.22518805726362923,
    "amplitude": 0.028420677422063466,
    "frequency": 3.3097703785990813,
    "direction": "vertical",
    "phase": 1.0027275733945002,
    "restitution": 0.7304149789132263,
    "mu_static": 0.991380672214931,
    "mu_kinetic_fraction": 0.740545706433447,
    "elastic_below": 0.001,
    "radius_fraction": 0.7530364263874791,
    "log_mass": -4.925663690877611,
    "inertia_factor": 0.18324132659104758,
    "drag": "none",
    "magnus": 0.0,
    "start": "rest",
    "x_fraction": 0.5137986111086027,
    "y_fraction": 0.3025691418725813,
    "v1": 0.5190159349944121,
    "v2": 0.15216389256099339,
    "omega": -177.07670539813535,
    "t0": 40.78181529175555,
    "model": "impacts",
}


def test_separating_contact_gets_no_impulse_with_the_rule_off():
    """Regression (found by the soak): with elastic_below = 0 a ball sliding along a curved
    wall is re-hit at a contact that never opened (w_n > 0). A contact only pushes, so no
    impulse may be applied; before the fix, the slip impulse created energy here."""
    check_energy(RULE_OFF, "event", 400)


def test_rk4_departure_taken_for_an_impact_creates_no_energy():
    """Regression (found by the soak): the rk4 baseline can take the departure point of
    the previous impact for a new one when the ball returns within one fixed step (its
    known weakness); the separating contact then gets no impulse, so no energy is made."""
    check_energy(RK4_DEPARTURE, "rk4", 60)


def test_soak_jobs_audit_runs_and_resumes():
    """The soak's unit of work, in miniature: a paper scene and a random scene that is
    also interrupted (a real SIGTERM), resumed and compared byte for byte."""
    import random

    from bench.soak import Job, random_draw, run_job

    paper = run_job(Job("wedge-6.6hz", 300, scene_name="wedge-6.6hz"))
    rng = random.Random(7)
    draw = {**random_draw(rng), "elastic_below": 0.01, "lid": True, "start": "rest"}
    draw["model"] = "impacts"
    scene = run_job(Job("random-0", 300, draw=draw, resume_at=123))
    for report in (paper, scene):
        assert report["impacts"] >= 1 and report["stop"] in ("complete", "collapse")
        for key in ("penetrations", "detached", "non_finite_rows", "energy_created"):
            assert report[key] == 0, (key, report)
    assert paper["impacts"] == 300 and paper["stop"] == "complete"
    assert scene["resume_interrupted"] == 1 and scene["resume_mismatches"] == 0
