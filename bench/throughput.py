"""Throughput, start-up time, peak memory and a profile of the default method."""

from __future__ import annotations

import cProfile
import pstats
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from billiard.record import MemoryRecorder
from billiard.scene import load_scene, with_values
from billiard.simulate import Simulation, simulate

_MEMORY_SCRIPT = """
import resource, sys, time
from billiard.scene import load_scene
from billiard.simulate import simulate
n, out = int(sys.argv[1]), sys.argv[2]
start = time.perf_counter()
if n:
    result = simulate(load_scene(sys.argv[3]), collisions=n, out_dir=out)
    assert len(result) == n, result.stop_reason
hwm = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM"))
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(hwm, rss, time.perf_counter() - start)
"""


def impact_rate(name: str, impacts: int, repeats: int, drag: str = "fowles") -> dict:
    """Median wall and CPU time of ``repeats`` in-memory runs of the built-in scene (the
    run loop only: building the simulation is excluded, as in ``Result.wall_time``)."""
    scene = with_values(load_scene(name), {"air.drag": drag})
    times, cpus = [], []
    for _ in range(repeats):
        sim = Simulation(scene)
        recorder = MemoryRecorder()
        wall0, cpu0 = time.perf_counter(), time.process_time()
        stop = sim.run(impacts, recorder)
        times.append(time.perf_counter() - wall0)
        cpus.append(time.process_time() - cpu0)
        assert not stop and len(recorder) == impacts, stop
    median = statistics.median(times)
    return {
        "scene": name,
        "drag": drag,
        "impacts": impacts,
        "times": times,
        "median": median,
        "cpu": statistics.median(cpus),
        "rate": impacts / median,
        "per_25000": 25000 * median / impacts,
    }


def billiard_command() -> list[str]:
    script = Path(sys.executable).with_name("billiard")
    return [str(script)] if script.exists() else [sys.executable, "-m", "billiard.cli"]


def wall(command: list[str], cwd: str) -> float:
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, check=True, capture_output=True)
    return time.perf_counter() - start


def startup(repeats: int) -> dict:
    """Wall time (median) of fresh processes: the interpreter alone, importing the run
    path, and ``billiard run parabola-5.4hz --collisions 1 --no-plot``."""
    py = sys.executable
    commands = {
        "python -c pass": [py, "-c", "pass"],
        "import billiard.simulate": [py, "-c", "import billiard.simulate, billiard.scene"],
        "billiard run parabola-5.4hz --collisions 1 --no-plot": billiard_command()
        + [
            "run",
            "parabola-5.4hz",
            "--collisions",
            "1",
            "--no-plot",
            "--out",
            "run",
            "--overwrite",
        ],
    }
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, command in commands.items():
            times = [wall(command, tmp) for _ in range(repeats)]
            out[label] = {"times": times, "median": statistics.median(times)}
        out["imports"] = import_times(tmp)
    return out


def import_times(cwd: str, top: int = 8) -> list[dict]:
    """The slowest top-level imports (cumulative) of ``billiard run parabola-5.4hz
    --collisions 1 --no-plot``, from ``python -X importtime``."""
    command = [
        sys.executable,
        "-X",
        "importtime",
        "-m",
        "billiard.cli",
        "run",
        "parabola-5.4hz",
        "--collisions",
        "1",
        "--no-plot",
        "--out",
        "run",
        "--overwrite",
    ]
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=True)
    rows = []
    for line in done.stderr.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)", line)
        if m and len(m.group(3)) <= 1:
            rows.append({"module": m.group(4), "cumulative_us": int(m.group(2))})
    return sorted(rows, key=lambda r: -r["cumulative_us"])[:top]


def memory(name: str, sizes: tuple[int, ...]) -> list[dict]:
    """Peak resident memory of a fresh process that runs the scene for n impacts
    streamed to disk; n = 0 is the process with the modules imported only.

    Both the peak of the process's own address space (VmHWM in /proc/self/status) and
    ``ru_maxrss`` are kept: on Linux ru_maxrss also holds the peak of the address space
    the process had before exec, i.e. of the parent that forked it (here the benchmark,
    with numpy, scipy and matplotlib loaded)."""
    rows = []
    for n in (0, *sizes):
        tmp = tempfile.mkdtemp()
        try:
            done = subprocess.run(
                [sys.executable, "-c", _MEMORY_SCRIPT, str(n), tmp, name],
                capture_output=True,
                text=True,
                check=True,
            )
            hwm, kib, seconds = done.stdout.split()
            size = (Path(tmp) / "collisions.csv").stat().st_size if n else 0
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        rows.append(
            {
                "impacts": n,
                "peak_mb": int(hwm) / 1024.0,
                "maxrss_mb": int(kib) / 1024.0,
                "wall": float(seconds),
                "csv_mb": size / 1e6,
            }
        )
        print(f"  memory {name} {n}: {int(hwm) / 1024:.1f} MB, {float(seconds):.1f} s", flush=True)
    return rows


def profile(name: str, impacts: int, top: int = 12) -> dict:
    """cProfile of one run: the functions with the most own time."""
    scene = load_scene(name)
    profiler = cProfile.Profile()
    profiler.enable()
    result = simulate(scene, collisions=impacts)
    profiler.disable()
    stats = pstats.Stats(profiler)
    total = stats.total_tt
    rows = []
    for (file, line, func), (_, calls, own, cumulative, _) in stats.stats.items():
        rows.append(
            {
                "function": f"{Path(file).name}:{line}({func})",
                "calls": calls,
                "own": own,
                "cumulative": cumulative,
                "share": own / total,
            }
        )
    rows.sort(key=lambda r: -r["own"])
    return {"scene": name, "impacts": len(result), "total": total, "top": rows[:top]}
