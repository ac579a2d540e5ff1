"""The paper's fixed-step detection (method ``rk4``) on the one engine
(:mod:`billiard.kernels.fixed_step`, ``run_chunk_fixed`` under the state machine): the
bytes the runtime's classes wrote before it ran there (``tests/data/rk4_sha256.json``,
checked where the pins were made: :data:`csv_pins.PINNED_ON`), the same records compiled
as interpreted, global nearest points answered along the way, and checkpoints that
continue bit for bit.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from billiard import jit
from billiard.engine import driver as engine_kernels
from billiard.engine import simulation as engine
from billiard.run.simulate import Simulation, simulate
from billiard.scene.scene import load_scene, with_values
from billiard.status import Status
from tests.csv_pins import require_pinned_platform

PINS = json.loads((Path(__file__).parents[1] / "data" / "rk4_sha256.json").read_text())

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


def rk4(name: str, drag: str):
    return with_values(load_scene(name), {"run.method": "rk4", "air.drag": drag})


@compiled
@pytest.mark.parametrize("key", sorted(PINS["sha256"]))
def test_compiled_rk4_writes_the_pinned_bytes(key, tmp_path):
    # the stop at impact 1045 below is a pinned value too: libm's last bits decide it
    require_pinned_platform()
    name, drag = key.split()
    result = simulate(rk4(name, drag), collisions=PINS["impacts"], out_dir=tmp_path)
    data = (tmp_path / "collisions.csv").read_bytes()
    assert hashlib.sha256(data).hexdigest() == PINS["sha256"][key]
    if key == "wedge-6.6hz fowles":
        assert result.status is Status.SOLVER_FAILED and len(result) == 1045
        assert "run.step = 0.0001 s is too coarse" in result.stop_reason
    else:
        assert len(result) == PINS["impacts"], result.stop_reason


@pytest.fixture
def answers(monkeypatch) -> list:
    """The global nearest points the kernels asked for, as (px, py, wall)."""
    asked: list = []
    answer = engine_kernels.answer_foot

    def counted(ctx, boundary):
        asked.append(tuple(float(ctx[engine_kernels.L.RK_ASK + k]) for k in range(3)))
        answer(ctx, boundary)

    monkeypatch.setattr(engine_kernels, "answer_foot", counted)
    return asked


def run(scene, impacts: int, *, kernels: bool, start=None, checkpoints=None):
    sim = Simulation(scene)
    if not kernels:
        sim.driver.interpreted = True  # the same source as plain Python
    records: list = []
    sim.run(impacts, records, start=start, checkpoint=checkpoints)
    return [repr(tuple(r)) for r in records], sim.state, sim.status


@pytest.mark.parametrize(
    ("name", "drag"), [("hyperbola-5.8hz", "none"), ("parabola-5.4hz", "fowles")]
)
def test_rk4_compiled_is_the_interpreted_engine(name, drag, answers):
    scene = rk4(name, drag)
    on_kernels = run(scene, 400, kernels=True)
    assert answers, "no global nearest point asked for: the test covers less than it says"
    on_classes = run(scene, 400, kernels=False)
    assert on_kernels == on_classes
    assert on_kernels[1].locator["feet"] != [0.0, 0.0]


def test_rk4_checkpoints_on_the_kernels_continue_bit_for_bit(monkeypatch, answers):
    monkeypatch.setattr(engine, "CHECKPOINT_INTERVAL", 0.0)
    scene = rk4("hyperbola-5.8hz", "none")
    states: list = []
    rows, *_ = run(scene, 300, kernels=True, checkpoints=states.append)
    assert len(states) > 30 and answers
    for state in states[::5]:
        tail, *_ = run(scene, 300, kernels=True, start=state)
        assert tail == rows[state.impacts :], state.impacts


def test_rk4_under_contact_phases_leaves_a_wall_for_good():
    """The fixed-step search has no grazing start: a ball leaving a wall with no normal
    speed met it again at once (three departures in a row stopped the wedge at impact
    378); under this search it leaves at RK4_DEPARTURE_SPEED, as before the event
    locator's grazing starts."""
    scene = with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases", "run.method": "rk4"})
    result = simulate(scene, collisions=400)
    assert result.stop_reason is None and len(result) == 400
    assert result.status is Status.COMPLETE
