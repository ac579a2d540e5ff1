"""The compiled engine against the interpreted one: CPU per impact, start-up, compile
time, and what numba's reference counting of array arguments costs.

    python -m bench.compiled [--impacts 20000] [--repeats 5] [--no-startup]

Times are CPU seconds (``time.process_time``) of the impact loop alone, medians of
``--repeats`` runs in this process (ratios measured in the same session); start-up and
compile time are wall seconds of a fresh interpreter, from start to the first impact
(``--no-startup`` skips them, and the reference-counting probe: the loop alone).
Not a timed test: the machine's load moves every number here.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time

SCENES = (("wedge-6.6hz", "none"), ("parabola-5.4hz", "fowles"))


class _Discard:
    def append(self, record):
        pass


def _scene(name: str, drag: str):
    from billiard.scene.scene import load_scene, with_values

    return with_values(load_scene(name), {"air.drag": drag})


def interpreted(name: str, drag: str, impacts: int, repeats: int) -> float:
    """Median CPU seconds per impact of Simulation.run (records discarded)."""
    from billiard.engine.simulation import Simulation

    times = []
    for _ in range(repeats):
        sim = Simulation(_scene(name, drag))
        start = time.process_time()
        sim.run(impacts, _Discard())
        times.append((time.process_time() - start) / impacts)
    return statistics.median(times)


def kernel(name: str, drag: str, impacts: int, repeats: int) -> tuple[float, float]:
    """Median CPU seconds per impact of run_chunk alone (one chunk of all impacts, on a
    copy of a fresh simulation's state vector), and of Simulation.run (the state
    machine in chunks, records in memory)."""
    import numpy as np

    from billiard.engine.simulation import Simulation
    from billiard.geometry.wall_functions import wall_functions
    from billiard.kernels import layout as L
    from billiard.kernels.loop import run_chunk
    from billiard.runfile.record import MemoryRecorder

    scene = _scene(name, drag)
    bare, whole = [], []
    for _ in range(repeats):
        sim = Simulation(scene)
        ctx = np.array(sim.ctx, dtype=np.float64)
        ctx[L.EN_TARGET] = float(impacts)
        params = np.array(sim.boundary.walls[0].p, dtype=np.float64)
        buffer = np.empty(impacts * L.NCOL)
        walls = wall_functions(sim)
        start = time.process_time()
        code, rows = run_chunk(ctx, params, walls, buffer, impacts)
        bare.append((time.process_time() - start) / rows)
        sim = Simulation(scene)
        recorder = MemoryRecorder()
        start = time.process_time()
        sim.run(impacts, recorder)
        whole.append((time.process_time() - start) / len(recorder))
    return statistics.median(bare), statistics.median(whole)


def startup(name: str, repeats: int, cache_dir: str | None = None) -> float:
    """Median wall seconds from a fresh interpreter's first line to the first impact."""
    from bench.throughput import first_impact

    return statistics.median(first_impact(name, repeats, cache_dir))


def refcount_cost(calls: int = 2_000_000, repeats: int = 5) -> tuple[float, float, float]:
    """ns per call of a non-inlined kernel that reads two numbers from an array passed
    to it, of one that takes the two numbers, and the share of the difference.

    numba increments and decrements the reference count of every array argument of a
    call it does not inline (two atomic operations)."""
    import numba
    import numpy as np

    @numba.njit(inline="never", nogil=True)
    def from_array(ctx, i):
        return ctx[i] * ctx[i + 1]

    @numba.njit(inline="never", nogil=True)
    def from_scalars(a, b):
        return a * b

    @numba.njit(nogil=True)
    def loop_array(ctx, n):
        s = 0.0
        for i in range(n):
            s += from_array(ctx, i & 7)
        return s

    @numba.njit(nogil=True)
    def loop_scalars(ctx, n):
        s = 0.0
        for i in range(n):
            k = i & 7
            s += from_scalars(ctx[k], ctx[k + 1])
        return s

    ctx = np.arange(16.0)
    loop_array(ctx, 10)
    loop_scalars(ctx, 10)
    ta, ts = [], []
    for _ in range(repeats):
        start = time.process_time()
        loop_array(ctx, calls)
        ta.append((time.process_time() - start) / calls * 1e9)
        start = time.process_time()
        loop_scalars(ctx, calls)
        ts.append((time.process_time() - start) / calls * 1e9)
    a, s = statistics.median(ta), statistics.median(ts)
    return a, s, (a - s) / a


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--impacts", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument(
        "--no-startup",
        action="store_true",
        help="measure the impact loop only (no start-up, cold compile or call probe)",
    )
    args = parser.parse_args(argv)
    from billiard import jit

    if not jit.ENABLED:
        sys.exit(f"numba is not available ({jit.numba_problem()}): nothing to compare")
    print(f"python {sys.version.split()[0]}, {args.impacts} impacts, median of {args.repeats}")
    for name, drag in SCENES:
        kernel(name, drag, 100, 1)  # compile or load the cache first
        bare, whole = kernel(name, drag, args.impacts, args.repeats)
        interp = interpreted(name, drag, args.impacts, max(1, args.repeats // 2))
        print(
            f"{name} drag={drag}: interpreted {interp * 1e6:.1f} us/impact, "
            f"run_chunk {bare * 1e6:.2f} us/impact ({interp / bare:.0f}x), "
            f"with records {whole * 1e6:.2f} us/impact ({interp / whole:.0f}x)"
        )
    if args.no_startup:
        return
    print(f"warm start-up to the first impact: {startup('wedge-6.6hz', 3):.2f} s (wall)")
    with tempfile.TemporaryDirectory() as cold:
        print(f"cold start-up (empty cache, compiles): {startup('wedge-6.6hz', 1, cold):.1f} s")
    a, s, share = refcount_cost()
    print(
        f"non-inlined call reading an array argument {a:.2f} ns, taking scalars {s:.2f} ns: "
        f"reference counting {share:.0%} of the call"
    )


def refcount(repeats: int) -> dict:
    """What numba's reference counting of an array argument costs a call that is not
    inlined (:func:`refcount_cost`)."""
    array_ns, scalar_ns, share = refcount_cost(repeats=repeats)
    return {"array_ns": array_ns, "scalar_ns": scalar_ns, "share": share}


if __name__ == "__main__":
    main()
