"""The rk4 baseline refuses to go on with a step too coarse for the scene: a chain of
impacts found at the point the ball had just left (it came back within one step) stops
the run with the step to use, instead of pumping spin and energy into the ball."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.cli import main
from billiard.models.rk4_locator import DEPARTURE_LIMIT
from billiard.run.simulate import Status, simulate
from billiard.scene.scene import load_scene, with_values


@pytest.mark.parametrize(("step", "finer"), [(0.003, "0.0003"), (0.001, "0.0001")])
def test_a_coarse_step_stops_the_run_with_the_step_to_use(step, finer):
    scene = with_values(load_scene("parabola-5.4hz"), {"run.step": step})
    result = simulate(scene, collisions=300, method="rk4")
    assert result.status == Status.SOLVER_FAILED
    assert result.stop_reason.startswith(
        f"run.step = {step:g} s is too coarse for this scene (use run.step <= {finer} s): "
        f"{DEPARTURE_LIMIT} impacts in a row were found within "
    ), result.stop_reason
    c = result.columns
    # stopped before the spurious impacts pumped the ball (before: spin 400 rad/s and
    # the energy up 2.9 times within 300 impacts, exit status 0)
    assert len(c["n"]) < 10
    assert np.abs(c["omega"]).max() < 100.0 and c["energy"].max() < 2 * c["energy"][0]


def test_the_command_line_stops_with_one_line(tmp_path, capsys):
    args = ["run", "parabola-5.4hz", "--method", "rk4", "--set", "run.step=0.003"]
    status = main([*args, "--collisions", "300", "--out", str(tmp_path / "r"), "--no-plot"])
    err = capsys.readouterr().err
    assert status == 3 and err.count("\n") == 1
    assert err.startswith("billiard: stopped: run.step = 0.003 s is too coarse for this scene")


@pytest.mark.parametrize(
    "name", ["parabola-5.4hz", "wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz"]
)
def test_the_default_step_runs_the_paper_scenes(name):
    result = simulate(load_scene(name), collisions=300, method="rk4")
    assert result.stop_reason is None and len(result) == 300
