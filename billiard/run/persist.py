"""Streamed runs that survive interruptions, and resuming them.

A streamed run (``simulate(..., out_dir=DIR)``) keeps three files in DIR:

``scene.toml``
    the fully resolved scene, written before the first impact.
``collisions.csv``
    one row per impact, written in whole rows and synced at least once a second; or,
    stored as binary (``store="npy"``, :mod:`billiard.run.store`), ``collisions.npy``:
    typed rows, the count in its header rewritten after each flush. The side files
    (``contacts``, ``trajectory``) are stored the same way.
``checkpoint.json``
    written atomically with every flush: the number of rows on disk and the complete
    :class:`~billiard.engine.state.EngineState` after the last of them. :func:`resume`
    continues from it, and the finished CSV equals that of an uninterrupted run byte for
    byte, because the engine state holds everything the engine carries from one impact
    to the next (the compensated clock, the collapse detector's window, the surfaces'
    Newton warm starts, the flight integrator's step proposal), written with
    :func:`repr` so that every float reads back exactly. The last checkpoint of a run
    that ended also holds its outcome (the simulated time reached, the ball's motion
    state, the time per motion state), which :func:`~billiard.run.load.open_run` reads.

SIGINT (Ctrl-C) and SIGTERM during a streamed run stop it at the next impact boundary:
the rows so far are flushed, a final checkpoint is written and
:class:`~billiard.engine.interrupt.RunInterrupted` (a ``KeyboardInterrupt``) is raised. A second
signal stops at once; the files then still hold a valid prefix of the run and the last
checkpoint, from which :func:`resume` redoes the few impacts after it. A SIGKILL leaves
the last checkpoint (at most a second old) and possibly rows after it, even an
unterminated last line; :func:`resume` keeps the whole rows after the checkpoint (it
compares each recomputed impact with the row on disk instead of writing it again) and
cuts an unterminated last line off. A failed write (a full disk) raises
:class:`RunWriteError` and leaves the same: whole rows, possibly after the checkpoint.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import shlex
import signal
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from billiard.engine.interrupt import RunInterrupted, StopRequest, signals_deferred
from billiard.engine.simulation import COLLAPSE_COUNT, Progress, Simulation
from billiard.engine.state import EngineState
from billiard.run.output_size import (
    SampleEstimate,
    check_samples,
    estimate_samples,
    guard_samples,
)
from billiard.run.result import Result, RunFile
from billiard.run.resume_checks import check_state
from billiard.run.store import choose_store
from billiard.run.verify import (
    UNVERIFIED,
    Recorded,
    recorded,
    table_file,
    verify_files,
    verify_sides,
)
from billiard.runfile.checkpoint import (
    CheckpointError,
    read_checkpoint,
    write_checkpoint,
    write_text_atomic,
)
from billiard.runfile.csvfile import _open_locked
from billiard.runfile.folder import CHECKPOINT_JSON
from billiard.runfile.npyfile import COLLISIONS, CONTACTS, TABLES, TRAJECTORY
from billiard.runfile.npystream import NpyMark, NpyRecorder, SideNpy
from billiard.runfile.record import CONTACT_COLUMNS, TRAJECTORY_COLUMNS
from billiard.runfile.sidecsv import SideCsv
from billiard.runfile.stream import CsvRecorder, RowMismatchError, RunBusyError, Truncation
from billiard.runfile.write_error import RunWriteError
from billiard.scene.scene import scene_from_toml, scene_to_toml
from billiard.scene.spec import check_collisions
from billiard.scene.userfile import MAX_SCENE_BYTES, FileRefused, read_limited
from billiard.status import Status

__all__ = [
    "CHECKPOINT_NAME",
    "CSV_NAME",
    "NPY_NAME",
    "SCENE_NAME",
    "RunWriteError",
    "resume",
    "run_streamed",
]

#: File names inside a run directory.
CSV_NAME = "collisions.csv"
NPY_NAME = COLLISIONS.npy_name
SCENE_NAME = "scene.toml"
CHECKPOINT_NAME = CHECKPOINT_JSON

OnRecord = Callable[[int], None]
Stream = CsvRecorder | NpyRecorder


def _store_of(stream: Stream) -> str:
    return "npy" if isinstance(stream, NpyRecorder) else "csv"


def _data_name(store: str) -> str:
    """The impacts' file of a run stored as ``store``."""
    return table_file("collisions", store)


def _side_name(name: str, store: str) -> str:
    """The file of the side table ``name`` (``contacts``, ``trajectory``) of a run
    stored as ``store``."""
    return table_file(name, store)


def _drop_other_store(out: Path, store: str) -> None:
    """Remove the files of the other store an earlier run left in ``out`` (a folder holds
    one run: its rows in one store), each after taking its lock: a run still writing one
    is left alone (:class:`RunBusyError`)."""
    for table in TABLES:
        path = out / (table.csv_name if store == "npy" else table.npy_name)
        if not path.exists():
            continue
        fd = _open_locked(path)
        try:
            path.unlink()
        finally:
            os.close(fd)


def run_streamed(
    sim: Simulation,
    out_dir: str | os.PathLike[str],
    *,
    collisions: int | None = None,
    progress: Progress | None = None,
    on_record: OnRecord | None = None,
    allow_large: bool = False,
    store: str = "csv",
    notify: Callable[[str], None] | None = None,
) -> Result:
    """Stream a run of ``sim`` (built by the caller, who may have given it its own impact
    law, e.g. to audit every impact) to ``out_dir``: write ``scene.toml`` first, then
    the records with checkpoints.

    ``store``: ``csv`` (collisions.csv), ``npy`` (collisions.npy) or ``auto``
    (:func:`billiard.run.store.choose_store`: binary for a large run, said in one line to
    ``notify``); the files of the other store an earlier run left in ``out_dir`` are
    removed.

    Raises:
        OutputSizeError: ``sim.sample_dt`` makes a trajectory.csv of more than 1 GB and
            ``allow_large`` is False (checked before anything is written), or more rows
            than estimated (raised when it gets there).
        RunBusyError: another process is writing a run in ``out_dir``.
        RunInterrupted: SIGINT or SIGTERM; the files are complete up to the last impact.
    """
    total = sim.scene.run.collisions if collisions is None else check_collisions(collisions)
    resolved = sim.resolved_scene(total)
    samples = _samples(sim, total, sim.initial.t, 0, allow_large)
    store, why = choose_store(store, total, samples)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    # first take the data file (locked: a run still going on in DIR is left alone) ...
    stream: Stream = (
        NpyRecorder(out / NPY_NAME, autoflush=False)
        if store == "npy"
        else CsvRecorder(out / CSV_NAME, autoflush=False)
    )
    try:
        _drop_other_store(out, store)
        # ... then drop the checkpoint of an earlier run, which must not outlive its rows
        (out / CHECKPOINT_NAME).unlink(missing_ok=True)
        write_text_atomic(out / SCENE_NAME, scene_to_toml(resolved))
    except BaseException:
        stream.close()
        raise
    if why is not None and notify is not None:
        notify(why)
    return _run_streamed(
        sim, total, out, stream, sim.start_state(), progress, on_record, samples=samples
    )


def resume(
    out_dir: str | os.PathLike[str],
    *,
    collisions: int | None = None,
    progress: Progress | None = None,
    notify: Callable[[str], None] | None = None,
    on_record: OnRecord | None = None,
    allow_large: bool = False,
) -> Result:
    """Continue a streamed run from its checkpoint.

    Whole rows after the checkpoint's row are kept: each recomputed impact is compared
    with the row on disk rather than written again (a row that differs raises
    :class:`CheckpointError`, the file unchanged); an unterminated last line is cut off.
    The finished file then equals that of an uninterrupted run byte for byte.

    Args:
        out_dir: the run directory (written by ``simulate(..., out_dir=...)``).
        collisions: a new total number of impacts (to extend a run); default the
            scene's ``run.collisions``.
        progress: as for :func:`~billiard.run.simulate.simulate`.
        notify: called with a one-line description of where the run continues from,
            before the first new impact.
        on_record: called with the impact number after each new record.
        allow_large: go on even when the rest of a sampled run may write more than
            1 GB of trajectory.csv (see :mod:`billiard.run.output_size`).

    Returns:
        A :class:`~billiard.run.result.Result`. A run that is already complete (and not
        extended) or that stopped early is left as it is: ``already_finished`` is True.

    Raises:
        CheckpointError: the directory has no usable checkpoint, or its CSV file or
            scene does not match it, or another process is still writing it.
        SceneError: DIR/scene.toml is not a valid scene.
        RunInterrupted: as for :func:`~billiard.run.simulate.simulate`.
        RunWriteError: a write failed (a full disk); every whole row is kept.
        OutputSizeError: as for :func:`run_streamed`.
    """
    out = Path(out_dir)
    if not out.is_dir():
        raise CheckpointError(f"{out} is not a run directory")
    checkpoint_path = out / CHECKPOINT_NAME
    data = read_checkpoint(checkpoint_path)
    try:
        status = data["status"]
        files = recorded(data)
        store, mark = files.store, files.mark
        fingerprint = data["scene_sha256"]
        engine = data["engine"]
        stop_reason = data.get("stop_reason")
        stop_status = Status(data.get("stop_status", Status.COMPLETE))
        sample = _sample_interval(data.get("sample"))
        side_sizes, side_crcs = files.side_sizes, files.side_crcs
        scene_file_sha256 = data.get("scene_toml_sha256")
    except CheckpointError as exc:  # first: it is a ValueError too
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    except (KeyError, TypeError, ValueError):
        raise CheckpointError(f"{checkpoint_path} lacks an entry it needs") from None
    if status not in ("running", "interrupted", "complete", "stopped"):
        raise CheckpointError(f"{checkpoint_path} has an unknown status {status!r}")
    scene_path = out / SCENE_NAME
    try:
        text = read_limited(scene_path, MAX_SCENE_BYTES).decode("utf-8")
    except FileNotFoundError:
        raise CheckpointError(f"{scene_path} is missing") from None
    except FileRefused as exc:
        raise CheckpointError(f"{scene_path} {exc.reason}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CheckpointError(f"{scene_path} cannot be read: {exc}") from None
    scene = scene_from_toml(text, source=f"'{scene_path}'")
    sim = Simulation(scene)
    sim.sample_dt = sample
    if _fingerprint(sim) != fingerprint:
        raise CheckpointError(
            f"{scene_path} is not the scene the checkpoint was written for (edited since?)"
        )
    if (
        scene_file_sha256 is not None
        and _sha256(text.encode("utf-8")) != scene_file_sha256
        # scene.toml as billiard writes it for a new total (an extended run, the
        # checkpoint not yet rewritten): the impact count is all that differs
        and text != scene_to_toml(sim.resolved_scene(scene.run.collisions))
    ):
        raise CheckpointError(
            f"{scene_path} was edited after the checkpoint was written (its sha256 differs)"
        )
    total = scene.run.collisions if collisions is None else check_collisions(collisions)
    rows = mark.rows
    csv_path = out / _data_name(store)
    if csv_path.is_file() and csv_path.stat().st_size < mark.size:
        samples = _samples(sim, total, sim.initial.t, 0, allow_large)
        return _recompute(
            out, scene, total, rows, progress, notify, on_record, sim.sample_dt, samples,
            store,
        )  # fmt: skip
    by_time = scene.run.duration is not None and collisions is None
    if status == "stopped" or (status == "complete" and (total <= rows or by_time)):
        if collisions is not None and total < rows:
            raise CheckpointError(
                f"the run in {out} already has {rows} impacts; to extend it, ask for more"
            )
        # a finished run is read as it is: its files must be the ones its checkpoint
        # describes, whole
        try:
            verify_files(out, files)
        except CheckpointError as exc:
            raise type(exc)(f"{exc}; {_restart_hint(out)}") from None
        if not files.checked and notify is not None:
            notify(f"{out}: {UNVERIFIED}")
        final_time = math.nan
        with contextlib.suppress(CheckpointError):
            last = EngineState.from_dict(engine, COLLAPSE_COUNT + 1)
            sim.counts, final_time = dict(last.counts), last.ball.t
        return Result(
            scene,
            RunFile(csv_path, rows),
            stop_status,
            stop_reason,
            0.0,
            sim.counts,
            final_time,
            regimes=sim.impact.regimes,
            resumed_from=rows,
            already_finished=True,
        )
    if total < rows:
        raise CheckpointError(f"the run in {out} already has {rows} impacts, more than {total}")
    if engine is None:
        raise CheckpointError(f"{checkpoint_path} holds no engine state to continue from")
    try:
        state = EngineState.from_dict(engine, COLLAPSE_COUNT + 1)
    except CheckpointError as exc:
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    if state.impacts != rows:
        raise CheckpointError(
            f"{checkpoint_path} is inconsistent: engine state after impact {state.impacts}, "
            f"CSV position after impact {rows}"
        )
    # check the state before touching the CSV file: a mismatch leaves everything as it was
    try:
        sim.restore(state)
        check_state(state, sim, rows=rows, sample=sample, regimes=tuple(sim.impact.regimes))
    except CheckpointError as exc:
        raise CheckpointError(f"{checkpoint_path}: {exc}") from None
    _check_sides(out, files, state.samples)
    sim.resolved_scene(total)  # validates the new total
    samples = _samples(sim, total, state.ball.t, state.impacts, allow_large)
    try:
        stream: Stream
        if isinstance(mark, NpyMark):
            stream, cut = NpyRecorder.reopen(csv_path, mark, autoflush=False)
        else:
            stream, cut = CsvRecorder.reopen(csv_path, mark, autoflush=False)
    except CheckpointError as exc:
        if isinstance(exc, RunBusyError):
            raise
        raise CheckpointError(f"{exc}; {_restart_hint(out)}") from None
    if notify is not None:
        notes = []
        if cut.rows:
            notes.append(
                f"{cut.rows} row(s) written after the checkpoint are kept "
                f"(each checked against the recomputed impact)"
            )
        if cut.partial_bytes:
            what = "a row cut short" if store == "npy" else "an unterminated last line"
            notes.append(f"dropped {what} ({cut.partial_bytes} bytes)")
        if not files.checked:
            notes.append(UNVERIFIED)
        note = f"; {'; '.join(notes)}" if notes else ""
        notify(f"resuming {out} after impact {rows} of {total}{note}")
    return _continue(
        sim, scene, total, out, stream, state, progress, on_record, rows, cut, side_sizes,
        samples, side_crcs,
    )  # fmt: skip


def _recompute(
    out: Path,
    scene: Any,
    total: int,
    checkpoint_rows: int,
    progress: Progress | None,
    notify: Callable[[str], None] | None,
    on_record: OnRecord | None,
    sample: float | None = None,
    samples: SampleEstimate | None = None,
    store: str = "csv",
) -> Result:
    """Resume a run whose data file is shorter than its checkpoint says (cut short by
    hand, or restored from an older copy): the run is deterministic, so it is recomputed
    from the scene's initial state, each recomputed row is checked against the row on
    disk (the file is left as it is and the old checkpoint kept until every whole row
    has matched), and the run continues after them."""
    csv_path = out / _data_name(store)
    recorder = NpyRecorder if store == "npy" else CsvRecorder
    try:
        header = recorder.header_mark(csv_path)
    except CheckpointError as exc:
        raise CheckpointError(f"{exc}; {_restart_hint(out)}") from None
    sim = Simulation(scene)  # a fresh engine: no memory of the checkpoint's state
    sim.sample_dt = sample
    sim.resolved_scene(total)  # validates the new total
    stream, cut = recorder.reopen(csv_path, header, autoflush=False)  # type: ignore[arg-type]
    if notify is not None:
        what = "a row cut short" if store == "npy" else "an unterminated last line"
        partial = (
            f" and {what} ({cut.partial_bytes} bytes), to be dropped" if cut.partial_bytes else ""
        )
        notify(
            f"{csv_path} holds {cut.rows} of the {checkpoint_rows} impacts its checkpoint "
            f"describes{partial}: recomputing the run from its start, checking each of "
            f"the {cut.rows} rows on disk against the recomputed impact, then continuing "
            f"to impact {total}"
        )
    return _continue(
        sim, scene, total, out, stream, sim.start_state(), progress, on_record, 0, cut,
        samples=samples,
    )  # fmt: skip


def _continue(
    sim: Simulation,
    scene: Any,
    total: int,
    out: Path,
    stream: Stream,
    start: EngineState,
    progress: Progress | None,
    on_record: OnRecord | None,
    resumed_from: int,
    cut: Truncation,
    side_sizes: Any = None,
    samples: SampleEstimate | None = None,
    side_crcs: Any = None,
) -> Result:
    """Go on with a resumed run from ``start`` (after recording a new total in scene.toml)."""
    if total != scene.run.collisions:
        write_text_atomic(out / SCENE_NAME, scene_to_toml(sim.resolved_scene(total)))
    with _mismatch_hint(out):
        return _run_streamed(
            sim, total, out, stream, start, progress, on_record,
            resumed_from=resumed_from, truncation=cut, side_sizes=side_sizes,
            samples=samples, side_crcs=side_crcs,
        )  # fmt: skip


@contextlib.contextmanager
def _mismatch_hint(out: Path) -> Iterator[None]:
    """Add the way forward to a row that does not match its recomputation."""
    try:
        yield
    except RowMismatchError as exc:
        raise CheckpointError(f"{exc}; {_restart_hint(out)}") from None


def _restart_hint(out: Path) -> str:
    """The command that starts the run in ``out`` again from its beginning."""
    return (
        f"to start it again from the beginning: `billiard run "
        f"{shlex.quote(str(out / SCENE_NAME))} --out {shlex.quote(str(out))} --overwrite`"
    )


def _sample_interval(value: Any) -> float | None:
    """The checkpoint's sampling interval (s): None, or a number > 0 (a zero would make
    the run sample one instant for ever)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CheckpointError(f"its sampling interval {value!r} is not a number")
    if not (math.isfinite(value) and value > 0):
        raise CheckpointError(f"its sampling interval {value!r} is not a number > 0 s")
    return float(value)


def _samples(
    sim: Simulation, total: int, start_time: float, start_impacts: int, allow_large: bool
) -> SampleEstimate | None:
    """The estimate of a sampled run's trajectory.csv from where it starts (None when it
    samples nothing); refused over the limit unless ``allow_large``."""
    if sim.sample_dt is None:
        return None
    estimate = estimate_samples(
        sim, total, start_time=start_time, start_impacts=start_impacts, in_memory=False
    )
    if not allow_large:
        estimate = check_samples(estimate, sample=sim.sample_dt, allow="allow_large=True")
    return estimate


def _check_sides(out: Path, files: Recorded, samples: int) -> None:
    """Check the side files' rows before the checkpoint (unchanged, and as many samples
    in trajectory.csv as the engine state made) before anything is written."""
    rows = verify_sides(out, files, whole=False, current=True)
    if "trajectory" in rows and rows["trajectory"] != samples:
        path = out / _side_name("trajectory", files.store)
        raise CheckpointError(
            f"{path} holds {rows['trajectory']} samples before the checkpoint, its engine "
            f"state says {samples} (was the file edited?)"
        )


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _fingerprint(sim: Simulation) -> str:
    """sha256 of the resolved scene, impact count aside (a run may be extended)."""
    return _sha256(scene_to_toml(sim.resolved_scene(1)).encode("utf-8"))


def _run_streamed(
    sim: Simulation,
    total: int,
    out: Path,
    stream: Stream,
    start: EngineState,
    progress: Progress | None,
    on_record: OnRecord | None,
    *,
    resumed_from: int | None = None,
    truncation: Truncation | None = None,
    side_sizes: Mapping[str, int] | None = None,
    samples: SampleEstimate | None = None,
    side_crcs: Mapping[str, int | None] | None = None,
) -> Result:
    """Run ``sim`` from ``start`` to ``total`` impacts, streaming rows to ``stream`` and
    keeping ``out/checkpoint.json`` in step with what the CSV file holds (and the side
    files, contacts.csv and trajectory.csv, cut back to ``side_sizes`` on a resume)."""
    checkpoint_path = out / CHECKPOINT_NAME
    fingerprint = _fingerprint(sim)
    saved = [start.impacts]
    store = _store_of(stream)
    sides: dict[str, SideCsv | SideNpy] = {}

    def side(name: str, columns: tuple[str, ...], size: int | None) -> SideCsv | SideNpy:
        path = out / _side_name(name, store)
        if store == "npy":
            table = CONTACTS if name == "contacts" else TRAJECTORY
            return SideNpy(path, table, size, crcs.get(name))
        return SideCsv(path, columns, size, crcs.get(name))

    cut_rows: list[Any] = []
    crcs = side_crcs or {}
    try:
        # the bytes of scene.toml as the run wrote it (a resume checks them)
        scene_file_sha256 = _sha256(read_limited(out / SCENE_NAME, MAX_SCENE_BYTES))
        if sim.phases:
            size = None if side_sizes is None else side_sizes.get("contacts")
            sides["contacts"] = side("contacts", CONTACT_COLUMNS, size)
            sim.on_contact = sides["contacts"].append
            # a phase cut by the run's end is written after the last checkpoint, which
            # does not count it: a resume cuts it off and redoes the phase whole
            sim.on_contact_cut = cut_rows.append
        if sim.sample_dt is not None:
            size = None if side_sizes is None else side_sizes.get("trajectory")
            trajectory = side("trajectory", TRAJECTORY_COLUMNS, size)
            sides["trajectory"] = trajectory
            if samples is None:  # pragma: no cover - every caller estimates them
                raise AssertionError("a sampled run without its estimate")
            sim.on_sample = guard_samples(trajectory.append, samples, start.samples, sim.sample_dt)
    except BaseException:
        for opened in sides.values():
            opened.close()
        stream.close()
        raise

    def save(
        state: EngineState, status: str, reason: str | None = None, *, end: bool = False
    ) -> None:
        if stream.checking:
            # rows already on disk are still being compared with the recomputed ones:
            # the existing checkpoint stays until they all match
            return
        mark = stream.flush()
        if state.impacts != mark.rows:  # pragma: no cover - an engine bug
            raise AssertionError(f"engine state after {state.impacts}, CSV {mark.rows}")
        # the samples the state has made (those of a contact phase a stop cut, which
        # the resumed run makes again, are after them: see ContactPhases._cut)
        marks = {
            name: opened.mark(state.samples - start.samples if name == "trajectory" else None)
            for name, opened in sides.items()
        }
        engine: dict[str, Any] | None = state.to_dict()
        if not _all_finite(engine):
            # only a stopped run can get here (a fault left a memory non-finite); its
            # checkpoint then records the stop without a state to continue from
            engine = None
        ends: dict[str, Any] = {}
        if status != "running":
            # the last checkpoint: the phase the end cut goes after the sizes a resume
            # cuts back to, and the whole files' lengths and CRC-32s let a reader check
            # every byte of them (billiard.run.verify)
            write_cut()
            ends = {"side_end": {n: [o.flush(), o.crc32] for n, o in sides.items()}}
        write_checkpoint(
            checkpoint_path,
            {
                "status": status,
                "stop_reason": reason,
                "stop_status": int(sim.status if sim.status is not None else Status.COMPLETE),
                "collisions": total,
                "method": sim.method,
                "scene_sha256": fingerprint,
                **({"store": "npy", "npy": mark.as_dict()} if store == "npy" else {}),
                **({"csv": mark.as_dict()} if store == "csv" else {}),
                "engine": engine,
                "sample": sim.sample_dt,
                "side": {name: size for name, (size, _) in marks.items()},
                "side_crc32": {name: crc for name, (_, crc) in marks.items()},
                **ends,
                "scene_toml_sha256": scene_file_sha256,
                **({"outcome": _outcome(sim)} if end else {}),
            },
        )
        saved[0] = mark.rows

    def write_cut() -> None:
        """The phase the run's end cut, after the checkpoint that leaves it out."""
        if cut_rows and "contacts" in sides:
            for row in cut_rows:
                sides["contacts"].append(row)
            sides["contacts"].flush()
        cut_rows.clear()

    request = StopRequest()
    began = time.perf_counter()
    try:
        save(start, "running")
        with signals_deferred(request):
            try:
                reason = sim.run(
                    total,
                    stream,
                    progress,
                    start=start,
                    checkpoint=lambda state: save(state, "running"),
                    stop=request,
                    on_record=on_record,
                )
            except RunInterrupted as exc:
                save(sim.state, "interrupted")
                write_cut()
                stream.close()
                exc.rows, exc.checkpoint_rows, exc.out_dir = stream.rows_on_disk, saved[0], out
                raise
            except KeyboardInterrupt as exc:
                # a second signal broke off an impact: the rows so far are whole and the
                # last checkpoint still describes a prefix of them
                stream.close()
                raise RunInterrupted(signal.SIGINT, stream.rows_on_disk, saved[0], out) from exc
            # the run is over: rows on disk it did not reach (none, unless the file
            # held more than the run makes) are not part of it
            stream.end_check()
            save(sim.state, "complete" if reason is None else "stopped", reason, end=True)
            write_cut()
    except OSError as exc:
        stream.close()
        raise RunWriteError.after(
            exc, out, stream.rows_on_disk, saved[0],
            csv=out / _data_name(store), resumable=(out / CHECKPOINT_NAME).is_file(),
        ) from exc  # fmt: skip
    finally:
        stream.close()
        for opened in sides.values():
            opened.close()
    if request.signum:
        # the signal came after the last impact: the files are complete; let it act now
        signal.raise_signal(request.signum)
    wall_time = time.perf_counter() - began
    return Result(
        sim.resolved_scene(total),
        stream,
        sim.status,
        reason,
        wall_time,
        sim.counts,
        sim.final_time,
        regimes=sim.impact.regimes,
        resumed_from=resumed_from,
        truncation=truncation,
        mode_times=sim.mode_times() if sim.phases or sim.sample_dt else None,
        contacts=out / _side_name("contacts", store) if "contacts" in sides else None,
        trajectory=out / _side_name("trajectory", store) if "trajectory" in sides else None,
        final_mode=sim.mode,
    )


def _outcome(sim: Simulation) -> dict[str, Any]:
    """What a run that ended leaves for :func:`~billiard.run.load.open_run` beyond its
    engine state: the simulated time it reached (s; the last impact, ``run.duration`` or
    the end of a rest or contact), the ball's motion state then and the time per motion
    state (s). A non-finite time, which JSON cannot hold, is left out (None)."""
    final_time = sim.final_time if math.isfinite(sim.final_time) else None
    mode_times = sim.mode_times() if sim.phases or sim.sample_dt else None
    if mode_times is not None and not _all_finite(mode_times):
        mode_times = None
    return {"final_time": final_time, "final_mode": sim.mode, "mode_times": mode_times}


def _all_finite(data: Any) -> bool:
    if isinstance(data, float):
        return math.isfinite(data)
    if isinstance(data, Mapping):
        return all(_all_finite(v) for v in data.values())
    if isinstance(data, (list, tuple)):
        return all(_all_finite(v) for v in data)
    return True
