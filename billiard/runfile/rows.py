"""Impact rows as the kernels write them: ``NCOL`` floats per impact, the columns of
``collisions.csv`` in order, regime and wall as codes (:mod:`billiard.kernels.layout`).

A run on the kernels hands its rows to the recorders as 2-D float64 arrays, one row per
impact; these helpers turn them into :class:`~billiard.runfile.record.ImpactRecord` objects,
into column arrays, and into ``collisions.csv`` lines with exactly the bytes a
:class:`csv.writer` writes for the records (floats with :func:`repr`). The wall code is
written as the integer it is: the wall's index, ``-1`` for the lid (:data:`LID_WALL`).

Compiled, the lines are written by :func:`billiard.kernels.float_text.format_rows`:
``repr``'s bytes, several times faster than ``repr`` itself (formatting rows took most
of a compiled run's time). Interpreted, ``repr`` is the faster of the two, and stays.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.kernels.layout import LID_LABEL, NCOL, REGIMES

__all__ = [
    "NCOL",
    "as_block",
    "column_arrays",
    "format_rows",
    "format_rows_bytes",
    "LID_WALL",
    "NO_WALL",
    "contact_walls",
    "regime_labels",
    "row_of",
    "wall_code",
    "wall_label",
]

_N, _REGIME, _WALL = 0, 10, 13

#: The ``wall`` column's code of an impact on the lid (the walls are numbered from 0).
LID_WALL = int(LID_LABEL)
#: The ``wall_other`` column of a contact phase on one wall: no second wall (-1 is the
#: lid, walls count from 0, so -2 is none of them).
NO_WALL = -2


def wall_code(wall: Any) -> int:
    """The ``wall`` column's integer of a wall: an int, or its text as files written
    before the column was an integer hold it (``"0"``, ``"1"``, ... or ``"lid"``).

    Raises:
        ValueError: ``wall`` is neither an integer nor ``lid``.
    """
    if isinstance(wall, str):
        text = wall.strip()
        return LID_WALL if text == "lid" else int(text)
    if isinstance(wall, float) and not wall.is_integer():
        raise ValueError(f"wall {wall!r} is not an integer")
    return int(wall)


def contact_walls(text: str) -> tuple[int, int]:
    """``(wall, wall_other)`` of a ``contacts.csv`` ``wall`` cell as files written before
    the column was an integer hold it: ``a+b`` for a phase held by two walls, else one
    wall (``0``, ``1``, ... or ``lid``) and :data:`NO_WALL`.

    Raises:
        ValueError: a part is neither an integer nor ``lid``.
    """
    first, plus, second = text.strip().partition("+")
    return wall_code(first), wall_code(second) if plus else NO_WALL


def wall_label(code: float) -> str:
    """The ``wall`` column's text of a wall code: the integer (``-1`` for the lid)."""
    return str(int(code))


def as_block(buffer: Any, start: int, stop: int) -> np.ndarray:
    """Rows ``start`` to ``stop`` of a kernel buffer (an array or, interpreted, a list)
    as a new ``(rows, NCOL)`` float64 array."""
    if isinstance(buffer, np.ndarray):
        return buffer[start * NCOL : stop * NCOL].reshape(stop - start, NCOL).copy()
    values = buffer[start * NCOL : stop * NCOL]
    return np.array(values, dtype=np.float64).reshape(stop - start, NCOL)


def row_of(record: Sequence[Any]) -> list[float]:
    """Inverse of :func:`billiard.runfile.record.record_of`."""
    row = [float(v) if i not in (_REGIME, _WALL) else 0.0 for i, v in enumerate(record)]
    row[_REGIME] = float(REGIMES.index(record[_REGIME]))
    row[_WALL] = float(wall_code(record[_WALL]))
    return row


def format_rows(block: np.ndarray, line_end: str) -> str:
    """``collisions.csv`` lines of the rows of ``block``, each ended by ``line_end``:
    written by the compiled formatter when the kernels are compiled, with ``repr``
    otherwise (the same bytes)."""
    if _jit.ENABLED and len(block):
        data = _format_rows_compiled(block, line_end)
        if data is not None:
            # decoded straight from the buffer (tobytes() would copy it once more)
            return str(data, "ascii")
    return _format_rows_repr(block, line_end)


def format_rows_bytes(block: np.ndarray, line_end: str) -> bytes:
    """:func:`format_rows` as the bytes written to the file (ASCII)."""
    if _jit.ENABLED and len(block):
        data = _format_rows_compiled(block, line_end)
        if data is not None:
            return data.tobytes()
    return _format_rows_repr(block, line_end).encode("ascii")


#: the compiled formatter was called in this process
_formatted = False
#: what the compiled formatter is given besides the rows, built on its first call
_compiled_constants: tuple[np.ndarray, np.ndarray, np.ndarray, int] | None = None


def _constants() -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The regime labels as one byte array and the offsets of each label in it, the
    lid's label, and the most bytes a row takes (without its line end): the labels
    reach the kernel as arrays, built once here."""
    global _compiled_constants
    if _compiled_constants is None:
        from billiard.kernels.float_text import MAX_FLOAT_BYTES, MAX_INT_BYTES

        encoded = [label.encode("ascii") for label in REGIMES]
        labels = np.frombuffer(b"".join(encoded), dtype=np.uint8)
        starts = np.cumsum([0] + [len(label) for label in encoded], dtype=np.int64)
        # the lid's code is written as the integer it is (the formatter's lid argument
        # holds its bytes)
        lid = np.frombuffer(str(LID_WALL).encode("ascii"), dtype=np.uint8)
        # n and the wall (ints), the regime, the other columns as floats,
        # and the commas between the NCOL columns
        row_bytes = (
            2 * max(MAX_INT_BYTES, lid.size)
            + max(len(label) for label in encoded)
            + (NCOL - 3) * MAX_FLOAT_BYTES
            + (NCOL - 1)
        )
        _compiled_constants = (labels, starts, lid, row_bytes)
    return _compiled_constants


def _format_rows_compiled(block: np.ndarray, line_end: str) -> memoryview | None:
    """:func:`format_rows` by :func:`billiard.kernels.float_text.format_rows`; None
    for a block with a code that formatter leaves to ``repr``'s path (a nan or
    out-of-range number or regime: that path formats it or raises as it always did)."""
    from billiard.kernels import float_text

    labels, starts, lid, row_bytes = _constants()
    block = np.ascontiguousarray(block, dtype=np.float64)
    end = np.frombuffer(line_end.encode("ascii"), dtype=np.uint8)
    rows = block.shape[0]
    out = np.empty(rows * (row_bytes + end.size), dtype=np.uint8)
    global _formatted
    if _formatted:
        size = float_text.format_rows(block, rows, out, labels, starts, lid, end)
    else:
        with _jit.compiling(float_text.format_rows):  # the first call may compile
            size = float_text.format_rows(block, rows, out, labels, starts, lid, end)
        _formatted = True
    if size < 0:
        return None
    return out[:size].data


def _format_rows_repr(block: np.ndarray, line_end: str) -> str:
    """:func:`format_rows` with ``repr``: the reference the compiled formatter equals,
    and the faster of the two interpreted."""
    lines = []
    for row in block.tolist():
        lines.append(
            f"{int(row[0])},{','.join(map(repr, row[1:10]))},{REGIMES[int(row[10])]},"
            f"{row[11]!r},{row[12]!r},{wall_label(row[13])},{','.join(map(repr, row[14:18]))}"
        )
    if not lines:
        return ""
    return line_end.join(lines) + line_end


def regime_labels(codes: np.ndarray) -> np.ndarray:
    """The ``regime`` column's labels (:data:`~billiard.kernels.layout.REGIMES`) of an
    array of regime codes, as narrow a string array as ``np.array(labels, str)``: every
    reader of a run file gives the column this way.

    Raises:
        ValueError: a code that is not one of the regimes' (nor an integer).
    """
    codes = np.asarray(codes)
    if codes.size == 0:
        return np.array([], dtype=str)
    whole = codes.astype(np.int64)
    if not (np.all(whole == codes) and whole.min() >= 0 and whole.max() < len(REGIMES)):
        bad = codes[(whole != codes) | (whole < 0) | (whole >= len(REGIMES))][0].item()
        raise ValueError(f"regime code {bad!r} is not one of 0 to {len(REGIMES) - 1}")
    present = np.bincount(whole, minlength=len(REGIMES)) > 0
    width = max(len(label) for label, used in zip(REGIMES, present, strict=True) if used)
    return np.array(REGIMES, dtype=f"<U{width}")[whole]


def column_arrays(names: Sequence[str], blocks: Iterable[np.ndarray]) -> dict[str, np.ndarray]:
    """Column name -> array over the rows of ``blocks``, with the dtypes of
    :func:`billiard.runfile.tables.read_collisions` (one column built at a time)."""
    blocks = list(blocks)
    out: dict[str, np.ndarray] = {}
    for index, name in enumerate(names):
        if blocks:
            column = np.concatenate([block[:, index] for block in blocks])
        else:
            column = np.empty(0, dtype=np.float64)
        if index == _N:
            out[name] = column.astype(np.int64)
        elif index == _REGIME:
            out[name] = regime_labels(column)
        elif index == _WALL:
            out[name] = column.astype(np.int64)
        else:
            out[name] = column
    return out
