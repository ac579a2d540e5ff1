"""Section ``ensemble``: the ensemble kernel's impacts per second on one core and on all,
the sweep's fixed cost per point and its scaling with workers, a point under contact
phases against one under the impacts model, and the GPU when there is one, against the
targets of the issues "Ensembles" and "One engine".

Run as a section of the benchmark (``billiard bench --only ensemble``) or alone from a
source checkout::

    python -m bench.ensemble            # a few minutes on 2 cores
    python -m bench.ensemble --quick    # under a minute, smaller sizes

It saves ``docs/figures/ensemble/bench.json`` and rewrites the section between the markers
``<!-- ensemble-bench -->`` and ``<!-- /ensemble-bench -->`` of ``docs/sweeps.md``, and
the cost of a point under contact phases between ``<!-- phases-point-bench -->`` and
``<!-- /phases-point-bench -->`` of ``docs/performance.md``; ``--phases`` measures that
part alone (the section's other saved results kept)::

    python -m bench.ensemble --phases   # about a minute
Times are wall-clock medians of several runs taken alternately, numba's cache loaded
first; the machine's load average is recorded with them.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench.common import section_arguments
from bench.markdown import publish_section

BEGIN, END = "<!-- ensemble-bench -->", "<!-- /ensemble-bench -->"
PHASES_BEGIN, PHASES_END = "<!-- phases-point-bench -->", "<!-- /phases-point-bench -->"
SCENE = "wedge-6.6hz"
#: the issue's targets
TARGETS = {
    "point_cpu_us": 50.0,
    "point_bytes": 100.0,
    "scaling_16": 12.0,
    "gpu_impacts_per_s": 1e8,
    "basin_seconds": 600.0,
    "phases_ratio": 2.0,
    "map_seconds": 900.0,
    "kernel_ratio": 1.2,
    "growing": 0.4,
}
#: the parameter map of the target: the parabola's drive.frequency x drive.amplitude
MAP_SCENE = "parabola-5.4hz"
MAP_POINTS = 10**6
#: (starts, impacts per start, repeats) of the kernel measurement
SIZES = {False: (4000, 1000, 3), True: (1000, 500, 2)}
#: (points, impacts per point, repeats) of the contact phases' cost per point
PHASES_SIZES = {False: (400, 100, 5), True: (100, 100, 3)}


def _starts(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n valid starts spread over the wedge (a grid, invalid ones dropped)."""
    side = int(np.ceil(np.sqrt(2.2 * n)))
    q1, q2 = np.meshgrid(np.linspace(-0.04, 0.04, side), np.linspace(0.02, 0.12, side))
    return q1.ravel(), q2.ravel()


def kernel_rates(starts: int, impacts: int, repeats: int, threads: list[int]) -> list[dict]:
    """Impacts per second of engine.ensemble.advance with each thread count."""
    from billiard.engine import ensemble as EN
    from billiard.kernels import ensemble as E
    from billiard.scene.scene import load_scene

    scene = load_scene(SCENE)
    setup = EN.prepare(scene)
    q1, q2 = _starts(starts)
    ctxs, ok = EN.start(setup, q1, q2)
    ctxs = ctxs[ok][:starts]
    consts = EN.constants(scene, 1e-5, 64, 256)

    def once(n_threads: int) -> tuple[float, int]:
        c = ctxs.copy()
        began = time.perf_counter()
        stats, _ = EN.advance(
            c, setup.params, setup.walls, consts, transient=0, impacts=impacts, width=256,
            threads=n_threads, nears=setup.nears,
        )  # fmt: skip
        return time.perf_counter() - began, int(stats[:, E.ST_TOTAL].sum())

    once(1)  # numba's cache loaded, pages touched
    walls: dict[int, list[float]] = {t: [] for t in threads}
    done = 0
    for _ in range(repeats):
        for t in threads:
            wall, done = once(t)
            walls[t].append(wall)
    rows = []
    for t in threads:
        median = statistics.median(walls[t])
        rows.append(
            {"threads": t, "walls": walls[t], "impacts": done, "impacts_per_s": done / median}
        )
    return rows


def phases_ratio(quick: bool) -> dict:
    """The cost of a sweep point under ``contact.model = "phases"`` over that of the
    same point under ``"impacts"``: the same starts in the wedge (q1 = 1 cm, q2 from 4
    to 12 cm), the same impacts per point, each model's points measured as a worker
    measures a chunk of them (``measure_chunk``: set-up, trajectories, measurements),
    the two models alternately; wall-clock medians of the repeats. Also the phases
    points one by one (a Simulation each: the path of ``--lyapunov``, and of every
    contact-phases point before the batched state machine)."""
    from billiard.scene.scene import load_scene, with_values
    from billiard.sweep import Sweep, parse_vary
    from billiard.sweep.measure import ChunkTask, _measure_points, measure_chunk

    points, impacts, repeats = PHASES_SIZES[quick]
    axes = (parse_vary(f"initial.q2=0.04:0.12:{points}"),)
    rows: dict[str, dict] = {}
    for model in ("impacts", "phases"):
        scene = with_values(load_scene(SCENE), {"contact.model": model, "initial.q1": 0.01})
        sweep = Sweep(scene, axes, impacts=impacts, transient=0)
        measure_chunk(ChunkTask(sweep, 0, sweep.size))  # numba's cache loaded, set up
        rows[model] = {"sweep": sweep, "walls": []}
    for _ in range(repeats):
        for row in rows.values():
            task = ChunkTask(row["sweep"], 0, row["sweep"].size)
            began = time.perf_counter()
            chunk = measure_chunk(task)
            row["walls"].append(time.perf_counter() - began)
            row["impacts"] = int(chunk.columns["total_impacts"].sum())
    single = []
    phases = rows["phases"]["sweep"]
    for _ in range(min(repeats, 3)):
        began = time.perf_counter()
        _measure_points(ChunkTask(phases, 0, phases.size), np.arange(phases.size))
        single.append(time.perf_counter() - began)
    out: dict[str, Any] = {
        "command": "python -m bench.ensemble --phases" + (" --quick" if quick else ""),
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "load": ", ".join(f"{x:.1f}" for x in os.getloadavg()),
        "points": points,
        "impacts_per_point": impacts,
        "one_by_one": {"walls": single, "us_per_point": statistics.median(single) / points * 1e6},
    }
    for model, row in rows.items():
        out[model] = {
            "walls": row["walls"],
            "impacts": row["impacts"],
            "us_per_point": statistics.median(row["walls"]) / points * 1e6,
        }
    out["ratio"] = out["phases"]["us_per_point"] / out["impacts"]["us_per_point"]
    return out


#: impacts kept per start in the GPU rate's ensemble (the basin map's ``--keep``)
GPU_KEEP = 10


def gpu_rate(starts: int, impacts: int, repeats: int) -> dict:
    """Impacts per second of the GPU ensemble (wedge, ``starts`` trajectories) on the
    path a sweep takes, where only the stats and :data:`GPU_KEEP` kept impacts per start
    come back: the whole call (``run_ensemble(..., states=False)``: the starts set up on
    all cores, the launches, the copies both ways, the host's measurement) and the
    kernel alone (the launches of the same ensemble, synchronised, without set-up or
    copies: ``gpu.advance_ensemble``'s clock); the device's name."""
    import billiard
    from billiard.engine import ensemble as EN
    from billiard.engine import gpu
    from billiard.kernels import ensemble as E
    from billiard.scene.scene import load_scene
    from billiard.sweep.attractor import PERIOD_WINDOW

    q1, q2 = _starts(starts)
    kw = dict(device="gpu", states=False, keep=GPU_KEEP)
    billiard.run_ensemble(SCENE, q1=q1[:256], q2=q2[:256], impacts=10, **kw)  # compile
    walls = []
    done = 0
    for _ in range(repeats):
        result = billiard.run_ensemble(SCENE, q1=q1, q2=q2, impacts=impacts, **kw)
        walls.append(result.seconds)
        done = int(result.columns["total_impacts"].sum())
    scene = load_scene(SCENE)
    setup = EN.prepare(scene)
    ctxs, ok = EN.start(setup, q1, q2)
    ctxs = np.ascontiguousarray(ctxs[ok])
    consts = EN.constants(scene, 1e-5, 64, PERIOD_WINDOW)
    kernel = []
    for _ in range(repeats):
        clock: dict[str, float] = {}
        stats, _ = gpu.advance_ensemble(
            setup.sim, ctxs, setup.params, consts, transient=0, impacts=impacts,
            width=PERIOD_WINDOW, keep=GPU_KEEP, states=False, clock=clock,
        )  # fmt: skip
        kernel.append(clock["kernel_s"])
    kernel_done = int(stats[:, E.ST_TOTAL].sum())
    from numba import cuda

    name = getattr(cuda.get_current_device(), "name", "numba's CUDA simulator")
    name = name.decode() if isinstance(name, bytes) else str(name)
    rate = done / statistics.median(walls)
    kernel_rate = kernel_done / statistics.median(kernel)
    return {
        "device": name,
        "starts": int((result.columns["attractor"] != "invalid").sum()),
        "impacts": done,
        "keep": GPU_KEEP,
        "walls": walls,
        "impacts_per_s": rate,
        "kernel_walls": kernel,
        "kernel_impacts_per_s": kernel_rate,
        "whole_to_kernel": rate / kernel_rate,
    }


def gpu_agreement(scene: str, side: int, transient: int, impacts: int) -> dict:
    """The share of a ``side`` x ``side`` basin map's valid starts whose attractor (class;
    for periodic ones also the period and the mean height within 1 mm) is the same on
    the GPU as on the CPU (all cores)."""
    import billiard

    q1, q2 = np.meshgrid(np.linspace(-0.04, 0.04, side), np.linspace(0.02, 0.12, side))
    kw = dict(q1=q1, q2=q2, impacts=impacts, transient=transient)
    cpu = billiard.run_ensemble(scene, **kw)
    gpu = billiard.run_ensemble(scene, device="gpu", **kw)
    a, b = cpu.columns, gpu.columns
    valid = a["attractor"] != "invalid"
    same = a["attractor"] == b["attractor"]
    periodic = a["attractor"] == "periodic"
    same &= ~periodic | (
        (a["period"] == b["period"]) & (np.abs(a["height_mean"] - b["height_mean"]) <= 1e-3)
    )
    names, counts = np.unique(a["attractor"][valid], return_counts=True)
    return {
        "scene": scene,
        "starts": int(valid.sum()),
        "transient": transient,
        "impacts": impacts,
        "agree": float(same[valid].mean()),
        "classes": {str(k): int(v) for k, v in zip(names, counts, strict=True)},
        "cpu_seconds": cpu.seconds,
        "gpu_seconds": gpu.seconds,
    }


def gpu_row(quick: bool) -> dict | None:
    """The GPU section, or why there is none."""
    try:
        from billiard.engine import gpu
    except ImportError as exc:  # pragma: no cover - the package has the module
        return {"missing": str(exc)}
    problem = gpu.available()
    if problem is not None or gpu.simulated():
        return {"missing": problem or "numba's CUDA simulator is not a GPU"}
    starts, side = (1 << 16, 200) if quick else (1 << 18, 500)
    print(f"bench.ensemble: GPU, {starts:,} trajectories ...", flush=True)
    rate = gpu_rate(starts, 1000, 2 if quick else 3)
    print(f"bench.ensemble: GPU {rate['impacts_per_s']:,.0f} impacts/s; agreement ...", flush=True)
    agree = [gpu_agreement(name, side, 500, 500) for name in ("hyperbola-4.5hz", SCENE)]
    return {"rate": rate, "agreement": agree}


def measure(quick: bool, save: Any = None) -> dict:
    """Every measurement of the section; ``save(results)`` is called after each part, so
    that an interrupted run keeps what it measured."""
    starts, impacts, repeats = SIZES[quick]
    cores = os.cpu_count() or 1
    threads = sorted({1, cores} | ({2, 4, 8, 16} & set(range(1, cores + 1))))
    result: dict[str, Any] = {
        "command": "billiard bench --only ensemble" + (" --quick" if quick else ""),
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "machine": ", ".join(
            x
            for x in (f"Python {platform.python_version()}", f"{cores} CPUs", platform.processor())
            if x
        ),
        "load": ", ".join(f"{x:.1f}" for x in os.getloadavg()),
        "scene": SCENE,
    }
    result["gpu"] = gpu_row(quick)
    _save(save, result)
    print(f"bench.ensemble: kernel on {threads} threads ...", flush=True)
    result["kernel"] = kernel_rates(starts, impacts, repeats, threads)
    _save(save, result)
    print("bench.ensemble: the sweep's cost per point ...", flush=True)
    result["overhead"] = sweep_overhead(quick)
    _save(save, result)
    print("bench.ensemble: a point under contact phases against impacts ...", flush=True)
    result["phases"] = phases_ratio(quick)
    _save(save, result)
    print("bench.ensemble: the ensemble kernel against the bare kernel ...", flush=True)
    result["kernel_ratio"] = kernel_ratio(quick)
    _save(save, result)
    print("bench.ensemble: a parameter map, patched set-ups against one each ...", flush=True)
    result["map"] = parameter_map(quick)
    _save(save, result)
    print("bench.ensemble: a cluster that grows from 1 to 4 workers ...", flush=True)
    try:
        result["growing"] = growing_cluster(quick)
    except ImportError as exc:  # no dask.distributed: the row says so
        result["growing"] = {"missing": str(exc)}
    _save(save, result)
    pair = sorted({1, min(cores, 16)})
    print(f"bench.ensemble: a sweep on {pair} workers ...", flush=True)
    result["scaling"] = sweep_scaling(quick, pair)
    result["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    _save(save, result)
    return result


def _save(save: Any, result: dict) -> None:
    if save is not None:
        save(result)


class _Silent:
    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


def _basin_sweep(side: int, transient: int, impacts: int, workers: int, keep: int = 10) -> dict:
    """A ``side`` x ``side`` wedge basin map through run_sweep (plots excluded): wall
    time, CPU seconds of this process and its workers, points computed, file sizes."""
    from billiard.scene.scene import load_scene
    from billiard.sweep import Sweep, parse_vary, run_sweep
    from billiard.sweep.progress import SweepProgress

    sweep = Sweep(
        load_scene(SCENE),
        (parse_vary(f"initial.q1=-0.04:0.04:{side}"), parse_vary(f"initial.q2=0.02:0.12:{side}")),
        impacts=impacts,
        transient=transient,
        keep=keep,
    )
    with tempfile.TemporaryDirectory() as tmp:
        cpu0 = _cpu()
        began = time.perf_counter()
        progress = SweepProgress(sweep.size, stream=_Silent())
        outcome = run_sweep(sweep, Path(tmp) / "s", workers=workers, progress=progress, plots=False)
        wall = time.perf_counter() - began
        cpu = _cpu() - cpu0
        sizes = {p.name: p.stat().st_size for p in outcome.directory.iterdir() if p.is_file()}
    return {
        "side": side,
        "points": sweep.size,
        "computed": len(outcome.computed),
        "impacts_per_point": transient + impacts,
        "workers": workers,
        "wall": wall,
        "cpu": cpu,
        "files": sizes,
        "keep": keep,
    }


def sweep_overhead(quick: bool) -> dict:
    """The fixed cost of a point: two basin maps of one-impact points on one worker;
    the difference of their CPU seconds (parent and worker) over the difference of
    their points is the cost of one more point (the sweep's start-up cancels out)."""
    from billiard.sweep.columns import disk_dtype

    small, large = (60, 150) if quick else (100, 300)
    a = _basin_sweep(small, 0, 1, 1)
    b = _basin_sweep(large, 0, 1, 1)
    per_point = (b["cpu"] - a["cpu"]) / (b["points"] - a["points"])
    size = b["files"]["points.npy"]
    row = disk_dtype(b["keep"]).itemsize
    return {
        "runs": [a, b],
        "cpu_us_per_point": per_point * 1e6,
        "bytes_per_point": row - 16 * b["keep"],
        "points_npy": size,
    }


def _map(side: int) -> Any:
    """The targets' ``side`` x ``side`` drive.frequency x drive.amplitude map of the
    parabola: 200 impacts after a 300-impact transient, 10 kept."""
    from billiard.scene.scene import load_scene
    from billiard.sweep import Sweep, parse_vary

    axes = (
        parse_vary(f"drive.frequency=4.5:6.5:{side}"),
        parse_vary(f"drive.amplitude=0.01:0.04:{side}"),
    )
    return Sweep(load_scene(MAP_SCENE), axes, impacts=200, transient=300, keep=10)


def _map_sweep(side: int, workers: int, patched: bool = True) -> dict:
    """A ``side`` x ``side`` drive.frequency x drive.amplitude map of the parabola, 200
    impacts after a 300-impact transient, through run_sweep (plots excluded); with
    ``patched`` False every parameter set is set up on its own (the path before)."""
    from billiard.sweep import batch, run_sweep
    from billiard.sweep.progress import SweepProgress

    sweep = _map(side)
    before = os.environ.get(batch.PATCH_ENV)
    os.environ[batch.PATCH_ENV] = "1" if patched else "0"  # read by the workers too
    try:
        with tempfile.TemporaryDirectory() as tmp:
            began = time.perf_counter()
            progress = SweepProgress(sweep.size, stream=_Silent())
            outcome = run_sweep(
                sweep, Path(tmp) / "m", workers=workers, progress=progress, plots=False
            )
            wall = time.perf_counter() - began
    finally:
        if before is None:
            os.environ.pop(batch.PATCH_ENV, None)
        else:
            os.environ[batch.PATCH_ENV] = before
    return {"side": side, "points": sweep.size, "workers": workers, "wall": wall,
            "computed": len(outcome.computed), "patched": patched}  # fmt: skip


def _bare_per_impact(starts: list[tuple[float, float]], impacts: int) -> float:
    """CPU seconds per impact of the bare single-trajectory kernel (``run_chunk``, one
    chunk of ``impacts`` impacts per start, rows written) over the wedge ``starts``."""
    import numpy as np

    from billiard.engine.simulation import Simulation
    from billiard.geometry.wall_functions import wall_functions
    from billiard.kernels import layout as L
    from billiard.kernels.loop import run_chunk
    from billiard.scene.scene import load_scene, with_values

    spent, made = 0.0, 0
    buffer = np.empty(impacts * L.NCOL)
    for q1, q2 in starts:
        sim = Simulation(with_values(load_scene(SCENE), {"initial.q1": q1, "initial.q2": q2}))
        ctx = np.array(sim.ctx, dtype=np.float64)
        ctx[L.EN_TARGET] = float(impacts)
        params = np.array(sim.boundary.walls[0].p, dtype=np.float64)
        walls = wall_functions(sim)
        began = time.process_time()
        _, rows = run_chunk(ctx, params, walls, buffer, impacts)
        spent += time.process_time() - began
        made += rows
    return spent / max(made, 1)


def _ensemble_per_impact(q1: np.ndarray, q2: np.ndarray, impacts: int) -> tuple[float, float]:
    """CPU seconds per impact of the ensemble on one thread from the wedge starts
    (q1, q2): (the kernel alone, ``billiard.engine.ensemble.advance`` over the prepared
    state vectors; the whole call, ``run_ensemble``: set-up, starts, kernel and
    measurements)."""
    from billiard import run_ensemble
    from billiard.engine import ensemble as EN
    from billiard.kernels import ensemble as E
    from billiard.scene.scene import load_scene
    from billiard.sweep.attractor import PERIOD_WINDOW

    scene = load_scene(SCENE)
    setup = EN.prepare(scene)
    ctxs, valid = EN.start(setup, q1, q2, np.zeros_like(q1), np.zeros_like(q1),
                           np.zeros_like(q1))  # fmt: skip
    ctxs = np.ascontiguousarray(ctxs[valid])
    consts = EN.constants(scene, 1e-5, 64, PERIOD_WINDOW)
    began = time.process_time()
    stats, _ = EN.advance(ctxs, setup.params, setup.walls, consts, transient=0,
                          impacts=impacts, width=PERIOD_WINDOW, threads=1)  # fmt: skip
    kernel = (time.process_time() - began) / max(float(stats[:, E.ST_TOTAL].sum()), 1.0)
    began = time.process_time()
    result = run_ensemble(scene, q1=q1, q2=q2, impacts=impacts, threads=1)
    whole = (time.process_time() - began) / max(float(result.columns["total_impacts"].sum()), 1)
    return kernel, whole


def kernel_ratio(quick: bool) -> dict:
    """CPU per impact of the ensemble kernel on one thread against the bare
    single-trajectory kernel over the same wedge starts (a sample of :func:`_starts`),
    the two taken alternately: the kernel alone (the target), and the whole call with
    its set-up and measurements (which a short run does not amortize)."""
    count, impacts, repeats = (20, 2000, 3) if quick else (40, 5000, 5)
    # starts well inside the wedge (each a valid start of a run)
    q1 = np.linspace(-0.02, 0.02, count)
    q2 = np.linspace(0.12, 0.07, count)
    _ensemble_per_impact(q1[:2], q2[:2], 10)  # kernels loaded
    _bare_per_impact([(q1[0], q2[0])], 10)
    bare, ensemble, whole = [], [], []
    for _ in range(repeats):
        bare.append(_bare_per_impact(list(zip(q1.tolist(), q2.tolist(), strict=True)), impacts))
        kernel, call = _ensemble_per_impact(q1, q2, impacts)
        ensemble.append(kernel)
        whole.append(call)
    b, e, w = (statistics.median(x) for x in (bare, ensemble, whole))
    return {"bare_us": 1e6 * b, "ensemble_us": 1e6 * e, "ratio": e / b,
            "whole_us": 1e6 * w, "whole_ratio": w / b,
            "bare": bare, "ensemble": ensemble, "whole": whole, "starts": len(q1),
            "impacts": impacts}  # fmt: skip


def _cluster_sweep(side: int, grow_after: float | None, workers: int = 4) -> dict:
    """A wedge basin map on a Dask ``LocalCluster`` of worker processes (one thread
    each) that starts with one worker; ``grow_after`` s after the sweep starts it is
    scaled to ``workers`` (None: it stays at one). Wall time from the call to the result
    file, worker start-up included."""
    import threading

    import distributed

    from billiard.scene.scene import load_scene
    from billiard.sweep import Sweep, parse_vary, run_sweep
    from billiard.sweep.progress import SweepProgress

    sweep = Sweep(
        load_scene(SCENE),
        (parse_vary(f"initial.q1=-0.03:0.03:{side}"), parse_vary(f"initial.q2=0.07:0.12:{side}")),
        impacts=500,
        transient=500,
        keep=10,
    )
    with distributed.LocalCluster(
        n_workers=1, processes=True, threads_per_worker=1, dashboard_address=None
    ) as cluster, tempfile.TemporaryDirectory() as tmp:  # fmt: skip
        cluster.wait_for_workers(1, timeout=120)
        timer = None
        if grow_after is not None:
            timer = threading.Timer(grow_after, cluster.scale, args=(workers,))
            timer.start()
        try:
            began = time.perf_counter()
            run_sweep(
                sweep, Path(tmp) / "g", dask=cluster.scheduler_address, plots=False,
                progress=SweepProgress(sweep.size, stream=_Silent()),
            )  # fmt: skip
            wall = time.perf_counter() - began
        finally:
            if timer is not None:
                timer.cancel()
    return {"side": side, "points": sweep.size, "grow_after": grow_after, "wall": wall}


def growing_cluster(quick: bool) -> dict:
    """A sweep on a cluster that starts with one worker and gains three after 10 s,
    against the same sweep on one worker throughout."""
    # one worker runs some 2e6 impacts/s: the map takes 15-30 s on it, well beyond the
    # 10 s after which the cluster grows
    side = 180 if quick else 250
    one = _cluster_sweep(side, None)
    grown = _cluster_sweep(side, 10.0)
    return {"one": one, "grown": grown, "ratio": grown["wall"] / one["wall"],
            "cores": os.cpu_count() or 1}  # fmt: skip


def _map_chunk(side: int, patched: bool) -> float:
    """Seconds of one worker's measuring of a ``side`` x ``side`` map as one chunk, in
    this process (no pool, no files): set-ups, trajectories and measurements."""
    import numpy as np

    from billiard.sweep import batch

    sweep = _map(side)
    os.environ[batch.PATCH_ENV] = "1" if patched else "0"
    try:
        began = time.perf_counter()
        batch.measure_batch(sweep, np.arange(sweep.size), sweep.settings())
        return time.perf_counter() - began
    finally:
        os.environ.pop(batch.PATCH_ENV, None)


def parameter_map(quick: bool) -> dict:
    """A parameter map's cost: a chunk of it measured in this process with patched
    set-ups and with a set-up per parameter set (the path before), alternately; and
    through the sweep on all cores at two sizes, whose slope (start-up cancelled)
    projects the 10^6-point map. The files of that map are estimated, the parent's
    peak memory measured."""
    from billiard.sweep.execute import estimate_size

    cores = os.cpu_count() or 1
    chunk = 12 if quick else 20
    _map_chunk(2, True)  # kernels loaded
    pairs = [(_map_chunk(chunk, True), _map_chunk(chunk, False)) for _ in range(2 if quick else 3)]
    patched = statistics.median(p for p, _ in pairs) / chunk**2
    each = statistics.median(u for _, u in pairs) / chunk**2
    small, large = (20, 40) if quick else (60, 120)
    runs = []
    for _ in range(1 if quick else 2):
        runs += [_map_sweep(small, cores), _map_sweep(large, cores)]
    a = statistics.median(r["wall"] for r in runs if r["side"] == small)
    b = statistics.median(r["wall"] for r in runs if r["side"] == large)
    per_point = (b - a) / (large**2 - small**2)
    side = int(MAP_POINTS**0.5)
    big = _map(side)
    return {
        "runs": runs,
        "chunk_pairs": pairs,
        "chunk": chunk,
        "patched_ms_per_point": 1e3 * patched,
        "own_setup_ms_per_point": 1e3 * each,
        "speedup": each / patched,
        "workers": cores,
        "per_point_s": per_point,
        "projected_s": a + per_point * (MAP_POINTS - small**2),
        "small": small,
        "large": large,
        "files_bytes": sum(estimate_size(big).values()),
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def sweep_scaling(quick: bool, workers: list[int]) -> dict:
    """One basin map of 1000-impact points on each worker count (start-up included)."""
    side = 120 if quick else 300
    runs = [_basin_sweep(side, 500, 500, w) for w in workers]
    return {"runs": runs, "speedup": runs[0]["wall"] / runs[-1]["wall"]}


def _cpu() -> float:
    """CPU seconds of this process and its finished children."""
    me, children = (
        resource.getrusage(resource.RUSAGE_SELF),
        resource.getrusage(resource.RUSAGE_CHILDREN),
    )
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def _verdict(value: float, target: float, more: bool) -> str:
    met = value >= target if more else value <= target
    return "met" if met else "**missed**"


def render(results: dict) -> str:
    """The section of docs/sweeps.md."""
    lines = [
        BEGIN,
        "### Measured",
        "",
        f"Measured by `{results['command']}` on {results['date']} ({results['machine']}; "
        f"load average {results['load']} at the start), scene {results['scene']}; times are "
        "wall-clock medians of the runs listed.",
        "",
        "**The ensemble kernel on the CPU** (`billiard.run_ensemble`, threads of one process):",
        "",
        "| threads | impacts/s | ratio to 1 thread | runs (s) |",
        "| --- | --- | --- | --- |",
    ]
    one = results["kernel"][0]["impacts_per_s"]
    for row in results["kernel"]:
        walls = ", ".join(f"{w:.2f}" for w in row["walls"])
        lines.append(
            f"| {row['threads']} | {row['impacts_per_s']:,.0f} | "
            f"{row['impacts_per_s'] / one:.2f}x | {walls} |"
        )
    o = results["overhead"]
    a, b = o["runs"]
    lines += [
        "",
        f"**A sweep's cost per point** (`billiard sweep`, one worker): basin maps of "
        f"{a['points']:,} and {b['points']:,} one-impact points took {a['cpu']:.2f} s and "
        f"{b['cpu']:.2f} s of CPU (parent and worker); one more point costs "
        f"**{o['cpu_us_per_point']:.1f} us of CPU** (checking its start, its chunk's "
        "set-up, measuring, storing), and "
        f"**{o['bytes_per_point']:.0f} bytes** in `points.npy` beyond the kept impacts.",
        "",
    ]
    ph = results.get("phases")
    if ph is not None:
        a, b = ph["impacts"], ph["phases"]
        lines += [
            f'**Contact phases** (a sweep point under `contact.model = "phases"` against the '
            f'same point under `"impacts"`: {ph["points"]} wedge starts of '
            f"{ph['impacts_per_point']} impacts, measured as a worker measures a chunk, the "
            f"two models alternately; `{ph['command']}` on {ph['date']}, load average "
            f"{ph['load']}): {b['us_per_point']:.0f} us per point against "
            f"{a['us_per_point']:.0f} us ({b['impacts']:,} and {a['impacts']:,} impacts "
            f"made), **{ph['ratio']:.2f}x**.",
            "",
        ]
    kr = results.get("kernel_ratio")
    if kr is not None:
        lines += [
            f"**The ensemble kernel against the bare kernel** (CPU per impact, one thread, "
            f"taken alternately): {kr['ensemble_us']:.2f} us per impact for "
            f"{kr['starts']:,} wedge starts of {kr['impacts']} impacts, against "
            f"{kr['bare_us']:.2f} us for the bare kernel (`run_chunk`, a row written per "
            f"impact) from the same starts (**{kr['ratio']:.2f}x**).",
            "",
        ]
        if "whole_us" in kr:  # results saved before the whole call was timed apart
            lines[-2] += (
                f" The whole call (`run_ensemble`: its set-up, starts and measurements too) "
                f"took {kr['whole_us']:.2f} us per impact ({kr['whole_ratio']:.2f}x): its "
                "set-up is paid once per call, so its share falls as the call grows."
            )
    mp = results.get("map")
    if mp is not None:
        lines += [
            f"**A parameter map** (`billiard sweep {MAP_SCENE} --vary drive.frequency=4.5:6.5:N "
            "--vary drive.amplitude=0.01:0.04:N --impacts 200 --transient 300 --keep 10`): "
            "the parameter sets of a chunk run as one ensemble, set up once and patched per "
            f"point. A {mp['chunk']} x {mp['chunk']} chunk measured in one process: "
            f"{mp['patched_ms_per_point']:.2f} ms per point, against "
            f"{mp['own_setup_ms_per_point']:.2f} ms with a set-up per parameter set (the "
            f"path before; **{mp['speedup']:.1f}x**). Through the sweep on "
            f"{mp['workers']} workers, {mp['small']}^2 and {mp['large']}^2-point maps give "
            f"{1e3 * mp['per_point_s']:.2f} ms of wall time per point, so a 1000 x 1000 map "
            f"takes about **{mp['projected_s'] / 60:.1f} min** (projected), with "
            f"{mp['files_bytes'] / 2**20:,.0f} MiB of files; the parent peaked at "
            f"{mp['peak_rss_mib']:.0f} MiB.",
            "",
        ]
    gr = results.get("growing")
    if gr is not None and "ratio" in gr:
        one, grown = gr["one"], gr["grown"]
        lines += [
            f"**A cluster that grows** (a {one['side']} x {one['side']} wedge basin map of "
            "1000-impact points on a Dask `LocalCluster` of worker processes): one worker "
            f"throughout took {one['wall']:.1f} s; started with one and scaled to four after "
            f"10 s, {grown['wall']:.1f} s (**{gr['ratio']:.2f}x**; on {gr['cores']} cores, "
            "four workers can at most share them).",
            "",
        ]
    sc = results["scaling"]
    runs = sc["runs"]
    lines += [
        f"**Workers** (`billiard sweep --workers N`, a {runs[0]['side']} x {runs[0]['side']} "
        f"basin map, {runs[0]['computed']:,} points of {runs[0]['impacts_per_point']} "
        "impacts; wall time from the call to the result file, worker start-up included):",
        "",
        "| workers | wall (s) | impacts/s | ratio to 1 worker |",
        "| --- | --- | --- | --- |",
    ]
    for r in runs:
        rate = r["computed"] * r["impacts_per_point"] / r["wall"]
        ratio = runs[0]["wall"] / r["wall"]
        lines.append(f"| {r['workers']} | {r['wall']:.1f} | {rate:,.0f} | {ratio:.2f}x |")
    g = results.get("gpu") or {}
    lines.append("")
    if "rate" in g:
        rate = g["rate"]
        walls = ", ".join(f"{w:.2f}" for w in rate["walls"])
        kernel = ", ".join(f"{w:.2f}" for w in rate["kernel_walls"])
        lines += [
            f'**GPU** ({rate["device"]}, `billiard.run_ensemble(..., device="gpu", '
            f"states=False, keep={rate['keep']})`, what a sweep copies back): "
            f"{rate['starts']:,} wedge trajectories of 1000 impacts in {walls} s, the whole "
            "call (the starts set up on all cores, the launches, the copies both ways): "
            f"**{rate['impacts_per_s']:,.0f} impacts/s**; the kernel's launches alone in "
            f"{kernel} s, {rate['kernel_impacts_per_s']:,.0f} impacts/s: the whole call at "
            f"**{100 * rate['whole_to_kernel']:.0f} %** of its kernel.",
            "",
            "| scene | starts | classes (CPU) | CPU, all cores (s) | GPU (s) | same attractor |",
            "| --- | --- | --- | --- | --- | --- |",
        ]
        for r in g["agreement"]:
            classes = ", ".join(f"{k} {v:,}" for k, v in r["classes"].items())
            lines.append(
                f"| {r['scene']} | {r['starts']:,} | {classes} | {r['cpu_seconds']:.1f} | "
                f"{r['gpu_seconds']:.1f} | {100 * r['agree']:.2f} % |"
            )
        lines.append("")
    else:
        lines += [
            f"No GPU where this was measured ({g.get('missing', 'not measured')}); on a "
            "machine with one, `billiard bench --only ensemble` adds its rows.",
            "",
        ]
    lines += ["| target | measured | verdict |", "| --- | --- | --- |"]
    lines.append(
        f"| <= {TARGETS['point_cpu_us']:.0f} us of CPU per point | "
        f"{o['cpu_us_per_point']:.1f} us | "
        f"{_verdict(o['cpu_us_per_point'], TARGETS['point_cpu_us'], False)} |"
    )
    lines.append(
        f"| <= {TARGETS['point_bytes']:.0f} bytes per point beyond the kept impacts | "
        f"{o['bytes_per_point']:.0f} | "
        f"{_verdict(o['bytes_per_point'], TARGETS['point_bytes'], False)} |"
    )
    if gr is not None and "ratio" in gr:
        reason = "" if gr["ratio"] <= TARGETS["growing"] else f" ({gr['cores']} cores)"
        lines.append(
            f"| 1 worker, 3 more after 10 s: <= {TARGETS['growing']:.1f}x the 1-worker time | "
            f"{gr['ratio']:.2f}x | {_verdict(gr['ratio'], TARGETS['growing'], False)}{reason} |"
        )
    if kr is not None:
        lines.append(
            f"| ensemble kernel <= {TARGETS['kernel_ratio']:.1f}x the bare kernel per impact | "
            f"{kr['ratio']:.2f}x | {_verdict(kr['ratio'], TARGETS['kernel_ratio'], False)} |"
        )
    if mp is not None:
        lines.append(
            f"| a 1000 x 1000 parameter map <= {TARGETS['map_seconds'] / 60:.0f} min | "
            f"{mp['projected_s'] / 60:.1f} min (projected) | "
            f"{_verdict(mp['projected_s'], TARGETS['map_seconds'], False)} |"
        )
    if ph is not None:
        lines.append(
            f"| a point under contact phases <= {TARGETS['phases_ratio']:.0f}x one under "
            f"impacts | {ph['ratio']:.2f}x | "
            f"{_verdict(ph['ratio'], TARGETS['phases_ratio'], False)} |"
        )
    if runs[-1]["workers"] >= 16:
        lines.append(
            f"| 16 workers >= {TARGETS['scaling_16']:.0f}x one worker | {sc['speedup']:.1f}x | "
            f"{_verdict(sc['speedup'], TARGETS['scaling_16'], True)} |"
        )
    if "rate" in g:
        lines.append(
            f"| GPU, the whole call, >= 1e8 impacts/s | {g['rate']['impacts_per_s']:.3g} | "
            f"{_verdict(g['rate']['impacts_per_s'], TARGETS['gpu_impacts_per_s'], True)} |"
        )
        worst = min(r["agree"] for r in g["agreement"])
        lines.append(
            f"| GPU attractors = CPU's on >= 99 % of a basin map | {100 * worst:.2f} % | "
            f"{_verdict(worst, 0.99, True)} |"
        )
    lines.append("")
    return "\n".join(lines + [END]) + "\n"


def saved_results(docs: Path) -> Path:
    return docs / "figures" / "ensemble" / "bench.json"


def render_phases(results: dict) -> str:
    """The section of docs/performance.md: a sweep point under contact phases."""
    ph = results.get("phases")
    if ph is None:
        return f"{PHASES_BEGIN}\n{PHASES_END}\n"
    a, b, one = ph["impacts"], ph["phases"], ph["one_by_one"]
    verdict = _verdict(ph["ratio"], TARGETS["phases_ratio"], False)
    lines = [
        PHASES_BEGIN,
        "## Sweep points under contact phases",
        "",
        'A sweep point under `contact.model = "phases"` runs, batched with the other points '
        "of its chunk, on the compiled state machine of `billiard run`, as a point under "
        '`"impacts"` runs on the impact loop (docs/sweeps.md, "What takes the ensemble '
        f'path"). Measured by `{ph["command"]}` on {ph["date"]} (load average '
        f"{ph['load']}): {ph['points']} wedge starts of {ph['impacts_per_point']} impacts, "
        "each model's points measured as a worker measures a chunk, alternately, wall-clock "
        "medians.",
        "",
        "| point | us per point | runs (s) |",
        "| --- | --- | --- |",
    ]
    for name, row in (
        ("impacts, batched", a),
        ("phases, batched", b),
        ("phases, one by one (a Simulation each)", one),
    ):
        walls = ", ".join(f"{w:.3f}" for w in row["walls"])
        lines.append(f"| {name} | {row['us_per_point']:,.0f} | {walls} |")
    lines += [
        "",
        f"A point under contact phases costs **{ph['ratio']:.2f}x** one under the impacts "
        f"model (target <= {TARGETS['phases_ratio']:.0f}x: {verdict}); one by one it cost "
        f"{one['us_per_point'] / a['us_per_point']:.0f}x.",
        PHASES_END,
    ]
    return "\n".join(lines) + "\n"


def publish(docs: Path, results: dict | None = None) -> bool:
    """Save ``results`` (when given) and write the section of ``docs/sweeps.md`` and the
    contact phases' part of ``docs/performance.md`` from the saved results; False when
    there are none."""
    saved = saved_results(docs)
    if not publish_section(saved, docs / "sweeps.md", render, BEGIN, END, results):
        return False
    return publish_section(saved, docs / "performance.md", render_phases, PHASES_BEGIN, PHASES_END)


def remeasure_phases(docs: Path, quick: bool) -> None:
    """Measure the cost of a point under contact phases again and publish it, the
    section's other saved results kept."""
    saved = saved_results(docs)
    results = json.loads(saved.read_text()) if saved.exists() else None
    if results is None:
        raise SystemExit(f"bench.ensemble: no saved results in {saved}: measure them all first")
    results["phases"] = phases_ratio(quick)
    publish(docs, results)


def _partial(docs: Path, results: dict) -> None:
    """Keep what is measured so far (``bench.json.partial``)."""
    saved = saved_results(docs)
    saved.parent.mkdir(parents=True, exist_ok=True)
    saved.with_suffix(".json.partial").write_text(json.dumps(results, indent=1))


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    phases = "--phases" in argv
    argv = [a for a in argv if a != "--phases"]
    args, docs = section_arguments(
        "python -m bench.ensemble", __doc__, "small sizes, under a minute", argv
    )
    if phases:
        remeasure_phases(docs, args.quick)
    elif args.render:
        publish(docs)
    else:
        publish(docs, measure(args.quick, save=lambda r: _partial(docs, r)))
        # the whole measurement is in bench.json now: the partial copy only served an
        # interrupted run
        saved_results(docs).with_suffix(".json.partial").unlink(missing_ok=True)
    print(f"bench.ensemble: wrote the ensemble section of {docs / 'sweeps.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
