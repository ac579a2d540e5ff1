"""The seam between the CPU and a device (:mod:`billiard.kernels.wallcall`): the call of
a wall function is ``walls[k][w](x, p)`` on the CPU and, in a device twin, branches to
the device's function k of wall w; and a stop of the impact path leaves its code in
``ctx[EN_STOP]`` before it raises (a GPU thread's only report)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from billiard.generated.curves import parabola, wedge

from billiard import jit
from billiard.geometry.wall_functions import WallFunction, WallTable
from billiard.kernels import interpreted as twin_py
from billiard.kernels import twin
from billiard.kernels.wallcall import call_wall

P = np.array([wedge.PARAMETERS["b"], wedge.PARAMETERS["c"]])
#: the generated functions of the wedge, rows f, f', f''
ROWS = tuple(tuple(getattr(wedge, f"{name}_{w}") for w in (0, 1)) for name in ("f", "df", "d2f"))
#: the same, as the kernels take them (compiled when numba is there)
COMPILED = WallTable([[WallFunction(f) for f in row] for row in ROWS]) if jit.ENABLED else ROWS


class _Device:
    """A device twin's hooks, with the plain functions standing for the device's."""

    walls = ROWS

    @staticmethod
    def jit(fn, inline):
        return fn


@pytest.fixture(scope="module")
def device_call():
    """call_wall of a device twin over the wedge's functions."""
    twin.load_package("billiard.kernels_test_device", {"DEVICE": _Device()})
    return twin.load_module("billiard.kernels_test_device", "wallcall").call_wall


@pytest.mark.parametrize("x", [-0.03, -0.0, 0.0, 0.021])
def test_device_branches_call_function_k_of_wall_w(device_call, x):
    for k in range(3):
        for w in range(2):
            expected = ROWS[k][w](x, P)
            assert device_call(None, k, w, x, P) == expected, (k, w)
            # on the CPU: the table's entry, compiled and interpreted
            assert call_wall(COMPILED, k, w, x, P) == expected, (k, w)
            assert twin_py.surfaces.call_wall(ROWS, k, w, x, P) == expected, (k, w)


def test_device_twin_is_its_own_package(device_call):
    decorators = twin.load_module("billiard.kernels_test_device", "decorators")
    assert decorators.DEVICE and decorators.WALLS is ROWS
    assert twin_py.surfaces.call_wall is not device_call
    assert not twin.load_module(twin_py.PACKAGE, "decorators").DEVICE


def test_a_stop_leaves_its_code_in_ctx():
    L = twin_py.layout
    ctx = [0.0] * L.SIZE
    base = L.SURF
    ctx[base + L.S_KIND] = L.CURVED
    ctx[base + L.S_A] = 1.55e-3  # the offset radius (m)
    # a wall of infinite slope: every Newton step of the offset inversion is nan
    walls = ((parabola.f_0,), (lambda x, p: math.inf,), (parabola.d2f_0,))
    p = [parabola.PARAMETERS["a"], parabola.PARAMETERS["c"]]
    with pytest.raises(L.KernelError) as stop:
        twin_py.surfaces.foot(ctx, p, walls, base, 0.01, 0.0, math.nan)
    assert stop.value.args[0] == L.E_INVERSION
    assert ctx[L.EN_STOP] == L.E_INVERSION
    assert ctx[L.EN_ERR_VALUE] == 0.01


def test_a_compiled_stop_leaves_its_code_in_ctx():
    from billiard.engine.ctx import state_vector
    from billiard.engine.simulation import Simulation
    from billiard.geometry.wall_functions import wall_functions
    from billiard.kernels import layout as L
    from billiard.kernels.loop import run_chunk
    from billiard.scene.scene import load_scene

    sim = Simulation(load_scene("parabola-5.4hz"))
    ctx = np.array(state_vector(sim))
    ctx[L.EN_TARGET] = 1.0
    ctx[L.EN_FAULT] = 1.0  # a collapse pending: the next step stops
    p = np.array(sim.boundary.walls[0].p, dtype=np.float64)
    with pytest.raises(L.KernelError) as stop:
        run_chunk(ctx, p, wall_functions(sim), np.zeros(L.NCOL), 1)
    assert stop.value.args[0] == L.E_COLLAPSE
    assert ctx[L.EN_STOP] == L.E_COLLAPSE
