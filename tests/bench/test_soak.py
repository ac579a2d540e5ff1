"""The soak's energy audit (bench/soak.py): the low-velocity rule's lift is allowed its
designed energy under the impacts model only, and a landing after a summed chatter
series is audited as a transition."""

from __future__ import annotations

import dataclasses
import math

import pytest

from billiard.engine.state import BallState
from billiard.models.impact import Contact
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import scene_from_dict

G = 9.81
R = 1.55e-3


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The flat curve "0.001" is derived on first use into a temporary BILLIARD_HOME."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


def floor(model: str, elastic_below: float, initial: dict, drive: dict | None = None):
    return scene_from_dict(
        {
            "boundary": {"curve": "0.001", "escape_height": 10.0, "ceiling": 5.0},
            "drive": drive or {"amplitude": 0.0, "frequency": 1.0},
            "contact": {
                "model": model,
                "restitution": 0.5,
                "elastic_below": elastic_below,
                "mu_static": 0.0,
                "mu_kinetic": 0.0,
            },
            "air": {"drag": "none"},
            "initial": initial,
        }
    )


@pytest.mark.parametrize(("model", "created"), [("impacts", 0), ("phases", 1)])
def test_a_lift_is_allowed_its_energy_under_the_impacts_model_only(model, created):
    from bench.soak import AuditedSimulation

    sim = AuditedSimulation(floor(model, 0.01, {"q1": 0.0, "q2": 0.001 + R}))
    audit = sim.impact_audit
    assert audit.lift_allowed is (model == "impacts")
    # the law itself, told the ball lies pressed on the floor at 1e-3 m/s: it lifts it
    # to 0.01 m/s (the impacts model's rule; the phases engine never asks for it)
    res = audit.apply(
        BallState(0.0, 0.0, 0.0, 0.001 + R, 0.0, -1e-3, 0.0), Contact(0.0, 0, 0, True)
    )
    assert res.resting and res.u2 == pytest.approx(0.01)
    assert audit.lifts == 1 and audit.created == created


def test_a_summed_chatter_landing_is_an_audited_transition():
    from bench.soak import AuditedSimulation, PhaseAudit

    gamma, f = 1.2, 20.0
    w = 2 * math.pi * f
    drive = {"amplitude": gamma * G / w**2, "frequency": f, "direction": "vertical"}
    sim = AuditedSimulation(floor("phases", 0.0, {"q1": 0.0, "q2": 0.001 + R + 0.01}, drive))
    records: list = []
    sim.on_contact = records.append
    sim.run(200, MemoryRecorder())
    audit: PhaseAudit = sim.phase_audit
    assert len(records) > 5 and audit.phases == len(records)
    # every phase is linked to the event before it (a transition each), and the landings
    # at the series' ends are audited steps of their own from the impact before them
    assert audit.unlinked == 0 and audit.transitions == audit.phases
    assert audit.chatter_landings >= len(records) - 1
    assert audit.transition_jumps == audit.transition_energy_created == 0
    assert sim.impact_audit.created == sim.impact_audit.lifts == 0
    # a landing that moved the ball relative to the table would be counted
    fresh = PhaseAudit.of(sim)
    before = sim.state.ball
    moved = dataclasses.replace(before, t=before.t + 1e-9, q2=before.q2 + 1e-6)
    fresh.chatter(before, moved)
    assert fresh.transition_jumps == 1


@pytest.mark.parametrize("law", ["walton", "power-law", "viscoelastic", "point-particle"])
def test_the_soak_draws_and_audits_every_impact_law(law):
    import random

    from bench.soak import LAWS, Job, random_draw, run_job, scene_from_draw
    from billiard.scene.spec import LAW_PARAMETERS

    assert set(LAWS) == set(LAW_PARAMETERS)
    rng = random.Random(11)
    draw = {**random_draw(rng), "law": law, "model": "impacts", "start": "inside"}
    draw.update(elastic_below=0.0, lid=True, amplitude=0.0, drag="none")
    scene = scene_from_draw(draw)
    assert scene.contact.law == law
    for key in sum(LAW_PARAMETERS[law], ()):
        assert getattr(scene.contact, key) == draw[key]
    report = run_job(Job(f"random-{law}", 200, draw=draw))
    assert report["law"] == law and report["impacts"] >= 1
    assert report["energy_created"] == 0 and report["penetrations"] == 0
