"""A run folder's data files checked against its checkpoint: what
:func:`~billiard.run.load.open_run` and ``billiard run --resume`` read is the run that
was written, byte for byte.

Each checkpoint records, for every data file of the run (the impacts,
``collisions.csv`` or ``collisions.npy``, and the side tables ``contacts`` and
``trajectory``), where its committed rows end and the CRC-32 of their bytes. The
CRC-32 runs along with the writing (each flush continues it from its value: nothing is
read again), and the checkpoint is written atomically after the rows it describes are
synced, so it never describes a byte that is not on disk. The last checkpoint of a run
that ended (complete, stopped or interrupted) describes the whole files, the contact
phase its end cut included (``side_end``): such a file must end there. Rows written
after the last checkpoint of a run that was killed are not covered (a resume checks
them against their recomputation).

A CRC-32, not a cryptographic hash: it is there to find damage (a file edited, cut,
overwritten, or replaced by another run's), which it finds unless the damage happens to
keep the same 32 bits (2^-32), and unlike a SHA-256 it continues from its stored value,
so a resume and each flush extend it without reading the file again. It is no
protection against a deliberate forgery: anyone can compute a checkpoint's checksums.
"""

from __future__ import annotations

import contextlib
import os
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from billiard.errors import UnverifiedDataWarning
from billiard.runfile.checkpoint import CheckpointError, open_checked, read_checkpoint
from billiard.runfile.csvfile import CsvMark, is_crc32
from billiard.runfile.folder import CHECKPOINT_JSON, data_file
from billiard.runfile.npyfile import COLLISIONS, CONTACTS, TRAJECTORY
from billiard.runfile.npystream import NpyMark, check_side_npy
from billiard.runfile.npystream import check_mark as check_npy_mark
from billiard.runfile.record import RunDataError
from billiard.runfile.sidecsv import check_side
from billiard.runfile.stream import check_mark as check_csv_mark

__all__ = [
    "UNVERIFIED",
    "DamagedRunError",
    "Recorded",
    "UnverifiedRunWarning",
    "recorded",
    "table_file",
    "verify_files",
    "verify_run",
    "verify_sides",
]

#: Statuses of a checkpoint written when its run ended: it describes whole files.
ENDED = ("complete", "stopped", "interrupted")
#: Why the files of a run with a checkpoint of version 2 are not verified.
UNVERIFIED = (
    "its checkpoint is of an earlier version, without the checksums of the rows before "
    "it: they are not checked"
)


class UnverifiedRunWarning(UnverifiedDataWarning):
    """A run opened without its files checked: it has no readable checkpoint, or one
    written before the checksums (version 2)."""


class DamagedRunError(CheckpointError, RunDataError):
    """A run file differs from what its checkpoint recorded (edited, cut, overwritten,
    another file in its place). The message is one line naming the file and what
    differs; the command line exits with status 2. Both a
    :class:`~billiard.runfile.checkpoint.CheckpointError` (what a resume raises) and a
    :class:`~billiard.runfile.record.RunDataError` (what reading a run raises)."""


def table_file(name: str, store: str) -> str:
    """The file of the table ``name`` (``collisions``, ``contacts``, ``trajectory``) of
    a run stored as ``store`` (``csv`` or ``npy``)."""
    table = {t.name: t for t in (COLLISIONS, CONTACTS, TRAJECTORY)}[name]
    return table.npy_name if store == "npy" else table.csv_name


@dataclass(frozen=True)
class Recorded:
    """What a checkpoint records of a run's data files."""

    #: ``csv`` or ``npy``
    store: str
    #: where the impacts' committed rows end, and their CRC-32
    mark: CsvMark | NpyMark
    #: each side table's committed bytes (what a resume cuts the file back to) ...
    side_sizes: dict[str, int]
    #: ... and their CRC-32 (None: not recorded, a checkpoint of version 2)
    side_crcs: dict[str, int | None]
    #: each side table's whole length and CRC-32 when the run ended (the cut phase
    #: included); empty for a run still going and in checkpoints written before them
    side_ends: dict[str, tuple[int, int]]
    #: the checkpoint has the checksums (version 3 and later)
    checked: bool
    #: the checkpoint was written when its run ended: the files end where it says
    ended: bool


def recorded(data: Mapping[str, Any]) -> Recorded:
    """The files' marks of the checkpoint ``data`` (read by
    :func:`~billiard.runfile.checkpoint.read_checkpoint`).

    Raises:
        CheckpointError: an entry is missing or malformed (one line, without the path).
    """
    try:
        store = data.get("store", "csv")
        if store not in ("csv", "npy"):
            raise CheckpointError(f"its store {store!r} is neither csv nor npy")
        mark: CsvMark | NpyMark = (
            NpyMark.from_dict(data["npy"]) if store == "npy" else CsvMark.from_dict(data["csv"])
        )
        sizes = {str(k): int(v) for k, v in data.get("side", {}).items()}
        if not set(sizes) <= {"contacts", "trajectory"}:
            raise CheckpointError("its 'side' entry is malformed")
        ends = data.get("side_end") or {}
        if not isinstance(ends, Mapping) or not set(ends) <= set(sizes):
            raise CheckpointError("its 'side_end' entry is malformed")
        side_ends = {str(k): (int(v[0]), int(v[1])) for k, v in ends.items()}
        if not all(is_crc32(crc) for _, crc in side_ends.values()):
            raise CheckpointError("its 'side_end' entry is malformed")
        return Recorded(
            store,
            mark,
            sizes,
            _side_crcs(data.get("side_crc32", {}), sizes),
            side_ends,
            checked=data["version"] >= 3,
            ended=data.get("status") in ENDED,
        )
    except CheckpointError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError):
        raise CheckpointError("it lacks an entry it needs") from None


def _side_crcs(data: Any, sizes: Mapping[str, int]) -> dict[str, int | None]:
    """The checkpoint's CRC-32 of each side file (None where it has none)."""
    if not isinstance(data, Mapping) or not set(data) <= set(sizes):
        raise CheckpointError("its 'side_crc32' entry is malformed")
    crcs = {name: data.get(name) for name in sizes}
    if not all(crc is None or is_crc32(crc) for crc in crcs.values()):
        raise CheckpointError("its 'side_crc32' entry is malformed")
    return crcs


def verify_files(out: Path, files: Recorded) -> None:
    """Check every data file of the run in ``out`` against what its checkpoint recorded
    (``files``): its format (a ``.npy`` file's header is that of its table; a CSV file's
    header and the checkpoint's last line where it says), its committed bytes and their
    CRC-32, and for a run that ended, that nothing follows them. Nothing is changed.

    Cost: one read of each file, at the speed of the disk or of the CRC-32 (a run of
    10^6 impacts is 137 MB binary, 321 MB as CSV).

    Raises:
        DamagedRunError: a file is missing, of another format, or differs from what the
            checkpoint recorded (one line naming the file and what differs).
    """
    path = out / table_file("collisions", files.store)
    with _damaged():
        fd = open_checked(path)
        try:
            if isinstance(files.mark, NpyMark):
                check_npy_mark(fd, path, files.mark, whole=files.ended)
            else:
                check_csv_mark(fd, path, files.mark, whole=files.ended)
        finally:
            os.close(fd)
    verify_sides(out, files, whole=files.ended, missing_ok=True)


def verify_sides(
    out: Path, files: Recorded, *, whole: bool, missing_ok: bool = False, current: bool = False
) -> dict[str, int]:
    """Check the side files (``contacts``, ``trajectory``) of the run in ``out`` against
    what its checkpoint recorded: the bytes a resume keeps, and with ``whole`` (a run
    that ended) the whole files where the checkpoint has their ends. Nothing is changed.
    ``missing_ok``: a side file that is not there is not checked (a reader reads the run
    without it, e.g. trajectory.csv deleted to save space; a resume needs it).
    ``current``: the files must have this version's columns (a resume appends rows to
    them); else contacts written before ``wall`` was an integer are read as they are.

    Returns:
        The rows before the checkpoint's place in each side file checked, by name.

    Raises:
        DamagedRunError: as :func:`verify_files`.
    """
    rows = {}
    with _damaged():
        for name, size in files.side_sizes.items():
            path = out / table_file(name, files.store)
            if missing_ok and not os.path.lexists(path):
                continue
            crc = files.side_crcs.get(name)
            end = files.side_ends.get(name) if whole else None
            table = CONTACTS if name == "contacts" else TRAJECTORY
            if files.store == "npy":
                rows[name] = check_side_npy(path, table, size, crc, end, current=current)
            else:
                columns = table.columns if current else None
                rows[name] = check_side(path, size, crc, end, columns)
    return rows


@contextlib.contextmanager
def _damaged() -> Iterator[None]:
    """A file's check that failed, as a :class:`DamagedRunError`."""
    try:
        yield
    except DamagedRunError:
        raise
    except CheckpointError as exc:
        raise DamagedRunError(str(exc)) from None


def verify_run(
    run_dir: str | os.PathLike[str], *, absent_ok: bool = False
) -> tuple[dict[str, Any], Recorded] | None:
    """Check the data files of the run in the folder ``run_dir`` against its checkpoint
    (:func:`verify_files`: their formats, the CRC-32s of their committed bytes, and for
    a run that ended, that nothing follows them), before they are read.

    Returns:
        The checkpoint and what it records of the files; None where the folder has no
        readable checkpoint: then an :class:`UnverifiedRunWarning` says that the files
        are not verified (as it does for a checkpoint written before the checksums,
        version 2), unless ``absent_ok`` and the folder has no checkpoint at all (a
        folder of tables put together by hand, which a figure may be drawn from).

    Raises:
        DamagedRunError: a data file is missing, of another format than its name says, or
            differs from what the checkpoint recorded; or the checkpoint lacks an entry.
    """
    out = Path(run_dir)
    if absent_ok and not os.path.lexists(out / CHECKPOINT_JSON):
        return None
    try:
        checkpoint = read_checkpoint(out / CHECKPOINT_JSON)
    except CheckpointError as exc:
        # the tables are still there to read: only the outcome is lost, and what the
        # files are checked against
        warnings.warn(f"{exc}: the run's files are not verified", UnverifiedRunWarning, 3)
        return None
    try:
        files = recorded(checkpoint)
    except CheckpointError as exc:
        raise DamagedRunError(f"{out / CHECKPOINT_JSON}: {exc}") from None
    table, expected = data_file(out), out / table_file("collisions", files.store)
    if table != expected and expected.exists():  # a file of the other store: not this run's
        raise DamagedRunError(
            f"{table} is not part of the run in {out}: its checkpoint describes a run "
            f"stored as {expected.name}"
        )
    verify_files(out, files)
    if not files.checked:
        warnings.warn(f"{out}: {UNVERIFIED}", UnverifiedRunWarning, 3)
    return checkpoint, files
