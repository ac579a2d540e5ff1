"""The phase on the lid (``billiard/kernels/lid.py``, the state machine's ``lid_step``):
compiled and interpreted alike, bit for bit, through landing on the lid, sliding,
rolling, lift-off and the wall-lid corner, with samples inside the phases."""

from __future__ import annotations

import numpy as np
import pytest

from billiard import jit
from billiard.run.simulate import Simulation
from billiard.runfile.record import LID_WALL, MemoryRecorder
from tests.validation.test_lid import B, billiard_home, lid_scene  # noqa: F401 (a fixture)

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


def outputs(scene, until, sample, interpreted):
    """(impact columns as bytes, contact rows, samples) of a sampled run to ``until``."""
    sim = Simulation(scene)
    sim.driver.interpreted = interpreted
    contacts, samples = [], []
    sim.on_contact = contacts.append
    sim.sample_dt, sim.on_sample = sample, lambda *row: samples.append(row)
    recorder = MemoryRecorder()
    sim.run(1000, recorder, until=until)
    rows = {k: np.asarray(v).tobytes() for k, v in recorder.columns().items()}
    return rows, [repr(tuple(c)) for c in contacts], [repr(r) for r in samples]


@compiled
@pytest.mark.parametrize("curve, parameters, v1", [("0", None, 0.2), ("wedge", {"b": B}, 2.0)])
def test_sampled_runs_on_the_lid_are_the_same_compiled_and_interpreted(curve, parameters, v1):
    scene = lid_scene(curve, parameters and {**parameters, "c": 0.0}, v1=v1)
    compiled_run = outputs(scene, 0.08, 0.001, False)
    on_lid = [c for c in compiled_run[1] if f", {LID_WALL}, " in c]
    assert on_lid and compiled_run[2]
    assert outputs(scene, 0.08, 0.001, True) == compiled_run
