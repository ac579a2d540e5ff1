"""The engine state survives the trip into the kernels' state vector and back:
EngineState -> ctx -> EngineState is the identity, mid-run and after a checkpoint's
restore, for every paper scene with drag on and off."""

from __future__ import annotations

import dataclasses
import json

import pytest

from billiard.engine.ctx import engine_state, state_vector, write_state
from billiard.engine.state import EngineState
from billiard.kernels import layout as L
from billiard.run.simulate import COLLAPSE_COUNT, Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene, with_values

SCENES = ["wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz", "parabola-5.4hz"]


def _kernel_part(state: EngineState) -> EngineState:
    # the motion state of the impacts model is always flight, without samples
    return dataclasses.replace(state, mode="flight", contact=(), samples=0)


def _round_trip(sim: Simulation) -> None:
    state = sim.state
    ctx = state_vector(sim)
    back = engine_state(ctx, sim.impact.regimes, len(sim.boundary.offsets))
    assert back == _kernel_part(state)
    # and written into a fresh vector, read back again
    other = state_vector(Simulation(sim.scene))
    write_state(other, state)
    assert engine_state(other, sim.impact.regimes, len(sim.boundary.offsets)) == back


@pytest.mark.parametrize("drag", ["none", "fowles"])
@pytest.mark.parametrize("name", SCENES)
def test_engine_state_round_trip(name, drag):
    sim = Simulation(with_values(load_scene(name), {"air.drag": drag}))
    _round_trip(sim)  # the start
    sim.run(150, MemoryRecorder())
    assert sim.state.impacts == 150 and sim.state.recent
    _round_trip(sim)
    # through a checkpoint's JSON, restored into another engine
    data = json.loads(json.dumps(sim.state.to_dict()))
    restored = Simulation(sim.scene)
    restored.restore(EngineState.from_dict(data, COLLAPSE_COUNT + 1))
    assert restored.state == sim.state
    _round_trip(restored)


def test_collapse_window_ring_is_read_oldest_first():
    sim = Simulation(load_scene("wedge-6.6hz"))
    ctx = state_vector(sim)
    ring = COLLAPSE_COUNT + 1
    ctx[L.EN_RHEAD], ctx[L.EN_RCOUNT] = float(ring - 2), 4.0
    for i, t in enumerate((1.0, 2.0, 3.0, 4.0)):
        ctx[L.RECENT + (ring - 2 + i) % ring] = t
    assert engine_state(ctx, sim.impact.regimes, 3).recent == (1.0, 2.0, 3.0, 4.0)
