"""One source: the interpreted twin of the kernels (``billiard.kernels_py``, which the
runtime's classes call) is the kernel files themselves, loaded as plain Python, and
gives the compiled kernels' results to the last bit."""

from __future__ import annotations

import inspect
import math
import random
import types

import numpy as np
import pytest

from billiard import jit
from billiard.engine.ctx import state_vector
from billiard.engine.simulation import Simulation
from billiard.kernels import interpreted as twin
from billiard.kernels import layout as L
from billiard.scene.scene import load_scene, with_values

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")
MODULES = (
    "flight",
    "surfaces",
    "locate",
    "impact",
    "loop",
    "contact",
    "contact_forces",
    "illinois",
    "vertex",
)


def _kernel(name: str) -> types.ModuleType:
    import importlib

    return importlib.import_module(f"billiard.kernels.{name}")


def _twin(name: str) -> types.ModuleType:
    import importlib

    return importlib.import_module(f"{twin.PACKAGE}.{name}")


@pytest.mark.parametrize("name", MODULES)
def test_the_twin_runs_the_kernel_files_as_plain_functions(name):
    kernel, plain = _kernel(name), _twin(name)
    assert plain.__file__ == kernel.__file__
    functions = [
        key
        for key, value in vars(plain).items()
        if isinstance(value, types.FunctionType) and value.__module__ == plain.__name__
    ]
    assert functions
    for key in functions:
        fn = getattr(plain, key)
        assert inspect.isfunction(fn), key
        source = getattr(kernel, key)
        source = getattr(source, "py_func", source)
        assert fn.__code__.co_filename == source.__code__.co_filename, key
        assert fn.__code__.co_code == source.__code__.co_code, key
    # the generated equations are the generated functions themselves
    from billiard.generated import ball, contact

    assert _twin("ball").impact_stick is ball.impact_stick
    assert _twin("contact_equations").roll_rhs is contact.roll_rhs


def _setup(scene_name: str, drag: str = "none"):
    sim = Simulation(with_values(load_scene(scene_name), {"air.drag": drag}))
    values = state_vector(sim)
    walls = sim.boundary.walls
    plain = (
        tuple(w.f for w in walls),
        tuple(w.df for w in walls),
        tuple(w.d2f for w in walls),
    )
    return sim, values, plain


@compiled
@pytest.mark.parametrize(
    ("scene", "drag"), [("wedge-6.6hz", "none"), ("hyperbola-5.8hz", "fowles")]
)
def test_a_run_is_the_same_interpreted_and_compiled(scene, drag):
    from billiard.geometry.wall_functions import wall_functions

    sim, values, plain = _setup(scene, drag)
    rows = 300
    ctx = list(values)
    ctx[L.EN_TARGET] = float(rows)
    out = [0.0] * (rows * L.NCOL)
    done = _twin("loop").run_chunk(ctx, tuple(sim.boundary.walls[0].p), plain, out, rows)
    array = np.array(values, dtype=np.float64)
    array[L.EN_TARGET] = float(rows)
    buffer = np.zeros(rows * L.NCOL)
    params = np.array(sim.boundary.walls[0].p, dtype=np.float64)
    again = _kernel("loop").run_chunk(array, params, wall_functions(sim), buffer, rows)
    assert done == again == (L.DONE, rows)
    assert np.array(out).tobytes() == buffer.tobytes()
    assert np.array(ctx).tobytes() == array.tobytes()


@compiled
def test_gaps_steps_and_impacts_are_the_same_interpreted_and_compiled():
    from billiard.geometry.wall_functions import wall_functions

    rng = random.Random(7)
    sim, values, plain = _setup("hyperbola-5.8hz", "fowles")
    p = tuple(sim.boundary.walls[0].p)
    params = np.array(p, dtype=np.float64)
    walls = wall_functions(sim)
    ctx, array = list(values), np.array(values, dtype=np.float64)
    kernels = {name: (_twin(name), _kernel(name)) for name in ("surfaces", "flight", "impact")}
    surfaces, flight, impact = kernels["surfaces"], kernels["flight"], kernels["impact"]
    nsurf = int(values[L.NSURF])
    for _ in range(2000):
        j = rng.randrange(nsurf)
        px, py = rng.uniform(-0.1, 0.1), rng.uniform(0.0, 0.3)
        vx, vy, ax, ay = (rng.uniform(-2.0, 2.0) for _ in range(4))
        a = surfaces[0].gap_rate(ctx, p, plain, j, px, py, vx, vy)
        b = surfaces[1].gap_rate(array, params, walls, j, px, py, vx, vy)
        assert a == b
        a = surfaces[0].gap_accel(ctx, p, plain, j, px, py, vx, vy, ax, ay)
        b = surfaces[1].gap_accel(array, params, walls, j, px, py, vx, vy, ax, ay)
        assert a == b
        assert surfaces[0].contact(ctx, p, plain, j, px) == surfaces[1].contact(
            array, params, walls, j, px
        )
    assert np.array(ctx).tobytes() == array.tobytes()  # the same warm starts
    for _ in range(200):
        y = [rng.uniform(-0.1, 0.1), rng.uniform(0.0, 0.3)] + [rng.uniform(-2, 2) for _ in "uv"]
        u3 = rng.uniform(-100.0, 100.0)
        flight[0].begin(ctx, *y, u3)
        flight[1].begin(array, *y, u3)
        ta = 0.0
        for _ in range(5):
            target = ta + rng.uniform(1e-4, 0.05)
            tb = flight[0].advance(ctx, ta, target)
            assert tb == flight[1].advance(array, ta, target)
            tau = rng.uniform(ta, tb)
            assert flight[0].state(ctx, tau) == flight[1].state(array, tau)
            ta = tb
    for _ in range(2000):
        u1, u2, vb1, vb2 = (rng.uniform(-1.0, 1.0) for _ in range(4))
        u3, z = rng.uniform(-100.0, 100.0), rng.uniform(-1.2, 1.2)
        pressing = rng.random() < 0.5
        a = impact[0].kane_levinson(ctx, u1, u2, u3, z, vb1, vb2, pressing)
        b = impact[1].kane_levinson(array, u1, u2, u3, z, vb1, vb2, pressing)
        assert [float(x) for x in a] == [float(x) for x in b]
        assert not any(isinstance(x, float) and math.isnan(x) for x in a)


def test_a_stop_in_the_twin_is_worded_as_the_engine_words_it():
    ctx = [0.0] * L.SIZE
    ctx[L.EN_ERR_VALUE] = 0.25
    error = twin.stop(twin.layout.KernelError(L.E_INVERSION), ctx)
    assert str(error) == "offset-curve inversion did not converge at x = 0.25 m"
