"""The side files of a streamed run with ``contact.model = "phases"`` or ``--sample``:
``contacts.csv`` (one row per finished contact phase) and ``trajectory.csv`` (one row
per sample). Each grows by whole rows; a checkpoint records their sizes, and a resumed
run cuts them back to those sizes and writes on, so that they end up byte for byte as
an uninterrupted run writes them.
"""

from __future__ import annotations

import os
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from billiard.runfile.checkpoint import CheckpointError, open_checked
from billiard.runfile.csvfile import _read_at, check_recorded, prefix_crc32, rows_past_flush
from billiard.runfile.record import RunDataError, format_field
from billiard.runfile.rows import contact_walls, wall_code
from billiard.scene.userfile import read_limited

__all__ = ["CONTACTS_NAME", "TRAJECTORY_NAME", "SideCsv", "check_side", "read_side_csv"]

CONTACTS_NAME = "contacts.csv"
TRAJECTORY_NAME = "trajectory.csv"
_TEXT = frozenset({"mode", "end"})
#: Characters of rows collected before they are written (not synced) whatever the time
#: to the next flush: a long flight sampled finely makes millions of rows between two
#: impacts, which would otherwise all wait in memory.
SPILL_CHARS = 1 << 22
#: Bytes read at a time when a mark before the last rows is looked for (:meth:`SideCsv.mark`).
_SCAN_CHUNK = 1 << 20


class SideCsv:
    """A CSV file written by whole rows, buffered until :meth:`flush`, with the CRC-32 of
    what it holds (:attr:`crc32`, for a checkpoint) and the rows appended since it was
    opened (:attr:`appended`).

    Args:
        path: the file.
        columns: its header.
        size: None to start the file afresh; else the size (bytes) a checkpoint
            recorded, to which the file is cut back before writing on.
        crc32: with ``size``, the CRC-32 of the file's first ``size`` bytes, already
            checked (:func:`check_side`); None to compute it here.
    """

    def __init__(
        self,
        path: Path,
        columns: Sequence[str],
        size: int | None = None,
        crc32: int | None = None,
    ):
        self.path = Path(path)
        self._pending: list[str] = []
        self._pending_chars = 0
        self.appended = 0
        if size is None:
            # read as well: a mark before the last rows reads them back (see mark)
            self._file = open(self.path, "w+b")  # noqa: SIM115 - closed by close()
            header = (",".join(columns) + "\n").encode()
            self._file.write(header)
            self.crc32 = zlib.crc32(header)
            size = len(header)
        else:
            try:
                self._file = open(self.path, "r+b")  # noqa: SIM115
            except FileNotFoundError:
                raise CheckpointError(f"{self.path} is missing") from None
            if os.fstat(self._file.fileno()).st_size < size:
                self._file.close()
                raise CheckpointError(f"{self.path} is shorter than its checkpoint says")
            if crc32 is None:
                crc32, _ = prefix_crc32(self._file.fileno(), size)
            self.crc32 = crc32
            self._file.truncate(size)
            self._file.seek(size)
        #: (rows appended, size, CRC-32) at the last flush: where mark reads from
        self._flushed = (0, size, self.crc32)

    def append(self, row: Sequence[Any]) -> None:
        line = ",".join(format_field(v) for v in row) + "\n"
        self._pending.append(line)
        self._pending_chars += len(line)
        self.appended += 1
        if self._pending_chars >= SPILL_CHARS:
            # written, not synced: a resume cuts the file back to its checkpoint's size
            self._write()

    def _write(self) -> None:
        if self._pending:
            data = "".join(self._pending).encode()
            self._file.write(data)
            self.crc32 = zlib.crc32(data, self.crc32)
            self._pending.clear()
            self._pending_chars = 0

    def flush(self) -> int:
        """Write the buffered rows; returns the file's size (bytes)."""
        self._write()
        self._file.flush()
        os.fsync(self._file.fileno())
        size = self._file.tell()
        self._flushed = (self.appended, size, self.crc32)
        return size

    def mark(self, rows: int | None = None) -> tuple[int, int]:
        """Write and sync the buffered rows; return the (size in bytes, CRC-32) of the
        file up to the first ``rows`` rows appended since it was opened (default all of
        them), for a checkpoint. The rows after them stay in the file, after the size the
        checkpoint records (samples of a contact phase cut by a stop, which the engine
        reports again when the run resumes: a resume cuts the file back to that size).

        Raises:
            ValueError: ``rows`` is before the last flush or after the last row.
        """
        done, size, crc = self._flushed
        end = self.flush()
        past = rows_past_flush(done, self.appended, rows)
        if past is None:
            return end, self.crc32
        return _line_mark(self._file.fileno(), size, crc, past)

    def close(self) -> None:
        if not self._file.closed:
            self.flush()
            self._file.close()


def _line_mark(fd: int, offset: int, crc: int, lines: int) -> tuple[int, int]:
    """(offset, CRC-32) just after the ``lines``-th line end at or after ``offset`` in the
    open file ``fd``, the CRC-32 continued from ``crc`` (that of the bytes before
    ``offset``)."""
    while True:
        chunk = _read_at(fd, _SCAN_CHUNK, offset)
        if not chunk:
            raise ValueError(f"the file ends {lines} lines before the mark")
        found = chunk.count(b"\n")
        if found >= lines:
            end = -1
            for _ in range(lines):
                end = chunk.index(b"\n", end + 1)
            return offset + end + 1, zlib.crc32(chunk[: end + 1], crc)
        crc = zlib.crc32(chunk, crc)
        offset += len(chunk)
        lines -= found


def check_side(
    path: Path,
    size: int,
    crc32: int | None,
    end: tuple[int, int] | None = None,
    columns: Sequence[str] | None = None,
) -> int:
    """Check that the side file ``path`` still holds the ``size`` bytes its checkpoint
    recorded, unchanged (their CRC-32 is ``crc32``; None: not recorded, by an earlier
    version), without changing it: before a run resumes, and when a run is opened.
    ``end`` (the last checkpoint of a run that ended): the file's whole length and the
    CRC-32 of all of it, the phase its end cut included; the file must end there.
    ``columns`` (a resume, which appends rows): the header the file must have.

    Returns:
        The number of rows (line ends after the header's) in the first ``size`` bytes.

    Raises:
        CheckpointError: the file is missing, not a regular file, shorter than ``size``,
            its first ``size`` bytes were changed, or its columns are not ``columns``
            (written by an earlier version: rows of this one would not fit them); with
            ``end``, it differs after ``size`` or goes on after ``end``.
    """
    fd = open_checked(path)
    try:
        length = os.fstat(fd).st_size
        if length < size:
            raise CheckpointError(f"{path} is shorter than its checkpoint says")
        crc, lines = prefix_crc32(fd, size)
        header = (",".join(columns) + "\n").encode() if columns is not None else b""
        if header and os.pread(fd, len(header), 0) != header:
            raise CheckpointError(
                f"{path} has other columns than this version writes (written by an earlier "
                f"version?): it cannot be continued; run the scene again without --resume"
            )
        check_recorded(path, fd, crc, crc32, size, end)
        if end is not None:
            stop = end[0]
            if length > stop:
                raise CheckpointError(
                    f"{path} holds {length - stop} bytes after the rows of the finished "
                    f"run its checkpoint describes (was the file edited?)"
                )
    finally:
        os.close(fd)
    return lines - 1


def read_side_csv(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Column name -> numpy array of a side file: text columns as str, ``wall`` and
    ``wall_other`` int64, the rest float64. A ``contacts.csv`` written before ``wall``
    was an integer (``a+b`` for a phase held by two walls, ``lid`` for the lid) reads as
    one written now: ``a+b`` as ``wall`` a and ``wall_other`` b, one wall with
    ``wall_other`` :data:`~billiard.runfile.rows.NO_WALL`.

    Raises:
        OSError: the file cannot be read, or is not a regular file
            (:class:`~billiard.scene.userfile.FileRefused`: a device or a pipe never ends).
        UnicodeDecodeError: the file is not UTF-8 text.
        ValueError: a value that is not of its column's type; RunDataError (a
            ValueError): a row with more or fewer fields than the header has columns.
    """
    lines = read_limited(path, None).decode("utf-8").splitlines()
    names = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:] if line]
    for number, row in enumerate(rows, start=2):
        if len(row) != len(names):
            raise RunDataError(
                f"{path}: line {number} has {len(row)} fields where the header names "
                f"{len(names)} columns (a damaged file?)"
            )
    out: dict[str, np.ndarray] = {}
    for i, name in enumerate(names):
        values = [row[i] for row in rows]
        if name == "wall" and "wall_other" not in names:
            pairs = [contact_walls(v) for v in values]
            out[name] = np.array([a for a, _ in pairs], dtype=np.int64)
            out["wall_other"] = np.array([b for _, b in pairs], dtype=np.int64)
        elif name == "wall":
            out[name] = np.array([wall_code(v) for v in values], dtype=np.int64)
        elif name == "wall_other":
            out[name] = np.array([int(v) for v in values], dtype=np.int64)
        else:
            out[name] = np.array(values, dtype=str if name in _TEXT else np.float64)
    if "wall_other" in out and "wall_other" not in names:
        out["wall_other"] = out.pop("wall_other")  # the last column, as in a file of now
    return out
