"""Sweep throughput: 1 and 2 worker processes, and a measured 10^6-impact sweep.

Run as a section of the benchmark (``billiard bench --only sweep``), or alone from a
source checkout::

    python -m bench.sweep            # about 10 minutes on 2 cores
    python -m bench.sweep --quick    # about 1 minute, smaller sizes

It measures with :func:`billiard.sweep.run_sweep`, the code behind ``billiard sweep``
(worker start-up, checking the points, writing points.npy and the result file all
included; plots excluded), saves ``docs/figures/sweeps/bench.json`` and rewrites the
section between the markers ``<!-- sweep-bench -->`` and ``<!-- /sweep-bench -->`` of
``docs/performance.md`` (appending it if absent).
"""

from __future__ import annotations

import hashlib
import os
import platform
import resource
import statistics
import tempfile
import time
from pathlib import Path

from bench.common import section_arguments
from bench.markdown import publish_section
from billiard import load_scene
from billiard.sweep import Sweep, parse_vary, run_sweep
from billiard.sweep.progress import SweepProgress

BEGIN, END = "<!-- sweep-bench -->", "<!-- /sweep-bench -->"


class _Silent:
    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


def _timed(sweep: Sweep, workers: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        progress = SweepProgress(sweep.size, stream=_Silent())
        started = time.perf_counter()
        outcome = run_sweep(sweep, Path(tmp) / "s", workers=workers, progress=progress, plots=False)
        wall = time.perf_counter() - started
        impacts = sum(int(r["total_impacts"]) for r in outcome.records)
        digest = hashlib.sha256(outcome.result.read_bytes()).hexdigest()
    return {"workers": workers, "wall": wall, "impacts": impacts, "sha256": digest}


def throughput(points: int, impacts: int, repeats: int) -> dict:
    """The same sweep (parabola at the calibrated amplitude, frequencies 5.0 to 5.8 Hz:
    period-two orbits of even cost) on 1 and 2 workers, alternating, ``repeats`` times."""
    sweep = Sweep(
        load_scene("parabola-5.4hz"),
        (parse_vary(f"drive.frequency=5.0:5.8:{points}"),),
        impacts=impacts,
        transient=500,
    )
    runs: dict[int, list[dict]] = {1: [], 2: []}
    for _ in range(repeats):
        for workers in (1, 2):
            runs[workers].append(_timed(sweep, workers))
            print(f"  {workers} worker(s): {runs[workers][-1]['wall']:.2f} s", flush=True)
    same = len({r["sha256"] for rs in runs.values() for r in rs}) == 1
    out = {"points": points, "impacts_per_point": impacts + 500, "repeats": repeats}
    for workers, rs in runs.items():
        wall = statistics.median(r["wall"] for r in rs)
        out[str(workers)] = {
            "walls": [r["wall"] for r in rs],
            "median_wall": wall,
            "points_per_s": points / wall,
            "impacts_per_s": rs[0]["impacts"] / wall,
        }
    out["speedup"] = out["1"]["median_wall"] / out["2"]["median_wall"]
    out["identical_results"] = same
    return out


def million(points: int, impacts: int) -> dict:
    """A realistic sweep of ``points x impacts`` impacts on 2 workers: the parabola over
    4 to 7 Hz (resting, periodic, lid-bouncing and chaotic points mixed)."""
    sweep = Sweep(
        load_scene("parabola-5.4hz"),
        (parse_vary(f"drive.frequency=4:7:{points}"),),
        impacts=impacts - 500,
        transient=500,
    )
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    run = _timed(sweep, 2)
    peak_kib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return {
        "points": points,
        "impacts": run["impacts"],
        "wall": run["wall"],
        "impacts_per_s": run["impacts"] / run["wall"],
        "worker_peak_rss_mib": max(peak_kib, before) / 1024,
    }


# Python's own allocation peak (tracemalloc), in kB: deterministic, unlike the
# process's peak resident size, which an allocator may serve from memory freed earlier.
_MEMORY = """
import sys, tracemalloc, billiard
scene = billiard.load_scene("wedge-6.6hz", overrides=["air.drag=none"])
billiard.simulate(scene, collisions=100)
tracemalloc.start()
billiard.simulate(scene, collisions=int(sys.argv[1])).columns
print(tracemalloc.get_traced_memory()[1] // 1024)
"""


def memory_per_impact(impacts: int = 40000) -> float:
    """Bytes of peak memory per impact of one in-memory run (a fresh interpreter)."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _MEMORY, str(impacts)], capture_output=True, text=True, check=True
    )
    return int(out.stdout.split()[-1]) * 1024 / impacts


def _busy_note(results: dict) -> list[str]:
    """A warning when the machine was not free: then 2 workers had no second core."""
    load = float(results["load"].split(",")[0])
    cpus = int(results["machine"].split(",")[1].split()[0])
    if load < 0.5 * cpus:
        return []
    return [
        f"**The machine was busy** (load average {load:.1f} on {cpus} CPUs when the "
        "measurement started, from other work): the second worker had no free core to "
        "run on, so this speed-up measures the load, not the code's scaling; measure it "
        "again on an idle machine. The points are independent and share nothing but the "
        "parent's queue (one small task and one JSON line per point), so the expected "
        "speed-up on two free cores is close to 2 minus the worker start-up (about a "
        "second per sweep).",
        "",
    ]


def render(results: dict) -> str:
    t, m = results["throughput"], results["million"]
    one, two = t["1"], t["2"]
    per_worker = m["impacts_per_s"] / 2
    worker_hours = 1e8 / per_worker / 3600
    rss = m["worker_peak_rss_mib"]
    per_impact = results["bytes_per_impact"]
    per_point = m["impacts"] // m["points"]
    largest = 1.5 * 2**30 / per_impact
    lines = [
        BEGIN,
        "## Sweeps: parallel throughput and a plan for 10^8 impacts",
        "",
        f"Measured by `{results['command']}` ({results['date']}, {results['machine']}; "
        f"load average {results['load']} at the start); a section of `billiard bench`, "
        "kept when the rest of the page is rewritten.",
        "",
        f"**1 against 2 worker processes.** The same sweep, {t['points']} points of "
        f"{t['impacts_per_point']} impacts (the parabola at 25.43 mm, 5.0 to 5.8 Hz: "
        f"period-two orbits of even cost), run {t['repeats']} times on each, alternating; "
        "wall time from the call to the finished result file (worker start-up and point "
        "checks included), medians:",
        "",
        "| workers | median wall (s) | all runs (s) | points/s | impacts/s (aggregate) |",
        "| --- | --- | --- | --- | --- |",
    ]
    for workers, row in (("1", one), ("2", two)):
        walls = ", ".join(f"{w:.2f}" for w in row["walls"])
        lines.append(
            f"| {workers} | {row['median_wall']:.2f} | {walls} | {row['points_per_s']:.2f} | "
            f"{row['impacts_per_s']:,.0f} |"
        )
    lines += [
        "",
        f"Speed-up with 2 workers: **{t['speedup']:.2f}x** (target >= 1.8x). The result "
        f"files of all {2 * t['repeats']} runs are byte-identical: "
        f"{'yes' if t['identical_results'] else 'NO'}. With the compiled engine a point "
        "of 5,000 impacts takes milliseconds, so each worker's own start-up (importing "
        "numba and loading the cached kernels, about a second) and the points' checks "
        "weigh on a sweep this short; the long sweep below is the measure of throughput.",
        "",
        *_busy_note(results),
        f"**A measured {m['impacts']:,}-impact sweep.** {m['points']} points over 4 to 7 "
        "Hz (resting, periodic, lid-bouncing and irregular points mixed), "
        f"{m['impacts']:,} impacts in "
        f"{m['wall']:.0f} s on 2 workers: {m['impacts_per_s']:,.0f} impacts/s in "
        f"aggregate, {per_worker:,.0f} per worker; peak memory of a worker process "
        f"{rss:.0f} MiB.",
        "",
        "**Plan for a 10^8-impact sweep on a cluster** (`billiard sweep ... --dask "
        "tcp://scheduler:8786`), scaled from that run:",
        "",
        f"* work: 10^8 / {per_worker:,.0f} impacts/s = **{worker_hours:.1f} worker-hours** "
        "(one worker = one core, one thread: the compiled loop releases the GIL but the "
        "rest of a point is Python that holds it, so start Dask workers with "
        "`--nthreads 1` and as many workers as cores).",
        f"* 64 workers (e.g. four 16-core nodes): **{worker_hours / 64 * 60:.1f} min**; "
        f"16 workers: {worker_hours / 16 * 60:.1f} min. Points are independent, so the time "
        "scales with 1/workers as long as there are several points per worker: cut the "
        "sweep into at least 10x as many points as workers (e.g. 2 x 10^4 points of "
        "5,000 impacts), so the last points do not leave most workers idle.",
        f"* memory: a worker holds one point's impacts in memory while it measures them "
        f"({per_impact:.0f} bytes per impact at the peak, measured on a 40,000-impact run), "
        f"on top of the interpreter: {rss:.0f} MiB peak per worker measured with "
        f"{per_point:,}-impact points. Give each worker 2 GiB and keep points below "
        f"{largest:,.0f} impacts (memory grows with impacts per point, not with the "
        "number of points).",
        "* output: the parent process appends each chunk of points to `points.npy` "
        "(1,696 bytes per point with `--keep 100`: 34 MB for 2 x 10^4 points) and writes "
        "`sweep.nc` (about the same size) at the end; the scheduler sees one task per "
        "chunk of points (up to 4096, at least four chunks per worker).",
        "* interruptions: a lost worker or a stopped parent loses only the chunks in "
        "flight (at most two per worker thread); `--resume DIR` computes the rest.",
        "* check before the big run: run a 10^6-impact slice of the same sweep with the "
        "same options on the cluster and scale its wall time by 100 / (its share of "
        "workers), as here.",
        END,
    ]
    return "\n".join(lines) + "\n"


def measure(quick: bool) -> dict:
    """All the sweep measurements (throughput on 1 and 2 workers, the 10^6-impact sweep,
    memory per impact)."""
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    if quick:
        sizes = {"throughput": (8, 1500, 2), "million": (40, 2500)}
    else:
        sizes = {"throughput": (16, 4500, 3), "million": (200, 5000)}
    print("bench.sweep: 1 and 2 workers ...", flush=True)
    t = throughput(*sizes["throughput"])
    print(f"bench.sweep: speed-up {t['speedup']:.2f}x; the 10^6-impact sweep ...", flush=True)
    m = million(*sizes["million"])
    print("bench.sweep: memory per impact ...", flush=True)
    per_impact = memory_per_impact()
    return {
        "bytes_per_impact": per_impact,
        "command": "billiard bench --only sweep" + (" --quick" if quick else ""),
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "machine": f"Python {platform.python_version()}, {os.cpu_count()} CPUs",
        "load": load,
        "throughput": t,
        "million": m,
    }


def saved_results(docs: Path) -> Path:
    return docs / "figures" / "sweeps" / "bench.json"


def publish(docs: Path, results: dict | None = None) -> bool:
    """Save ``results`` (when given) and write the sweep section of
    ``docs/performance.md`` from the saved results; False when there are none."""
    return publish_section(
        saved_results(docs), docs / "performance.md", render, BEGIN, END, results
    )


def main(argv: list[str] | None = None) -> int:
    args, docs = section_arguments(
        "python -m bench.sweep", __doc__, "small sizes, about a minute", argv
    )
    publish(docs, None if args.render else measure(args.quick))
    print(f"bench.sweep: wrote the sweep section of {docs / 'performance.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
