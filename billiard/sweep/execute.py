"""Running a sweep: check every point, then measure the rest on an executor.

One code path for both places a sweep runs: points are submitted to a
``concurrent.futures`` executor, a :class:`~concurrent.futures.ProcessPoolExecutor` on
this machine or a ``dask.distributed`` client's executor (``client.get_executor()``) on
a cluster, at most two points per worker in flight. Each finished point is appended to
``DIR/points.jsonl`` at once, so an interrupted sweep keeps everything finished and
``resume`` computes only the rest.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from billiard.sweep.definition import Sweep, SweepError, read_sweep_file, sweep_to_toml
from billiard.sweep.measure import PointTask, empty_record, measure_point
from billiard.sweep.netcdf import RESULT_NAME, write_result
from billiard.sweep.progress import SweepProgress
from billiard.sweep.store import (
    POINTS_NAME,
    SCENE_NAME,
    SWEEP_NAME,
    PointStore,
    StoreError,
    read_points,
)

__all__ = ["SweepInterrupted", "SweepOutcome", "StopSweep", "load_sweep_dir", "run_sweep"]

DASK_HINT = 'pip install "realworld-billiard[dask]"'


class StopSweep(Exception):
    """Raised by an ``on_point`` callback to stop the sweep after the current point (as
    Ctrl-C does)."""


class SweepInterrupted(KeyboardInterrupt):
    """The sweep stopped before every point was finished; the finished ones are kept."""

    def __init__(self, directory: Path, done: int, total: int):
        super().__init__(f"{done} of {total} points kept in {directory}")
        self.directory, self.done, self.total = directory, done, total


@dataclass
class SweepOutcome:
    """What :func:`run_sweep` did.

    Attributes:
        directory: the sweep folder.
        result: path of the result file.
        computed: indices of the points measured in this session, in finishing order.
        records: every point's record, by index.
        plots: the plot files drawn.
        where: where the points ran (for the log and the summary).
    """

    directory: Path
    result: Path
    computed: list[int]
    records: list[dict[str, Any]]
    where: str
    plots: list[Path] = field(default_factory=list)

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.records if r["status"] != "ok"]


# ----------------------------------------------------------------------------------------
# checking the points


def _describe(values: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in values.items())


_GEOMETRY_PREFIXES = ("boundary.", "ball.", "initial.")


def prepare(sweep: Sweep, skip_invalid: bool = False) -> list[PointTask | dict[str, Any]]:
    """Every point's task, after checking that its scene is valid and its geometry can be
    simulated (one impact); curves are derived here, once, before any worker starts.

    Raises:
        SweepError: a point's scene is invalid (naming the point and the key), unless
            ``skip_invalid``, which records such points as ``invalid`` instead.
    """
    from billiard import simulate, with_values
    from billiard.curves import load_curve

    settings = sweep.settings()
    per_point = any(a.key.startswith(_GEOMETRY_PREFIXES) for a in sweep.axes)
    checked: dict[Any, str | None] = {}
    out: list[PointTask | dict[str, Any]] = []
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
            if geometry not in checked:
                try:
                    load_curve(curve[0], dict(curve[1]))  # derived (and cached) once
                    simulate(scene, collisions=1)
                    checked[geometry] = None
                except ValueError as exc:  # SceneError, GeometryError, curve errors
                    checked[geometry] = str(exc)
            problem = checked[geometry]
        if problem is not None:
            message = " ".join(problem.split())
            if not skip_invalid:
                raise SweepError(
                    f"point {index} ({_describe(values)}): {message} "
                    "(no point was run; --skip-invalid records such points as invalid)"
                )
            out.append(empty_record(index, values, "invalid", message))
            continue
        out.append(PointTask(index, values, scene, settings))
    return out


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
    try:
        client = distributed.Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
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


# ----------------------------------------------------------------------------------------
# the sweep folder


def load_sweep_dir(directory: Path) -> Sweep:
    """The sweep stored in a sweep folder (``DIR/sweep.toml`` and ``DIR/scene.toml``)."""
    path = directory / SWEEP_NAME
    if not path.is_file():
        raise SweepError(f"cannot resume {directory}: no {SWEEP_NAME} (not a sweep folder)")
    scene, axes, settings, _ = read_sweep_file(path)
    return Sweep(scene, tuple(axes), **settings)


def _start_dir(directory: Path, sweep: Sweep) -> None:
    if directory.exists() and not directory.is_dir():
        raise SweepError(f"cannot write the sweep: {directory} is a file")
    if (directory / SWEEP_NAME).exists() or (directory / POINTS_NAME).exists():
        raise SweepError(
            f"{directory} already holds a sweep; continue it with `billiard sweep --resume "
            f"{directory}` or choose another --out"
        )
    directory.mkdir(parents=True, exist_ok=True)
    from billiard.scene import scene_to_toml

    for name, text in (
        (SCENE_NAME, scene_to_toml(sweep.scene)),
        (SWEEP_NAME, sweep_to_toml(sweep)),
    ):
        tmp = directory / f".{name}.tmp"
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, directory / name)


def _check_records(sweep: Sweep, records: dict[int, dict[str, Any]], directory: Path) -> None:
    for index, record in records.items():
        if not 0 <= index < sweep.size or record.get("values") != sweep.point_values(index):
            raise SweepError(
                f"cannot resume {directory}: {POINTS_NAME} has point {index} with values "
                f"{record.get('values')!r}, which is not in {SWEEP_NAME}"
            )


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
    if workers is not None and workers < 1:
        raise SweepError(f"--workers {workers}: needs at least 1 worker")
    tasks = prepare(sweep, skip_invalid=skip_invalid or sweep.skip_invalid)  # nothing written yet
    try:
        stored, _ = read_points(directory / POINTS_NAME) if resume else ([], 0)
    except StoreError as exc:
        raise SweepError(f"cannot resume: {exc}") from None
    finished = {int(r["index"]) for r in stored}
    work = any(isinstance(t, PointTask) and t.index not in finished for t in tasks)
    computed: list[int] = []
    where = "nothing to compute"
    with contextlib.ExitStack() as stack:
        executor = slots = None
        if work:  # reach the workers (or the scheduler) before writing anything
            stack.enter_context(_terminate_as_interrupt())
            opener = dask_executor(dask) if dask else local_executor(workers or os.cpu_count() or 1)
            executor, slots, where = stack.enter_context(opener)
        if not resume:
            _start_dir(directory, sweep)
        try:
            store = stack.enter_context(PointStore(directory))
        except StoreError as exc:
            raise SweepError(str(exc)) from None
        _check_records(sweep, store.records, directory)
        for item in tasks:  # skipped invalid points are recorded at once
            if isinstance(item, dict) and item["index"] not in store.records:
                store.append(item)
        todo = [t for t in tasks if isinstance(t, PointTask) and t.index not in store.records]
        if progress is None:
            progress = SweepProgress(sweep.size, done=len(store.records))
        if todo and executor is not None:
            started = time.perf_counter()
            store.log(f"start: {len(todo)} of {sweep.size} points on {where}")
            try:
                _drive(executor, todo, 2 * slots, store, progress, on_point, computed)
            except (KeyboardInterrupt, StopSweep):
                progress.close()
                store.log(f"interrupted: {len(store.records)} of {sweep.size} points kept")
                raise SweepInterrupted(directory, len(store.records), sweep.size) from None
            finally:
                progress.close()
            elapsed = time.perf_counter() - started
            store.log(
                f"done: {len(computed)} points in {elapsed:.2f} s on {where} "
                f"({progress.impacts / max(elapsed, 1e-9):,.0f} impacts/s)"
            )
        records = [store.records[i] for i in range(sweep.size)]
        from billiard.scene import scene_to_toml

        result = write_result(directory / RESULT_NAME, sweep, records, scene_to_toml(sweep.scene))
        outcome = SweepOutcome(directory, result, computed, records, where)
        if plots:
            from billiard.sweep.plots import plot_sweep

            outcome.plots = plot_sweep(sweep, records, directory)
        store.log(f"wrote {result.name}" + "".join(f", {p.name}" for p in outcome.plots))
    return outcome


def _drive(
    executor: Executor,
    todo: Sequence[PointTask],
    window: int,
    store: PointStore,
    progress: SweepProgress,
    on_point: Callable[[dict[str, Any]], None] | None,
    computed: list[int],
) -> None:
    queue = iter(todo)
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
