"""Running a sweep: check its size and every point, then measure the rest on an executor.

One code path for both places a sweep runs: chunks of points (:class:`ChunkTask`,
thousands of points each in a large sweep, but at least four chunks per worker) are
submitted to a ``concurrent.futures`` executor, a
:class:`~concurrent.futures.ProcessPoolExecutor` on this machine or a
``dask.distributed`` client's executor (``client.get_executor()``) on a cluster, at most
two chunks per worker in flight; on a cluster the window follows the workers present
(read again every second), so workers that join later get chunks. Each finished chunk is
appended to ``DIR/points.npy`` at once (one sync per chunk), so an interrupted sweep
keeps everything finished and ``resume`` computes only the rest.

Memory does not grow with the points finished: tasks are made one at a time as workers
free up, finished chunks go to disk and are dropped, and the result file is built from
points.npy, mapped, in arrays the size of the result.
"""

from __future__ import annotations

import array
import asyncio
import contextlib
import itertools
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
import warnings
from collections import Counter, OrderedDict
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from billiard.engine import ensemble
from billiard.lifeline import die_with_parent
from billiard.sweep.attractor import CLASSES
from billiard.sweep.columns import STATUSES, ChunkResult, empty_columns, record_of_row
from billiard.sweep.definition import Sweep, SweepError, read_sweep_file, sweep_to_toml
from billiard.sweep.ensemble import check_device
from billiard.sweep.measure import ChunkTask, measure_chunk
from billiard.sweep.netcdf import RESULT_NAME, open_result, write_result
from billiard.sweep.progress import SweepProgress
from billiard.sweep.store import (
    CHECKSUMS_NAME,
    DIGEST_NAME,
    LEGACY_POINTS_NAME,
    LOG_NAME,
    POINTS_NAME,
    REASONS_NAME,
    SCENE_NAME,
    SWEEP_NAME,
    ChunkStore,
    StoreError,
    UnverifiedSweepWarning,
    definition_digest,
    digest_lines,
    points_table,
    read_reasons,
    stored_points,
)

__all__ = [
    "SweepInterrupted",
    "SweepOutcome",
    "StopSweep",
    "check_starts",
    "chunk_size",
    "estimate_size",
    "load_sweep_dir",
    "run_sweep",
]

DASK_HINT = 'pip install "realworld-billiard[dask]"'
DATA_HINT = 'pip install "realworld-billiard[data]"'

#: Seconds to reach a Dask scheduler and hear it answer as one (``--dask``): a live
#: address that is something else (an HTTP server, the dashboard's port) must not hang.
DASK_TIMEOUT = 10.0

#: Simulated time (s) the check of a point's geometry runs at most (up to one impact),
#: when the sweep and its scene set no shorter duration: under ``contact.model =
#: "phases"`` a ball that rolls never has an impact, and the check must still end.
PRECHECK_SPAN = 1.0

#: A sweep larger than this needs ``--yes`` (``yes=True``): points, and bytes of its
#: output files (points.npy and sweep.nc).
MAX_POINTS_UNCONFIRMED = 100_000
MAX_BYTES_UNCONFIRMED = 10**9

#: Geometry checks remembered (for grids whose points share a container and start).
_CHECK_CACHE = 4096

#: Most points in one chunk (one task of a worker; one sync of points.npy).
MAX_CHUNK = 4096
#: Fewest chunks per worker (so that every worker stays busy to the end).
CHUNKS_PER_WORKER = 4
#: Seconds between two looks at a cluster's workers (the in-flight window follows them).
WORKERS_INTERVAL = 1.0


class StopSweep(Exception):
    """Raised by an ``on_point`` callback to stop the sweep (as Ctrl-C does); the chunk
    the point came in is already stored."""


class SweepInterrupted(KeyboardInterrupt):
    """The sweep stopped before every point was finished; the finished ones are kept."""

    def __init__(self, directory: Path, done: int, total: int):
        super().__init__(f"{done} of {total} points kept in {directory}")
        self.directory, self.done, self.total = directory, done, total


@dataclass(repr=False)
class SweepOutcome:
    """What :func:`run_sweep` did; :attr:`dataset` opens its result in xarray.

    Printed, it is one line (the folder, points per status and per attractor class, where
    they ran); in a notebook a small table.

    Attributes:
        directory: the sweep folder.
        result: path of the result file.
        computed: indices of the points measured in this session, in finishing order
            (an ``array`` of int64: 8 bytes per point).
        where: where the points ran (for the log and the summary).
        classes: points per attractor class.
        statuses: points per status (``ok``, ``failed``, ``invalid``).
        failed_examples: the records of the first few failed points (by index).
        plots: the plot files drawn.
    """

    directory: Path
    result: Path
    computed: array.array
    where: str
    classes: Counter = field(default_factory=Counter)
    statuses: Counter = field(default_factory=Counter)
    failed_examples: list[dict[str, Any]] = field(default_factory=list)
    plots: list[Path] = field(default_factory=list)
    sweep: Sweep | None = None

    @property
    def records(self) -> list[dict[str, Any]]:
        """Every point's record (the dict of ``measure_point``), by index, read from
        ``points.npy`` on each access (a sweep does not hold them: use ``read_result``
        for large sweeps)."""
        sweep = self.sweep if self.sweep is not None else load_sweep_dir(self.directory)
        return _records(self.directory, sweep)

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.records if r["status"] != "ok"]

    @property
    def measured(self) -> int:
        """Points measured (status ``ok``)."""
        return self.statuses.get("ok", 0)

    @property
    def dataset(self) -> Any:
        """The result file as an ``xarray.Dataset`` (opened lazily: arrays are read when
        used), coordinates the swept keys' values, missing values masked, units in each
        variable's ``attrs``, ``attractor`` as class names
        (:func:`~billiard.sweep.netcdf.open_result`); e.g.
        ``outcome.dataset.height_mean.sel(drive_amplitude=0.027)``.

        Raises:
            ModuleNotFoundError: xarray is not installed (one line naming the extra).
        """
        try:
            import xarray  # noqa: F401
        except ImportError:
            raise ModuleNotFoundError(
                f"SweepOutcome.dataset needs xarray: {DATA_HINT}", name="xarray"
            ) from None
        return open_result(self.result)

    def _summary(self) -> dict[str, str]:
        """The outcome in a few short lines (for its repr and its HTML table)."""
        from billiard.sweep.attractor import CLASSES

        total = sum(self.statuses.values())
        order = ("ok", "failed", "invalid")
        statuses = sorted(self.statuses.items(), key=lambda kv: (kv[0] not in order, kv[0]))
        classes = sorted(
            self.classes.items(),
            key=lambda kv: CLASSES.index(kv[0]) if kv[0] in CLASSES else len(CLASSES),
        )
        return {
            "folder": str(self.directory),
            "points": f"{total} (" + ", ".join(f"{n} {name}" for name, n in statuses) + ")",
            "attractors": ", ".join(f"{n} {name}" for name, n in classes) or "none",
            "computed": f"{len(self.computed)} in this session on {self.where}",
            "files": ", ".join(p.name for p in (self.result, *self.plots)),
        }

    def __repr__(self) -> str:
        s = self._summary()
        return (
            f"<SweepOutcome {s['folder']}: points {s['points']}; attractors {s['attractors']}; "
            f"computed {s['computed']}; files {s['files']}>"
        )

    def _repr_html_(self) -> str:
        from billiard.scene.display import html_table

        caption = "SweepOutcome (.dataset: the result as an xarray.Dataset)"
        return html_table(list(self._summary().items()), caption)


# ----------------------------------------------------------------------------------------
# size


def estimate_size(sweep: Sweep) -> dict[str, int]:
    """Bytes the sweep's output files will take, about: ``points.npy`` (one packed row
    per point: 96 bytes and 16 bytes per stored height and time of flight, and a header
    of a few hundred bytes) and ``sweep.nc`` (8 bytes per number, the last K heights and
    times of flight included, and a header with the definition: some 6 kB and 32 bytes
    per axis value), from the grid's shape alone (nothing is materialised).
    ``reasons.jsonl`` holds a line only per failed or invalid point and is left out."""
    from billiard.runfile.npyfile import header_size

    keep = sweep.keep
    table = points_table(keep)
    per_cell = 4 * 5 + 8 * 10 + 2 * keep * 8 + 64  # ints, floats, last K, class strings
    header = 6000 + 32 * sum(sweep.shape)
    return {
        POINTS_NAME: header_size(table.dtype) + sweep.size * table.dtype.itemsize,
        RESULT_NAME: sweep.size * per_cell + header,
    }


def _bytes(n: float) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} bytes"


def check_size(sweep: Sweep, yes: bool) -> None:
    """Refuse (SweepError, one line naming the estimate) a sweep beyond
    MAX_POINTS_UNCONFIRMED points or MAX_BYTES_UNCONFIRMED bytes of output, unless
    ``yes``."""
    sizes = estimate_size(sweep)
    total = sum(sizes.values())
    if yes or (sweep.size <= MAX_POINTS_UNCONFIRMED and total <= MAX_BYTES_UNCONFIRMED):
        return
    shape = " x ".join(f"{n:,}" for n in sweep.shape)
    files = ", ".join(f"{name} {_bytes(n)}" for name, n in sizes.items())
    raise SweepError(
        f"the sweep has {sweep.size:,} points ({shape}) and would write about "
        f"{_bytes(total)} ({files}); beyond {MAX_POINTS_UNCONFIRMED:,} points or "
        f"{_bytes(MAX_BYTES_UNCONFIRMED)} a sweep runs only with --yes: "
        "give it, or fewer values per --vary or a smaller --keep"
    )


# ----------------------------------------------------------------------------------------
# checking the points


def _describe(values: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in values.items())


_GEOMETRY_PREFIXES = ("boundary.", "ball.", "initial.")


def precheck_duration(sweep: Sweep, scene: Any) -> float:
    """Simulated time (s) the check of a point runs at most: the point's own duration
    (the sweep's, else the scene's), and never more than PRECHECK_SPAN."""
    duration = sweep.duration if sweep.duration is not None else scene.run.duration
    return PRECHECK_SPAN if duration is None else min(float(duration), PRECHECK_SPAN)


def check_starts(scene: Any, q1s: np.ndarray, q2s: np.ndarray) -> dict[int, str]:
    """The starting positions (m, lab frame, at the scene's start time) among ``q1s``,
    ``q2s`` that put the ball into a wall or the lid or above the escape height, with the
    engine's one-line reason, by position in the arrays; one Simulation is built for the
    scene (its ball at rest) and each start checked as the engine checks it.

    Raises:
        ValueError: the scene cannot be set up (its geometry is invalid).
    """
    from billiard.run.simulate import Simulation

    if ensemble.supports(scene) is None:
        # the ensemble kernel's start check, compiled (the engine's own, with fresh warm
        # starts), and a short reason (the engine's names how deep: a root search per
        # start, 0.2 ms, for each of a basin map's hundreds of thousands of outside pixels)
        return _refused_starts(scene, q1s, q2s)
    simulation = Simulation(ensemble.at_rest_scene(scene))
    boundary, warm = simulation.boundary, simulation.warm
    theta = simulation.drive.angle(scene.initial.t)
    reasons: dict[int, str] = {}
    for position in range(len(q1s)):
        try:
            boundary.check_initial_position(float(q1s[position]), float(q2s[position]), theta, warm)
        except ValueError as exc:
            reasons[position] = str(exc)
    return reasons


def _refused_starts(scene: Any, q1s: np.ndarray, q2s: np.ndarray) -> dict[int, str]:
    """The starts the ensemble kernel's set-up refuses, with a one-line reason each."""
    setup = ensemble.prepare(scene)
    codes = ensemble.start_verdicts(setup, q1s, q2s, t=scene.initial.t)
    return {
        int(k): f"initial position q1 = {q1s[k]:.6g} m, q2 = {q2s[k]:.6g} m puts the ball "
        f"{ensemble.VERDICTS[codes[k]]}"
        for k in np.nonzero(codes)[0]
    }


def _one_line(message: str) -> str:
    return message if "\n" not in message and "  " not in message else " ".join(message.split())


def _refuse(sweep: Sweep, index: int, message: str) -> SweepError:
    return SweepError(
        f"point {index} ({_describe(sweep.point_values(index))}): {message} "
        "(no point was run; --skip-invalid records such points as invalid)"
    )


def prepare(sweep: Sweep, skip_invalid: bool = False) -> dict[int, str]:
    """Check every point: its scene is valid and its geometry can be simulated (up to one
    impact, within :func:`precheck_duration`); curves are derived here, once, before any
    worker starts. Nothing is simulated per point: each distinct set of the swept keys
    other than ``initial.*`` is built and validated once, each distinct geometry simulated
    once (a short run), and the starting positions of a basin map are checked against the
    walls by :func:`check_starts`.

    Returns:
        The invalid points' one-line reasons, by index (empty unless ``skip_invalid``).

    Raises:
        SweepError: a point's scene is invalid (naming the point and the key), unless
            ``skip_invalid``, which records such points as ``invalid`` instead.
    """
    from billiard.scene.scene import with_values

    starts = [i for i, axis in enumerate(sweep.axes) if axis.key.startswith("initial.")]
    others = [i for i in range(len(sweep.axes)) if i not in starts]
    shape = sweep.shape
    checked: OrderedDict[Any, str | None] = OrderedDict()  # a bounded memory of checks
    invalid: dict[int, str] = {}

    def record(indices: np.ndarray, messages: Any, outside: bool = False) -> None:
        """Points found invalid: refused (the lowest index named), or recorded; starts
        ``outside`` the container are recorded always (a basin map's rectangle)."""
        if not len(indices):
            return
        order = np.argsort(indices, kind="stable")
        if not skip_invalid and not outside:
            first = int(order[0])
            message = messages if isinstance(messages, str) else messages[first]
            raise _refuse(sweep, int(indices[first]), " ".join(message.split()))
        one = " ".join(messages.split()) if isinstance(messages, str) else None
        for k in order.tolist():
            invalid[int(indices[k])] = one if one is not None else _one_line(messages[k])

    for combo in itertools.product(*(range(shape[i]) for i in others)):
        pairs = zip(others, combo, strict=True)
        values = {sweep.axes[i].key: sweep.axes[i].values[j] for i, j in pairs}
        # the points of this parameter set: every start, in index order
        multi = [np.zeros(1, dtype=np.int64)] * len(shape)
        for i, j in zip(others, combo, strict=True):
            multi[i] = np.array([j])
        if starts:
            grids = np.meshgrid(*(np.arange(shape[i]) for i in starts), indexing="ij")
            for i, g in zip(starts, grids, strict=True):
                multi[i] = g.ravel()
        count = max(len(m) for m in multi)
        multi = [np.broadcast_to(m, (count,)) for m in multi]
        indices = np.ravel_multi_index(multi, shape).astype(np.int64)
        try:
            scene = with_values(sweep.scene, values)
        except ValueError as exc:
            record(indices, str(exc))
            continue
        if not starts:
            problem = _geometry_problem(sweep, scene, checked)
            if problem is not None:
                record(indices, problem)
            continue
        _check_set(sweep, scene, starts, multi, indices, checked, record)
    return invalid


def _geometry_problem(
    sweep: Sweep, scene: Any, checked: OrderedDict[Any, str | None]
) -> str | None:
    """Why the scene cannot be simulated (None: it runs), from a short run once per
    distinct geometry and start (remembered in ``checked``)."""
    from billiard.geometry.curves import load_curve
    from billiard.run.simulate import simulate

    curve = (scene.boundary.curve, scene.boundary.parameters)
    geometry = (curve, scene.boundary, scene.ball, scene.initial)
    if geometry in checked:
        checked.move_to_end(geometry)
    else:
        try:
            load_curve(curve[0], dict(curve[1]))  # derived (and cached) once
            simulate(scene, collisions=1, duration=precheck_duration(sweep, scene))
            checked[geometry] = None
        except ValueError as exc:  # SceneError, GeometryError, curve errors
            checked[geometry] = str(exc)
        if len(checked) > _CHECK_CACHE:
            checked.popitem(last=False)
    return checked[geometry]


def _check_set(
    sweep: Sweep,
    scene: Any,
    starts: list[int],
    multi: list[np.ndarray],
    indices: np.ndarray,
    checked: OrderedDict[Any, str | None],
    record: Callable[[np.ndarray, Any], None],
) -> None:
    """Check the starts of one parameter set (the ``initial.*`` axes): each value of each
    axis once, then each start's position, then one short run from the first valid
    start."""
    from billiard.scene.scene import with_values

    bad = np.zeros(len(indices), dtype=bool)
    messages: dict[int, str] = {}
    for i in starts:  # each value of each initial axis, validated once
        axis = sweep.axes[i]
        for j, value in enumerate(axis.values):
            try:
                with_values(scene, {axis.key: value})
            except ValueError as exc:
                for k in np.flatnonzero((multi[i] == j) & ~bad).tolist():
                    messages[k] = str(exc)
                bad[multi[i] == j] = True
    keys = {sweep.axes[i].key: i for i in starts}
    base = scene.initial

    def column(name: str) -> np.ndarray | None:
        """The points' start coordinate ``name`` (float64), None where the engine
        resolves it (not given, or not a number)."""
        if f"initial.{name}" in keys:
            i = keys[f"initial.{name}"]
            axis = sweep.axes[i]
            if not axis.numeric:
                return None
            return np.asarray(axis.values, dtype=np.float64)[multi[i]]
        value = getattr(base, name)
        return None if value is None else np.full(len(indices), float(value))

    q1s, q2s = column("q1"), column("q2")
    found = None
    done = np.zeros(len(indices), dtype=bool)  # recorded already
    if q1s is not None and q2s is not None and "initial.t" not in keys:
        ok = np.flatnonzero(~bad)
        try:
            found = check_starts(scene, q1s[ok], q2s[ok])
        except ValueError:  # no ball at rest to set up (no bottom): each start on its own
            found = None
        del q1s, q2s
    if found is not None:
        # a start outside the container is a blank pixel of a basin map, not bad input
        outside = np.array(sorted(int(ok[position]) for position in found), dtype=np.int64)
        record(indices[outside], [_one_line(found[p]) for p in sorted(found)], True)
        for position in found:
            bad[ok[position]] = True
        done[outside] = True
        good = np.flatnonzero(~bad)
        if len(good):  # one short run of this parameter set, from its first valid start
            k = int(good[0])
            point = with_values(scene, _start_values(sweep, starts, multi, k))
            problem = _geometry_problem(sweep, point, checked)
            if problem is not None:
                for k in good.tolist():
                    messages[k] = problem
                bad[good] = True
    else:  # starts the engine resolves (a q1 or q2 left out), or no ball at rest: each one
        for k in np.flatnonzero(~bad).tolist():
            point = with_values(scene, _start_values(sweep, starts, multi, k))
            problem = _geometry_problem(sweep, point, checked)
            if problem is not None:
                messages[k] = problem
                bad[k] = True
    where = np.flatnonzero(bad & ~done)
    record(indices[where], [messages[int(k)] for k in where.tolist()])


def _start_values(
    sweep: Sweep, starts: list[int], multi: list[np.ndarray], k: int
) -> dict[str, Any]:
    return {sweep.axes[i].key: sweep.axes[i].values[int(multi[i][k])] for i in starts}


# ----------------------------------------------------------------------------------------
# executors


def _worker_init(parent: int) -> None:
    """Workers leave Ctrl-C to the parent, which stops them, and end with the parent
    (a parent killed by SIGKILL stops none)."""
    die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@dataclass
class Workers:
    """Where chunks run: an executor, a description, and the workers present now.

    Attributes:
        executor: the ``concurrent.futures`` executor chunks are submitted to.
        where: where they run, for the log and the summary.
        present: worker name -> threads, asked again as the sweep goes (a cluster's
            workers come and go).
    """

    executor: Executor
    where: str
    present: Callable[[], dict[str, int]]
    #: the answer of the last look at the workers (the sweep looks every
    #: WORKERS_INTERVAL s), which sizes the chunks still to hand out
    seen: dict[str, int] = field(default_factory=dict)
    #: workers missing from the last answer alone (not yet said to have left)
    missing: dict[str, int] = field(default_factory=dict)

    def threads(self, present: dict[str, int] | None = None) -> int:
        return max(1, sum((self.present() if present is None else present).values()))


@contextlib.contextmanager
def local_executor(workers: int) -> Iterator[Workers]:
    """A process pool of ``workers`` fresh interpreters (spawned, so they inherit no
    threads or locks, and read the same environment, e.g. ``BILLIARD_HOME``)."""
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_worker_init,
        initargs=(os.getpid(),),
    )
    clean = False
    try:
        where = f"{workers} local worker process{'es' if workers > 1 else ''}"
        yield Workers(pool, where, lambda: {"local": workers})
        clean = True
    finally:
        if clean:
            pool.shutdown(wait=True)
        else:  # interrupted: drop queued points and stop the running ones now
            _stop_pool(pool)


#: Seconds an interrupted sweep gives its workers to end on SIGTERM before SIGKILL.
STOP_GRACE = 0.5


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Drop the pool's queued chunks and end its workers now: the chunks they run are
    lost (a resume computes them). The processes are taken before ``shutdown``, which
    forgets them: a worker left running goes on with its chunk, and the interpreter's
    exit waits for it (4 to 10 s after Ctrl-C)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        with contextlib.suppress(OSError, ValueError):  # already ended, or closed
            process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + STOP_GRACE
    for process in processes:
        with contextlib.suppress(OSError, ValueError):
            process.join(max(0.0, deadline - time.monotonic()))
            if process.is_alive():
                process.kill()
                process.join(1.0)


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[Workers]:
    """The ``concurrent.futures`` executor of a client of the Dask scheduler at
    ``address``; its workers need this package installed (and, for a curve expression,
    the same curve cache, ``BILLIARD_HOME``). The dashboard's link is printed on stderr
    when the scheduler has one."""
    try:
        import distributed
    except ImportError:
        raise SweepError(f"--dask needs dask.distributed: {DASK_HINT}") from None
    probe_scheduler(address, DASK_TIMEOUT)
    try:
        client = distributed.Client(address, timeout=f"{DASK_TIMEOUT}s", set_as_default=False)
    except Exception as exc:  # the probe answered: any failure now is a protocol fault
        message = " ".join(str(exc).split()) or type(exc).__name__
        raise SweepError(f"cannot reach the Dask scheduler at {address}: {message}") from None

    def present() -> dict[str, int]:
        workers = client.scheduler_info()["workers"]
        return {name: int(w.get("nthreads", 1)) for name, w in workers.items()}

    try:
        threads = sum(present().values())
        try:
            link = client.dashboard_link
        except Exception:  # no dashboard: the scheduler runs without one
            link = None
        if link:
            print(f"billiard sweep: Dask dashboard at {link}", file=sys.stderr)
        executor = client.get_executor(pure=False)
        clean = False
        try:
            where = f"Dask scheduler {address} ({threads} worker threads at the start)"
            yield Workers(executor, where, present)
            clean = True
        finally:
            executor.shutdown(wait=clean)
    finally:
        client.close()


def probe_scheduler(address: str, timeout: float) -> None:
    """Ask ``address`` who it is, as Dask's own clients do (an ``identity`` message),
    and return only when a Dask scheduler answers within ``timeout`` seconds.

    ``distributed.Client`` waits for ever on a live address that accepts the connection
    and never answers in Dask's protocol (an HTTP server: the dashboard's port), and
    reading another service's bytes as Dask frames can raise anything (a frame length of
    exabytes: numpy's ArrayMemoryError). The question runs in a thread of its own with its
    own event loop, under a deadline, so it ends whatever the other side does.

    Raises:
        SweepError: no Dask scheduler answered at ``address`` (one line, naming why).
    """
    from distributed.comm import connect

    async def ask() -> Any:
        comm = await connect(address, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    outcome: dict[str, Any] = {}

    def target() -> None:
        try:
            outcome["reply"] = asyncio.run(asyncio.wait_for(ask(), timeout))
        except BaseException as exc:  # any answer but a Dask reply is a refusal
            outcome["error"] = exc

    thread = threading.Thread(target=target, name="billiard-dask-probe", daemon=True)
    thread.start()
    thread.join(timeout + 5.0)  # the deadline inside ends it; this is a second guard
    reply, error = outcome.get("reply"), outcome.get("error")
    where = f"cannot reach a Dask scheduler at {address}"
    if "reply" not in outcome and error is None or isinstance(error, TimeoutError):
        raise SweepError(
            f"{where}: no answer in Dask's protocol within {timeout:g} s (is it a "
            "scheduler's address, e.g. tcp://host:8786, not its dashboard's?)"
        )
    if error is not None:
        message = " ".join(str(error).split())[:200] or type(error).__name__
        if isinstance(error, OSError):
            raise SweepError(f"{where}: {message}")
        raise SweepError(
            f"{where}: the address answered, but not in Dask's protocol "
            f"({type(error).__name__}: {message})"
        )
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise SweepError(f"{where}: the address answered as {kind!s:.60}, not as a scheduler")


# ----------------------------------------------------------------------------------------
# the sweep folder


def load_sweep_dir(directory: Path) -> Sweep:
    """The sweep stored in a sweep folder (``DIR/sweep.toml`` and ``DIR/scene.toml``),
    refused when either was edited since the sweep started (``DIR/sweep.sha256``)."""
    path = directory / SWEEP_NAME
    if not path.is_file():
        raise SweepError(f"cannot resume {directory}: no {SWEEP_NAME} (not a sweep folder)")
    digest_path = directory / DIGEST_NAME
    if digest_path.is_file():  # folders of sweeps started before the digest have none
        try:
            stored = digest_path.read_text(encoding="utf-8")
            now = definition_digest(directory)
        except (OSError, UnicodeDecodeError) as exc:
            why = getattr(exc, "strerror", None) or exc
            raise SweepError(f"cannot resume {directory}: {why}") from None
        if stored != now:
            stored_lines, now_lines = stored.splitlines(), now.splitlines()
            edited = [
                line.split()[-1] for line in now_lines if line not in stored_lines and line.split()
            ] or [DIGEST_NAME]
            raise SweepError(
                f"cannot resume {directory}: {' and '.join(edited)} changed since the sweep "
                f"started (SHA-256 differs from {DIGEST_NAME}); its points would mix two "
                f"definitions: restore the file, or start a new sweep with `billiard sweep "
                f"{directory / SWEEP_NAME} --out OTHER_DIR`"
            )
    scene, axes, settings, changes = read_sweep_file(path)
    return Sweep(scene, tuple(axes), **settings, changes=tuple(changes))


#: Files of a ``billiard run`` folder: a sweep there would replace its scene.toml.
_RUN_FILES = (
    "collisions.csv",
    "collisions.npy",
    "checkpoint.json",
    "contacts.csv",
    "contacts.npy",
    "trajectory.csv",
    "trajectory.npy",
)
#: Files a sweep writes (besides its definition) that it must not replace unasked.
_SWEEP_OUTPUTS = (
    SCENE_NAME,
    DIGEST_NAME,
    CHECKSUMS_NAME,
    RESULT_NAME,
    REASONS_NAME,
    LOG_NAME,
    "bifurcation.png",
    "heatmaps.png",
    "basins.png",
)


def _check_new_dir(directory: Path) -> None:
    """Refuse a folder a new sweep must not write into (before any work is done)."""
    if directory.exists() and not directory.is_dir():
        raise SweepError(f"cannot write the sweep: {directory} is a file")
    if any((directory / name).exists() for name in (SWEEP_NAME, POINTS_NAME, LEGACY_POINTS_NAME)):
        raise SweepError(
            f"{directory} already holds a sweep; continue it with `billiard sweep --resume "
            f"{directory}` or choose another --out"
        )
    run_files = [name for name in _RUN_FILES if (directory / name).exists()]
    if run_files:
        raise SweepError(
            f"{directory} holds a run of `billiard run` ({run_files[0]}); a sweep there "
            f"would replace its {SCENE_NAME}: choose another --out"
        )
    taken = [name for name in _SWEEP_OUTPUTS if (directory / name).exists()]
    if taken:
        raise SweepError(
            f"{directory} already holds {', '.join(taken)}, which the sweep would replace: "
            "choose another --out (or an empty or new folder)"
        )


def _start_dir(directory: Path, sweep: Sweep) -> None:
    _check_new_dir(directory)  # again: the folder may have changed while points were checked
    directory.mkdir(parents=True, exist_ok=True)
    from billiard.scene.scene import scene_to_toml

    scene_text, sweep_text = scene_to_toml(sweep.scene), sweep_to_toml(sweep)
    digest = digest_lines({SWEEP_NAME: sweep_text.encode(), SCENE_NAME: scene_text.encode()})
    # sweep.toml comes last: its presence marks a complete definition, digest included
    for name, text in ((SCENE_NAME, scene_text), (DIGEST_NAME, digest), (SWEEP_NAME, sweep_text)):
        tmp = directory / f".{name}.tmp"
        tmp.write_bytes(text.encode("utf-8"))
        os.replace(tmp, directory / name)


def _finished(directory: Path, sweep: Sweep) -> bytearray:
    """One byte per point, 1 for a point stored in the folder (read-only; no lock),
    checked against the folder's checksums before any worker starts."""
    if not (directory / POINTS_NAME).exists() and (directory / LEGACY_POINTS_NAME).exists():
        raise StoreError(
            f"{directory} holds a sweep of an older version ({LEGACY_POINTS_NAME}); "
            f"run it again: `billiard sweep {directory / SWEEP_NAME} --out OTHER_DIR`"
        )
    return stored_points(directory, sweep.size, sweep.keep)


#: points per chunk on the GPU: enough threads to fill a GPU (a chunk's state vectors
#: and rings, about 24 kB a point, stay on the device while it runs; what comes back
#: is what the sweep stores, about 112 bytes and 16 per kept impact a point)
GPU_CHUNK = 1 << 17


def _phases_note(sweep: Sweep) -> str:
    """What of a GPU sweep runs on the CPU: its contact-phases points, if it may have
    any (the GPU kernels have the impacts model only)."""
    phases = sweep.scene.contact.model == "phases"
    if phases or any(axis.key == "contact.model" for axis in sweep.axes):
        return "; contact phases on the CPU: the GPU kernels have the impacts model only"
    return ""


def chunk_size(points: int, workers: int) -> int:
    """Points per chunk: up to MAX_CHUNK, but at least CHUNKS_PER_WORKER chunks per
    worker while there are points enough (every worker busy to the end)."""
    return min(MAX_CHUNK, max(1, math.ceil(points / (CHUNKS_PER_WORKER * max(workers, 1)))))


# ----------------------------------------------------------------------------------------
# running


def run_sweep(
    sweep: Sweep | None,
    directory: str | os.PathLike[str],
    *,
    workers: int | None = None,
    dask: str | None = None,
    resume: bool = False,
    skip_invalid: bool = False,
    on_point: Callable[[dict[str, Any]], None] | None = None,
    progress: SweepProgress | None = None,
    plots: bool = True,
    yes: bool = False,
    chunk: int | None = None,
    device: str = "cpu",
) -> SweepOutcome:
    """Run (or, with ``resume=True`` and ``sweep=None``, continue) a sweep in ``directory``.

    Args:
        sweep: the sweep; None with ``resume`` (read from the folder).
        directory: the sweep folder; everything the sweep writes goes inside it.
        workers: local worker processes (default: all cores).
        dask: address of a ``dask.distributed`` scheduler to run the points on instead.
        resume: continue the sweep stored in ``directory``.
        skip_invalid: record points whose scene is invalid as ``invalid`` instead of
            refusing the sweep.
        on_point: called in this process with each point's record, after the chunk the
            point came in is stored; it may raise :class:`StopSweep` to stop the sweep as
            Ctrl-C does (the chunk stays stored).
        progress: progress reporter (default: one on stderr).
        plots: draw the plots at the end.
        yes: run a new sweep beyond MAX_POINTS_UNCONFIRMED points or
            MAX_BYTES_UNCONFIRMED bytes of output files (``--yes``).
        chunk: points per chunk (default: :func:`chunk_size` of the points to compute
            and the workers); the results do not depend on it.
        device: ``"cpu"`` or ``"gpu"``: where the trajectories the ensemble kernel takes
            run. On the GPU one local worker process drives the device, chunks of up to
            GPU_CHUNK points (the GPU's results are the same physics, not the same bits).

    Raises:
        SweepError: bad input, reported before any point runs.
        SweepInterrupted: Ctrl-C, SIGTERM or :class:`StopSweep`; finished chunks are kept.
    """
    directory = Path(directory)
    if resume:
        stored = load_sweep_dir(directory)
        sweep = stored if sweep is None else sweep
    elif sweep is None:
        raise SweepError("no sweep given")
    else:
        check_size(sweep, yes)  # before any work: the estimate needs only the grid's shape
        _check_new_dir(directory)
    if workers is not None and workers < 1:
        raise SweepError(f"--workers {workers}: needs at least 1 worker")
    if chunk is not None and chunk < 1:
        raise SweepError(f"chunk {chunk}: needs at least 1 point")
    if device == "gpu":
        if dask:
            raise SweepError("--device gpu runs on this machine's GPU: leave out --dask")
        try:
            check_device(device)
        except ValueError as exc:
            raise SweepError(str(exc)) from None
        workers = 1  # one process drives the GPU
    elif device != "cpu":
        raise SweepError(f"--device {device!r}: choose cpu or gpu")
    invalid = prepare(sweep, skip_invalid=skip_invalid or sweep.skip_invalid)  # nothing written
    try:
        done = _finished(directory, sweep) if resume else bytearray(sweep.size)
    except StoreError as exc:
        raise SweepError(f"cannot resume: {exc}") from None
    flags = np.frombuffer(done, dtype=np.uint8)
    to_compute = sweep.size - int(np.count_nonzero(flags)) - sum(1 for i in invalid if not flags[i])
    del flags
    computed = array.array("q")
    where = "nothing to compute"
    with contextlib.ExitStack() as stack:
        pool = None
        if to_compute:  # reach the workers (or the scheduler) before writing anything
            stack.enter_context(_terminate_as_interrupt())
            opener = dask_executor(dask) if dask else local_executor(workers or os.cpu_count() or 1)
            # the workers' own stack, closed once the points are computed: their memory
            # (some 300 MiB a process) is given back before the result file and the
            # plots are made (a 10^6-point map's peak: 1.1 GB with them, measured)
            pool_stack = stack.enter_context(contextlib.ExitStack())
            pool = pool_stack.enter_context(opener)
            where = pool.where
        if not resume:
            _start_dir(directory, sweep)
        try:
            store = stack.enter_context(ChunkStore(directory, sweep.size, sweep.keep))
        except StoreError as exc:
            raise SweepError(str(exc)) from None
        if store.unverified:
            warnings.warn(store.unverified, UnverifiedSweepWarning, stacklevel=2)
            store.log(store.unverified)
        _store_invalid(store, sweep, invalid)  # skipped invalid points are recorded at once
        del invalid
        todo = sweep.size - store.count
        if progress is None:
            progress = SweepProgress(sweep.size, done=store.count)
        if todo and pool is not None:
            started = time.perf_counter()
            pool.seen = pool.present()
            size: int | Callable[[int], int] = chunk or (
                min(todo, GPU_CHUNK)
                if device == "gpu"
                # sized again at each hand-out from the points left and the workers seen
                # then: workers that join a cluster late find chunks left to take
                else lambda left: chunk_size(left, pool.threads(pool.seen))
            )
            first = size if isinstance(size, int) else size(todo)
            on = (
                f"{where} (trajectories on the GPU{_phases_note(sweep)})"
                if device == "gpu"
                else where
            )
            store.log(
                f"start: {todo} of {sweep.size} points on {on}, {first} per chunk"
                + ("" if isinstance(size, int) else " (resized as workers come and go)")
            )
            try:
                tasks = _chunks(sweep, store.done, size, device)
                _drive(pool, tasks, store, progress, on_point, computed, sweep)
            except (KeyboardInterrupt, StopSweep):
                progress.close()
                store.log(f"interrupted: {store.count} of {sweep.size} points kept")
                raise SweepInterrupted(directory, store.count, sweep.size) from None
            finally:
                progress.close()
            elapsed = time.perf_counter() - started
            store.log(
                f"done: {len(computed)} points in {elapsed:.2f} s on {where} "
                f"({progress.impacts / max(elapsed, 1e-9):,.0f} impacts/s)"
            )
            pool_stack.close()
        from billiard.scene.scene import scene_to_toml

        outcome = SweepOutcome(directory, directory / RESULT_NAME, computed, where, sweep=sweep)
        _summarise(store, sweep, outcome)
        result = write_result(
            directory / RESULT_NAME, sweep, store.blocks, store.reasons, scene_to_toml(sweep.scene)
        )
        if plots:
            from billiard.sweep.netcdf import read_result
            from billiard.sweep.plots import plot_sweep

            outcome.plots = plot_sweep(sweep, read_result(result, _plotted(sweep)), directory)
        store.log(f"wrote {result.name}" + "".join(f", {p.name}" for p in outcome.plots))
        if not outcome.measured:
            store.log(f"no point measured: {dict(outcome.statuses)}")
    return outcome


def _plotted(sweep: Sweep) -> list[str]:
    """The result's variables the plots read (a large sweep's text variables and tails
    are not read back for them)."""
    from billiard.sweep.units import variable_name

    names = [variable_name(axis.key) for axis in sweep.axes]
    names += ["attractor", "status", "period", "height_mean", "lyapunov", "rest_height"]
    if len(sweep.axes) == 1:
        names += ["last_height", "last_tof"]
    return names


def _store_invalid(store: ChunkStore, sweep: Sweep, invalid: dict[int, str]) -> None:
    """Record the invalid points not stored yet, 16 x MAX_CHUNK at a time (a sync each)."""
    indices = [i for i in sorted(invalid) if i not in store]
    step = 16 * MAX_CHUNK
    for start in range(0, len(indices), step):
        part = indices[start : start + step]
        columns = empty_columns(len(part), sweep.keep)
        columns["index"][:] = part
        columns["status"][:] = STATUSES.index("invalid")
        columns["attractor"][:] = CLASSES.index("invalid")
        store.append(ChunkResult(columns, {i: invalid[i] for i in part}))


def _summarise(store: ChunkStore, sweep: Sweep, outcome: SweepOutcome) -> None:
    """Points per status and per class, and the first failed points' records."""
    statuses = np.zeros(len(STATUSES), dtype=np.int64)
    classes = np.zeros(len(CLASSES), dtype=np.int64)
    failed: dict[int, np.void] = {}  # the five lowest indices
    for part in store.blocks():
        statuses += np.bincount(part["status"], minlength=len(STATUSES))
        classes += np.bincount(part["attractor"], minlength=len(CLASSES))
        lost = part[part["status"] == STATUSES.index("failed")]
        for row in lost[np.argsort(lost["index"])][:5]:
            failed[int(row["index"])] = row
        for index in sorted(failed)[5:]:
            del failed[index]
    outcome.statuses.update({STATUSES[i]: int(n) for i, n in enumerate(statuses) if n})
    outcome.classes.update({CLASSES[i]: int(n) for i, n in enumerate(classes) if n})
    if failed:
        reasons = {i: r for i, r in store.reasons() if i in failed}
        outcome.failed_examples = [
            record_of_row(failed[i], sweep.point_values(i), reasons.get(i, ""))
            for i in sorted(failed)
        ]


def _records(directory: Path, sweep: Sweep) -> list[dict[str, Any]]:
    """Every stored point's record, by index (for small sweeps and tests)."""
    from billiard.runfile.npyfile import open_rows

    rows = open_rows(directory / POINTS_NAME, points_table(sweep.keep))  # small sweeps
    done = bytearray(sweep.size)
    for i in rows["index"].tolist():
        done[i] = 1
    reasons = dict(read_reasons(directory / REASONS_NAME, done))
    by_index = {int(row["index"]): row for row in rows}
    return [
        record_of_row(by_index[i], sweep.point_values(i), reasons.get(i, ""))
        for i in sorted(by_index)
    ]


def _chunks(
    sweep: Sweep, done: bytearray, size: int | Callable[[int], int], device: str = "cpu"
) -> Iterator[ChunkTask]:
    """The points still to compute, in index order, each chunk made when a worker can
    take it (nothing is held per point beyond the chunk's indices). ``size``: points per
    chunk, or a function of the points not yet handed out that gives the next chunk's
    size (asked as each chunk begins)."""
    flags = np.frombuffer(done, dtype=np.uint8)
    left = sweep.size - int(np.count_nonzero(flags[: sweep.size]))

    def next_size() -> int:
        return max(1, int(size if isinstance(size, int) else size(left)))

    start = 0
    block = 1 << 16
    pending: list[np.ndarray] = []
    count = 0
    want = next_size()
    while start < sweep.size:
        stop = min(start + max(block, want), sweep.size)
        free = np.flatnonzero(flags[start:stop] == 0) + start
        start = stop
        while len(free):
            take = free[: want - count]
            free = free[len(take) :]
            pending.append(take)
            count += len(take)
            if count == want:
                left -= count
                yield _task(sweep, np.concatenate(pending), device)
                pending, count = [], 0
                want = next_size()
    if count:
        yield _task(sweep, np.concatenate(pending), device)


def _task(sweep: Sweep, indices: np.ndarray, device: str = "cpu") -> ChunkTask:
    start, stop = int(indices[0]), int(indices[-1]) + 1
    whole = stop - start == len(indices)
    return ChunkTask(sweep, start, stop, None if whole else indices.astype(np.int64), device)


def _drive(
    pool: Workers,
    tasks: Iterator[ChunkTask],
    store: ChunkStore,
    progress: SweepProgress,
    on_point: Callable[[dict[str, Any]], None] | None,
    computed: array.array,
    sweep: Sweep,
) -> None:
    pending: dict[Future, ChunkTask] = {}
    submitted_at: dict[int, float] = {}
    present = pool.seen or pool.present()
    pool.seen = present
    looked = time.monotonic()

    def fill() -> None:
        window = 2 * pool.threads(present)  # two chunks per worker thread present now
        while len(pending) < window:
            task = next(tasks, None)
            if task is None:
                return
            pending[pool.executor.submit(measure_chunk, task)] = task
            submitted_at[task.start] = time.perf_counter()

    try:
        fill()
        while pending:
            done, _ = wait(list(pending), timeout=1.0, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: pending[f].start):
                task = pending.pop(future)
                try:
                    chunk = future.result()
                except Exception as exc:  # a worker died (killed, out of memory)
                    message = " ".join(str(exc).split()) or type(exc).__name__
                    raise SweepError(
                        f"points {task.start} to {task.stop - 1}: the worker running them "
                        f"failed ({message}); finished points are kept: continue with --resume"
                        + _script_hint(computed)
                    ) from None
                store.append(chunk)
                indices = chunk.columns["index"]
                computed.extend(indices.tolist())
                impacts = int(chunk.columns["total_impacts"].sum())
                ok = int(np.count_nonzero(chunk.columns["status"] == 0))
                seconds = time.perf_counter() - submitted_at.pop(task.start)
                store.log(
                    f"chunk {task.start}-{task.stop - 1}: {len(chunk)} points ({ok} ok), "
                    f"{impacts} impacts, {seconds:.3f} s since submitted"
                )
                progress.chunk(len(chunk), impacts)
                if on_point is not None:
                    _call_per_point(on_point, chunk, sweep)
            if time.monotonic() - looked >= WORKERS_INTERVAL:
                present = _look_at_workers(pool, present, store)
                pool.seen = present
                looked = time.monotonic()
            fill()
            progress.tick()
    finally:
        for future in pending:
            future.cancel()


def _script_hint(computed: array.array) -> str:
    """Why a local pool may break before its first chunk: a Python script that starts a
    sweep at its top level. Each spawned worker imports the script again (as
    multiprocessing's "spawn" does), starts a sweep of its own and dies."""
    main = sys.modules.get("__main__")
    if computed or main is None or getattr(main, "__spec__", None) is not None:
        return ""
    if not getattr(main, "__file__", None):
        return ""  # a notebook or an interactive session: nothing is imported again
    return (
        f" (if {os.path.basename(main.__file__)} starts the sweep at its top level, put "
        'that under `if __name__ == "__main__":`: each worker imports the script again)'
    )


def _look_at_workers(pool: Workers, before: dict[str, int], store: ChunkStore) -> dict[str, int]:
    """The workers present now; those that left or joined since ``before`` are logged.

    A worker is said to have left once it is missing from two answers in a row: a
    scheduler's answer can omit a worker that is there (one such answer wrote a false
    "left" line, and a "joined" line for the same worker a look later). Until then it
    stays among the workers present."""
    try:
        now = dict(pool.present())
    except Exception:  # the scheduler did not answer this time: keep the last count
        return before
    gone = {name: before[name] for name in set(before) - set(now)}
    for name in sorted(gone):
        if name in pool.missing:
            store.log(f"worker {name} left; its chunks are recomputed")
    pool.missing = {name: n for name, n in gone.items() if name not in pool.missing}
    for name in sorted(set(now) - set(before)):
        store.log(f"worker {name} joined ({now[name]} threads)")
    return {**pool.missing, **now}


def _call_per_point(
    on_point: Callable[[dict[str, Any]], None], chunk: ChunkResult, sweep: Sweep
) -> None:
    columns = chunk.columns
    for k, index in enumerate(columns["index"].tolist()):
        row = {name: column[k] for name, column in columns.items()}
        on_point(record_of_row(row, sweep.point_values(index), chunk.reasons.get(index, "")))


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM stops the sweep like Ctrl-C (finished points kept, workers stopped)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
