"""The run file: one row per impact (:class:`ImpactRecord`), one column list, one reader
and one writer; rows kept in memory. Streaming a run to disk is :mod:`billiard.runfile.stream`,
its checkpoints :mod:`billiard.runfile.checkpoint`.

Columns (the first thirteen, in this order, are a contract for plots and analyses):

=========  ===============================================================================
n          impact index, 1-based
t          impact time (s)
q1, q2     centre position in the lab frame at the impact (m)
v1, v2     centre velocity just after the impact (m/s)
omega      spin just after the impact (rad/s, counter-clockwise positive)
u4, un     centre velocity just after the impact along c1 (the paper's u4) and c2 (m/s)
tof        time since the previous impact (s); for n = 1 the time since the start
regime     ``stick``, ``slip`` or ``elastic`` (the low-velocity rule)
z          tangent angle of the boundary at the contact (rad; pi for the lid)
energy     mechanical energy just after the impact (J), potential zero at q2 = 0
wall       index of the wall hit (``0``, ``1``, ...), ``-1`` for the lid (:data:`LID_WALL`)
Rt, Rn     impulse on the ball along c1 and c2 (N s)
s          abscissa of the contact point in the boundary frame (m)
q3         rotation angle of the ball (rad), the integral of the spin
=========  ===============================================================================

Floats are written with :func:`repr`, so a CSV file reads back bit for bit. ``wall`` is an
integer in the file too; files written before it was (the lid as the word ``lid``) still
read, the lid as ``-1``. A run may instead be stored as ``collisions.npy``, typed binary
rows (:mod:`billiard.runfile.npyfile`); :func:`billiard.runfile.tables.read_collisions`
reads either.

A streamed file (:mod:`billiard.runfile.stream`) only ever grows by whole rows; an unterminated
last line, the remains of a write cut short by a kill, is skipped by the reader here.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from billiard.kernels.layout import REGIMES
from billiard.runfile.rows import (
    LID_WALL,
    NO_WALL,
    column_arrays,
    format_rows,
    row_of,
    wall_code,
)
from billiard.scene.userfile import FileRefused, check_regular

__all__ = [
    "record_of",
    "COLUMNS",
    "CONTACT_COLUMNS",
    "TRAJECTORY_COLUMNS",
    "ContactRecord",
    "REQUIRED_COLUMNS",
    "TEXT_COLUMNS",
    "ImpactRecord",
    "LID_WALL",
    "NO_WALL",
    "RunDataError",
    "MemoryRecorder",
    "read_collisions_csv",
    "format_field",
    "header_line",
    "write_collisions",
]


class ImpactRecord(NamedTuple):
    """One impact, as :meth:`billiard.engine.simulation.Simulation.step` returns it and as it is
    written to ``collisions.csv`` (one row; the fields are the columns, in order)."""

    n: int
    t: float
    q1: float
    q2: float
    v1: float
    v2: float
    omega: float
    u4: float
    un: float
    tof: float
    regime: str
    z: float
    energy: float
    wall: int
    Rt: float
    Rn: float
    s: float
    q3: float


class ContactRecord(NamedTuple):
    """One rolling or sliding phase (``contact.model = "phases"``), as
    :meth:`billiard.engine.simulation.Simulation.step` returns it and as it is written to
    ``contacts.csv`` (columns in the README's table). ``wall`` is the wall's index (-1
    the lid); a phase held by two walls (``mode`` ``held``) has the second in
    ``wall_other``, every other phase :data:`NO_WALL` there (the last column, so that a
    phase on one wall is built without it)."""

    t_start: float
    t_end: float
    wall: int
    mode: str
    end: str
    t_settle: float
    q1_start: float
    q2_start: float
    v1_start: float
    v2_start: float
    omega_start: float
    q1_end: float
    q2_end: float
    v1_end: float
    v2_end: float
    omega_end: float
    wall_other: int = NO_WALL


#: The columns of ``contacts.csv``, in order.
CONTACT_COLUMNS: tuple[str, ...] = ContactRecord._fields
#: The columns of ``trajectory.csv`` (``billiard run --sample DT``), in order.
TRAJECTORY_COLUMNS: tuple[str, ...] = ("t", "q1", "q2", "v1", "v2", "omega", "energy", "mode")

#: The columns of ``collisions.csv``, in order: the fields of :class:`ImpactRecord`.
COLUMNS: tuple[str, ...] = ImpactRecord._fields
#: Columns every run file must have for plots and analyses (the first thirteen).
REQUIRED_COLUMNS: tuple[str, ...] = COLUMNS[:13]
#: Columns read as text; ``n`` and ``wall`` are integers, every other column a float.
TEXT_COLUMNS: frozenset[str] = frozenset({"regime"})
_TEXT = TEXT_COLUMNS | {"mode", "end"}  # the latter two: contacts.csv, trajectory.csv
_INTEGER = frozenset({"n", "wall"})
_SIDE_INTEGER = frozenset({"wall", "wall_other"})  # contacts.csv
#: Line terminator of the rows written: a plain newline, so that line tools (awk, cut,
#: sort) see ``0.5`` and not ``0.5\r``. Files written with ``\r\n`` (by older versions)
#: still read, and a resumed one is continued with its own terminator.
LINE_END = "\n"
_LINE_ENDS = ("\n", "\r\n")


class RunDataError(ValueError):
    """A run's files cannot be read; the message is one line naming the file."""


def _as_arrays(columns: dict[str, list[Any]]) -> dict[str, np.ndarray]:
    """Arrays of the values of each column: those of ``collisions.csv`` or of a side
    table (contacts, samples)."""
    out: dict[str, np.ndarray] = {}
    for name, values in columns.items():
        if name in _TEXT:
            out[name] = np.array(values, dtype=str)
        elif name == "wall":
            out[name] = np.array([wall_code(v) for v in values], dtype=np.int64)
        elif name in _INTEGER or name in _SIDE_INTEGER:
            out[name] = np.array(values, dtype=np.int64)
        else:
            out[name] = np.array(values, dtype=np.float64)
    return out


def format_field(value: Any) -> str:
    """A CSV field's text: floats by :func:`repr` (read back bit for bit), integers and
    text as they are."""
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, np.integer):
        return str(int(value))
    return str(value)


class MemoryRecorder:
    """Rows kept in memory, column by column; impact rows from the kernels
    (:meth:`append_rows`) are kept as the float64 blocks they come in, so a long run
    holds no Python object per impact."""

    def __init__(self, columns: Sequence[str] = COLUMNS):
        self.names = tuple(columns)
        self._data: list[list[Any]] = [[] for _ in self.names]
        self._blocks: list[np.ndarray] = []
        self._block_rows = 0

    def append(self, row: Sequence[Any]) -> None:
        if self._blocks:
            self.append_rows(np.array([row_of(row)], dtype=np.float64))
            return
        for column, value in zip(self._data, row, strict=True):
            column.append(value)

    def append_rows(self, block: np.ndarray) -> None:
        """Append impact rows (``(rows, NCOL)`` float64, :mod:`billiard.runfile.rows`); only
        for the columns of ``collisions.csv``."""
        if self.names != COLUMNS:
            raise ValueError("rows of impacts go to a recorder of the collisions.csv columns")
        if self._data[0]:
            # records appended before: kept as a block too, in order
            first = [row_of(row) for row in zip(*self._data, strict=True)]
            self._blocks.append(np.array(first, dtype=np.float64))
            self._block_rows += len(first)
            self._data = [[] for _ in self.names]
        self._blocks.append(block)
        self._block_rows += len(block)

    def __len__(self) -> int:
        return self._block_rows + len(self._data[0])

    def close(self) -> None:
        pass

    def columns(self) -> dict[str, np.ndarray]:
        if self._blocks:
            return column_arrays(self.names, self._blocks)
        columns = dict(zip(self.names, self._data, strict=True))
        return _as_arrays(columns)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if not self._blocks:
            write_collisions(path, dict(zip(self.names, self._data, strict=True)))
            return
        with open(path, "w", newline="", encoding="utf-8") as handle:
            handle.write(header_line(self.names))
            for block in self._blocks:
                handle.write(format_rows(block, LINE_END))


def header_line(columns: Sequence[str], line_end: str = LINE_END) -> str:
    """The CSV header line of ``columns``, ended by ``line_end``."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator=line_end).writerow(columns)
    return buffer.getvalue()


def _fail(path: str | os.PathLike[str], problem: str) -> RunDataError:
    return RunDataError(f"{path}: {' '.join(problem.split())}")


def read_collisions_csv(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a run's impacts from ``collisions.csv`` into numpy arrays, one per column
    (:func:`billiard.runfile.tables.read_collisions` reads the binary file too, and is
    the reader to call).

    The first non-blank line that does not start with ``#`` is the header; blank lines
    and ``#`` comment lines are skipped, and so is an unterminated last row (a write cut
    short when the run was killed; resuming the run completes it). A file as billiard
    writes it is parsed in bulk (:mod:`billiard.runfile.csvbulk`), any other one line by
    line; both give the same values, bit for bit.

    Returns:
        A dict column name -> 1-D array with one entry per impact, in file order, with
        the same dtypes as ``Result.columns``: ``n`` and ``wall`` int64 (``wall`` -1 for
        the lid, :data:`LID_WALL`; the word ``lid`` of older CSV files reads as -1),
        ``regime`` strings, every other column of :data:`COLUMNS` float64 in SI units (s,
        m, m/s, rad/s, J, N s). Extra columns are kept (float64 when every value is a
        number, else strings). A file with a header and no rows gives arrays of length 0.

    Raises:
        RunDataError: the file is missing or unreadable, has no header, lacks one of
            :data:`REQUIRED_COLUMNS`, has a row with the wrong number of fields, a value
            that is not of its column's type, or impact times that decrease.
    """
    try:
        check_regular(path)  # /dev/zero or a pipe would be read without end
        from billiard.runfile.csvbulk import read_bulk

        columns = read_bulk(path, COLUMNS, REQUIRED_COLUMNS)
        if columns is not None:
            _check_times(path, columns["t"], None)
            return columns
        with open(path, newline="", encoding="utf-8") as handle:
            return _read_blocks(path, handle)
    except FileRefused as exc:
        raise _fail(path, exc.reason) from None
    except FileNotFoundError:
        raise _fail(path, "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise _fail(path, f"cannot read: {exc}") from None


#: The first bytes of a ``.npy`` file (NumPy's format), by which a binary run file is
#: told from a CSV one.
NPY_MAGIC = b"\x93NUMPY"


def _check_times(path: str | os.PathLike[str], t: np.ndarray, lines: np.ndarray | None) -> None:
    """Refuse impact times that decrease; ``lines``: the file's line number of each row
    (None: the rows are lines 2, 3, ... of a file without blank or comment lines)."""
    if t.size > 1 and np.any(np.diff(t) < 0):
        first_bad = int(np.argmax(np.diff(t) < 0)) + 1
        line = first_bad + 2 if lines is None else int(lines[first_bad])
        raise _fail(path, f"line {line}: impact times decrease (column t must be non-decreasing)")


#: rows parsed at a time: a long run's file is turned into arrays block by block, so
#: reading it never holds a Python string per cell of the whole file
READ_BLOCK = 20_000


def _data_lines(handle: Any) -> Iterator[tuple[int, str]]:
    """(line number, line) of the header and the rows: no blank or ``#`` lines, and no
    unterminated last row (a header alone is kept without its line end)."""
    previous = None
    count = 0
    for number, line in enumerate(handle, start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if previous is not None:
            yield previous
            count += 1
        previous = (number, line)
    if previous is not None and (count == 0 or previous[1].endswith("\n")):
        yield previous


def _read_blocks(path: str | os.PathLike[str], handle: Any) -> dict[str, np.ndarray]:
    lines = _data_lines(handle)
    first = next(lines, None)
    if first is None:
        raise _fail(path, "empty file (no header line)")
    try:
        header = [name.strip() for name in next(csv.reader([first[1]]))]
    except csv.Error as exc:
        raise _fail(path, f"not valid CSV: {exc}") from None
    missing = [name for name in REQUIRED_COLUMNS if name not in header]
    if missing:
        raise _fail(
            path, f"missing column(s) {', '.join(missing)} (header: {','.join(header)[:120]})"
        )
    duplicated = sorted({name for name in header if header.count(name) > 1})
    if duplicated:
        raise _fail(path, f"duplicated column(s) {', '.join(duplicated)}")
    parts: dict[str, list[Any]] = {name: [] for name in header}
    numbers: list[np.ndarray] = []
    block: list[tuple[int, str]] = []
    for item in lines:
        block.append(item)
        if len(block) == READ_BLOCK:
            numbers.append(_read_block(path, header, block, parts))
            block = []
    if block:
        numbers.append(_read_block(path, header, block, parts))
    columns: dict[str, np.ndarray] = {}
    for name in header:
        if name in TEXT_COLUMNS:
            columns[name] = _joined(parts[name], str)
        elif name in COLUMNS:
            columns[name] = _joined(parts[name], int if name in _INTEGER else float)
        else:  # an extra column: numbers if every cell is one, else strings
            cells = [cell for chunk in parts[name] for cell in chunk]
            try:
                columns[name] = np.array([float(cell) for cell in cells], dtype=float)
            except ValueError:
                columns[name] = np.array(cells, dtype=str)
    for name in _INTEGER:
        if columns[name].dtype != np.int64:
            columns[name] = columns[name].astype(np.int64)
    if columns["t"].size > 1:
        _check_times(path, columns["t"], np.concatenate(numbers))
    return columns


def _joined(chunks: list[np.ndarray], kind: type) -> np.ndarray:
    if not chunks:
        return np.array([], dtype=kind)
    return np.concatenate(chunks) if len(chunks) > 1 else chunks[0]


def _read_block(
    path: str | os.PathLike[str],
    header: list[str],
    block: list[tuple[int, str]],
    parts: dict[str, list[Any]],
) -> np.ndarray:
    """Parse the rows of ``block`` into ``parts`` (one array, or for extra columns one
    list of cells, per column); returns their line numbers."""
    try:
        body = list(csv.reader(line for _, line in block))
    except csv.Error as exc:
        raise _fail(path, f"not valid CSV: {exc}") from None
    if len(body) != len(block):
        raise _fail(path, "not valid CSV: a quoted field spans lines")
    width = len(header)
    for (number, _), row in zip(block, body, strict=True):
        if len(row) != width:
            raise _fail(path, f"line {number}: expected {width} fields, got {len(row)}")
    table = list(zip(*body, strict=True))
    for index, name in enumerate(header):
        cells = [cell.strip() for cell in table[index]]
        if name in TEXT_COLUMNS:
            parts[name].append(np.array(cells, dtype=str))
            continue
        if name not in COLUMNS:
            parts[name].append(cells)
            continue
        kind: Any = int if name in _INTEGER else float
        if name == "wall":
            kind = wall_code  # an int, or the word lid of files written before
        dtype = float if kind is float else int
        try:
            parts[name].append(np.array([kind(cell) for cell in cells], dtype=dtype))
        except ValueError:
            for (number, _), cell in zip(block, cells, strict=True):
                try:
                    kind(cell)
                except ValueError:
                    what = {int: "an integer", wall_code: "an integer (or lid)"}.get(
                        kind, "a number"
                    )
                    raise _fail(
                        path, f"line {number}: column {name}: {cell[:40]!r} is not {what}"
                    ) from None
    return np.array([number for number, _ in block], dtype=np.int64)


def write_collisions(path: str | os.PathLike[str], columns: Mapping[str, Sequence[Any]]) -> Path:
    """Write columns (name -> one value per impact) as a CSV file in the
    ``collisions.csv`` format: header line, one row per impact, each ended by
    :data:`LINE_END`, floats with :func:`repr` so that they read back bit for bit."""
    path = Path(path)
    names = list(columns)
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator=LINE_END)
        writer.writerow(names)
        for row in zip(*(columns[name] for name in names), strict=True):
            writer.writerow([format_field(v) for v in row])
    return path


def record_of(row: Sequence[float]) -> Any:
    """The :class:`~billiard.runfile.record.ImpactRecord` of one row (Python floats)."""
    return ImpactRecord(
        int(row[0]),
        *row[1:10],
        REGIMES[int(row[10])],
        row[11],
        row[12],
        int(row[13]),
        *row[14:18],
    )
