"""Binary run files: a run's tables as NumPy ``.npy`` files of typed rows
(``collisions.npy``, ``contacts.npy``, ``trajectory.npy``), the same columns as the CSV
files, read back lazily.

A file is NumPy's format 1.0: a header that names the row type (a structured dtype,
little-endian, packed) and the number of rows, then the rows, raw. The header has a
fixed size for its table (padded with spaces, room for a 20-digit row count), so a file
that grows is rewritten in place: rows are appended at the end and the count in the
header is updated after them (:mod:`billiard.runfile.npystream`). Any NumPy reads it::

    rows = numpy.load("collisions.npy", mmap_mode="r")   # lazy: mapped, not read
    rows["q2"], rows["wall"], rows.dtype.names

Typed columns (units as in the CSV files):

* ``collisions.npy``: ``n`` int64; ``regime`` int8, the code of
  :data:`~billiard.kernels.layout.REGIMES` (0 ``stick``, 1 ``slip``, 2 ``elastic``);
  ``wall`` int64, the wall's index, ``-1`` for the lid; every other column float64.
  137 bytes per impact.
* ``contacts.npy``: ``wall`` and ``wall_other`` int64 (the wall, -1 the lid; the second
  wall of a phase held by two, else -2), ``mode`` and ``end`` fixed-width ASCII text
  (``S5``, ``S8``), the rest float64. Files written before (``wall`` text ``S15``, ``a+b``
  for two walls, no ``wall_other``) read as these.
* ``trajectory.npy``: ``mode`` ASCII text (``S6``), the rest float64.

:func:`read_table` gives the columns with the dtypes of the CSV readers (text as ``str``
arrays, ``regime`` decoded to its labels); its numeric columns are read-only views of the
mapped file.
"""

from __future__ import annotations

import ast
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from billiard.kernels.layout import NCOL
from billiard.runfile.record import (
    COLUMNS,
    CONTACT_COLUMNS,
    LINE_END,
    NPY_MAGIC,
    TRAJECTORY_COLUMNS,
    RunDataError,
    format_field,
    header_line,
)
from billiard.runfile.rows import contact_walls, format_rows_bytes, regime_labels
from billiard.scene.userfile import FileRefused, check_regular

__all__ = [
    "COLLISIONS",
    "CONTACTS",
    "TRAJECTORY",
    "Table",
    "block_of",
    "export_csv",
    "header_bytes",
    "is_legacy_contacts",
    "read_header",
    "read_table",
    "rows_of_block",
    "rows_of_records",
]


@dataclass(frozen=True)
class Table:
    """One table of a run: its file names, its columns and the row type of its binary
    file."""

    #: the table's name in a checkpoint and in messages (``collisions``, ...)
    name: str
    csv_name: str
    npy_name: str
    columns: tuple[str, ...]
    dtype: np.dtype

    @property
    def text(self) -> tuple[str, ...]:
        """The columns stored as fixed-width ASCII text."""
        return tuple(n for n in self.columns if self.dtype[n].kind == "S")


def _dtype(columns: Sequence[str], kinds: dict[str, str]) -> np.dtype:
    """Packed little-endian rows: each column ``kinds[name]``, else float64."""
    return np.dtype([(name, kinds.get(name, "<f8")) for name in columns])


COLLISIONS = Table(
    "collisions",
    "collisions.csv",
    "collisions.npy",
    COLUMNS,
    _dtype(COLUMNS, {"n": "<i8", "regime": "i1", "wall": "<i8"}),
)
CONTACTS = Table(
    "contacts",
    "contacts.csv",
    "contacts.npy",
    CONTACT_COLUMNS,
    _dtype(CONTACT_COLUMNS, {"wall": "<i8", "wall_other": "<i8", "mode": "S5", "end": "S8"}),
)
TRAJECTORY = Table(
    "trajectory",
    "trajectory.csv",
    "trajectory.npy",
    TRAJECTORY_COLUMNS,
    _dtype(TRAJECTORY_COLUMNS, {"mode": "S6"}),
)
TABLES = (COLLISIONS, CONTACTS, TRAJECTORY)

#: digits of the largest row count a header has room for
_COUNT_DIGITS = 20
#: NumPy aligns the data of a .npy file to this many bytes
_ALIGN = 64


def _header_text(dtype: np.dtype, rows: int) -> str:
    descr = np.lib.format.dtype_to_descr(dtype)
    return f"{{'descr': {descr!r}, 'fortran_order': False, 'shape': ({rows},), }}"


def header_size(dtype: np.dtype) -> int:
    """Bytes of the header of a file of ``dtype`` rows, whatever its row count."""
    longest = len(_header_text(dtype, 10**_COUNT_DIGITS - 1)) + 1  # + its newline
    return -(-(len(NPY_MAGIC) + 4 + longest) // _ALIGN) * _ALIGN


def header_bytes(dtype: np.dtype, rows: int) -> bytes:
    """The header of a file of ``rows`` rows of ``dtype`` (:func:`header_size` bytes):
    NumPy's format 1.0, the dict padded with spaces."""
    size = header_size(dtype)
    text = _header_text(dtype, rows).encode("latin1")
    body = size - len(NPY_MAGIC) - 4
    if len(text) + 1 > body:
        raise ValueError(f"{rows} rows do not fit a header of {size} bytes")
    return NPY_MAGIC + b"\x01\x00" + body.to_bytes(2, "little") + text.ljust(body - 1) + b"\n"


def read_header(head: bytes) -> tuple[np.dtype, int, int]:
    """(row dtype, rows, data offset) of a file starting with the bytes ``head``.

    Raises:
        ValueError: not a .npy header of a one-dimensional array of rows.
    """
    if not head.startswith(NPY_MAGIC) or len(head) < len(NPY_MAGIC) + 4:
        raise ValueError("not a .npy file")
    major = head[len(NPY_MAGIC)]
    if major == 1:
        length, start = int.from_bytes(head[8:10], "little"), 10
    elif major in (2, 3):
        length, start = int.from_bytes(head[8:12], "little"), 12
    else:
        raise ValueError(f".npy format version {major} is not known")
    text = head[start : start + length]
    if len(text) < length:
        raise ValueError("its header is cut short")
    try:
        fields = ast.literal_eval(text.decode("latin1" if major < 3 else "utf-8"))
        dtype = np.lib.format.descr_to_dtype(fields["descr"])
        shape, fortran = fields["shape"], fields["fortran_order"]
    except (ValueError, SyntaxError, KeyError, TypeError):
        raise ValueError("its header cannot be read") from None
    if not (isinstance(shape, tuple) and len(shape) == 1 and isinstance(shape[0], int)):
        raise ValueError(f"it holds an array of shape {shape!r}, not a table of rows")
    if fortran or dtype.names is None or shape[0] < 0:
        raise ValueError("it holds no rows of named columns")
    return dtype, shape[0], start + length


def rows_of_block(block: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The ``collisions.npy`` rows of impact rows ``(rows, NCOL)`` float64 (the
    kernels' rows, :mod:`billiard.runfile.rows`), written into ``out`` when given (a
    ``(rows, itemsize)`` uint8 array, e.g. part of a larger buffer).

    The float columns are copied as bytes, a run of consecutive columns at a time (the
    rows are packed: a field-by-field copy into them is several times slower); on a
    big-endian machine field by field, converted to the file's little-endian order.
    """
    block = np.asarray(block, dtype=np.float64).reshape(-1, NCOL)
    rows = len(block)
    item = COLLISIONS.dtype.itemsize
    if out is None:
        out = np.empty((rows, item), dtype=np.uint8)
    if sys.byteorder != "little":  # pragma: no cover - the machines billiard runs on
        fields = out.view(COLLISIONS.dtype).reshape(rows)
        for index, name in enumerate(COLUMNS):
            fields[name] = block[:, index]
        return fields
    for start, stop, offset, kind in _RUNS:
        part = block[:, start:stop]
        if kind is not None:  # an integer column: its value converted, then its bytes
            part = part.astype(kind)
        size = part.shape[1] * part.itemsize
        # one opaque item of ``size`` bytes per row: copied whole, not byte by byte
        whole = np.dtype(f"V{size}")
        out[:, offset : offset + size].view(whole)[...] = part.view(whole)
    return out.view(COLLISIONS.dtype).reshape(rows)


def _byte_runs() -> tuple[tuple[int, int, int, Any], ...]:
    """(first column, column after, byte offset, integer type or None) of each run of
    consecutive float64 columns of ``collisions.npy`` and of each integer column."""
    runs: list[tuple[int, int, int, Any]] = []
    fields = COLLISIONS.dtype.fields or {}
    for index, name in enumerate(COLUMNS):
        kind, offset = fields[name][:2]
        if kind != np.dtype("<f8"):
            runs.append((index, index + 1, offset, kind))
        elif runs and runs[-1][3] is None and runs[-1][1] == index:
            first, _, at, _ = runs[-1]
            runs[-1] = (first, index + 1, at, None)
        else:
            runs.append((index, index + 1, offset, None))
    return tuple(runs)


_RUNS = _byte_runs()


def block_of(rows: np.ndarray) -> np.ndarray:
    """Impact rows ``(rows, NCOL)`` float64 of ``collisions.npy`` rows: the inverse of
    :func:`rows_of_block` (every value is exact in a float64)."""
    out = np.empty((len(rows), NCOL), dtype=np.float64)
    for index, name in enumerate(COLUMNS):
        out[:, index] = rows[name]
    return out


def rows_of_records(records: Sequence[Sequence[Any]], table: Table) -> np.ndarray:
    """The rows of a side table (contacts, samples) of ``records``, tuples of its
    columns' values.

    Raises:
        ValueError: a text longer than its column's width (never cut short).
    """
    for name in table.text:
        width = table.dtype[name].itemsize
        index = table.columns.index(name)
        longest = max(records, key=lambda record: len(record[index]), default=None)
        if longest is not None and len(longest[index]) > width:
            raise ValueError(
                f"{table.name} column {name}: {longest[index]!r} is over {width} characters"
            )
    return np.array([tuple(record) for record in records], dtype=table.dtype)


def _fail(path: str | os.PathLike[str], problem: str) -> RunDataError:
    return RunDataError(f"{path}: {problem}")


def is_legacy_contacts(dtype: np.dtype, table: Table) -> bool:
    """Rows of ``contacts.npy`` as written before ``wall`` was an integer: ``wall`` text
    (``a+b`` for two walls), no ``wall_other``."""
    names = dtype.names or ()
    return (
        table is CONTACTS
        and "wall" in names
        and dtype["wall"].kind == "S"
        and "wall_other" not in names
    )


def _legacy_walls(column: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(``wall``, ``wall_other``) int64 of a legacy ``wall`` text column."""
    pairs = [contact_walls(v.decode("ascii")) for v in column.tolist()]
    wall = np.array([a for a, _ in pairs], dtype=np.int64)
    return wall, np.array([b for _, b in pairs], dtype=np.int64)


def open_rows(path: str | os.PathLike[str], table: Table) -> np.ndarray:
    """The rows of the binary file ``path`` of ``table``, mapped read-only (a plain empty
    array when it has none): the rows its header counts.

    Raises:
        RunDataError: the file is missing or unreadable, is not a .npy file of rows,
            lacks one of the table's columns, or is shorter than its header says.
    """
    try:
        check_regular(path)
        with open(path, "rb") as handle:
            head = handle.read(1 << 16)
            size = os.fstat(handle.fileno()).st_size
    except FileRefused as exc:
        raise _fail(path, exc.reason) from None
    except FileNotFoundError:
        raise _fail(path, "file not found") from None
    except OSError as exc:
        raise _fail(path, f"cannot read: {exc}") from None
    try:
        dtype, rows, offset = read_header(head)
    except ValueError as exc:
        raise _fail(path, f"not a binary run file ({exc})") from None
    legacy = is_legacy_contacts(dtype, table)
    missing = [
        name
        for name in table.columns
        if name not in dtype.names and not (legacy and name == "wall_other")
    ]
    if missing:
        raise _fail(path, f"missing column(s) {', '.join(missing)}")
    if offset + rows * dtype.itemsize > size:
        raise _fail(
            path,
            f"its header counts {rows} rows, the file holds "
            f"{max(size - offset, 0) // dtype.itemsize} (cut short?)",
        )
    if rows == 0:
        return np.empty(0, dtype=dtype)
    try:
        mapped = np.memmap(path, dtype=dtype, mode="r", offset=offset, shape=(rows,))
    except (OSError, ValueError) as exc:
        raise _fail(path, f"cannot read: {exc}") from None
    return mapped.view(np.ndarray)


def read_table(path: str | os.PathLike[str], table: Table) -> dict[str, np.ndarray]:
    """The columns of the binary file ``path`` of ``table``, with the dtypes of the CSV
    readers: numeric columns as read-only views of the mapped file, ``regime`` decoded to
    its labels, text columns as ``str`` arrays (as narrow as the longest value).

    A legacy ``contacts.npy`` (:func:`is_legacy_contacts`) reads as one written now:
    ``wall`` and ``wall_other`` int64 (``a+b`` as a and b, one wall with -2).

    Raises:
        RunDataError: as :func:`open_rows`, a regime code that is none of the regimes',
            or a legacy ``wall`` that names no wall.
    """
    rows = open_rows(path, table)
    out: dict[str, np.ndarray] = {}
    legacy = is_legacy_contacts(rows.dtype, table)
    for name in rows.dtype.names or ():
        column = rows[name]
        if name == "regime" and table is COLLISIONS:
            try:
                out[name] = regime_labels(column)
            except ValueError as exc:
                raise _fail(path, str(exc)) from None
        elif name == "wall" and legacy:
            try:
                out[name], other = _legacy_walls(column)
            except (ValueError, UnicodeDecodeError) as exc:
                raise _fail(path, f"column wall: {exc}") from None
        elif column.dtype.kind == "S":
            out[name] = _text(column)
        else:
            out[name] = column
    if legacy:
        out["wall_other"] = other  # the last column, as in a file of now
    return out


def _text(column: np.ndarray) -> np.ndarray:
    """A fixed-width ASCII column as a ``str`` array as narrow as ``np.array(list, str)``."""
    if column.size == 0:
        return np.array([], dtype=str)
    width = max(int(np.char.str_len(column).max()), 1)
    return column.astype(f"<U{width}")


#: rows converted at a time by :func:`export_csv`
EXPORT_ROWS = 100_000


def export_csv(source: str | os.PathLike[str], target: str | os.PathLike[str], table: Table) -> int:
    """Write the CSV file of ``table`` of the binary file ``source`` to ``target`` (into
    a temporary file beside it, renamed at the end): the bytes a run storing CSV writes.
    Returns the number of rows.

    Raises:
        RunDataError: as :func:`open_rows`.
        OSError: ``target`` cannot be written.
    """
    rows = open_rows(source, table)
    legacy = is_legacy_contacts(rows.dtype, table)
    target = Path(target)
    temp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        with open(temp, "wb") as handle:
            handle.write(header_line(table.columns).encode("utf-8"))
            for start in range(0, len(rows), EXPORT_ROWS):
                part = rows[start : start + EXPORT_ROWS]
                if table is COLLISIONS:
                    handle.write(format_rows_bytes(block_of(part), LINE_END))
                    continue
                lines = []
                wall = table.columns.index("wall") if legacy else -1
                for row in part.tolist():
                    cells = [v.decode("ascii") if isinstance(v, bytes) else v for v in row]
                    if legacy:  # the columns of a file of now
                        try:
                            cells[wall], other = contact_walls(cells[wall])
                        except ValueError as exc:
                            raise _fail(source, f"column wall: {exc}") from None
                        cells.append(other)
                    lines.append(",".join(format_field(v) for v in cells) + "\n")
                handle.write("".join(lines).encode("utf-8"))
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, target)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    return len(rows)
