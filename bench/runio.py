"""Section ``io``: a run's files. What writing them costs beyond the physics, their bytes
per impact, how long reading a run back into numpy and pandas takes, and ``billiard plot``
of a long run, for a run stored as CSV (``collisions.csv``) and as binary rows
(``collisions.npy``, ``billiard run --store npy``), against the targets of the issue
"Results where users work".

Every time is the wall time of a fresh process's call, imports and start-up excluded
(the plot: the whole command), the median of several runs taken alternately; the files
are in the page cache, as they are right after a run.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench.markdown import table

SCENE = "wedge-6.6hz"
#: impacts of the run measured (full, quick)
IMPACTS = {False: 1_000_000, True: 50_000}
#: runs of each write and read measurement, and of the plot (full, quick)
REPEATS = {False: 5, True: 2}
PLOT_REPEATS = {False: 3, True: 1}
#: the targets: seconds to read 10^6 impacts, microseconds of writing per impact
#: beyond the physics, bytes per impact, seconds of `billiard plot` of 10^6 impacts
TARGETS = {"read_s": 1.0, "write_us": 0.2, "bytes": 150.0, "plot_s": 5.0}

# a run in a fresh process, timed from after a warm-up run (numba's cache loaded):
# "discard" keeps no row at all (the physics alone), "memory" keeps them as simulate()
# does, "npy" and "csv" stream them to a run folder as billiard run does
_RUN = """
import sys, time
from billiard.run.simulate import Simulation, simulate
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
how, impacts, out, name = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
scene = load_scene(name)
class Discard(MemoryRecorder):
    def append_rows(self, block):
        pass
simulate(scene, collisions=100)
start = time.perf_counter()
if how == "discard":
    Simulation(scene).run(impacts, Discard())
elif how == "memory":
    simulate(scene, collisions=impacts)
else:
    simulate(scene, collisions=impacts, out_dir=out, store=how)
print(time.perf_counter() - start)
"""

# reading a run's impacts: every value in memory at the end (a binary file is mapped:
# opening it reads nothing, so "numpy" copies every column out of it)
_READ = """
import sys, time
import numpy as np
import billiard
how, path = sys.argv[1], sys.argv[2]
if how.startswith("pandas"):
    try:
        import pandas as pd
    except ImportError:
        print("none")
        raise SystemExit(0)
start = time.perf_counter()
if how == "numpy":
    columns = {k: np.array(v) for k, v in billiard.read_collisions(path).items()}
elif how == "open":
    columns = billiard.read_collisions(path)
elif how == "pandas":
    frame = pd.DataFrame(billiard.read_collisions(path))
elif how == "pandas read_csv":
    frame = pd.read_csv(path)
print(time.perf_counter() - start)
"""

#: (label, reading, file) of the reads measured
READS = (
    ("binary into numpy, every value", "numpy", "npy"),
    ("binary opened (mapped, lazy)", "open", "npy"),
    ("binary into pandas", "pandas", "npy"),
    ("CSV into numpy (read_collisions)", "numpy", "csv"),
    ("CSV into pandas (pandas.read_csv)", "pandas read_csv", "csv"),
)
WRITES = ("discard", "memory", "npy", "csv")


def _seconds(script: str, *args: str) -> float | None:
    done = subprocess.run(
        [sys.executable, "-c", script, *args], capture_output=True, text=True, check=True
    )
    last = done.stdout.split()[-1]
    return None if last == "none" else float(last)


def _plot_seconds(folder: Path, out: Path) -> float:
    import time

    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "billiard.cli", "plot", str(folder), "--out", str(out)],
        capture_output=True,
        text=True,
        check=True,
    )
    return time.perf_counter() - start


def _median(values: list[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return statistics.median(known) if known else None


def measure(quick: bool) -> dict:
    impacts, repeats = IMPACTS[quick], REPEATS[quick]
    with tempfile.TemporaryDirectory() as tmp:
        folders = {store: Path(tmp) / store for store in ("npy", "csv")}
        writes: dict[str, list[float]] = {how: [] for how in WRITES}
        for _ in range(repeats):
            for how in WRITES:
                out = str(folders.get(how, Path(tmp) / "none"))
                seconds = _seconds(_RUN, how, str(impacts), out, SCENE)
                writes[how].append(float(seconds or 0.0))
                print(f"  write {how}: {seconds:.3f} s", flush=True)
        files = {store: folders[store] / f"collisions.{store}" for store in ("npy", "csv")}
        sizes = {store: files[store].stat().st_size for store in files}
        reads = {label: [] for label, _, _ in READS}
        for _ in range(repeats):
            for label, how, store in READS:
                reads[label].append(_seconds(_READ, how, str(files[store])))
        print("  reads: " + ", ".join(f"{k} {_median(v)}" for k, v in reads.items()), flush=True)
        plots: dict[str, list[float]] = {"npy": [], "csv": []}
        for _ in range(PLOT_REPEATS[quick]):
            for store in plots:
                plots[store].append(_plot_seconds(folders[store], Path(tmp) / f"plots-{store}"))
        print(f"  plot: {plots}", flush=True)
    try:
        import pandas

        pandas_version = pandas.__version__
    except ImportError:
        pandas_version = None
    median_writes = {how: statistics.median(v) for how, v in writes.items()}
    return {
        "scene": SCENE,
        "impacts": impacts,
        "repeats": repeats,
        "writes": writes,
        "write_median": median_writes,
        "bytes": sizes,
        "reads": reads,
        "read_median": {k: _median(v) for k, v in reads.items()},
        "plots": plots,
        "plot_median": {k: statistics.median(v) for k, v in plots.items()},
        "pandas": pandas_version,
        "numpy": __import__("numpy").__version__,
        "targets": TARGETS,
        "cpus": os.cpu_count(),
    }


# ---------------------------------------------------------------------------- results


def _per_impact_us(io: dict, how: str, baseline: str) -> float:
    m = io["write_median"]
    return (m[how] - m[baseline]) / io["impacts"] * 1e6


def _met(ok: bool) -> str:
    return "met" if ok else "missed"


def _s(x: float | None) -> str:
    return "-" if x is None else f"{x:.2f} s"


def target_rows(io: dict) -> list[list[str]]:
    """target, measured, verdict: the four targets of the section. The times to read
    and to plot are judged on a run of 10^6 impacts only (quick mode measures fewer: "-");
    bytes and microseconds per impact on any."""
    t = io["targets"]
    n = io["impacts"]
    full = n == 10**6
    size = "" if full else f" ({n:,} impacts: judged at 10^6 only)"
    r = io["read_median"]
    npy_numpy = r["binary into numpy, every value"]
    npy_pandas = r["binary into pandas"]
    reads = [x for x in (npy_numpy, npy_pandas) if x is not None]
    write = _per_impact_us(io, "npy", "discard")
    per = io["bytes"]["npy"] / n
    plot = io["plot_median"]["npy"]
    return [
        [
            f"reading a 10^6-impact run into numpy or pandas <= {t['read_s']:g} s",
            f"binary: numpy {_s(npy_numpy)}, pandas {_s(npy_pandas)}{size}",
            _met(bool(reads) and max(reads) <= t["read_s"]) if full else "-",
        ],
        [
            f"writing costs <= {t['write_us']:g} us per impact beyond the physics",
            f"binary: {write:.2f} us per impact (a run storing collisions.npy against one "
            f"keeping no row)",
            _met(write <= t["write_us"]),
        ],
        [
            f"file <= {t['bytes']:.0f} bytes per impact",
            f"collisions.npy: {per:.0f} bytes",
            _met(per <= t["bytes"]),
        ],
        [
            f"`billiard plot` of a 10^6-impact run <= {t['plot_s']:g} s",
            f"binary run: {_s(plot)}{size}",
            _met(plot <= t["plot_s"]) if full else "-",
        ],
    ]


def page_section(io: dict, link: str) -> str:
    """performance.md's section: the targets' verdicts, in words."""
    n = io["impacts"]
    r = io["read_median"]
    m = io["write_median"]
    rows = [
        ["bytes per impact", f"{io['bytes']['csv'] / n:.0f}", f"{io['bytes']['npy'] / n:.0f}"],
        [
            "run, s (keeping no row: " + f"{m['discard']:.2f} s)",
            f"{m['csv']:.2f}",
            f"{m['npy']:.2f}",
        ],
        [
            "writing beyond the physics, us per impact",
            f"{_per_impact_us(io, 'csv', 'discard'):.2f}",
            f"{_per_impact_us(io, 'npy', 'discard'):.2f}",
        ],
        [
            "read into numpy, s",
            _s(r["CSV into numpy (read_collisions)"]).removesuffix(" s"),
            _s(r["binary into numpy, every value"]).removesuffix(" s"),
        ],
        [
            "read into pandas, s",
            _s(r["CSV into pandas (pandas.read_csv)"]).removesuffix(" s"),
            _s(r["binary into pandas"]).removesuffix(" s"),
        ],
        [
            "`billiard plot`, s",
            f"{io['plot_median']['csv']:.1f}",
            f"{io['plot_median']['npy']:.1f}",
        ],
    ]
    verdicts = [row[2] for row in target_rows(io)]
    met = sum(v == "met" for v in verdicts)
    judged = sum(v != "-" for v in verdicts)
    return "\n".join(
        [
            "## 7. Run files: writing, reading, plotting\n",
            f"A run of {n:,} impacts of {io['scene']} stored as CSV (`collisions.csv`) and "
            "as binary rows (`collisions.npy`, `billiard run --store npy`): what each "
            "costs to write, its size, reading it back, and `billiard plot` of it; fresh "
            f"processes, medians ({link}). {met} of the {judged} targets judged are met.\n",
            table(["", "CSV", "binary"], rows) + "\n",
            IO_CONCLUSIONS,
        ]
    )


IO_CONCLUSIONS = """What it means: the CSV file is text, every float spelled out in
up to 24 characters so that it reads back bit for bit; writing it is formatting (the
compiled formatter, on a thread of its own), reading it is parsing every number again.
The binary rows are the floats as they are in memory: written with a copy, read without
parsing (mapped, the columns are views of the file). A plot of a long CSV run spends most
of its time reading the file.
"""


def tables_section(io: dict, command: str) -> str:
    """performance-tables.md's section: every run of every measurement."""
    n = io["impacts"]
    writes = [
        [how, ", ".join(f"{v:.3f}" for v in io["writes"][how]), f"{io['write_median'][how]:.3f}"]
        for how in WRITES
    ]
    reads = [
        [
            label,
            ", ".join("-" if v is None else f"{v:.3f}" for v in io["reads"][label]),
            _s(io["read_median"][label]),
        ]
        for label, _, _ in READS
    ]
    plots = [
        [
            f"`billiard plot` of the {store} run",
            ", ".join(f"{v:.2f}" for v in io["plots"][store]),
            f"{io['plot_median'][store]:.2f} s",
        ]
        for store in ("csv", "npy")
    ]
    pandas = f"pandas {io['pandas']}" if io["pandas"] else "pandas not installed"
    return "\n".join(
        [
            "## 7. Run files: writing, reading, plotting\n",
            f"`{command} --only io`: {n:,} impacts of {io['scene']}, each measurement in "
            f"a fresh process, {io['repeats']} runs of each taken alternately (numpy "
            f"{io['numpy']}, {pandas}). Runs: the wall time of the call, after a warm-up "
            "run; *discard* keeps no row (the physics alone), *memory* keeps the rows as "
            "`simulate()` does, *npy* and *csv* stream them to a run folder with "
            "checkpoints as `billiard run` does (`store=`):\n",
            table(["run", "seconds, each run", "median s"], writes) + "\n",
            f"Bytes: collisions.csv {io['bytes']['csv']:,} ({io['bytes']['csv'] / n:.1f} "
            f"per impact), collisions.npy {io['bytes']['npy']:,} "
            f"({io['bytes']['npy'] / n:.1f} per impact, its header included).\n",
            "Reading the impacts back, the file in the page cache (a binary file opened "
            "is only mapped: *every value* copies each column out of it):\n",
            table(["read", "seconds, each run", "median"], reads) + "\n",
            table(["command", "seconds, each run", "median"], plots) + "\n",
            "Targets:\n",
            table(["target", "measured", "verdict"], target_rows(io)) + "\n",
        ]
    )
