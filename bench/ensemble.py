"""Section ``ensemble``: the ensemble kernel's impacts per second on one core and on all,
the sweep's fixed cost per point and its scaling with workers, and the GPU when there is
one, against the targets of the issue "Ensembles".

Run as a section of the benchmark (``billiard bench --only ensemble``) or alone from a
source checkout::

    python -m bench.ensemble            # a few minutes on 2 cores
    python -m bench.ensemble --quick    # under a minute, smaller sizes

It saves ``docs/figures/ensemble/bench.json`` and rewrites the section between the markers
``<!-- ensemble-bench -->`` and ``<!-- /ensemble-bench -->`` of ``docs/sweeps.md``.
Times are wall-clock medians of several runs taken alternately, numba's cache loaded
first; the machine's load average is recorded with them.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

BEGIN, END = "<!-- ensemble-bench -->", "<!-- /ensemble-bench -->"
SCENE = "wedge-6.6hz"
#: the issue's targets
TARGETS = {
    "point_cpu_us": 50.0,
    "point_bytes": 100.0,
    "scaling_16": 12.0,
    "gpu_impacts_per_s": 1e8,
    "basin_seconds": 600.0,
}
#: (starts, impacts per start, repeats) of the kernel measurement
SIZES = {False: (4000, 1000, 3), True: (1000, 500, 2)}


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
            threads=n_threads,
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


def gpu_row(starts: int, impacts: int, repeats: int) -> dict | None:
    """The GPU's impacts per second (None without one), and the share of starts of a
    basin map whose attractor class and period agree with the CPU's."""
    try:
        from billiard.engine import gpu
    except ImportError:
        return None
    if gpu.available() is not None:
        return {"missing": gpu.available()}
    return gpu.bench(SCENE, starts, impacts, repeats)


def measure(quick: bool) -> dict:
    starts, impacts, repeats = SIZES[quick]
    cores = os.cpu_count() or 1
    threads = sorted({1, cores} | ({2, 4, 8, 16} & set(range(1, cores + 1))))
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"bench.ensemble: kernel on {threads} threads ...", flush=True)
    rates = kernel_rates(starts, impacts, repeats, threads)
    result = {
        "command": "billiard bench --only ensemble" + (" --quick" if quick else ""),
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "machine": f"Python {platform.python_version()}, {cores} CPUs, {platform.processor()}",
        "load": load,
        "scene": SCENE,
        "kernel": rates,
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    print("bench.ensemble: sweep overhead and workers ...", flush=True)
    result["sweep"] = sweep_costs(quick, [w for w in threads if w <= cores])
    gpu = gpu_row(10**5 if quick else 10**6, 1000, repeats)
    if gpu is not None:
        result["gpu"] = gpu
    return result


def sweep_costs(quick: bool, workers: list[int]) -> dict:
    """The fixed cost of a sweep point (a basin map of 1-impact points: CPU time of the
    parent and its workers per point, bytes per point) and the wall time of one basin
    map on each worker count."""
    from billiard.scene.scene import load_scene
    from billiard.sweep import Sweep, parse_vary, run_sweep
    from billiard.sweep.progress import SweepProgress

    class Silent:
        def write(self, text: str) -> int:
            return len(text)

        def flush(self) -> None:
            pass

    scene = load_scene(SCENE)
    side = 100 if quick else 200

    def run(impacts: int, transient: int, n_workers: int) -> dict:
        sweep = Sweep(
            scene,
            (
                parse_vary(f"initial.q1=-0.04:0.04:{side}"),
                parse_vary(f"initial.q2=0.02:0.12:{side}"),
            ),
            impacts=impacts,
            transient=transient,
            keep=10,
            skip_invalid=True,
        )
        with tempfile.TemporaryDirectory() as tmp:
            cpu0 = _cpu()
            began = time.perf_counter()
            progress = SweepProgress(sweep.size, stream=Silent())
            outcome = run_sweep(
                sweep, Path(tmp) / "s", workers=n_workers, progress=progress, plots=False
            )
            wall = time.perf_counter() - began
            cpu = _cpu() - cpu0
            sizes = {p.name: p.stat().st_size for p in outcome.directory.iterdir() if p.is_file()}
        return {"points": sweep.size, "wall": wall, "cpu": cpu, "files": sizes}

    overhead = run(1, 0, 1)
    runs = {}
    for w in workers:
        runs[str(w)] = run(200, 0, w)
    return {"overhead": overhead, "keep": 10, "scaling": runs}


def _cpu() -> float:
    """CPU seconds of this process and its finished children."""
    me, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN
    )
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def render(results: dict) -> str:
    lines = [
        BEGIN,
        "### Measured: the ensemble kernel, the sweep's cost per point, workers and GPU",
        "",
        f"Measured by `{results['command']}` ({results['date']}; {results['machine']}; "
        f"load average {results['load']} at the start), {results['scene']}.",
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
    lines.append("")
    return "\n".join(lines + [END]) + "\n"


def write_section(doc: Path, section: str) -> None:
    text = doc.read_text() if doc.exists() else ""
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1].lstrip("\n")
        text = head + section + ("\n" + tail if tail else "")
    else:
        text = text.rstrip("\n") + "\n\n" + section
    doc.write_text(text)


def saved_results(docs: Path) -> Path:
    return docs / "figures" / "ensemble" / "bench.json"


def publish(docs: Path, results: dict | None = None) -> bool:
    """Save ``results`` (when given) and write the section of ``docs/sweeps.md`` from
    the saved results; False when there are none."""
    saved = saved_results(docs)
    if results is not None:
        saved.parent.mkdir(parents=True, exist_ok=True)
        saved.write_text(json.dumps(results, indent=1))
    elif not saved.exists():
        return False
    write_section(docs / "sweeps.md", render(json.loads(saved.read_text())))
    return True


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.ensemble", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small sizes, under a minute")
    parser.add_argument(
        "--docs", help="documentation folder (default docs, or runs/bench-quick with --quick)"
    )
    parser.add_argument(
        "--render", action="store_true", help="measure nothing: rewrite the section from bench.json"
    )
    args = parser.parse_args(argv)
    docs = Path(args.docs or ("runs/bench-quick" if args.quick else "docs"))
    publish(docs, None if args.render else measure(args.quick))
    print(f"bench.ensemble: wrote the ensemble section of {docs / 'sweeps.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
