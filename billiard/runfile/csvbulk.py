"""``collisions.csv`` parsed in bulk: the file as billiard writes it, turned into arrays
a block of some 100,000 rows at a time by numpy rather than a row at a time by the
:mod:`csv` module (a million rows: seconds instead of a quarter of a minute).

Only a plain file is taken this way: a header of known columns, then rows with exactly
one field per column, no quotes, no blank or ``#`` comment lines, no extra columns,
labels where the text columns hold them. Anything else (a file edited by hand, a
malformed row) makes :func:`read_bulk` return None, and the careful reader of
:mod:`billiard.runfile.record` reads the file line by line, with its messages; whatever
the bulk path accepts, the careful one reads to the same values.

Compiled (numba), the rows are parsed in one pass by
:func:`billiard.kernels.float_parse.parse_rows`: each float correctly rounded, as
:func:`float` rounds it, and the few fields it leaves (``nan``, ``inf``, text that is not
a plain decimal, a rounding it cannot decide) read by :func:`float` itself. Interpreted,
floats are parsed by ``numpy.fromstring``, which rounds correctly too: either way the
values are the file's bit for bit (the tests compare the readers). A 10^6-impact file
(317 MB) takes 1.3 s of CPU compiled, 4.1 s with ``fromstring`` (medians of 3).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence

import numpy as np

from billiard import jit as _jit
from billiard.kernels.layout import REGIMES
from billiard.runfile.rows import regime_labels

__all__ = ["read_bulk", "read_lines"]

#: Bytes read and parsed at a time (whole lines of it; about 100,000 rows).
CHUNK_BYTES = 1 << 25
_COMMA, _NEWLINE, _RETURN, _SPACE = ord(","), ord("\n"), ord("\r"), ord(" ")
_LID = b"lid"  # the lid's wall in files written before the column was an integer
#: powers of ten: the number of digits of an integer by a sorted search
_POWERS = 10 ** np.arange(1, 19, dtype=np.int64)


class _Refused(Exception):
    """The file is not one the bulk path takes (the careful reader reads it)."""


def read_bulk(
    path: str | os.PathLike[str], columns: Sequence[str], required: Sequence[str]
) -> dict[str, np.ndarray] | None:
    """The columns of the ``collisions.csv`` file ``path`` (dtypes as
    :func:`billiard.runfile.tables.read_collisions`), or None when the file is not a plain
    one (see the module's note) and has to be read line by line.

    Args:
        path: the file.
        columns: the names the header may hold (those of ``collisions.csv``).
        required: the names it must hold.

    Raises:
        OSError: the file cannot be read.
    """
    with open(path, "rb") as handle:
        header = handle.readline()
        try:
            names, line_end = _header(header, columns, required)
            return _rows(handle, names, line_end)
        except _Refused:
            return None


def _header(line: bytes, columns: Sequence[str], required: Sequence[str]) -> tuple[list, bytes]:
    """The names of a header line and its line end; refused unless every name is one of
    ``columns`` (once) and every one of ``required`` is there."""
    if line.endswith(b"\r\n"):
        end = b"\r\n"
    elif line.endswith(b"\n"):
        end = b"\n"
    else:
        raise _Refused  # no row, or an unterminated header: the careful reader decides
    text = line[: -len(end)]
    if not text or any(c in text for c in b'"# \t\r'):
        raise _Refused
    names = text.decode("ascii", errors="replace").split(",")
    known = set(columns)
    if len(set(names)) != len(names) or not set(names) <= known or not set(required) <= set(names):
        raise _Refused
    return names, end


def _rows(handle, names: list[str], line_end: bytes) -> dict[str, np.ndarray]:
    """Parse the rows after the header, chunk by chunk; an unterminated last line is left
    out, as the careful reader leaves it."""
    width = len(names)
    parts: dict[str, list[np.ndarray]] = {name: [] for name in names}
    carry = b""
    while True:
        chunk = handle.read(CHUNK_BYTES)
        if not chunk:
            break
        data = carry + chunk if carry else chunk
        cut = data.rfind(b"\n") + 1
        carry = data[cut:]
        if cut:
            parsed = _parse_compiled(data, cut, names, line_end) if _jit.ENABLED else None
            if parsed is None:
                parsed = _parse(data[:cut], names, width, line_end)
            for name, values in parsed.items():
                parts[name].append(values)
    out: dict[str, np.ndarray] = {}
    for name in names:
        chunks = parts[name]
        if name == "regime":
            codes = np.concatenate(chunks) if chunks else np.empty(0, dtype=np.int8)
            out[name] = regime_labels(codes)
        elif name in ("n", "wall"):
            out[name] = np.concatenate(chunks) if chunks else np.empty(0, dtype=np.int64)
        else:
            out[name] = np.concatenate(chunks) if chunks else np.empty(0, dtype=np.float64)
    return out


def _parse(data: bytes, names: list[str], width: int, line_end: bytes) -> dict[str, np.ndarray]:
    """The columns of whole lines ``data`` (each ended by ``line_end``); regime as codes."""
    if b"#" in data or b'"' in data:
        raise _Refused
    a = np.frombuffer(data, dtype=np.uint8).copy()
    ends = np.flatnonzero(a == _NEWLINE)
    rows = ends.size
    commas = np.flatnonzero(a == _COMMA)
    if commas.size != rows * (width - 1):
        raise _Refused
    starts = np.empty(rows, dtype=np.int64)
    starts[0] = 0
    starts[1:] = ends[:-1] + 1
    stops = ends  # the end of each line's last field
    if line_end == b"\r\n":
        stops = ends - 1
        if np.count_nonzero(a == _RETURN) != rows or not np.all(a[stops] == _RETURN):
            raise _Refused
    elif _RETURN in a:
        raise _Refused
    commas = commas.reshape(rows, width - 1)
    # exactly width - 1 commas on each line: its first after its start, its last before
    # its end (the total being right, no line can then hold more or fewer)
    if width > 1 and not (np.all(commas[:, 0] >= starts) and np.all(commas[:, -1] < stops)):
        raise _Refused
    first = np.concatenate([starts[:, None], commas + 1], axis=1)  # each field's first byte
    last = np.concatenate([commas, stops[:, None]], axis=1)  # the byte after it
    lengths = last - first
    if np.any(lengths == 0):
        raise _Refused  # an empty field
    out: dict[str, np.ndarray] = {}
    lid = None
    if "regime" in names:
        k = names.index("regime")
        out["regime"] = _regime_codes(a, first[:, k], lengths[:, k])
        _blank(a, first[:, k], lengths[:, k], out["regime"] + ord("0"))
    if "wall" in names:
        k = names.index("wall")
        lid = _is_label(a, first[:, k], lengths[:, k], _LID)
        if lid.any():
            at = first[lid, k]
            a[at], a[at + 1], a[at + 2] = ord("-"), ord("1"), _SPACE
    a[ends] = _COMMA
    if line_end == b"\r\n":
        a[stops] = _SPACE
    with warnings.catch_warnings():
        # numpy warns (and stops) at text that is not a number: the careful reader's case
        warnings.simplefilter("error", DeprecationWarning)
        try:
            values = np.fromstring(a.tobytes(), dtype=np.float64, sep=",")
        except (ValueError, DeprecationWarning):
            raise _Refused from None
    if values.size != rows * width:
        raise _Refused
    values = values.reshape(rows, width)
    for k, name in enumerate(names):
        if name == "regime":
            continue
        column = values[:, k]
        if name in ("n", "wall"):
            expected = None
            if name == "wall" and lid is not None and lid.any():
                expected = np.where(lid, len(_LID), -1)
            out[name] = _integers(column, lengths[:, k], expected)
        else:
            out[name] = np.ascontiguousarray(column)
    return out


#: the fields of a chunk :func:`_parse_compiled` leaves to :func:`float` at most (more:
#: the chunk is parsed by ``fromstring``)
FALLBACK_FIELDS = 1 << 14
#: the compiled parser was called in this process
_parsed = False


def read_lines(data: bytes, names: list[str], line_end: bytes) -> dict[str, np.ndarray] | None:
    """The columns of the whole lines ``data`` (after the header ``names``), as
    :func:`read_bulk` parses them; None when they are not plain rows. The first call
    in a process may compile the parser (:mod:`billiard.engine.compile_all` calls it
    so)."""
    try:
        parsed = _parse_compiled(data, len(data), names, line_end) if _jit.ENABLED else None
        return parsed if parsed is not None else _parse(data, names, len(names), line_end)
    except _Refused:
        return None


def _parse_compiled(data: bytes, cut: int, names: list[str], line_end: bytes) -> dict | None:
    """The columns of the whole lines ``data[:cut]``, parsed by the compiled kernel
    (regime as codes); None when more fields than :data:`FALLBACK_FIELDS` need
    :func:`float`."""
    global _parsed
    from billiard.kernels import float_parse as fp

    stray = (b"#", b'"', b"\r") if line_end == b"\n" else (b"#", b'"')
    if any(data.find(byte, 0, cut) >= 0 for byte in stray):
        raise _Refused
    kind = {"n": fp.FIELD_INT, "wall": fp.FIELD_WALL, "regime": fp.FIELD_REGIME}
    kinds = np.array([kind.get(name, fp.FIELD_FLOAT) for name in names], dtype=np.int64)
    rows, width = data.count(b"\n", 0, cut), len(names)
    floats = np.empty((rows, width), dtype=np.float64)
    ints = np.empty((rows, width), dtype=np.int64)
    fallback = np.empty((min(rows * width, FALLBACK_FIELDS), 3), dtype=np.int64)
    labels, starts = _regime_bytes()
    buffer = np.frombuffer(data, dtype=np.uint8, count=cut)
    crlf = line_end == b"\r\n"
    if _parsed:
        parsed, listed = fp.parse_rows(buffer, kinds, crlf, labels, starts, floats, ints, fallback)
    else:
        with _jit.compiling(fp.parse_rows):  # the first call may compile
            parsed, listed = fp.parse_rows(
                buffer, kinds, crlf, labels, starts, floats, ints, fallback
            )
        _parsed = True
    if parsed == -1 and listed == fallback.shape[0]:
        return None  # the list was full: not this parser's kind of file
    if parsed != rows:
        raise _Refused
    flat = floats.reshape(-1)
    for index, start, stop in fallback[:listed].tolist():
        try:
            # as the careful reader reads a field: the UTF-8 text, stripped, by float()
            flat[index] = float(data[start:stop].decode("utf-8").strip())
        except (ValueError, UnicodeDecodeError):
            raise _Refused from None
    out: dict[str, np.ndarray] = {}
    for k, name in enumerate(names):
        if kinds[k] == fp.FIELD_FLOAT:
            out[name] = np.ascontiguousarray(floats[:, k])
        elif kinds[k] == fp.FIELD_REGIME:
            out[name] = ints[:, k].astype(np.int8)
        else:
            out[name] = np.ascontiguousarray(ints[:, k])
    return out


def _regime_bytes() -> tuple[np.ndarray, np.ndarray]:
    """The regime labels' bytes, one after another, and where each starts (and the last
    ends) among them."""
    encoded = [label.encode("ascii") for label in REGIMES]
    starts = np.cumsum([0] + [len(label) for label in encoded], dtype=np.int64)
    return np.frombuffer(b"".join(encoded), dtype=np.uint8), starts


def _is_label(a: np.ndarray, first: np.ndarray, lengths: np.ndarray, label: bytes) -> np.ndarray:
    """Which fields (first byte, length) are exactly ``label``."""
    match = lengths == len(label)
    last = a.size - 1
    for j, byte in enumerate(label):
        match &= a[np.minimum(first + j, last)] == byte
    return match


def _regime_codes(a: np.ndarray, first: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The regime code of each field, every one of which must be a regime's label."""
    codes = np.full(first.size, -1, dtype=np.int8)
    for code, label in enumerate(REGIMES):
        codes[_is_label(a, first, lengths, label.encode("ascii"))] = code
    if np.any(codes < 0):
        raise _Refused  # another text: the careful reader keeps it as it is
    return codes


def _blank(a: np.ndarray, first: np.ndarray, lengths: np.ndarray, digit: np.ndarray) -> None:
    """Put ``digit`` (a byte per field) in place of each field, padded with spaces."""
    a[first] = digit
    for j in range(1, int(lengths.max(initial=1))):
        inside = j < lengths
        a[first[inside] + j] = _SPACE


def _integers(column: np.ndarray, lengths: np.ndarray, expected: np.ndarray | None) -> np.ndarray:
    """An integer column as int64: every value a whole number written as ``str(int)``
    writes it (no sign but a minus, no leading zero, no point: what :func:`int` reads),
    its field as long as those digits (``expected`` >= 0: a field of that length, the
    word lid)."""
    if not np.all(np.isfinite(column)) or np.any(np.abs(column) >= 2.0**53):
        raise _Refused
    whole = column.astype(np.int64)
    if not np.array_equal(whole, column):
        raise _Refused
    magnitude = np.abs(whole)
    digits = np.searchsorted(_POWERS, magnitude, side="right") + 1 + (whole < 0)
    if expected is not None:
        digits = np.where(expected >= 0, expected, digits)
    if not np.array_equal(digits, lengths):
        raise _Refused
    return whole
