"""Contact phases (``contact.model = "phases"``): regressions of the faults the soak
found (a phase that starts in the wedge's vertex slid through the other wall; a ball
rolling or sliding up a wall went through the lid, or on above the escape level), and
the soak's audits of contact phases: clean on real runs, and able to fail."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.run.simulate import Simulation
from billiard.runfile.record import LID_WALL, MemoryRecorder
from billiard.scene.scene import load_scene, with_values
from billiard.status import Status

GAP_LIMIT = 1e-9  # m, as bench.soak.GAP_LIMIT

WEDGE_VERTEX = """\
name = "wedge-vertex"

[boundary]
curve = "wedge"
ceiling = 0.16054087828235847
escape_height = 0.16054087828235847

[drive]
amplitude = 0.002922917279842001
frequency = 8.83321842320769
direction = "horizontal"
phase = 3.889351980831287

[ball]
radius = 0.0019134148662900002
mass = 0.005892833235280414
inertia_factor = 0.4254241203501097

[contact]
restitution = 0.4964144951134918
mu_static = 0.37017818892232124
mu_kinetic = 0.19683123789238322
elastic_below = 0.01
model = "phases"

[air]
drag = "fowles"
c_lin = 5.931586085499001e-07
c_quad = 3.22181767647483e-06
magnus = 6.989944337295713e-09

[initial]
t = 3.6600433729834014

[run]
duration = 0.3
"""


def run_events(scene, impacts: int):
    """Run in memory: (simulation, impact columns, contact records)."""
    sim = Simulation(scene)
    phases = []
    sim.on_contact = phases.append
    rows = MemoryRecorder()
    reason = sim.run(impacts, rows)
    return sim, rows.columns(), phases, reason


def clearances(sim, columns, phases) -> list[tuple[str, float]]:
    """Clearance (m) of the centre at every impact and at both ends of every phase."""
    drive, boundary = sim.drive, sim.boundary
    out = []

    def at(label: str, t: float, q1: float, q2: float) -> None:
        px, py, _, _ = drive.to_boundary_frame(drive.angle(t), q1, q2, 0.0, 0.0)
        out.append((label, boundary.clearance(px, py)))

    for n, t, q1, q2 in zip(columns["n"], columns["t"], columns["q1"], columns["q2"], strict=True):
        at(f"impact {n}", float(t), float(q1), float(q2))
    for i, p in enumerate(phases):
        at(f"phase {i + 1} start", p.t_start, p.q1_start, p.q2_start)
        at(f"phase {i + 1} end ({p.mode}, {p.end})", p.t_end, p.q1_end, p.q2_end)
    return out


def test_a_phase_starting_in_the_wedges_vertex_does_not_slide_through_the_other_wall(
    tmp_path,
):
    """Regression (found by the soak, random scene 1 of seed 7): a ball landing on one
    wall of the shaken wedge while it touched the other (gap -1.7e-18 m, closing at
    0.9 mm/s) slid through that wall: the crossing test needed the gap positive at the
    phase's start, so the phase ran to the wall's end at the vertex, 3 mm deep in the
    other wall (impacts 22 on, clearance -0.00296 m). Now it is an impact at once, after
    which both walls hold the ball."""
    path = tmp_path / "wedge-vertex.toml"
    path.write_text(WEDGE_VERTEX)
    sim, columns, phases, reason = run_events(load_scene(path), 60)
    # it rolls into the vertex and stays there: the wedge's peak acceleration
    # A w^2 = 9.0 m/s^2 is below g tan(beta) = 18 m/s^2, so both walls hold it
    drive = sim.drive
    assert drive.amplitude * drive.omega**2 < sim.scene.run.gravity * 1.85
    # slides, rolls into the vertex and meets the other wall, where the series of impacts
    # at that instant is one impact whose limit is rest: held there (before, a row per
    # impact of the series, a roll on the other wall and one more impact 7.5 ms later:
    # 5 rows, 3 phases)
    assert len(phases) >= 2 and len(columns["n"]) >= 3 and sim.mode == "held"
    worst = min(clearances(sim, columns, phases), key=lambda item: item[1])
    assert worst[1] >= -GAP_LIMIT, worst
    ends = {(p.mode, p.end) for p in phases}
    assert ("slide", "wall-end") not in ends and ("roll", "wall-end") not in ends


def rolling_up(**values):
    """A ball started on the bottom of the fixed parabola with 1.5 m/s along it: rolling
    and sliding, it would rise 8 cm."""
    base = {
        "contact.model": "phases",
        "drive.amplitude": 0.0,
        "drive.frequency": 0.0,
        "air.drag": "none",
        "initial.v1": 1.5,
        "run.duration": 0.5,
    }
    return with_values(load_scene("parabola-5.4hz"), {**base, **values})


def test_a_ball_rolling_up_a_wall_meets_the_lid():
    """Regression (found by the soak): a contact phase watched the other walls but not
    the lid, so a ball rolling or sliding up the wall went through it (soak: clearance
    down to -0.188 m at a phase's end, and impacts on the lid from inside it). With the
    lid at 3 cm the ball used to roll up to q2 = 8.8 cm; now the phase ends at the lid
    with an impact there."""
    sim, columns, phases, reason = run_events(rolling_up(**{"boundary.ceiling": 0.03}), 20)
    assert reason is None
    level = sim.boundary.lid.level
    assert phases[1].end == "impact" and phases[1].q2_end == pytest.approx(level, abs=1e-12)
    assert LID_WALL in set(columns["wall"].tolist())
    worst = min(clearances(sim, columns, phases), key=lambda item: item[1])
    assert worst[1] >= -GAP_LIMIT, worst
    for p in phases:
        assert max(p.q2_start, p.q2_end) <= level + GAP_LIMIT


def test_a_ball_rolling_up_above_the_escape_level_escapes():
    """Regression: in an open container the escape level ends a contact phase too (the
    ball used to roll on above it and come back)."""
    scene = rolling_up(**{"boundary.ceiling": None, "boundary.escape_height": 0.03})
    sim, columns, phases, reason = run_events(scene, 20)
    assert sim.status == Status.ESCAPED
    assert reason.startswith("ball escaped above escape_height = 0.03 m at t = ")
    assert phases[-1].end == "impact" and phases[-1].q2_end == pytest.approx(0.03, abs=1e-12)


# ---------------------------------------------------------------------------------
# The soak's audits of contact phases (bench.soak): clean on real runs, and able to fail.

STATIC_DRAW = {  # a fixed parabola, ball thrown inside: sliding and rolling phases
    "curve": "parabola",
    "lid": True,
    "top": 0.14322037755054962,
    "amplitude": 0.0,
    "frequency": 9.291484184287023,
    "direction": "vertical",
    "phase": 4.146839500264662,
    "restitution": 0.4419324807696866,
    "mu_static": 0.30699626412765785,
    "mu_kinetic_fraction": 0.891726920317737,
    "elastic_below": 0.01,
    "radius_fraction": 0.42237659582962933,
    "log_mass": -4.248202088508626,
    "inertia_factor": 0.6707558154151272,
    "drag": "fowles",
    "magnus": 3.84418682899903e-09,
    "start": "inside",
    "x_fraction": 0.9208034002519163,
    "y_fraction": 0.1278250990185416,
    "v1": -0.5970194388301491,
    "v2": 1.582611645720014,
    "omega": -275.6565360223453,
    "t0": 3.206950780004314,
    "model": "phases",
}
SHAKEN_DRAW = {  # a vertically shaken parabola with a lid: landings, lift-offs, slips
    "curve": "parabola",
    "lid": True,
    "top": 0.4586707684431828,
    "amplitude": 0.011530336737222495,
    "frequency": 6.691772422665341,
    "direction": "vertical",
    "phase": 3.2186388591630335,
    "restitution": 0.06429079259075188,
    "mu_static": 0.8665810021694228,
    "mu_kinetic_fraction": 0.9850832441340993,
    "elastic_below": 0.001,
    "radius_fraction": 0.9439602819553082,
    "log_mass": -4.685661217181505,
    "inertia_factor": 0.3390078451091678,
    "drag": "fowles",
    "magnus": 1.8155139141117104e-09,
    "start": "rest",
    "x_fraction": 0.819777268337117,
    "y_fraction": 0.6421749556662888,
    "v1": 1.7840062456908528,
    "v2": -0.37620868833756616,
    "omega": 21.95933425056114,
    "t0": 25.739130962861672,
    "model": "phases",
}


def test_the_soak_audits_phases_scenes_and_finds_nothing():
    """The soak's unit of work on phases scenes: every event audited (impacts, contact
    phases and the transitions into them), the static scene's phase energies too, and a
    run interrupted by a real SIGTERM, resumed, and compared byte for byte (collisions.csv
    and contacts.csv)."""
    from bench.soak import MUST_BE_ZERO, Job, run_job

    static = run_job(Job("random-static", 60, draw=STATIC_DRAW))
    shaken = run_job(Job("random-shaken", 150, draw=SHAKEN_DRAW, resume_at=97))
    for report in (static, shaken):
        assert report["model"] == "phases" and report["contact_phases"] >= 3, report
        assert report["events"] == report["impacts"] + report["contact_rows"]
        assert report["contact_rows"] == report["contact_phases"]
        assert report["transitions"] == report["contact_phases"]
        for key in MUST_BE_ZERO:
            assert report.get(key, 0) == 0, (key, report)
    assert static["static"] == 1 and static["static_phases"] == static["contact_phases"]
    assert static["worst_phase_energy_ratio"] < 1.0  # drag on: energy only lost
    assert shaken["static"] == 0 and shaken["static_phases"] == 0
    assert shaken["impacts"] == 150 and shaken["stop"] == "complete"
    assert {"slide/lift-off", "roll/slip"} <= set(shaken["phase_ends"])
    assert shaken["resume_interrupted"] == 1 and shaken["resume_phases"] == 1
    assert shaken["resume_mismatches"] == 0


def recorded_phases():
    """A static scene's contact phases, audited as the soak audits them: (simulation,
    its records)."""
    from bench.soak import AuditedSimulation

    sim = AuditedSimulation(rolling_up(**{"run.duration": 1.0}))
    records = []
    sim.on_contact = records.append
    assert sim.run(50, MemoryRecorder()) is None
    assert len(records) >= 4 and records[0].t_start == sim.initial.t
    return sim, records


def test_the_phase_audit_counts_a_doctored_record():
    """A contact record that gains energy over its phase, starts with more kinetic
    energy than the event before it left, jumps, or starts at no event is counted."""
    from bench.soak import PhaseAudit

    sim, records = recorded_phases()
    audit = sim.phase_audit
    assert audit.phases == len(records) and audit.static_phases == len(records)
    assert audit.transition_energy_created == audit.phase_energy_created == 0
    assert audit.transition_jumps == audit.unlinked == 0
    assert audit.worst_phase < 1.0 and audit.worst_transition <= 1e-12

    def audited(*recs):
        fresh = PhaseAudit.of(sim)
        for rec in recs:
            fresh.contact(rec, steps=1000)
        return fresh

    first, second = records[0], records[1]
    assert (second.mode, second.end) == ("roll", "slip")  # rolling, drag off: conserving
    assert audited(first, second).examples == []
    gains = audited(first, second._replace(v1_end=second.v1_end * 1.0001))
    assert gains.phase_energy_created == 1 and gains.worst_phase > 1.0
    rises = audited(first, second._replace(q2_end=second.q2_end + 1e-6))
    assert rises.phase_energy_created == 1 and rises.transition_energy_created == 0
    kick = audited(first, second._replace(v2_start=second.v2_start * (1.0 + 1e-9)))
    assert kick.transition_energy_created == 1 and kick.phase_energy_created == 0
    jump = audited(first, second._replace(q1_start=second.q1_start + 1e-8))
    assert jump.transition_jumps == 1 and jump.transition_energy_created == 0
    late = audited(first, second._replace(t_start=second.t_start + 1e-9))
    assert late.unlinked == 1 and late.transitions == 1


def test_the_event_audit_counts_an_energy_rise_on_a_still_boundary():
    """On a static boundary the state just before an event holds no more mechanical
    energy than the state after the event before it, with no allowance (nothing there
    adds energy): the real records pass, a phase starting 1e-9 m higher (within the
    transition's jump limit) or 1e-9 faster is counted."""
    from bench.soak import PhaseAudit

    sim, records = recorded_phases()
    audit = sim.phase_audit
    assert audit.event_checks >= len(records) and audit.event_energy_rises == 0
    assert audit.worst_event <= 1e-12

    def audited(*recs):
        fresh = PhaseAudit.of(sim)
        for rec in recs:
            fresh.contact(rec, steps=1000)
        return fresh

    first, second = records[0], records[1]
    assert audited(first, second).event_energy_rises == 0
    higher = audited(first, second._replace(q2_start=second.q2_start + 1e-9))
    assert higher.event_energy_rises == 1 and higher.transition_jumps == 0
    faster = audited(first, second._replace(v1_start=second.v1_start * (1.0 + 1e-9)))
    assert faster.event_energy_rises == 1
    assert "mechanical energy" in faster.examples[0]


def test_the_impulse_audit_counts_rows_below_1e_20_n_s():
    from bench.soak import audit_impulses

    rn = np.array([1e-3, 0.0, 5e-21, 2e-20, 1e-25])
    rt = np.array([0.0, 0.0, -5e-21, 0.0, -3e-20])
    assert audit_impulses({"Rn": rn, "Rt": rt}) == {
        "zero_impulse_rows": 1,
        "small_impulse_rows": 2,
    }


def test_the_contact_rows_audit_counts_a_ball_off_the_wall():
    """A contacts.csv row whose end leaves the wall's offset curve by 1 um either way, or
    holds a NaN, is counted."""
    from bench.soak import audit_contact_rows

    sim, records = recorded_phases()

    def rows(recs):
        return {name: np.array([getattr(r, name) for r in recs]) for name in records[0]._fields}

    clean = audit_contact_rows(sim.boundary, sim.drive, rows(records))
    assert clean["contact_rows"] == len(records)
    assert clean["contact_penetrations"] == clean["contact_detached"] == 0
    assert clean["contact_non_finite_rows"] == 0
    assert abs(clean["contact_lowest_clearance"]) < 1e-12

    last = records[-1]
    for change, key in ((1e-6, "contact_detached"), (-1e-6, "contact_penetrations")):
        doctored = records[:-1] + [last._replace(q2_end=last.q2_end + change)]
        report = audit_contact_rows(sim.boundary, sim.drive, rows(doctored))
        assert report[key] == 1, report
        assert report["contact_examples"][0].startswith(f"contact phase {len(records)} end")
    broken = records[:-1] + [last._replace(omega_end=math.nan)]
    report = audit_contact_rows(sim.boundary, sim.drive, rows(broken))
    assert report["contact_non_finite_rows"] == 1
