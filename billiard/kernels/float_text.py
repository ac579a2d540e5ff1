"""Floats as text, compiled: the bytes of CPython's ``repr(float)`` written into a
uint8 array, and the ``collisions.csv`` lines of a block of rows
(:func:`billiard.runfile.rows.format_rows`).

Why: a compiled run makes an impact in about a microsecond, and formatting its row
with ``repr`` cost about 17 us, almost all of it David Gay's ``dtoa`` (500-800 ns per
17-digit float, 16 floats per row). The digits here are Ryu's
(:mod:`~billiard.kernels.ryu`), the same as ``repr``'s; the layout follows
``float_repr`` (format code 'r' with ``Py_DTSF_ADD_DOT_0``).
``tests/kernels/test_float_text.py`` compares the bytes with ``repr`` on millions of random
bit patterns and on the hard cases.
"""

from __future__ import annotations

import numpy as np

from .decorators import inline, jit
from .layout import LID_LABEL
from .ryu import (
    _EXPONENT_MASK,
    _FRACTION,
    _POW10,
    _U0,
    _U1,
    _U10,
    _U52,
    _U63,
    _U100,
    _ZERO_CHAR,
    _float_bits,
    shortest,
)

__all__ = ["MAX_FLOAT_BYTES", "MAX_INT_BYTES", "format_floats", "format_rows", "shortest"]

#: longest repr of a float: sign, 17 digits, '.', 'e', exponent sign, 3 digits
MAX_FLOAT_BYTES = 24
#: longest decimal int64: sign and 19 digits
MAX_INT_BYTES = 20


# ASCII codes of the characters written
_MINUS = ord("-")
_PLUS = ord("+")
_DOT = ord(".")
_COMMA = ord(",")
_DIGIT0 = ord("0")
_E = ord("e")
_NAN = (ord("n"), ord("a"), ord("n"))
_INF = (ord("i"), ord("n"), ord("f"))

#: "00" "01" ... "99": two digits per division
_DIGIT_PAIRS = np.frombuffer("".join(f"{k:02d}" for k in range(100)).encode("ascii"), np.uint8)


@inline
def _ascii(out, pos, a, b, c):
    """Three ASCII characters (codes) at ``pos``."""
    out[pos] = a
    out[pos + 1] = b
    out[pos + 2] = c
    return pos + 3


@inline
def _write_digits(v, n, out, pos):
    """The ``n`` decimal digits of ``v`` at ``pos``, two at a time from the right
    (each division waits for the previous one); returns the position after them."""
    end = pos + n
    k = end
    while v >= _U100:
        pair = np.int64(v % _U100) * 2
        v = v // _U100
        k -= 2
        out[k] = _DIGIT_PAIRS[pair]
        out[k + 1] = _DIGIT_PAIRS[pair + 1]
    if v >= _U10:
        pair = np.int64(v) * 2
        out[k - 2] = _DIGIT_PAIRS[pair]
        out[k - 1] = _DIGIT_PAIRS[pair + 1]
    else:
        out[k - 1] = np.uint8(_ZERO_CHAR + v)
    return end


@inline
def _write_digits_dot(v, n, dot, out, pos):
    """The ``n`` digits of ``v`` at ``pos`` with a '.' after the first ``dot`` of them
    (0 < dot < n): written one place to the right, then the first ``dot`` moved back."""
    end = _write_digits(v, n, out, pos + 1)
    for k in range(pos, pos + dot):
        out[k] = out[k + 1]
    out[pos + dot] = _DOT
    return end


@inline
def _decimal_length(v):
    """Number of decimal digits of ``v`` (at least 1): counted down from 20 above
    10**8 (a float's shortest digits mostly number 16 or 17), up from 1 below (the
    impact numbers and walls, the short decimals)."""
    if v >= _POW10[8]:
        n = 20
        while v < _POW10[n - 1]:
            n -= 1
        return n
    n = 1
    while n < 8 and v >= _POW10[n]:
        n += 1
    return n


@inline
def write_float(x, out, pos):
    """``repr(x)`` as ASCII bytes into ``out`` (uint8) at ``pos``, at most
    :data:`MAX_FLOAT_BYTES` of them; returns the position after them."""
    bits = _float_bits(x)
    fraction = bits & _FRACTION
    exponent = np.int64((bits >> _U52) & _EXPONENT_MASK)
    negative = (bits >> _U63) != _U0
    if exponent == 0x7FF:
        if fraction != _U0:
            # repr of every nan, negative ones too
            return _ascii(out, pos, _NAN[0], _NAN[1], _NAN[2])
        if negative:
            out[pos] = _MINUS
            pos += 1
        return _ascii(out, pos, _INF[0], _INF[1], _INF[2])
    if negative:
        out[pos] = _MINUS
        pos += 1
    if exponent == 0 and fraction == _U0:
        return _ascii(out, pos, _DIGIT0, _DOT, _DIGIT0)
    digits, e10 = shortest(fraction, exponent)
    while digits % _U10 == _U0:
        digits = digits // _U10
        e10 += 1
    n = _decimal_length(digits)
    # value = 0.d1...dn * 10**decpt, as dtoa reports it
    decpt = n + e10
    if -4 < decpt <= 16:
        # fixed notation, always with a fractional part
        if decpt <= 0:
            out[pos] = _DIGIT0
            out[pos + 1] = _DOT
            pos += 2
            for _ in range(-decpt):
                out[pos] = _DIGIT0
                pos += 1
            return _write_digits(digits, n, out, pos)
        if decpt < n:
            return _write_digits_dot(digits, n, decpt, out, pos)
        pos = _write_digits(digits, n, out, pos)
        for _ in range(decpt - n):
            out[pos] = _DIGIT0
            pos += 1
        out[pos] = _DOT
        out[pos + 1] = _DIGIT0
        return pos + 2
    # exponent notation: d.ddd (no '.' for one digit), 'e', sign, at least two digits
    if n == 1:
        pos = _write_digits(digits, 1, out, pos)
    else:
        pos = _write_digits_dot(digits, n, 1, out, pos)
    out[pos] = _E
    e = decpt - 1
    if e < 0:
        out[pos + 1] = _MINUS
        e = -e
    else:
        out[pos + 1] = _PLUS
    pos += 2
    if e >= 100:
        out[pos] = _DIGIT0 + e // 100
        pos += 1
        e = e % 100
    out[pos] = _DIGIT0 + e // 10
    out[pos + 1] = _DIGIT0 + e % 10
    return pos + 2


@inline
def write_int(n, out, pos):
    """``str(n)`` of an int64 as ASCII bytes into ``out`` at ``pos``; returns the
    position after them."""
    if n < 0:
        out[pos] = _MINUS
        pos += 1
        # -(n + 1) + 1 reaches the magnitude of -2**63 without overflowing
        v = np.uint64(-(n + 1)) + _U1
    else:
        v = np.uint64(n)
    return _write_digits(v, _decimal_length(v), out, pos)


# the columns of a row that hold codes (kernels/loop.py writes them, rows.py reads them)
_REGIME_COLUMN = 10
_WALL_COLUMN = 13

# the floats of this range convert to an int64 exactly (truncated, as int() does)
_INT64_LOW = -(2.0**63)
_INT64_HIGH = 2.0**63


@inline
def _small_int(x):
    """(ok, int(x)): ok is False where int(x) would raise (nan, inf) or not fit an
    int64."""
    if _INT64_LOW <= x < _INT64_HIGH:
        return True, np.int64(x)
    return False, np.int64(0)


@inline
def _copy(source, start, stop, out, pos):
    """Bytes ``start .. stop`` of ``source`` at ``pos``; returns the position after
    them."""
    for k in range(start, stop):
        out[pos] = source[k]
        pos += 1
    return pos


@jit
def format_rows(block, nrows, out, labels, label_starts, lid, line_end):
    """The ``collisions.csv`` lines of rows ``0 .. nrows`` of ``block`` (float64,
    ``(rows, NCOL)``) into ``out`` (uint8), each ended by ``line_end``: column 0 as an
    int, the regime code (column 10) as its label (``labels[label_starts[k]:
    label_starts[k + 1]]``, a negative code counted from the end as Python indexes),
    the wall code (column 13) as ``lid`` when it is ``LID_LABEL`` and an int otherwise,
    every other column with :func:`write_float`. ``out`` holds at least the longest
    row times ``nrows``. Returns the number of bytes, or -1 when a code is not an
    integer :func:`billiard.runfile.rows.format_rows` can format (nan, out of range): its
    repr path then formats or raises as it always did."""
    count = label_starts.size - 1
    pos = 0
    for r in range(nrows):
        ok, n = _small_int(block[r, 0])
        if not ok:
            return -1
        pos = write_int(n, out, pos)
        for c in range(1, block.shape[1]):
            out[pos] = _COMMA
            pos += 1
            x = block[r, c]
            if c == _REGIME_COLUMN:
                ok, k = _small_int(x)
                if k < 0:
                    k += count
                if not ok or k < 0 or k >= count:
                    return -1
                pos = _copy(labels, label_starts[k], label_starts[k + 1], out, pos)
            elif c == _WALL_COLUMN:
                if x == LID_LABEL:
                    pos = _copy(lid, 0, lid.size, out, pos)
                else:
                    ok, n = _small_int(x)
                    if not ok:
                        return -1
                    pos = write_int(n, out, pos)
            else:
                pos = write_float(x, out, pos)
        pos = _copy(line_end, 0, line_end.size, out, pos)
    return pos


@jit
def format_floats(values, out, sep):
    """``repr`` of every float of ``values`` (float64, 1-D), each followed by the bytes
    of ``sep``, into ``out`` (at least ``values.size * (MAX_FLOAT_BYTES + sep.size)``
    bytes); returns the number of bytes. One compiled call for many floats: what the
    tests compare with ``repr``."""
    pos = 0
    for k in range(values.size):
        pos = write_float(values[k], out, pos)
        pos = _copy(sep, 0, sep.size, out, pos)
    return pos
