"""The kernels' state vector is declared once (``billiard/kernels/layout.py``): its
slots follow one another without gap or overlap, every constant the kernels read is the
index its declaration gives, and a quantity is found by name in a real run's ``ctx``."""

from __future__ import annotations

import pytest

from billiard.engine.simulation import Simulation
from billiard.kernels import interpreted as twin
from billiard.kernels import layout as L
from billiard.kernels.rules import COLLAPSE_COUNT
from billiard.models.impact import KaneLevinsonImpact
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene, with_values

LAYOUTS = {"ctx": L.CTX, "surface": L.SURFACE}


@pytest.mark.parametrize("name", LAYOUTS)
def test_slots_are_consecutive(name):
    layout = LAYOUTS[name]
    slots = sorted(layout.slots, key=lambda s: s.index)
    assert slots == layout.slots  # declared in order
    assert slots[0].index == 0
    for before, after in zip(slots, slots[1:], strict=False):
        assert after.index == before.stop, (before.constant, after.constant)
    assert all(s.size >= 1 for s in slots)
    assert layout.size == slots[-1].stop
    # each block covers its quantities and nothing else
    for block, start, stop in layout.blocks:
        inside = [s for s in slots if s.name.startswith(f"{block}.")]
        assert (inside[0].index, inside[-1].stop) == (start, stop), block
        assert all(start <= s.index < stop for s in inside)


@pytest.mark.parametrize("module", [L, twin.layout], ids=["compiled", "twin"])
def test_every_constant_is_its_declared_index(module):
    namespace = vars(module)
    for layout in (module.CTX, module.SURFACE):
        assert layout.mismatches(namespace) == []
        names = [s.name for s in layout.slots] + [s.constant for s in layout.slots]
        assert len(set(names)) == len(names)
        for s in layout.slots:
            assert layout.slot(s.name) is layout.slot(s.constant) is s
    assert module.SIZE == module.CTX.size
    assert module.SURF_STRIDE == module.SURFACE.size
    assert module.CTX.slot("surfaces").size == module.MAX_SURFACES * module.SURF_STRIDE
    # the blocks' first and last constants
    blocks = {name: (start, stop) for name, start, stop in module.CTX.blocks}
    assert (module.PH, module.PH_END) == blocks["phase"]
    assert (module.VX, module.VX_END) == blocks["hold"]
    assert (module.RK, module.RK_END) == blocks["rk4"]


def test_a_mismatched_constant_is_reported():
    namespace = dict(vars(L))
    namespace["IM_E"] = L.IM_E + 1
    del namespace["FL_YA"]
    assert L.CTX.mismatches(namespace) == [
        f"FL_YA = None, declared {L.FL_YA}",
        f"IM_E = {L.IM_E + 1}, declared {L.IM_E}",
    ]


def test_a_quantity_is_declared_once():
    layout = L.Layout("test")
    layout.begin("ball")
    assert layout.add("A", "mass", 1, "kg", "mass") == 0
    assert layout.add("B", "spin", 3, "rad/s", "spins") == 1
    assert layout.end() == 4
    with pytest.raises(ValueError, match="declared twice"):
        layout.add("A", "other", 1, "", "")
    layout.begin("ball")
    with pytest.raises(ValueError, match="ball.mass declared twice"):
        layout.add("C", "mass", 1, "kg", "")
    with pytest.raises(ValueError, match="0 slots"):
        layout.add("D", "nothing", 0, "", "")
    with pytest.raises(KeyError, match="no quantity 'ball.radius'"):
        layout.slot("ball.radius")


def test_the_collapse_ring_holds_the_collapse_window():
    assert L.CTX.slot("recent").size == COLLAPSE_COUNT + 1


def test_describe_lists_every_slot():
    table = [line.split() for line in L.describe().splitlines()]
    for s in (*L.CTX.slots, *L.SURFACE.slots):
        rows = [row[:4] for row in table if len(row) > 2 and row[2] == s.constant]
        assert rows == [[str(s.index), str(s.size), s.constant, s.name]]


def _scene(model: str):
    # coefficients other than the paper's, so that no default can pass for them
    values = {
        "contact.model": model,
        "contact.restitution": 0.8125,
        "contact.elastic_below": 0.0375,
    }
    return with_values(load_scene("wedge-6.6hz"), values)


def test_quantities_are_read_by_name_from_a_run():
    sim = Simulation(_scene("impacts"))
    sim.run(300, MemoryRecorder())
    ctx = sim.ctx
    state = sim.state
    assert L.CTX.read(ctx, "impact.restitution") == 0.8125
    assert L.CTX.read(ctx, "impact.elastic_below") == 0.0375
    assert L.CTX.read(ctx, "impact.mass") == sim.scene.ball.mass
    assert L.CTX.read(ctx, "engine.impacts") == 300 == state.impacts
    ball = state.ball
    names = ("t", "theta", "q1", "q2", "u1", "u2", "u3", "q3")
    assert [L.CTX.read(ctx, f"engine.{n}") for n in names] == [getattr(ball, n) for n in names]
    keys = ("stick", "slip", "elastic", "resting")
    assert L.CTX.read(ctx, "engine.counts") == tuple(float(state.counts[k]) for k in keys)


def test_landing_reads_the_impact_laws_slots():
    """Under contact.model = "phases" the landing test reads the law's restitution and
    elastic_below (IM_E, IM_EB): the law's, when a law other than the scene's is given."""
    scene = _scene("phases")
    sim = Simulation(scene)
    sim.run(300, MemoryRecorder())
    ctx = sim.ctx
    assert L.CTX.read(ctx, "engine.land_on") == 1.0
    assert L.CTX.read(ctx, "impact.restitution") == 0.8125
    assert L.CTX.read(ctx, "impact.elastic_below") == 0.0375
    for restitution, below in ((0.5, 0.0375), (0.8125, 0.05)):
        law = KaneLevinsonImpact(
            scene.ball.mass,
            scene.ball.radius,
            scene.ball.inertia_factor,
            restitution,
            scene.contact.mu_static,
            scene.contact.mu_kinetic,
            below,
        )
        other = Simulation(scene, law=law)
        assert L.CTX.read(other.ctx, "impact.restitution") == restitution
        assert L.CTX.read(other.ctx, "impact.elastic_below") == below
