"""The GPU backend (:mod:`billiard.engine.gpu`): under numba's CUDA simulator
(``NUMBA_ENABLE_CUDASIM=1``, in a fresh interpreter, so that numba.cuda is the simulator
there and nowhere else) the device twin advanced by the ``advance`` kernel writes the
rows of the CPU's ``run_chunk``, impact by impact, bit for bit (the simulator runs the
kernels as Python on numpy floats); and :func:`available` says in one line why the
backend cannot run.

The twin reaches a curve's walls by branches on (function, wall)
(:mod:`billiard.kernels.wallcall`): the wedge's walls are straight (f'' = 0 on both) and
the parabola has one wall, so a curve with two curved walls of different curvature
(:data:`CURVED`) is what sees a branch to the wrong wall's f, f' or f''."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from billiard.engine import gpu
from billiard.engine.ctx import state_vector
from billiard.engine.simulation import Simulation
from billiard.geometry.wall_functions import wall_functions
from billiard.kernels import layout as L
from billiard.kernels.loop import run_chunk
from billiard.runfile.record import COLUMNS
from billiard.scene.scene import load_scene, with_values
from tests.copies import COUNT_COPIES

#: impacts per trajectory
IMPACTS = 40
#: two curved walls joined at a kink at x = 0 with different curvatures:
#: f'' = 2 a + 6 c x on the right, 2 a - 6 c x on the left (1/m). Each wall's formula
#: lies below the other wall for all x beyond the kink, so the container (the region above
#: both formulas) is the curve's.
CURVED = {
    "boundary.curve": "a*x**2 + b*abs(x) + c*abs(x)**3 + 0.0063",
    "boundary.parameters": {"a": 20.0, "b": 2.0, "c": 100.0},
}
#: per case, the built-in scene and the trajectories: scene values changed (initial
#: position, m; a curve parameter, which goes to the kernel per trajectory)
CASES = {
    "wedge-6.6hz": (
        "wedge-6.6hz",
        [
            {"initial.q1": -0.01, "initial.q2": 0.05},
            {"initial.q1": 0.012, "initial.q2": 0.05},
            {"initial.q1": 0.02, "initial.q2": 0.08, "boundary.parameters.b": 1.7},
        ],
    ),
    "parabola-5.4hz": (
        "parabola-5.4hz",
        [
            {"initial.q1": 0.0, "initial.q2": 0.05},
            {"initial.q1": -0.015, "initial.q2": 0.07},
            {"initial.q1": 0.01, "initial.q2": 0.06, "boundary.parameters.a": 24.0},
        ],
    ),
    "two-curved-walls": (
        "parabola-5.4hz",
        [
            {**CURVED, "initial.q1": -0.012, "initial.q2": 0.05},
            {**CURVED, "initial.q1": 0.015, "initial.q2": 0.06, "boundary.parameters.c": 60.0},
        ],
    ),
}

_SIMULATED = """
import json, sys
import numpy as np
from billiard.engine import gpu
from billiard.engine.simulation import Simulation
from billiard.scene.scene import load_scene, with_values
assert gpu.simulated() and gpu.available() is None
cases, impacts, folder = json.loads(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
for name, (scene, changes) in cases.items():
    sims = [Simulation(with_values(load_scene(scene), values)) for values in changes]
    rows, ends, ctxs = gpu.run_rows_gpu(sims, impacts)
    np.savez(f"{folder}/{name}.npz", rows=rows, ends=ends, ctxs=ctxs)
"""

needs_numba_cuda = pytest.mark.skipif(
    importlib.util.find_spec("numba_cuda") is None,
    reason=f"numba-cuda is not installed ({gpu.INSTALL})",
)


def _sims(name: str) -> list[Simulation]:
    scene, changes = CASES[name]
    return [Simulation(with_values(load_scene(scene), values)) for values in changes]


def _cpu_rows(sim: Simulation) -> tuple[np.ndarray, tuple[int, int], np.ndarray]:
    """run_chunk's rows, (status, rows) and ctx after IMPACTS impacts of ``sim``."""
    ctx = np.array(state_vector(sim), dtype=np.float64)
    ctx[L.EN_TARGET] = IMPACTS
    out = np.zeros(IMPACTS * L.NCOL)
    p = np.array(sim.boundary.walls[0].p, dtype=np.float64)
    status, rows = run_chunk(ctx, p, wall_functions(sim), out, IMPACTS)
    return out.reshape(IMPACTS, L.NCOL), (int(status), int(rows)), ctx


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    """The curve with two curved walls is derived on first use into a temporary
    BILLIARD_HOME (here and in the simulator's interpreter, which inherits it)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> dict[str, dict[str, np.ndarray]]:
    """The rows, ends and ctxs of every case, advanced by the simulated GPU."""
    folder = tmp_path_factory.mktemp("gpu")
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    subprocess.run(
        [sys.executable, "-c", _SIMULATED, json.dumps(CASES), str(IMPACTS), str(folder)],
        env=env,
        check=True,
    )
    return {name: dict(np.load(folder / f"{name}.npz")) for name in CASES}


@needs_numba_cuda
@pytest.mark.parametrize("name", CASES)
def test_simulated_gpu_rows_are_the_cpu_rows(simulated, name):
    got = simulated[name]
    for i, sim in enumerate(_sims(name)):
        rows, ends, ctx = _cpu_rows(sim)
        if name == "two-curved-walls":  # each trajectory takes both walls' branches
            assert {0.0, 1.0} <= set(rows[:, COLUMNS.index("wall")]), i
        assert ends == (L.DONE, IMPACTS)
        assert tuple(got["ends"][i]) == ends
        for r in range(IMPACTS):  # impact by impact: the first that differs is named
            assert np.array_equal(_bits(got["rows"][i, r]), _bits(rows[r])), (i, r)
        # the whole state after the last impact: warm starts, clock, counters
        assert np.array_equal(_bits(got["ctxs"][i]), _bits(ctx))
        assert got["ctxs"][i, L.EN_STOP] == 0.0


def test_available_without_numba_cuda(monkeypatch):
    real = importlib.util.find_spec

    def find_spec(name, *args):
        return None if name == "numba_cuda" else real(name, *args)

    monkeypatch.setattr(gpu.importlib.util, "find_spec", find_spec)
    assert gpu.available() == (
        'no CUDA GPU: numba-cuda is not installed (pip install "realworld-billiard[gpu]")'
    )


@needs_numba_cuda
def test_available_without_a_gpu(monkeypatch):
    monkeypatch.setattr(gpu, "cuda", SimpleNamespace(is_available=lambda: False))
    assert gpu.available() == "no CUDA GPU: numba-cuda found no CUDA GPU"

    def broken():
        raise RuntimeError("CUDA driver library cannot be found\nsecond line")

    monkeypatch.setattr(gpu, "cuda", SimpleNamespace(is_available=broken))
    assert gpu.available() == (
        "no CUDA GPU: numba-cuda could not start (CUDA driver library cannot be found)"
    )
    monkeypatch.setattr(gpu, "cuda", SimpleNamespace(is_available=lambda: True))
    assert gpu.available() is None


def test_one_launch_takes_one_curve_and_the_impacts_model():
    wedge, parabola = _sims("wedge-6.6hz")[0], _sims("parabola-5.4hz")[0]
    with pytest.raises(ValueError, match="share one curve"):
        gpu.run_rows_gpu([wedge, parabola], 10)
    phases = Simulation(with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"}))
    with pytest.raises(ValueError, match="impacts model only"):
        gpu.run_rows_gpu([phases], 10)
    with pytest.raises(ValueError, match="no simulations"):
        gpu.run_rows_gpu([], 10)


#: threads on the simulated GPU, one of which stops at its 5th impact as a device thread
#: stops (its code in its state vector, its statistics pending, the thread ended)
_STOPPED = """
from numba import cuda
from billiard.engine import ensemble as EN, gpu
from billiard.kernels import ensemble as E, layout as L
from billiard.scene.scene import load_scene
assert gpu.simulated()
setup = EN.prepare(load_scene("wedge-6.6hz"))
ctxs, ok = EN.start(setup, [-0.01, 0.012, 0.0], [0.06, 0.08, 0.07])
assert ok.all()
measure = gpu.device_module(setup.sim, "ensemble").measure
def stopping(ctxs, params, rows, rings, stats, consts, transient, total, target):
    i = cuda.grid(1)
    if i < ctxs.shape[0]:
        measure(ctxs[i], params[i], 0, rows[i], rings[i], stats[i], consts[i], transient,
                total, target)
        if i == 1 and target == 5:
            ctxs[i, L.EN_STOP] = L.E_NO_IMPACT
gpu._measure[gpu.device_kernels(setup.sim).__name__] = cuda.jit(stopping)
consts = EN.constants(setup.scene, 1e-5, 64, 256)
stats, _ = gpu.advance_ensemble(
    setup.sim, ctxs, setup.params, consts, transient=2, impacts=10, width=256, rounds=5
)
for row in stats:
    print(int(row[E.ST_STATUS]), int(row[E.ST_CODE]), int(row[E.ST_TOTAL]))
"""


@needs_numba_cuda
def test_a_thread_stopped_in_one_launch_is_failed_not_stepped_on(tmp_path):
    """A GPU thread that stops in a kernel stop just ends, its code in its state vector:
    in the next launch it is failed with that code, and not stepped on from its stopped
    state (which could end "complete", with measurements of a broken trajectory)."""
    from billiard.kernels import ensemble as E

    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    done = subprocess.run(
        [sys.executable, "-c", _STOPPED], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr[-3000:]
    rows = [tuple(map(int, line.split())) for line in done.stdout.splitlines()]
    complete, failed = int(E.RUN_COMPLETE), int(E.RUN_FAILED)
    assert rows == [(complete, 0, 12), (failed, L.E_NO_IMPACT, 5), (complete, 0, 12)]


#: a parameter map's ensemble on the simulated GPU against the CPU: the reduced copy
#: (stats and the kept tails: what a sweep stores) and the full one (rings and state
#: vectors). Threads that stop as a device thread stops (their code in their state
#: vector, nothing else written) are injected into the real kernel: one in its first
#: launch, stepped no further after it; one in its last, whose code comes from the
#: end-of-batch kernel. Prints the bytes copied back per trajectory, both ways.
_REDUCED = (
    COUNT_COPIES
    + """
import numpy as np
from numba import cuda
from billiard.engine import ensemble as EN, gpu
from billiard.kernels import ensemble as E, layout as L
from billiard.scene.scene import load_scene, with_values
from billiard.sweep.attractor import PERIOD_WINDOW
assert gpu.simulated() and gpu.available() is None

gpu.BATCH, gpu.ROUNDS = 4, 5  # six trajectories in two batches, launches of 5 impacts
transient, impacts, keep = 6, 12, 4
base = EN.prepare(load_scene("wedge-6.6hz"))
family = [base] + [
    EN.patch(base, with_values(base.scene, values))
    for values in ({"drive.frequency": 6.3, "contact.restitution": 0.4}, {"drive.amplitude": 0.025})
]
ctxs, consts = [], []
for k, setup in enumerate(family):
    c, ok = EN.start(setup, [-0.01 + 0.01 * k, 0.012], [0.06, 0.08 - 0.01 * k])
    assert ok.all()
    ctxs.append(c)
    for tolerance in (1e-5, 0.2):  # none, or a period within this tolerance (m)
        consts.append(EN.constants(setup.scene, tolerance, 64, PERIOD_WINDOW))
ctxs, consts = np.concatenate(ctxs), np.array(consts)
n = ctxs.shape[0]
kw = dict(transient=transient, impacts=impacts, width=PERIOD_WINDOW)
cpu_ctxs = ctxs.copy()
cpu, (cpu_h, cpu_t) = EN.advance_setup(base, cpu_ctxs, consts, threads=1, keep=keep, **kw)
assert (cpu[:, E.ST_STATUS] == E.RUN_COMPLETE).all()
assert (cpu[:, E.ST_PERIOD] > 0).any() and (cpu[:, E.ST_PERIOD] == 0).any()

measure = gpu.device_module(base.sim, "ensemble").measure
FIRST, LAST = float(L.E_NO_IMPACT), float(L.E_ROOT)
def stopping(ctxs, params, rows, rings, stats, consts, transient, total, target):
    i = cuda.grid(1)
    if i < ctxs.shape[0]:
        if i == 2 and target == total:
            ctxs[i, L.EN_STOP] = LAST
            return
        measure(ctxs[i], params[i], 0, rows[i], rings[i], stats[i], consts[i], transient,
                total, target)
        if i == 1 and target == gpu.ROUNDS:
            ctxs[i, L.EN_STOP] = FIRST
package = gpu.device_kernels(base.sim).__name__
gpu._measure[package] = cuda.jit(stopping)
copied.clear()
given = ctxs.copy()
got, (h, t) = EN.advance_setup(base, given, consts, device="gpu", keep=keep, states=False, **kw)
reduced = sum(copied) / n
assert np.array_equal(given, ctxs, equal_nan=True)  # no state vector came back
failed = {1: FIRST, 5: FIRST, 2: LAST}  # thread 1 of each batch, thread 2 of the first
for i in range(n):
    if i in failed:
        assert got[i, E.ST_STATUS] == E.RUN_FAILED and got[i, E.ST_CODE] == failed[i], (i, got[i])
        continue
    assert np.array_equal(got[i], cpu[i]), i
    assert np.array_equal(h[i], cpu_h[i], equal_nan=True), i
    assert np.array_equal(t[i], cpu_t[i], equal_nan=True), i

del gpu._measure[package]  # the real kernel: the full copy, nothing stopped
copied.clear()
given = ctxs.copy()
got, rings = EN.advance_setup(base, given, consts, device="gpu", **kw)
full = sum(copied) / n
assert np.array_equal(got, cpu) and np.array_equal(given, cpu_ctxs, equal_nan=True)
h, t = EN.last_impacts(got, rings, keep)
assert np.array_equal(h, cpu_h, equal_nan=True) and np.array_equal(t, cpu_t, equal_nan=True)
print(reduced, full)
"""
)


@needs_numba_cuda
def test_the_reduced_copy_is_the_cpus_measurements_and_small(tmp_path):
    """What a sweep stores, copied back from the (simulated) GPU: stats, periods,
    heights and times of flight of a parameter map equal the CPU's bit for bit, the
    stop codes of failed threads arrive, and each trajectory brings back at most 100 +
    16 * keep + 8 * NSTAT bytes (against its state vector and ring by default)."""
    from billiard.kernels.ensemble import NSTAT

    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    done = subprocess.run(
        [sys.executable, "-c", _REDUCED], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr[-3000:]
    reduced, full = (float(x) for x in done.stdout.split())
    keep = 4
    assert NSTAT * 8 <= reduced <= 100 + 16 * keep + NSTAT * 8
    assert full > L.SIZE * 8  # the default copy brings the state vectors back
