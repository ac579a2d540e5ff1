"""Throughput, start-up time, peak memory and a profile of the default method."""

from __future__ import annotations

import cProfile
import json
import os
import pstats
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene

_MEMORY_SCRIPT = """
import resource, sys, time
from billiard.scene.scene import load_scene
from billiard.run.simulate import simulate
n, out = int(sys.argv[1]), sys.argv[2]
start = time.perf_counter()
if n:
    result = simulate(load_scene(sys.argv[3]), collisions=n, out_dir=out)
    assert len(result) == n, result.stop_reason
hwm = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM"))
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(hwm, rss, time.perf_counter() - start)
"""


#: The issue's targets for the compiled engine (CPU per impact in s, walls in s, MB).
TARGETS = {
    "ratio": 30.0,
    "cpu_wedge": 1e-6,
    "cpu_parabola_drag": 3e-6,
    "wall_25000": 0.6,
    "wall_million": 2.0,
    "peak_million_mb": 200.0,
    "warm_start": 0.6,
    "cold_compile": 20.0,
}

# One engine measured in a fresh process: NUMBA_DISABLE_JIT=1 in its environment makes it
# the interpreted reference, the same kernels run by CPython. The run loop only is timed
# (building the simulation excluded, as in Result.wall_time); the first short run loads
# the compiled kernels from numba's cache (or compiles them) before any timing.
_RATE_SCRIPT = """
import json, statistics, sys, time
from billiard import jit
from billiard.engine.simulation import Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene, with_values
name, drag, n, repeats = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
scene = with_values(load_scene(name), {"air.drag": drag})
Simulation(scene).run(min(n, 100), MemoryRecorder())
walls, cpus = [], []
for _ in range(repeats):
    sim = Simulation(scene)
    recorder = MemoryRecorder()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    stop = sim.run(n, recorder)
    cpus.append(time.process_time() - cpu0)
    walls.append(time.perf_counter() - wall0)
    assert not stop and len(recorder) == n, stop
print(json.dumps({"compiled": jit.ENABLED, "walls": walls, "cpus": cpus}))
"""


def _engine_env(interpreted: bool) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    if interpreted:
        env["NUMBA_DISABLE_JIT"] = "1"
    return env


def engine_rate(name: str, drag: str, impacts: int, repeats: int, interpreted: bool) -> dict:
    """CPU seconds per impact (median of ``repeats`` in-memory runs in one fresh process)
    of the compiled engine, or of the same kernels interpreted."""
    done = subprocess.run(
        [sys.executable, "-c", _RATE_SCRIPT, name, drag, str(impacts), str(repeats)],
        env=_engine_env(interpreted),
        capture_output=True,
        text=True,
        check=True,
    )
    out = json.loads(done.stdout.splitlines()[-1])
    cpu = statistics.median(out["cpus"])
    return {
        "compiled": out["compiled"],
        "impacts": impacts,
        "cpus": out["cpus"],
        "walls": out["walls"],
        "cpu": cpu,
        "cpu_per_impact": cpu / impacts,
        "wall": statistics.median(out["walls"]),
    }


def impact_rate(
    name: str, impacts: int, repeats: int, drag: str = "fowles", interpreted_impacts: int = 0
) -> dict:
    """The compiled engine against the interpreted one on a built-in scene: CPU per
    impact of the run loop, medians, both measured in this bench run."""
    fast = engine_rate(name, drag, impacts, repeats, interpreted=False)
    slow = engine_rate(name, drag, interpreted_impacts or impacts, repeats, interpreted=True)
    print(
        f"  {name} drag={drag}: compiled {fast['cpu_per_impact'] * 1e6:.2f} us/impact, "
        f"interpreted {slow['cpu_per_impact'] * 1e6:.1f} us/impact",
        flush=True,
    )
    return {
        "scene": name,
        "drag": drag,
        "impacts": impacts,
        "compiled": fast,
        "interpreted": slow,
        "ratio": slow["cpu_per_impact"] / fast["cpu_per_impact"],
        # the fields of the earlier, engine-agnostic table
        "times": fast["walls"],
        "median": fast["wall"],
        "cpu": fast["cpu"],
        "rate": impacts / fast["wall"],
        "per_25000": 25000 * fast["wall"] / impacts,
    }


_FIRST_IMPACT = """
import time
start = time.perf_counter()
from billiard.engine.simulation import Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
Simulation(load_scene({name!r})).run(1, MemoryRecorder())
print(time.perf_counter() - start)
"""


def first_impact(name: str, repeats: int, cache_dir: str | None = None) -> list[float]:
    """Wall seconds from a fresh interpreter's first line to the first impact (the
    kernels loaded from the cache; with ``cache_dir`` an empty cache: compiled)."""
    env = _engine_env(False)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    times = []
    for _ in range(repeats):
        done = subprocess.run(
            [sys.executable, "-c", _FIRST_IMPACT.format(name=name)],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        times.append(float(done.stdout.split()[-1]))
    return times


def bytecode_state() -> dict:
    """How many of billiard's modules have current bytecode (``__pycache__``): without it
    every start compiles them from source, about 0.1 s (a fresh checkout run with
    ``PYTHONDONTWRITEBYTECODE`` set, which never writes it)."""
    import importlib.util

    package = Path(__file__).resolve().parent.parent / "billiard"
    sources = sorted(package.rglob("*.py"))
    current = 0
    for source in sources:
        cached = Path(importlib.util.cache_from_source(str(source)))
        try:
            header = cached.read_bytes()[:16]
        except OSError:
            continue
        stat = source.stat()
        mtime = int.from_bytes(header[8:12], "little")
        size = int.from_bytes(header[12:16], "little")
        flags = int.from_bytes(header[4:8], "little")
        if flags == 0 and mtime == int(stat.st_mtime) & 0xFFFFFFFF and size == stat.st_size:
            current += 1
    return {
        "current": current,
        "modules": len(sources),
        "dont_write": bool(os.environ.get("PYTHONDONTWRITEBYTECODE")),
    }


def whole_runs(scenes: tuple[str, ...], impacts: int, repeats: int) -> list[dict]:
    """Wall seconds of a fresh process, start-up included: ``billiard run SCENE
    --collisions N --no-plot`` (the CSV written) and the in-memory ``simulate`` call."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in scenes:
            commands = {
                "billiard run": billiard_command()
                + [
                    "run",
                    name,
                    "--collisions",
                    str(impacts),
                    "--no-plot",
                    "--out",
                    "run",
                    "--overwrite",
                ],
                "simulate() in memory": [
                    sys.executable,
                    "-c",
                    "import sys; from billiard import load_scene, simulate; "
                    "r = simulate(load_scene(sys.argv[1]), collisions=int(sys.argv[2])); "
                    "assert len(r) == int(sys.argv[2]), r.stop_reason",
                    name,
                    str(impacts),
                ],
            }
            for label, command in commands.items():
                times = [wall(command, tmp) for _ in range(repeats)]
                rows.append(
                    {
                        "scene": name,
                        "how": label,
                        "impacts": impacts,
                        "times": times,
                        "median": statistics.median(times),
                    }
                )
                print(f"  {label} {name} {impacts}: {rows[-1]['median']:.2f} s", flush=True)
    return rows


_MILLION_SCRIPT = """
import sys, time
from billiard.scene.scene import load_scene
from billiard.run.simulate import simulate
n, out, name = int(sys.argv[1]), sys.argv[2], sys.argv[3]
start = time.perf_counter()
result = simulate(load_scene(name), collisions=n, out_dir=out or None)
assert len(result) == n, result.stop_reason
seconds = time.perf_counter() - start
status = dict(line.split(":", 1) for line in open("/proc/self/status"))
kb = [status[key].split()[0] for key in ("VmHWM", "RssFile", "RssAnon")]
print(*kb, seconds)
"""


def million(name: str, impacts: int) -> list[dict]:
    """Wall time (the run call, start-up excluded) and peak memory (VmHWM) of a fresh
    process running ``impacts`` impacts in memory and streamed to collisions.csv."""
    rows = []
    for how in ("in memory", "streamed to collisions.csv"):
        tmp = tempfile.mkdtemp()
        try:
            out = tmp if how.startswith("streamed") else ""
            done = subprocess.run(
                [sys.executable, "-c", _MILLION_SCRIPT, str(impacts), out, name],
                env=_engine_env(False),
                capture_output=True,
                text=True,
                check=True,
            )
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        hwm, file_kb, anon_kb, seconds = done.stdout.split()[-4:]
        rows.append(
            {
                "scene": name,
                "how": how,
                "impacts": impacts,
                "wall": float(seconds),
                "peak_mb": int(hwm) / 1024.0,
                # at the end of the run: mapped files (numba's LLVM library, ~100 MB,
                # shared between processes) and the process's own memory
                "file_mb": int(file_kb) / 1024.0,
                "anon_mb": int(anon_kb) / 1024.0,
            }
        )
        print(f"  {how} {name} {impacts}: {float(seconds):.2f} s, {int(hwm) / 1024:.0f} MB")
    return rows


def compiled_startup(name: str, repeats: int) -> dict:
    """Warm start-up to the first impact (median of ``repeats``) and one cold compile."""
    warm = first_impact(name, repeats)
    with tempfile.TemporaryDirectory() as cold_dir:
        cold = first_impact(name, 1, cold_dir)
    return {
        "scene": name,
        "warm": warm,
        "warm_median": statistics.median(warm),
        "cold": cold[0],
    }


def engine_info() -> dict:
    from billiard import jit

    info: dict = {"compiled": jit.ENABLED, "problem": jit.numba_problem()}
    if jit.ENABLED:
        import numba

        info["numba"] = numba.__version__
    return info


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
        "import billiard.run.simulate": [
            py,
            "-c",
            "import billiard.run.simulate, billiard.scene.scene",
        ],
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
    """cProfile of one run: the functions with the most own time. A short run first
    loads the compiled kernels, so that the profile is of a run, not of start-up."""
    scene = load_scene(name)
    simulate(scene, collisions=10)
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
