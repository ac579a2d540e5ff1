"""The GPU backend (:mod:`billiard.engine.gpu`) on a real device: it compiles, how its
rows compare with the CPU's, a stop, and its speed. Run from the checkout's root on a
machine with an NVIDIA GPU and numba-cuda (``pip install -e ".[gpu]"``)::

    python bench/gpu_check.py [--small] [--out FILE]

It prints one line per part and writes them all as JSON (``--out``, default
``gpu_check.json``):

* per scene (wedge-6.6hz, parabola-5.4hz), 64 starts on a grid of initial positions,
  1000 impacts each by :func:`~billiard.engine.gpu.run_rows_gpu` and by the CPU's
  ``run_chunk``: the trajectories equal bit for bit, the first impact whose row differs,
  the impact after which the positions differ by more than 1 um, the largest position
  difference over the first ten impacts (m), and the mean impact height (m) and time of
  flight (s) of each;
* a stop: one of four threads starts with a collapse pending; it leaves E_COLLAPSE in
  its ``ctx[EN_STOP]`` while the others run on;
* speed: 131,072 wedge trajectories x 200 and x 1000 impacts, kernel time only
  (impacts/s).

``--small`` runs 4 starts, 20 impacts and a speed of 8 x 5, which the CUDA simulator
(``NUMBA_ENABLE_CUDASIM=1``) can do in seconds: a check of this script.
"""

from __future__ import annotations

import argparse
import json
import time
from importlib import metadata

import numpy as np

if not hasattr(np, "row_stack"):
    # numba-cuda 0.30.4 registers an overload of np.row_stack, which numpy 2.5 removed
    np.row_stack = np.vstack

import numba  # noqa: E402

from billiard import jit  # noqa: E402
from billiard.engine import gpu  # noqa: E402
from billiard.engine.ctx import state_vector  # noqa: E402
from billiard.engine.simulation import Simulation  # noqa: E402
from billiard.geometry.wall_functions import wall_functions  # noqa: E402
from billiard.kernels import layout as L  # noqa: E402
from billiard.kernels.loop import run_chunk  # noqa: E402
from billiard.scene.scene import load_scene, with_values  # noqa: E402


def starts(name: str, n: int) -> list[Simulation]:
    """``n`` (a square) simulations of ``name`` from a grid of initial positions (m)."""
    side = round(n**0.5)
    return [
        Simulation(with_values(load_scene(name), {"initial.q1": float(a), "initial.q2": float(b)}))
        for a in np.linspace(-0.02, 0.02, side)
        for b in np.linspace(0.06, 0.15, side)
    ]


def cpu_rows(sim: Simulation, impacts: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The CPU's rows of ``sim`` and its (status, rows written); (-1, rows) on a stop."""
    ctx = np.array(state_vector(sim))
    ctx[L.EN_TARGET] = impacts
    out = np.zeros(impacts * L.NCOL)
    p = np.array(sim.boundary.walls[0].p, dtype=np.float64)
    try:
        status, rows = run_chunk(ctx, p, wall_functions(sim), out, impacts)
    except L.KernelError:
        status, rows = -1, int(ctx[L.EN_IMPACTS])
    return out.reshape(impacts, L.NCOL), (int(status), int(rows))


def compare(name: str, n: int, impacts: int) -> dict:
    sims = starts(name, n)
    started = time.perf_counter()
    rows, ends, ctxs = gpu.run_rows_gpu(sims, impacts)
    first_call = time.perf_counter() - started
    same, first, apart, early = 0, [], [], []
    heights, flights = [], []
    for i, sim in enumerate(sims):
        cpu, end = cpu_rows(sim, impacts)
        k = min(end[1], max(int(ends[i, 1]), 0))
        differs = (cpu[:k].view(np.uint64) != rows[i, :k].view(np.uint64)).any(axis=1)
        first.append(int(np.argmax(differs)) + 1 if differs.any() else None)
        same += int(not differs.any() and end == tuple(ends[i]))
        gap = np.abs(cpu[:k, 2:4] - rows[i, :k, 2:4]).max(axis=1)
        apart.append(int(np.argmax(gap > 1e-6)) + 1 if (gap > 1e-6).any() else None)
        early.append(float(gap[:10].max()))
        heights.append((rows[i, :k, 3].mean(), cpu[:k, 3].mean()))
        flights.append((rows[i, :k, 9].mean(), cpu[:k, 9].mean()))
    return {
        "first_call_s": round(first_call, 2),
        "ends": np.unique(ends, axis=0).tolist(),
        "identical_trajectories": same,
        "first_differing_impact": sorted({f for f in first if f is not None}),
        "apart_by_1um_after_impacts": sorted(a for a in apart if a is not None),
        "never_apart_by_1um": sum(a is None for a in apart),
        "max_position_difference_first_10_m": max(early),
        "mean_height_gpu_cpu_m": np.mean(heights, axis=0).tolist(),
        "mean_flight_gpu_cpu_s": np.mean(flights, axis=0).tolist(),
    }


def stop(impacts: int) -> dict:
    sims = starts("wedge-6.6hz", 4)
    ctxs = np.array([state_vector(s) for s in sims])
    ctxs[:, L.EN_TARGET] = impacts
    ctxs[1, L.EN_FAULT] = 1.0  # a collapse pending: thread 1 stops at its first step
    params = np.array([s.boundary.walls[0].p for s in sims], dtype=np.float64)
    out = np.zeros((4, impacts * L.NCOL))
    ends = np.full((4, 2), -1, dtype=np.int64)
    try:
        gpu.launch(gpu.advance(sims[0]), 4, ctxs, params, out, impacts, ends, back=(0, 2, 4))
    except Exception as exc:  # the simulator re-raises a thread's stop (the twin's class)
        return {"raised": f"{type(exc).__name__}: {exc}"}
    codes = ctxs[:, L.EN_STOP].tolist()
    return {"ends": ends.tolist(), "EN_STOP": codes, "E_COLLAPSE": L.E_COLLAPSE}


def speed(n: int, impacts: int) -> dict:
    from numba import cuda

    sims = starts("wedge-6.6hz", 256 if n > 256 else 4)
    grid = np.array([state_vector(s) for s in sims])
    ctxs = grid[np.arange(n) % len(grid)].copy()
    ctxs[:, L.EN_TARGET] = impacts
    params = np.repeat(np.array([sims[0].boundary.walls[0].p], dtype=np.float64), n, axis=0)
    kernel = gpu.advance(sims[0])
    d_ctxs, d_params = cuda.to_device(ctxs), cuda.to_device(params)
    d_out = cuda.device_array((n, impacts * L.NCOL))
    d_ends = cuda.to_device(np.full((n, 2), -1, dtype=np.int64))
    blocks = (n + gpu.THREADS - 1) // gpu.THREADS
    cuda.synchronize()  # the kernel was compiled by compare()
    started = time.perf_counter()
    kernel[blocks, gpu.THREADS](d_ctxs, d_params, d_out, impacts, d_ends)
    cuda.synchronize()
    seconds = time.perf_counter() - started
    ends = d_ends.copy_to_host()
    done = int(ends[ends[:, 1] > 0, 1].sum())
    return {"trajectories": n, "impacts": done, "s": round(seconds, 3),
            "impacts_per_s": done / seconds, "stopped": int((ends[:, 0] < 0).sum())}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="a few trajectories (simulator)")
    parser.add_argument("--out", default="gpu_check.json", help="the JSON file written")
    args = parser.parse_args()
    jit.on_first_compile(None)  # compile only the kernels this script calls
    from numba import cuda

    report: dict = {
        "numba": numba.__version__,
        "numba_cuda": metadata.version("numba-cuda"),
        "available": gpu.available(),
        "device": str(getattr(cuda.get_current_device(), "name", "simulator")),
    }
    print(report, flush=True)
    n, impacts = (4, 20) if args.small else (64, 1000)
    for name in ("wedge-6.6hz", "parabola-5.4hz"):
        report[name] = compare(name, n, impacts)
        print(name, report[name], flush=True)
    report["stop"] = stop(50)
    print("stop", report["stop"], flush=True)
    for size in ((8, 5),) if args.small else ((1 << 17, 200), (1 << 17, 1000)):
        report[f"speed_{size[0]}x{size[1]}"] = result = speed(*size)
        print("speed", result, flush=True)
    with open(args.out, "w", encoding="utf-8") as file:
        json.dump(report, file, indent=1, default=str)


if __name__ == "__main__":
    main()
