"""Contact phases (``contact.model = "phases"``): regressions of the faults the soak
found (a phase that starts in the wedge's vertex slid through the other wall; a ball
rolling or sliding up a wall went through the lid, or on above the escape level)."""

from __future__ import annotations

import pytest

from billiard.record import MemoryRecorder
from billiard.scene import load_scene, with_values
from billiard.simulate import Simulation
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
    other wall (impacts 22 on, clearance -0.00296 m). Now it is an impact at once."""
    path = tmp_path / "wedge-vertex.toml"
    path.write_text(WEDGE_VERTEX)
    sim, columns, phases, reason = run_events(load_scene(path), 60)
    assert len(phases) >= 10 and len(columns["n"]) >= 20
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
    assert "lid" in set(columns["wall"].tolist())
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
