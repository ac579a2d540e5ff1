"""Every kernel a run can need, compiled together: one notice and one wait, once per
install or update, instead of a wait for each family of kernels on the first run that
needs it (the impact loop, again for a curve with another number of walls, the contact
phases, the CSV formatting and reading, the resting-position scan).

:func:`compile_all` is :mod:`billiard.jit`'s first-compile hook
(:func:`billiard.jit.on_first_compile`): before the first block of a process that may
compile a kernel, it looks for the mark that every kernel is in numba's cache
(:func:`billiard.jit.all_compiled`); without it, it runs :data:`JOBS` (short runs of
the paper's scenes) in :data:`WORKERS` fresh interpreters side by side, which compile
and cache what those runs need, and marks the cache. The process that asked then loads
each kernel from the cache in milliseconds. numba compiles one function at a time in a
process; two processes compile on two cores at once.

Every run is the state machine (:mod:`billiard.kernels.machine`), which links the
impact loop, the phase and the hold: the first worker compiles it for the curves of up
to two walls; the second compiles the ensemble kernels meanwhile, then waits until the
machine is in the cache (:data:`LOOP_CACHED`, :data:`WAIT_LOOP`) and runs the jobs that
load it (compiling what they add: the CSV formatting, the resting scan).

Not compiled here (each on its first use, with its own notice): method ``rk4``'s fixed
steps, a curve with more than two walls, and the wall functions of a curve other than
the wedge and the parabola (well under a second each). Where numba cannot cache (no
folder for the kernels' cache can be written) nothing is compiled ahead, and where no
worker can be started nothing is marked: each kernel compiles on its first use as
before. A worker whose run fails leaves what it did not reach to compile on first use,
and the cache is marked all the same (the workers are not started again in every
process).

The workers import this process's copy of the package, whatever folder they start in
(a source checkout's ``billiard/`` in the current folder would otherwise pass before an
installed copy, and be compiled into its own cache instead), and end with this process:
at the end of a pipe it holds (it ended, even by SIGKILL), on its way out of the wait
(KeyboardInterrupt and any other exception), and when SIGINT or SIGTERM comes under a
handler of the program's own (a run's), which also breaks off the compile.

:func:`run_jobs` runs jobs in this process: what a worker does.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from billiard import jit as _jit
from billiard.engine.interrupt import RunInterrupted

__all__ = ["ALL_NOTICE", "ALL_NOTICE_DONE", "JOBS", "WORKERS", "compile_all", "run_jobs"]

#: printed before the kernels compile together
ALL_NOTICE = (
    "billiard: compiling the engine's kernels with numba, once per install or update "
    "(about a minute on two free cores, minutes on a busy machine); cached for later runs"
)
#: printed when they are compiled
ALL_NOTICE_DONE = "billiard: compiled the engine's kernels in {seconds:.1f} s"
#: (scene, changed keys, impacts, CSV, rolling, sampled): short runs that together need
#: every kernel a run of a curve of up to two walls can need (the wall tables of such
#: curves share one type: :data:`billiard.geometry.wall_functions.WALL_SLOTS`); ``CSV``:
#: the CSV formatting too; ``rolling``: the ball starts at rest on the bowl's wall 2 mm
#: from its vertex; ``sampled``: with trajectory samples. Duration-limited where the
#: ball makes no impact.
JOBS: tuple[tuple[str, dict[str, Any], int, bool, bool, bool], ...] = (
    # the state machine: the impact loop (exact flight and air drag), the resting scan
    ("wedge-6.6hz", {}, 20, False, False, False),
    # the CSV formatting, the contact phases of a ball rolling in the bowl, then the hold
    # of a ball in the vertex
    (
        "parabola-5.4hz",
        {"drive.amplitude": 0.0, "contact.model": "phases", "run.duration": 0.05},
        1,
        True,
        True,
        True,
    ),
    (
        "wedge-6.6hz",
        {"drive.amplitude": 0.0, "contact.model": "phases", "run.duration": 0.05},
        1,
        False,
        False,
        True,
    ),
    # flights, landings and phases in one run
    ("wedge-6.6hz", {"contact.model": "phases"}, 20, False, False, False),
)
#: a worker's step that runs a small ensemble (the ensemble kernels)
ENSEMBLE_JOB = "ensemble"
#: the job after which its worker runs a small ensemble of its scene on the state
#: machine (a sweep's points under contact phases), the machine then in the cache
MACHINE_ENSEMBLE_JOB = 3
#: a worker's step that tells the other worker that the impact loop is in the cache ...
LOOP_CACHED = "loop-cached"
#: ... and the other worker's step that waits for it (at most WAIT_S seconds)
WAIT_LOOP = "wait-loop"
WAIT_S = 300.0
#: the jobs of each worker process, run side by side (numba compiles one function at a
#: time in a process: two processes compile on two cores). The state machine is compiled
#: once, by the first; the second waits for it after the ensemble kernels (numba would
#: otherwise compile the machine a second time).
WORKERS: tuple[tuple[int | str, ...], ...] = (
    (0, LOOP_CACHED),
    (ENSEMBLE_JOB, WAIT_LOOP, 1, 2, 3),
)
#: what a worker runs (``python -P -c``: the current folder not on ``sys.path``): it
#: ends when its standard input, a pipe the starting process holds, reaches its end (that
#: process ended, even by SIGKILL), imports the package from the starting process's
#: folder (``package``; never another copy, such as a source checkout in the current
#: folder beside an installed copy), and runs its jobs
_WORKER = """\
import importlib.util, os, sys, threading
def orphaned():
    sys.stdin.buffer.read()
    os._exit(1)
threading.Thread(target=orphaned, daemon=True).start()
spec = importlib.util.spec_from_file_location(
    "billiard", {init!r}, submodule_search_locations=[{package!r}]
)
sys.modules["billiard"] = module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
from billiard.engine.compile_all import run_jobs
run_jobs({jobs!r}, {package!r})
"""
#: a worker's exit status when it imported another copy of the package
WRONG_COPY = 3
#: the folder of this copy of the package (what the workers import)
_PACKAGE = Path(__file__).resolve().parents[1]
#: set in a worker's environment: its own first compile calls no hook
_WORKER_ENV = "BILLIARD_COMPILE_WORKER"
#: set in the workers' environment: the file whose existence says the loop is cached
_SIGNAL_ENV = "BILLIARD_COMPILE_SIGNAL"


def _rolling_start(scene: Any) -> dict[str, float]:
    """The initial keys of a ball at rest on the bowl's wall 2 mm from its vertex."""
    from billiard.generated import contact as _c

    p = dict(scene.boundary.parameters)
    a, c, s = p.get("a", 26.0), p.get("c", 0.0063), 2e-3
    q1, q2, _, _ = _c.centre_state(
        s, 0.0, a * s * s + c, 2 * a * s, 2 * a, 0.0, 0.0, 0.0, 0.0, scene.ball.radius
    )
    return {"initial.q1": q1, "initial.q2": q2, "initial.v1": 0.0, "initial.v2": 0.0}


def run_jobs(jobs: list[int | str], package: str | None = None) -> None:
    """Run :data:`JOBS` ``jobs`` in this process (each compiles what it needs), and the
    hand-over steps :data:`LOOP_CACHED` and :data:`WAIT_LOOP`. ``package``: the folder
    of the package the starting process imported; a worker that imported another copy
    exits with status :data:`WRONG_COPY` (it would compile into that copy's cache)."""
    if package is not None and _PACKAGE != Path(package).resolve():
        print(f"billiard: compile worker imported {_PACKAGE}, not {package}", file=sys.stderr)
        sys.exit(WRONG_COPY)
    import numpy as np

    from billiard.engine.simulation import Simulation
    from billiard.runfile.csvbulk import read_lines
    from billiard.runfile.record import COLUMNS, MemoryRecorder
    from billiard.runfile.rows import format_rows_bytes
    from billiard.scene.scene import load_scene, with_values

    handover = os.environ.get(_SIGNAL_ENV)
    for index in jobs:
        if index == LOOP_CACHED:
            if handover:
                open(handover, "w").close()
            continue
        if index == ENSEMBLE_JOB:
            _ensemble(load_scene("wedge-6.6hz"))
            continue
        if index == WAIT_LOOP:
            waited = time.monotonic() + WAIT_S
            while handover and not os.path.exists(handover) and time.monotonic() < waited:
                time.sleep(0.05)
            continue
        name, changes, impacts, csv, rolling, sampled = JOBS[int(index)]
        scene = load_scene(name)
        if rolling:
            changes = {**changes, **_rolling_start(scene)}
        scene = with_values(scene, changes)
        if csv:
            # the CSV formatting, and its reading (a run's plots read its file back)
            line = format_rows_bytes(np.zeros((1, len(COLUMNS))), "\n")
            read_lines(line, list(COLUMNS), b"\n")
        sim = Simulation(scene)
        if sampled:
            sim.sample_dt = 0.01
            sim.on_sample = _ignore
        sim.run(impacts, MemoryRecorder())
        if index == MACHINE_ENSEMBLE_JOB:
            _ensemble(scene)


def _ignore(*_: Any) -> None:
    """A trajectory sample's receiver that keeps nothing."""


def _ensemble(scene: Any) -> None:
    """A two-trajectory ensemble of ``scene``: the ensemble kernels (its start check,
    its measured loop and the reading of the kept impacts,
    :mod:`billiard.kernels.ensemble`)."""
    from billiard.engine import ensemble

    setup = ensemble.prepare(scene)
    ctxs, ok = ensemble.start(setup, [0.0, 0.01], [0.05, 0.06])
    consts = ensemble.constants(scene, 1e-5, 64, 256)
    stats, rings = ensemble.advance(
        ctxs[ok], setup.params, setup.walls, consts, transient=1, impacts=2, width=4,
        threads=1, nears=setup.nears,
    )  # fmt: skip
    ensemble.last_impacts(stats, rings, 2)


def compile_all() -> bool:
    """Compile every kernel a run can need, together, unless the cache has them all
    (or this is a worker); returns True when the workers ran and the cache is marked.

    Raises:
        RunInterrupted: SIGINT or SIGTERM under a handler of the program's own (a run's,
            which defers a stop to its next impact: there is none before the kernels);
            the workers are ended first, as on any other way out of here.
    """
    if not _jit.ENABLED or os.environ.get(_WORKER_ENV) or _jit.all_compiled():
        return False
    if not _jit.cache_stamped():
        return False  # nothing can be cached: each process compiles what it needs
    print(ALL_NOTICE, file=sys.stderr, flush=True)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="billiard-compile-") as folder:
        env = {
            **os.environ,
            _WORKER_ENV: "1",
            _SIGNAL_ENV: os.path.join(folder, "loop-cached"),
        }
        workers: list[subprocess.Popen] = []
        try:
            with _signals_stop_compile():
                try:
                    for jobs in WORKERS:
                        workers.append(_start_worker(list(jobs), env))
                except OSError:
                    return False  # no process to start: each kernel compiles on first use
                for worker in workers:
                    worker.wait()  # a signal's handler runs (and may raise) meanwhile
                    # a worker that ended without its hand-over (it failed) releases the other
                    if not os.path.exists(env[_SIGNAL_ENV]):
                        open(env[_SIGNAL_ENV], "w").close()
        finally:
            _end_workers(workers)
    _jit.mark_all_compiled()
    seconds = time.perf_counter() - started
    print(ALL_NOTICE_DONE.format(seconds=seconds), file=sys.stderr, flush=True)
    return True


def _start_worker(jobs: list[int | str], env: dict[str, str]) -> subprocess.Popen:
    """A worker process running ``jobs`` on this process's copy of the package; its
    standard input is a pipe this process holds open until the worker is ended."""
    code = _WORKER.format(init=str(_PACKAGE / "__init__.py"), package=str(_PACKAGE), jobs=jobs)
    return subprocess.Popen(
        [sys.executable, "-P", "-c", code],
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def _end_workers(workers: list[subprocess.Popen]) -> None:
    """The workers still running killed, and every worker's pipe closed."""
    for worker in workers:
        if worker.poll() is None:
            worker.kill()
        worker.wait()
        if worker.stdin is not None:
            worker.stdin.close()


@contextlib.contextmanager
def _signals_stop_compile() -> Iterator[None]:
    """SIGINT and SIGTERM also break off the compile where the program has a handler
    of its own for them (a run's turns them into a stop request at its next impact,
    which would come only after the whole compile): that handler runs, then
    :class:`RunInterrupted` is raised. Under the default handlers SIGINT raises
    KeyboardInterrupt and SIGTERM ends the process (the workers see their pipe's end),
    so these are left alone, as in any thread but the main one."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    installed: dict[int, Any] = {}

    def handler(signum: int, frame: Any) -> None:
        installed[signum](signum, frame)
        raise RunInterrupted(signum)

    for sig in (signal.SIGINT, signal.SIGTERM):
        previous = signal.getsignal(sig)
        if callable(previous) and previous is not signal.default_int_handler:
            installed[sig] = previous
            signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, previous in installed.items():
            signal.signal(sig, previous)


_jit.on_first_compile(compile_all)
