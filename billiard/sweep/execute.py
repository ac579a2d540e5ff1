"""Running a sweep: check its size and every point, then measure the rest on an executor.

One code path for both places a sweep runs: points are submitted to a
``concurrent.futures`` executor, a :class:`~concurrent.futures.ProcessPoolExecutor` on
this machine or a ``dask.distributed`` client's executor (``client.get_executor()``) on
a cluster, at most two points per worker in flight. Each finished point is appended to
``DIR/points.jsonl`` at once, so an interrupted sweep keeps everything finished and
``resume`` computes only the rest.

Memory does not grow with the points finished: tasks are made one at a time as workers
free up, finished records go to disk and are dropped, and the result file is built by
reading points.jsonl back line by line into arrays the size of the result.
"""

from __future__ import annotations

import array
import asyncio
import contextlib
import multiprocessing
import os
import signal
import threading
import time
from collections import Counter, OrderedDict
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from billiard.sweep.definition import Sweep, SweepError, read_sweep_file, sweep_to_toml
from billiard.sweep.measure import PointTask, empty_record, measure_point
from billiard.sweep.netcdf import RESULT_NAME, write_result
from billiard.sweep.progress import SweepProgress
from billiard.sweep.store import (
    DIGEST_NAME,
    LOG_NAME,
    POINTS_NAME,
    SCENE_NAME,
    SWEEP_NAME,
    PointStore,
    StoreError,
    definition_digest,
    digest_lines,
    iter_points,
)

__all__ = [
    "SweepInterrupted",
    "SweepOutcome",
    "StopSweep",
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
#: output files (points.jsonl and sweep.nc).
MAX_POINTS_UNCONFIRMED = 100_000
MAX_BYTES_UNCONFIRMED = 10**9

#: Geometry checks remembered (for grids whose points share a container and start).
_CHECK_CACHE = 4096


class StopSweep(Exception):
    """Raised by an ``on_point`` callback to stop the sweep after the current point (as
    Ctrl-C does)."""


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

    @property
    def records(self) -> list[dict[str, Any]]:
        """Every point's record, by index, read from ``points.jsonl`` on each access (a
        sweep does not hold them: use ``read_result`` for large sweeps)."""
        by_index = {int(r["index"]): r for r, _ in iter_points(self.directory / POINTS_NAME)}
        return [by_index[i] for i in sorted(by_index)]

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
        variable's ``attrs``; e.g. ``outcome.dataset.height_mean.sel(drive_amplitude=0.027)``.

        Raises:
            ModuleNotFoundError: xarray is not installed (one line naming the extra).
        """
        try:
            import xarray
        except ImportError:
            raise ModuleNotFoundError(
                f"SweepOutcome.dataset needs xarray: {DATA_HINT}", name="xarray"
            ) from None
        return xarray.open_dataset(self.result)

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
        from html import escape

        rows = "".join(
            f"<tr><th style='text-align:left'>{escape(name)}</th><td style='text-align:left'>"
            f"{escape(text)}</td></tr>"
            for name, text in self._summary().items()
        )
        return (
            "<table><caption style='text-align:left'><b>SweepOutcome</b> "
            "(<code>.dataset</code>: the result as an xarray.Dataset)</caption>"
            f"{rows}</table>"
        )


# ----------------------------------------------------------------------------------------
# size


def estimate_size(sweep: Sweep) -> dict[str, int]:
    """Bytes the sweep's output files will take, about: ``points.jsonl`` (one JSON line
    per point: some 600 bytes of fields and about 21 bytes per stored height and time of
    flight) and ``sweep.nc`` (8 bytes per number, the last K heights and times of flight
    included, and a header with the definition: some 6 kB and 32 bytes per axis value),
    from the grid's shape alone (nothing is materialised)."""
    keep = sweep.keep
    values = sum(len(axis.key) + 24 for axis in sweep.axes)  # "key": value, per point
    per_line = 600 + values + 2 * keep * 21
    per_cell = 4 * 5 + 8 * 10 + 2 * keep * 8 + 64  # ints, floats, last K, class strings
    header = 6000 + 32 * sum(sweep.shape)
    return {POINTS_NAME: sweep.size * per_line, RESULT_NAME: sweep.size * per_cell + header}


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


def prepare(sweep: Sweep, skip_invalid: bool = False) -> dict[int, str]:
    """Check every point: its scene is valid and its geometry can be simulated (up to one
    impact, within :func:`precheck_duration`); curves are derived here, once, before any
    worker starts. Points are visited one at a time, nothing is kept per valid point.

    Returns:
        The invalid points' one-line reasons, by index (empty unless ``skip_invalid``).

    Raises:
        SweepError: a point's scene is invalid (naming the point and the key), unless
            ``skip_invalid``, which records such points as ``invalid`` instead.
    """
    from billiard.geometry.curves import load_curve
    from billiard.run.simulate import simulate
    from billiard.scene.scene import with_values

    per_point = any(a.key.startswith(_GEOMETRY_PREFIXES) for a in sweep.axes)
    checked: OrderedDict[Any, str | None] = OrderedDict()  # a bounded memory of checks
    invalid: dict[int, str] = {}
    for index, values in enumerate(sweep.points()):
        problem = None
        scene = None
        try:
            scene = with_values(sweep.scene, values)
        except ValueError as exc:
            problem = str(exc)
        if scene is not None:
            curve = (scene.boundary.curve, scene.boundary.parameters)
            geometry = (curve, scene.ball, scene.initial) if per_point else "base"
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
            problem = checked[geometry]
        if problem is not None:
            message = " ".join(problem.split())
            if not skip_invalid:
                raise SweepError(
                    f"point {index} ({_describe(values)}): {message} "
                    "(no point was run; --skip-invalid records such points as invalid)"
                )
            invalid[index] = message
    return invalid


# ----------------------------------------------------------------------------------------
# executors


def _worker_init() -> None:
    """Workers leave Ctrl-C to the parent, which stops them."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def local_executor(workers: int) -> Iterator[tuple[Executor, int, str]]:
    """A process pool of ``workers`` fresh interpreters (spawned, so they inherit no
    threads or locks, and read the same environment, e.g. ``BILLIARD_HOME``)."""
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_worker_init,
    )
    clean = False
    try:
        yield pool, workers, f"{workers} local worker process{'es' if workers > 1 else ''}"
        clean = True
    finally:
        if clean:
            pool.shutdown(wait=True)
        else:  # interrupted: drop queued points and stop the running ones now
            pool.shutdown(wait=False, cancel_futures=True)
            terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
            if terminate is not None:
                terminate()
            else:
                for process in list((getattr(pool, "_processes", None) or {}).values()):
                    process.terminate()
                for process in list((getattr(pool, "_processes", None) or {}).values()):
                    process.join(5)


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[tuple[Executor, int, str]]:
    """The ``concurrent.futures`` executor of a client of the Dask scheduler at
    ``address``; its workers need this package installed (and, for a curve expression,
    the same curve cache, ``BILLIARD_HOME``)."""
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
    try:
        threads = sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values())
        executor = client.get_executor(pure=False)
        clean = False
        try:
            yield executor, max(threads, 1), f"Dask scheduler {address} ({threads} worker threads)"
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
    RESULT_NAME,
    LOG_NAME,
    "bifurcation.png",
    "heatmaps.png",
    "basins.png",
)


def _check_new_dir(directory: Path) -> None:
    """Refuse a folder a new sweep must not write into (before any work is done)."""
    if directory.exists() and not directory.is_dir():
        raise SweepError(f"cannot write the sweep: {directory} is a file")
    if (directory / SWEEP_NAME).exists() or (directory / POINTS_NAME).exists():
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


def _record_check(sweep: Sweep, directory: Path) -> Callable[[dict[str, Any]], None]:
    """A check that a stored record is the point of this sweep its index says."""

    def check(record: dict[str, Any]) -> None:
        index = int(record["index"])
        if not 0 <= index < sweep.size or record.get("values") != sweep.point_values(index):
            raise StoreError(
                f"cannot resume {directory}: {POINTS_NAME} has point {index} with values "
                f"{record.get('values')!r}, which is not in {SWEEP_NAME}"
            )

    return check


def _finished(path: Path, size: int) -> bytearray:
    """One byte per point, 1 for a point stored in ``path`` (read-only; no lock)."""
    done = bytearray(size)
    for record, _ in iter_points(path):
        index = record["index"]
        if 0 <= index < size:
            done[index] = 1
    return done


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
        on_point: called in this process after each point is stored (its record); it may
            raise :class:`StopSweep` to stop the sweep as Ctrl-C does.
        progress: progress reporter (default: one on stderr).
        plots: draw the plots at the end.
        yes: run a new sweep beyond MAX_POINTS_UNCONFIRMED points or
            MAX_BYTES_UNCONFIRMED bytes of output files (``--yes``).

    Raises:
        SweepError: bad input, reported before any point runs.
        SweepInterrupted: Ctrl-C, SIGTERM or :class:`StopSweep`; finished points are kept.
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
    invalid = prepare(sweep, skip_invalid=skip_invalid or sweep.skip_invalid)  # nothing written
    try:
        done = _finished(directory / POINTS_NAME, sweep.size) if resume else None
    except StoreError as exc:
        raise SweepError(f"cannot resume: {exc}") from None
    to_compute = sum(
        1 for i in range(sweep.size) if i not in invalid and not (done is not None and done[i])
    )
    computed = array.array("q")
    where = "nothing to compute"
    with contextlib.ExitStack() as stack:
        executor = slots = None
        if to_compute:  # reach the workers (or the scheduler) before writing anything
            stack.enter_context(_terminate_as_interrupt())
            opener = dask_executor(dask) if dask else local_executor(workers or os.cpu_count() or 1)
            executor, slots, where = stack.enter_context(opener)
        if not resume:
            _start_dir(directory, sweep)
        try:
            store = stack.enter_context(
                PointStore(directory, sweep.size, check=_record_check(sweep, directory))
            )
        except StoreError as exc:
            raise SweepError(str(exc)) from None
        for index, message in invalid.items():  # skipped invalid points are recorded at once
            if index not in store:
                store.append(empty_record(index, sweep.point_values(index), "invalid", message))
        todo = sweep.size - store.count
        if progress is None:
            progress = SweepProgress(sweep.size, done=store.count)
        if todo and executor is not None:
            started = time.perf_counter()
            store.log(f"start: {todo} of {sweep.size} points on {where}")
            try:
                tasks = _tasks(sweep, store)
                _drive(executor, tasks, 2 * slots, store, progress, on_point, computed)
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
        from billiard.scene.scene import scene_to_toml

        outcome = SweepOutcome(directory, directory / RESULT_NAME, computed, where)
        records = _summarised(store.records(), outcome)
        result = write_result(directory / RESULT_NAME, sweep, records, scene_to_toml(sweep.scene))
        if plots:
            from billiard.sweep.netcdf import read_result
            from billiard.sweep.plots import plot_sweep

            outcome.plots = plot_sweep(sweep, read_result(result), directory)
        store.log(f"wrote {result.name}" + "".join(f", {p.name}" for p in outcome.plots))
        if not outcome.measured:
            store.log(f"no point measured: {dict(outcome.statuses)}")
    return outcome


def _summarised(records: Iterable[dict[str, Any]], outcome: SweepOutcome) -> Iterator[dict]:
    """The records, passed on one at a time, counted into ``outcome`` on the way."""
    examples: dict[int, dict[str, Any]] = {}
    for record in records:
        outcome.classes[record["attractor"]] += 1
        outcome.statuses[record["status"]] += 1
        if record["status"] == "failed":
            examples[int(record["index"])] = record
            if len(examples) > 5:  # keep the five lowest indices
                examples.pop(max(examples))
        yield record
    outcome.failed_examples = [examples[i] for i in sorted(examples)]


def _tasks(sweep: Sweep, store: PointStore) -> Iterator[PointTask]:
    """The points still to compute, in index order, each made when a worker can take it
    (a grid's tasks, scenes included, are never all held)."""
    from billiard.scene.scene import with_values

    settings = sweep.settings()
    for index in range(sweep.size):
        if index in store:
            continue
        values = sweep.point_values(index)
        yield PointTask(index, values, with_values(sweep.scene, values), settings)


def _drive(
    executor: Executor,
    todo: Iterator[PointTask],
    window: int,
    store: PointStore,
    progress: SweepProgress,
    on_point: Callable[[dict[str, Any]], None] | None,
    computed: array.array,
) -> None:
    queue = todo
    pending: dict[Future, PointTask] = {}
    submitted_at: dict[int, float] = {}

    def fill() -> None:
        while len(pending) < window:
            task = next(queue, None)
            if task is None:
                return
            pending[executor.submit(measure_point, task)] = task
            submitted_at[task.index] = time.perf_counter()

    try:
        fill()
        while pending:
            done, _ = wait(list(pending), timeout=1.0, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: pending[f].index):
                task = pending.pop(future)
                try:
                    record = future.result()
                except Exception as exc:  # a worker died (killed, out of memory)
                    message = " ".join(str(exc).split()) or type(exc).__name__
                    raise SweepError(
                        f"point {task.index}: the worker running it failed ({message}); "
                        f"finished points are kept: continue with --resume"
                    ) from None
                store.append(record)
                computed.append(task.index)
                seconds = time.perf_counter() - submitted_at.pop(task.index)
                store.log(
                    f"point {task.index}: {record['status']} {record['attractor']}, "
                    f"{record['total_impacts']} impacts, {seconds:.3f} s since submitted"
                )
                progress.point(record)
                if on_point is not None:
                    on_point(record)
            fill()
            progress.tick()
    finally:
        for future in pending:
            future.cancel()


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
