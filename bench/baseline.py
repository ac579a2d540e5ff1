"""Before and after: start-up and time per impact of this checkout against another commit
of it, side by side in one bench run (``billiard bench --only throughput --baseline REF``).

The commit is checked out into a temporary git worktree (``git worktree add --detach``,
removed at the end). Both trees run in fresh processes of the same Python and virtual
environment, each with its own tree as the working directory and the only entry of
``PYTHONPATH``, so that ``import billiard`` finds that tree's package before any
installed copy; every process reports the files of the ``billiard`` modules it loaded
and a measurement whose files lie outside its tree is an error, not a figure.

The two trees are measured alternately, round after round, the order swapped each round,
so that the load of a shared machine falls on both; the figures are medians over all
rounds and the ratio is new / old of the medians. The processes use only the package's
public API (``from billiard import load_scene, simulate, with_values``) and its command
line (``python -m billiard.cli run``), which stay where they are when modules move.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

#: The two columns: this checkout's tree as it is, and the commit measured against it.
NEW, OLD = "new", "old"

#: The files of the billiard modules a process loaded (printed last by every script).
_MODULES = """
def _billiard_files():
    import sys
    names = [n for n in sys.modules if n == "billiard" or n.startswith("billiard.")]
    files = (getattr(sys.modules[n], "__file__", None) for n in names)
    return sorted({f for f in files if f})
"""

# Warm start of a short run: from the interpreter's first line to the first impact, the
# kernels loaded from numba's cache (the warm-up process filled it).
_FIRST_IMPACT = (
    """
import time
start = time.perf_counter()
from billiard import load_scene, simulate
result = simulate(load_scene(__import__("sys").argv[1]), collisions=1)
first = time.perf_counter() - start
assert len(result) == 1, result.stop_reason
import json
"""
    + _MODULES
    + """
print(json.dumps({"first": first, "files": _billiard_files()}))
"""
)

# Time per impact: the run loop of simulate(), records kept in memory, as Result.wall_time
# reports it (building the simulation excluded), and the CPU time of the whole call. A
# first short run loads the kernels before any timing.
_RATE = (
    """
import json, sys, time
from billiard import load_scene, simulate, with_values
name, drag, n, repeats = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
scene = with_values(load_scene(name), {"air.drag": drag})
simulate(scene, collisions=min(n, 100))
loops, cpus = [], []
for _ in range(repeats):
    cpu0 = time.process_time()
    result = simulate(scene, collisions=n)
    cpus.append(time.process_time() - cpu0)
    loops.append(result.wall_time)
    assert len(result) == n, result.stop_reason
"""
    + _MODULES
    + """
print(json.dumps({"loops": loops, "cpus": cpus, "files": _billiard_files()}))
"""
)

#: The start-up measurements: a short run's first impact timed from the interpreter's
#: first line, the same process timed whole (interpreter start and exit included), and a
#: whole ``billiard run`` of one impact (its files written).
FIRST = "simulate() to the first impact, in the process"
PROCESS = "simulate() of 1 impact, whole process"
CLI = "billiard run --collisions 1 --no-plot, whole process"
#: The scene each start-up measurement runs.
STARTUP = {FIRST: "wedge-6.6hz", PROCESS: "wedge-6.6hz", CLI: "parabola-5.4hz"}


#: Run first in every process: ``billiard.derivation`` and ``billiard.generated`` from
#: the folders beside the tree's ``billiard/`` (the current directory), as the package's
#: own checkout finder does in later commits; in a commit without it, an editable install
#: of the main checkout would answer for them, and the process would import them from
#: outside its tree.
_PRELUDE = """
import importlib.util as _util, os as _os, sys as _sys
class _TreeFolders:
    names = {"billiard.derivation": "derivation", "billiard.generated": "generated"}
    @classmethod
    def find_spec(cls, name, path=None, target=None):
        folder = cls.names.get(name)
        if folder is None:
            return None
        folder = _os.path.join(_os.getcwd(), folder)
        init = _os.path.join(folder, "__init__.py")
        return _util.spec_from_file_location(name, init, submodule_search_locations=[folder])
_sys.meta_path.insert(0, _TreeFolders)
"""
#: ``python -m MODULE ARGS`` with the prelude first
_RUN_MODULE = "import runpy; runpy.run_module({module!r}, run_name='__main__', alter_sys=True)"


class TreeError(RuntimeError):
    """A process of one tree failed, or imported billiard from outside its tree."""


def environment(tree: Path) -> dict[str, str]:
    """The environment of a process measuring ``tree``: the tree alone on PYTHONPATH (it
    comes before site-packages, where an editable install of the checkout would answer);
    bytecode written, so that neither tree compiles its modules from source at every
    start after the warm-up (a new worktree has no ``__pycache__``). NUMBA_DISABLE_JIT
    and NUMBA_CACHE_DIR are inherited: both trees run the same way."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def check_files(tree: Path, files: list[str]) -> None:
    """Every billiard module the process loaded is a file of ``tree``."""
    root = tree.resolve()
    outside = [f for f in files if not Path(f).resolve().is_relative_to(root)]
    if not files or outside:
        found = outside[0] if outside else "no billiard module"
        more = f" and {len(outside) - 1} more" if len(outside) > 1 else ""
        raise TreeError(
            f"a process measuring {tree} imported billiard from elsewhere: {found}{more}"
        )


def _python(tree: Path, args: list[str]) -> tuple[float, str]:
    """Run ``python ARGS`` in ``tree`` (``-c CODE ...`` or ``-m MODULE ...``, the
    prelude first): (wall seconds of the process, its stdout)."""
    if args[0] == "-m":
        code = [_PRELUDE + _RUN_MODULE.format(module=args[1]), *args[2:]]
    else:
        code = [_PRELUDE + args[1], *args[2:]]
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", *code],
        cwd=tree,
        env=environment(tree),
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        what = f"python {' '.join(args[:2])}" if args[0] == "-m" else "a measuring script"
        raise TreeError(f"{what} failed in {tree} (status {done.returncode}): {last}")
    return seconds, done.stdout


def _report(tree: Path, stdout: str) -> dict:
    out = json.loads(stdout.strip().splitlines()[-1])
    check_files(tree, out.pop("files"))
    return out


def first_impact(tree: Path, scene: str) -> tuple[float, float]:
    """(wall s of the process, s from its first line to the first impact)."""
    seconds, stdout = _python(tree, ["-c", _FIRST_IMPACT, scene])
    return seconds, _report(tree, stdout)["first"]


def cli_run(tree: Path, scene: str, out: Path) -> float:
    """Wall seconds of ``python -m billiard.cli run SCENE --collisions 1 --no-plot``."""
    command = ["-m", "billiard.cli", "run", scene, "--collisions", "1", "--no-plot"]
    seconds, _ = _python(tree, [*command, "--out", str(out), "--overwrite"])
    return seconds


def rate(tree: Path, scene: str, drag: str, impacts: int, repeats: int) -> dict:
    """``repeats`` in-memory runs of ``impacts`` impacts in one fresh process."""
    _, stdout = _python(tree, ["-c", _RATE, scene, drag, str(impacts), str(repeats)])
    return _report(tree, stdout)


def warm_up(tree: Path, scenes: tuple[str, ...]) -> float:
    """One process per tree before any timing: numba compiles the tree's kernels into
    its cache where they are not there yet (a new worktree: 20-60 s), Python writes its
    bytecode; the command line's own compiled functions are loaded once too."""
    start = time.perf_counter()
    for scene in scenes:
        for drag in ("fowles", "none"):
            rate(tree, scene, drag, 10, 1)
    with tempfile.TemporaryDirectory() as tmp:
        cli_run(tree, STARTUP[CLI], Path(tmp) / "run")
    return time.perf_counter() - start


def resolve(root: Path, ref: str) -> dict[str, str]:
    """The commit ``ref`` names in ``root``'s repository: ref, full hash, short hash and
    subject. Raises TreeError when git is missing or ``ref`` is no commit there."""
    if not ref or ref.startswith("-"):
        raise TreeError(f"{ref!r} is not a commit of the repository at {root}")
    try:
        done = subprocess.run(
            ["git", "rev-parse", "--verify", "--quiet", f"{ref}^{{commit}}"],
            cwd=root,
            capture_output=True,
            text=True,
        )
    except OSError as exc:
        raise TreeError(f"git is needed to check out {ref!r} ({exc.strerror})") from None
    if done.returncode != 0 and "not a git repository" in done.stderr:
        raise TreeError(f"the checkout {root} is not a git repository")
    commit = done.stdout.strip()
    if done.returncode != 0 or not commit:
        raise TreeError(f"{ref!r} is not a commit of the repository at {root}")
    shown = subprocess.run(
        ["git", "log", "-1", "--format=%h%x00%s", commit],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    short, subject = shown.split("\0", 1)
    return {"ref": ref, "commit": commit, "short": short, "subject": subject}


@contextlib.contextmanager
def worktree(root: Path, commit: str) -> Iterator[Path]:
    """A temporary detached worktree of ``commit``, removed (with what the runs wrote in
    it: bytecode, numba's cache) when the block ends, however it ends."""
    path = Path(tempfile.mkdtemp(prefix="billiard-baseline-"))
    try:
        done = subprocess.run(
            ["git", "worktree", "add", "--detach", "--quiet", str(path), commit],
            cwd=root,
            capture_output=True,
            text=True,
        )
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            raise TreeError(f"git worktree add of {commit[:12]} failed: {last}")
        yield path
    finally:
        subprocess.run(
            ["git", "worktree", "remove", "--force", str(path)], cwd=root, capture_output=True
        )
        shutil.rmtree(path, ignore_errors=True)
        subprocess.run(["git", "worktree", "prune"], cwd=root, capture_output=True)


def _median_ratio(new: list[float], old: list[float]) -> float:
    return statistics.median(new) / statistics.median(old)


def _column(times: list[float]) -> dict:
    return {"times": times, "median": statistics.median(times)}


def compare(
    trees: dict[str, Path],
    scenes: tuple[str, ...],
    drags: tuple[str, ...],
    impacts: int,
    repeats: int,
    rounds: int,
    startup_rounds: int,
) -> dict:
    """Measure both trees, alternately: ``startup_rounds`` rounds of the start-up
    processes, then ``rounds`` rounds of one rate process per scene and drag setting
    (``repeats`` runs of ``impacts`` impacts each). Keys of ``trees``: NEW and OLD."""
    names = (NEW, OLD)
    for name in names:
        took = warm_up(trees[name], scenes)
        print(f"  baseline: warm-up of {name} ({trees[name]}) took {took:.0f} s", flush=True)
    startup: dict[str, dict[str, list[float]]] = {
        label: {n: [] for n in names} for label in STARTUP
    }
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(startup_rounds):
            for name in names if k % 2 == 0 else names[::-1]:
                tree = trees[name]
                wall, first = first_impact(tree, STARTUP[FIRST])
                startup[FIRST][name].append(first)
                startup[PROCESS][name].append(wall)
                startup[CLI][name].append(cli_run(tree, STARTUP[CLI], Path(tmp) / "run"))
    startup_rows = []
    for label, scene in STARTUP.items():
        t = startup[label]
        row = {"what": label, "scene": scene, **{n: _column(t[n]) for n in names}}
        row["ratio"] = row[NEW]["median"] / row[OLD]["median"]
        startup_rows.append(row)
        print(
            f"  baseline: {label} ({scene}): new {row[NEW]['median']:.3f} s, "
            f"old {row[OLD]['median']:.3f} s ({row['ratio']:.2f}x)",
            flush=True,
        )
    rate_rows = []
    for drag in drags:
        for scene in scenes:
            runs: dict[str, list[dict]] = {n: [] for n in names}
            for k in range(rounds):
                for name in names if k % 2 == 0 else names[::-1]:
                    runs[name].append(rate(trees[name], scene, drag, impacts, repeats))
            row = {"scene": scene, "drag": drag, "impacts": impacts, "repeats": repeats}
            for name in names:
                loops = [x for r in runs[name] for x in r["loops"]]
                cpus = [x for r in runs[name] for x in r["cpus"]]
                row[name] = {
                    "loops": loops,
                    "cpus": cpus,
                    "per_impact": statistics.median(loops) / impacts,
                    "cpu_per_impact": statistics.median(cpus) / impacts,
                }
            row["ratio"] = row[NEW]["per_impact"] / row[OLD]["per_impact"]
            row["cpu_ratio"] = row[NEW]["cpu_per_impact"] / row[OLD]["cpu_per_impact"]
            # each round's pair of processes, one right after the other: how far the
            # load moved the ratio
            row["round_ratios"] = [
                _median_ratio(a["loops"], b["loops"])
                for a, b in zip(runs[NEW], runs[OLD], strict=True)
            ]
            rate_rows.append(row)
            print(
                f"  baseline: {scene} drag={drag}: new {row[NEW]['per_impact'] * 1e6:.2f} "
                f"us/impact, old {row[OLD]['per_impact'] * 1e6:.2f} ({row['ratio']:.2f}x)",
                flush=True,
            )
    return {"startup": startup_rows, "rates": rate_rows}


def engine() -> dict:
    """How the processes of both trees ran the kernels (one Python, one environment):
    compiled, unless NUMBA_DISABLE_JIT is set or numba is missing. Read from the
    environment, not from this process's billiard, which may have been imported under
    another setting."""
    if os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0"):
        return {"compiled": False, "problem": "NUMBA_DISABLE_JIT is set"}
    if importlib.util.find_spec("numba") is None:
        return {"compiled": False, "problem": "numba is not installed"}
    return {"compiled": True, "problem": None}


def measure(
    root: Path,
    commit: dict[str, str],
    scenes: tuple[str, ...],
    impacts: int,
    repeats: int,
    rounds: int,
    startup_rounds: int,
    drags: tuple[str, ...] = ("fowles", "none"),
) -> dict:
    """This checkout (``root``, as it is) against ``commit`` (from :func:`resolve`)."""
    from bench.version import code_version

    print(f"  baseline: {commit['short']} ({commit['ref']}) in a temporary worktree", flush=True)
    with worktree(root, commit["commit"]) as old:
        trees = {NEW: root, OLD: old}
        result = compare(trees, scenes, drags, impacts, repeats, rounds, startup_rounds)
    return {
        **commit,
        "new": code_version(),
        "engine": engine(),
        "rounds": rounds,
        "startup_rounds": startup_rounds,
        **result,
    }


def summary(b: dict) -> str:
    """The before-and-after figures as the terminal shows them at the end of the bench."""
    drag = {"fowles": "on", "none": "off"}
    lines = [
        f"bench: this code ({b['new']}) against {b['short']} (--baseline {b['ref']}), medians:"
    ]
    lines += [
        f"  {r['what']:<55} new {r[NEW]['median']:7.3f} s  old {r[OLD]['median']:7.3f} s  "
        f"new/old {r['ratio']:.2f}x"
        for r in b["startup"]
    ]
    lines += [
        f"  {'us per impact, ' + r['scene'] + ' drag ' + drag[r['drag']]:<55} "
        f"new {r[NEW]['per_impact'] * 1e6:7.2f}    old {r[OLD]['per_impact'] * 1e6:7.2f}    "
        f"new/old {r['ratio']:.2f}x"
        for r in b["rates"]
    ]
    return "\n".join(lines)
