"""The impact loop ``run_chunk`` (``billiard/kernels/loop.py``) as numba compiles it: no
reference counting left in its optimised machine code.

numba increments and decrements an array's reference count wherever a kernel receives
it, keeps it in a variable or passes it on; its pruning of those pairs gives up across
the loops, raises and wall-function calls of the inlined impact loop, which then spent
half of a wedge impact's time on some 400 atomic operations. ``run_chunk`` borrows its
arrays (``billiard.kernels.decorators.borrow``) so that LLVM folds every one of them
away. The count is read from the optimised LLVM IR numba reports for a fresh,
uncached compile of the kernel (``Dispatcher.inspect_llvm``; code loaded from numba's
cache cannot be inspected), typed for the wedge's arguments."""

from __future__ import annotations

import re

import numba
import numpy as np
import pytest

from billiard import jit, load_scene
from billiard.kernels import layout as L
from billiard.kernels import loop

pytestmark = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

#: a call of numba's runtime that changes a reference count
_REFOP = re.compile(r"call void @NRT_(incref|decref)\(")


def _refops(ir: str, function: str) -> dict[str, int]:
    """The reference-count calls in the body of each LLVM function whose name holds
    ``function``, numba's Python wrapper (``cpython.``) and C wrapper (``cfunc.``) aside:
    those unbox the caller's arrays, once per call."""
    counts: dict[str, int] = {}
    for body in re.finditer(r"^define [^@]*@([^(\s]+)\(.*?^}", ir, re.S | re.M):
        name = body.group(1)
        if function in name and not name.startswith(("_ZN7cpython", "cfunc.")):
            counts[name] = len(_REFOP.findall(body.group(0)))
    return counts


def _fresh_ir(dispatcher, args: tuple) -> str:
    """The optimised LLVM IR of ``dispatcher``'s function compiled anew (its options,
    the disk cache aside) for the types of ``args``."""
    options = {k: v for k, v in dispatcher.targetoptions.items() if k != "cache"}
    fresh = numba.jit(**options)(dispatcher.py_func)
    signature = tuple(numba.typeof(a) for a in args)
    fresh.compile(signature)
    return fresh.inspect_llvm(signature)


def test_run_chunk_counts_no_references_on_its_arrays():
    from billiard.engine.simulation import Simulation
    from billiard.geometry.wall_functions import wall_functions

    sim = Simulation(load_scene("wedge-6.6hz"))
    ctx = np.array(sim.ctx, dtype=np.float64)
    params = np.array(sim.boundary.walls[0].p, dtype=np.float64)
    args = (ctx, params, wall_functions(sim), np.empty(10 * L.NCOL), np.int64(10))
    counts = _refops(_fresh_ir(loop.run_chunk, args), "run_chunk")
    assert counts, "no compiled run_chunk in the IR"
    total = sum(counts.values())
    assert total == 0, (
        f"numba's reference counting is back in the impact loop: {total} "
        "NRT_incref/NRT_decref calls in run_chunk (none expected: its arrays are borrowed)"
    )
