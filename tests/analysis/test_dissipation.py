"""The energy an impact law removes per impact (billiard.analysis.dissipation), against
the energy column of the record: on a still boundary without drag the ball's energy is
constant in flight, so what an impact removes is the energy after the previous impact
less the energy after it; and the calibration of each law per impact law."""

from __future__ import annotations

import json

import numpy as np
import pytest

from billiard.analysis.dissipation import impact_dissipation, relative_energy
from billiard.cli import main
from billiard.models.impact import with_law
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values


@pytest.mark.parametrize("law", ["kane-levinson", "walton", "point-particle"])
def test_dissipation_is_the_energy_lost_at_impacts_on_a_still_boundary(law):
    scene = with_values(
        with_law(load_scene("parabola-5.4hz"), law),
        {
            "drive.amplitude": 0.0,
            "air.drag": "none",
            "contact.elastic_below": 0.0,
            "initial.q1": 0.03,
            "initial.q2": 0.06,
            "initial.v1": -0.4,
        },
    )
    columns = simulate(scene, collisions=30).columns
    lost = -np.diff(np.asarray(columns["energy"]))
    d = impact_dissipation(columns, scene)[1:]
    assert np.all(d >= 0.0)
    assert d == pytest.approx(lost, rel=1e-9, abs=1e-16)
    assert np.all(d <= relative_energy(columns, scene)[1:] * (1 + 1e-12))


def test_calibrating_the_point_particle_needs_a_lower_e_than_the_paper(capsys):
    # the paper's e = 0.393 has rotation and friction; without them the same orbit needs
    # less restitution to remove the energy the drive puts in
    args = ["calibrate", "parabola-5.4hz", "--law", "point-particle", "--target-height", "0.075"]
    assert main([*args, "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    assert fit["law"] == "point-particle" and fit["parameter"] == "contact.restitution"
    assert fit["orbit_height"] == pytest.approx(0.075, abs=1e-6)
    assert 0.1 < fit["value"] < 0.393 - 0.1
    assert 0.0 < fit["dissipated_per_impact"] < fit["relative_energy"]


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--law", "walten"], "scene key 'contact.law' = 'walten' must be one of"),
        ([], "calibrate: give --parameter KEY, or --law NAME"),
    ],
)
def test_calibrate_refuses_a_misspelled_law_in_one_line(capsys, args, fragment):
    assert main(["calibrate", "parabola-5.4hz", "--target-height", "0.075", *args]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and fragment in err[0]
