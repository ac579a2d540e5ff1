"""The contact phases as kernels (``billiard.kernels.contact``): the interpreted twin is
the kernel file itself (``tests/kernels/test_interpreted.py``), and the compiled kernels
continue every phase of real runs, sample by sample, to the same bits.

The phases are captured where the engine, run interpreted, begins them (the twin's
``begin``: the state vector, the parameters and the wall functions then), and run again
from there, once
through the twin and once compiled, with sample times every ``SAMPLE_DT`` seconds so
that the resumable path runs too; after every return the whole state vector must be the
same bytes, and a stop the same code.

The holds by two walls (``billiard.kernels.vertex``) are captured and replayed the same
way."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard import jit
from billiard.errors import BallAtRest
from billiard.kernels import interpreted as twin
from billiard.run.simulate import Simulation
from billiard.scene.scene import load_scene, with_values

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")
L = twin.layout
#: sample spacing (s) of the replayed table phases
SAMPLE_DT = 2.5e-3


def _capture(
    monkeypatch,
    scene,
    impacts: int,
    most: int,
    sample: float | None = None,
    module=twin.contact,
    until: float | None = None,
):
    """The first ``most`` phases (or holds: ``module`` the twin's ``vertex``) a run of
    ``scene`` to ``until`` (default its ``run.duration``) begins: the arguments of
    ``begin`` each, the state vector copied ((ctx, p, walls) of a phase, (ctx,) of a
    hold)."""
    phases = []
    begin = module.begin

    def capture(ctx, *args):
        if len(phases) < most:
            phases.append((list(ctx), *args))
        return begin(ctx, *args)

    monkeypatch.setattr(module, "begin", capture)
    sim = Simulation(scene)
    sim.driver.interpreted = True  # the engine's phases and holds through the twin
    if until is None:
        until = scene.run.duration or math.inf
    if sample is not None:
        sim.sample_dt = sample
        sim.on_sample = lambda *row: None
    try:
        for _ in range(impacts):
            if len(phases) >= most or sim.step(until=until) is None:
                break
    except BallAtRest:
        pass  # the static bowl's last phase: captured already
    monkeypatch.undo()
    return phases


def _replay(module, layout, ctx, args, dt: float, slots: str = "PH") -> list:
    """Run a captured phase (``args`` = (p, walls)) or hold (``args`` = (), ``slots``
    "VX") to its end with samples every ``dt`` seconds: after every return the status
    and the state vector's bytes (a stop: its code and the bytes)."""
    next_slot = getattr(layout, f"{slots}_NEXT")
    sample_t = getattr(layout, f"{slots}_SAMPLE_T")
    trace = []
    ctx[next_slot] = dt
    try:
        module.begin(ctx, *args)
        while True:
            status = module.advance(ctx, *args)
            trace.append((status, np.asarray(ctx, dtype=np.float64).tobytes()))
            if status != layout.PHASE_SAMPLE:
                break
            ctx[next_slot] = ctx[sample_t] + dt
    except layout.KernelError as exc:
        trace.append(("stop", exc.args[0], np.asarray(ctx, dtype=np.float64).tobytes()))
    return trace


def _cases():
    """(scene, impacts, phases, the run's sample interval, the replay's) of each run:
    the wedge without and with drag (every way a phase ends but the stops), a
    static bowl (the ball comes to rest: a stop; no samples, as its last steps are
    long), a shaken table (a time limit: drive periods at rest skipped, with samples)."""
    from bench.contact import _table

    def paper(name, drag):
        return with_values(load_scene(name), {"contact.model": "phases", "air.drag": drag})

    # the ball rolls for some 30 s before it comes to rest: a contact span beyond that
    bowl = with_values(
        paper("parabola-5.4hz", "fowles"), {"drive.amplitude": 0.0, "run.contact_span": 1e3}
    )
    table = with_values(_table("phases"), {"run.duration": 0.3})
    return [
        (paper("wedge-6.6hz", "none"), 3000, 200, None, 1e-3),
        (paper("wedge-6.6hz", "fowles"), 3000, 100, 0.004, 1e-3),
        (bowl, 50, 5, None, math.inf),
        (table, 50, 5, 0.004, SAMPLE_DT),
    ]


def test_captured_phases_cover_the_kernel_paths(monkeypatch):
    """The phases replayed below end in every way the kernel can end one."""
    seen = set()
    for scene, impacts, most, sample, dt in _cases():
        for ctx, p, walls in _capture(monkeypatch, scene, impacts, most, sample):
            for entry in _replay(twin.contact, L, list(ctx), (p, walls), dt):
                seen.add(entry[0] if entry[0] != "stop" else ("stop", entry[1]))
                if entry[0] == L.PHASE_END:
                    seen.add(("end", int(np.frombuffer(entry[1])[L.PH_END_I])))
    assert {L.PHASE_SAMPLE, L.PHASE_END, L.PHASE_LIMIT, ("stop", L.E_AT_REST)} <= seen
    assert {("end", 0), ("end", 3), ("end", 4)} <= seen  # lift-off, friction, impact


@compiled
def test_phases_are_the_same_interpreted_and_compiled(monkeypatch):
    from billiard.geometry.wall_functions import WallFunction
    from billiard.kernels import contact as kernel
    from billiard.kernels import layout as layout

    assert hasattr(kernel.advance, "py_func")  # compiled: a numba dispatcher
    replayed = 0
    for scene, impacts, most, sample, dt in _cases():
        for ctx, p, walls in _capture(monkeypatch, scene, impacts, most, sample):
            expected = _replay(twin.contact, L, list(ctx), (p, walls), dt)
            typed = walls  # the engine's own table, compiled functions
            if getattr(walls, "numba_type", None) is None:
                typed = tuple(tuple(WallFunction(fn) for fn in row) for row in walls)
            values = np.asarray(ctx, dtype=np.float64)
            got = _replay(kernel, layout, values, (np.asarray(p, dtype=np.float64), typed), dt)
            assert got == expected
            replayed += 1
    assert replayed >= 300


@compiled
@pytest.mark.parametrize("case", [0, 1, 3])
def test_the_engine_runs_phases_compiled_to_the_same_records(case, monkeypatch):
    """The engine compiled and the same source interpreted: its impacts, finished phases
    and samples, stepped one event at a time, to the last bit."""
    scene, impacts, _, sample, _ = _cases()[case]

    def run(compiled: bool):
        sim = Simulation(scene)
        sim.driver.interpreted = not compiled
        out = {"records": [], "contacts": [], "samples": []}
        sim.on_contact = out["contacts"].append
        if sample is not None:
            sim.sample_dt = sample
            sim.on_sample = lambda *row: out["samples"].append(row)
        until = scene.run.duration or math.inf
        for _ in range(min(impacts, 1500)):
            record = sim.step(until=until)
            if record is None:
                break
            out["records"].append(record)
        return out

    twin_run = run(False)
    compiled_run = run(True)
    assert compiled_run["contacts"] or compiled_run["samples"]  # phases made something
    for key in ("records", "contacts", "samples"):
        # repr: every float to the last bit, and a numpy scalar would show as one
        got = [repr(tuple(r)) for r in compiled_run[key]]
        assert got == [repr(tuple(r)) for r in twin_run[key]], key


# ---------------------------------------------------------------- holds by two walls


def _replay_hold(module, layout, ctx, dt: float) -> list:
    """:func:`_replay` of a captured hold (its sample slots are the VX_* ones)."""
    return _replay(module, layout, ctx, (), dt, "VX")


def _hold_cases():
    """(scene, until, impacts, holds, the run's sample interval, the replay's) of each
    run, the wedge's vertex scenes of ``tests/validation/test_vertex.py``: at rest on a
    static wedge (a stop), spinning on it (the spin stops at a known time; a time
    limit), shaken so that a wall releases the ball (with and without drag), spinning
    in a shaken wedge (the spin stops within a step; released or, shaken gently, whole
    drive periods skipped before the time limit, or at rest for good without one), a
    ball that rolls into the vertex from a wall; and, for many holds, a wedge shaken
    just hard enough to release the ball (Gamma = 1.2, inelastic: it comes back into
    the vertex and is held again twice a period, released by either wall), with and
    without drag."""
    from billiard.scene.scene import with_values
    from tests.validation.test_contact import G, R, scene
    from tests.validation.test_vertex import B, wedge

    w = 2 * math.pi * 5.0
    drag = {"air.drag": "fowles", "air.c_lin": 5e-5, "air.c_quad": 1e-4}

    def shaken(gamma):
        amplitude = gamma * G * B / w**2
        drive = {"amplitude": amplitude, "frequency": 5.0, "direction": "horizontal"}
        return amplitude, drive

    def spinning(gamma, spin, restitution=0.5):
        amplitude, drive = shaken(gamma)
        contact = {"mu_static": 0.3, "mu_kinetic": 0.2, "restitution": restitution}
        return wedge(contact, {"v1": amplitude * w, "omega": spin}, drive)

    frictionless = {"mu_static": 0.0, "mu_kinetic": 0.0}
    amplitude, drive = shaken(1.5)
    dragged = with_values(wedge(frictionless, {"v1": amplitude * w}, drive), drag)
    amplitude3, drive3 = shaken(3.0)
    beta = math.atan(B)
    rolling_in = scene(
        "wedge", {"b": B, "c": 0.0}, {"restitution": 0.5},
        {"q1": 0.01, "q2": B * 0.01 + R / math.cos(beta), "v1": 0.0, "v2": 0.0},
    )  # fmt: skip
    static_spin = wedge({"mu_static": 0.4, "mu_kinetic": 0.3}, {"omega": -80.0})
    inf = math.inf
    return [
        (wedge(), inf, 5, 5, None, SAMPLE_DT),
        (static_spin, 0.2, 5, 5, 0.004, SAMPLE_DT),
        (wedge(frictionless, {"v1": amplitude * w}, drive), 1.0, 400, 40, None, SAMPLE_DT),
        (wedge(frictionless, {"v1": amplitude3 * w}, drive3), 1.0, 400, 40, 0.004, 1e-3),
        (dragged, 1.0, 400, 40, None, 1e-3),
        (spinning(2.0, 5.0), 1.0, 400, 40, 0.004, SAMPLE_DT),
        (spinning(0.6, 400.0), 1.0, 5, 5, None, SAMPLE_DT),
        (spinning(0.8, -300.0), inf, 5, 5, None, SAMPLE_DT),
        (rolling_in, inf, 5000, 5, None, SAMPLE_DT),
        (spinning(1.2, 5.0, 0.3), 6.0, 3000, 60, 0.004, 1e-3),
        (with_values(spinning(1.2, -50.0, 0.3), drag), 6.0, 3000, 60, None, SAMPLE_DT),
    ]


def _captured_holds(monkeypatch):
    for scene, until, impacts, most, sample, dt in _hold_cases():
        holds = _capture(monkeypatch, scene, impacts, most, sample, twin.vertex, until)
        for (ctx,) in holds:
            yield ctx, dt


def test_captured_holds_cover_the_kernel_paths(monkeypatch):
    """The holds replayed below end in every way the kernel can end one, and go through
    its samples, skipped periods and a static boundary's spin stop."""
    seen = set()
    for ctx, dt in _captured_holds(monkeypatch):
        for entry in _replay_hold(twin.vertex, L, list(ctx), dt):
            seen.add(entry[0] if entry[0] != "stop" else ("stop", entry[1]))
            values = np.frombuffer(entry[-1])
            if entry[0] == L.PHASE_END:
                seen.add(("keeps", int(values[L.VX_KEEPS])))
            if entry[0] == L.PHASE_SAMPLE and values[L.VX_STAGE] == L.STAGE_SKIP:
                seen.add("skipped")
            if math.isfinite(values[L.VX_STOPS]):
                seen.add("stops")
    assert {L.PHASE_SAMPLE, L.PHASE_END, L.PHASE_LIMIT, ("stop", L.E_AT_REST)} <= seen
    assert {("keeps", 0), ("keeps", 1), "skipped", "stops"} <= seen


@compiled
def test_holds_are_the_same_interpreted_and_compiled(monkeypatch):
    from billiard.kernels import layout as layout
    from billiard.kernels import vertex as kernel

    assert hasattr(kernel.advance, "py_func")  # compiled: a numba dispatcher
    replayed = 0
    for ctx, dt in _captured_holds(monkeypatch):
        expected = _replay_hold(twin.vertex, L, list(ctx), dt)
        got = _replay_hold(kernel, layout, np.asarray(ctx, dtype=np.float64), dt)
        assert got == expected
        replayed += 1
    assert replayed >= 100


@compiled
def test_sampled_runs_with_holds_are_the_same_compiled_and_interpreted():
    """Whole sampled runs through holds on the engine compiled and on the same source
    interpreted: the same impacts, contact phases and samples, bit for bit."""
    from billiard.runfile.record import MemoryRecorder

    def outputs(scene, until, impacts, sample, interpreted):
        sim = Simulation(scene)
        sim.driver.interpreted = interpreted
        contacts, samples = [], []
        sim.on_contact = contacts.append
        sim.sample_dt, sim.on_sample = sample, lambda *row: samples.append(row)
        recorder = MemoryRecorder()
        sim.run(impacts, recorder, until=until)
        rows = {k: np.asarray(v).tobytes() for k, v in recorder.columns().items()}
        return rows, [repr(tuple(c)) for c in contacts], [repr(r) for r in samples]

    for scene, until, impacts, _, sample, _ in _hold_cases()[-2:]:
        sample = 0.004 if sample is None else sample
        compiled_run = outputs(scene, until, impacts, sample, False)
        assert any("'held'" in c for c in compiled_run[1]) and compiled_run[2]
        assert outputs(scene, until, impacts, sample, True) == compiled_run
