"""Text as floats, compiled: the rows of a ``collisions.csv`` file as billiard writes it,
parsed in one pass (:func:`parse_rows`, for :mod:`billiard.runfile.csvbulk`).

Why: numpy's ``fromstring`` took 70 % of the 4.1 s of CPU that reading a 10^6-impact
file took (some 160 ns per number; pandas' C parser reads the file in 0.7 s). Each float
here is correctly rounded, as :func:`float` rounds it: its decimal significand (up to 19
digits) and exponent are read exactly, then turned into the nearest double by Clinger's
fast path (both exact doubles: one IEEE operation rounds) or by the Eisel-Lemire
algorithm (Daniel Lemire, "Number parsing at a gigabyte per second", Software: Practice
and Experience 51(8), 2021; as Go's ``strconv.eiselLemire64`` writes it, which gives up
rather than guess when the 128-bit product cannot decide the rounding, and leaves
subnormals and overflow to the slow path). A field it gives up on, or whose text is not
the plain ``-ddd.ddde-dd`` that :func:`repr` writes (``nan``, ``inf``, an underscore), is
listed for :func:`float` in Python: rare, and the same value either way.
``tests/kernels/test_float_parse.py`` compares the results with :func:`float` on
hundreds of thousands of random bit patterns and spellings, and on the hard cases.

numba has no 128-bit integers: the products come from :func:`~.ryu._mul_64x64`, and
every integer of the arithmetic is a ``np.uint64`` (numba types uint64 mixed with int64
as float64).
"""

from __future__ import annotations

import math

import numpy as np

from .decorators import inline, jit
from .ryu import _U0, _U1, _U10, _U63, _mul_64x64

__all__ = ["FIELD_FLOAT", "FIELD_INT", "FIELD_REGIME", "FIELD_WALL", "parse_rows"]

#: the kinds of column :func:`parse_rows` reads
FIELD_FLOAT, FIELD_INT, FIELD_WALL, FIELD_REGIME = 0, 1, 2, 3

_COMMA, _NEWLINE, _RETURN = ord(","), ord("\n"), ord("\r")
_MINUS, _PLUS, _DOT, _ZERO = ord("-"), ord("+"), ord("."), ord("0")
_LOWER_E, _UPPER_E = ord("e"), ord("E")
#: the word of the lid in the wall column of files written before it was an integer
_LID = (ord("l"), ord("i"), ord("d"))

# --- the powers of ten of Eisel-Lemire -------------------------------------------------
_MIN_EXP10, _MAX_EXP10 = -348, 347


def _powers_of_ten() -> tuple[np.ndarray, np.ndarray]:
    """The 128-bit significands of 10**e, e from -348 to 347, rounded down, normalized
    so that the top bit is set (Go's ``detailedPowersOfTen``): (high words, low words)."""
    high, low = [], []
    for e in range(_MIN_EXP10, _MAX_EXP10 + 1):
        if e >= 0:
            value = 10**e
            shift = value.bit_length() - 128
            m = value >> shift if shift > 0 else value << -shift
        else:
            d = 10**-e
            # 2**k / d with exactly 128 bits: k = 127 + bit_length(d) or one less
            k = 127 + d.bit_length()
            m = (1 << k) // d
            if m.bit_length() > 128:
                m = (1 << (k - 1)) // d
        assert m.bit_length() == 128
        high.append(m >> 64)
        low.append(m & ((1 << 64) - 1))
    return np.array(high, dtype=np.uint64), np.array(low, dtype=np.uint64)


_POW10_HIGH, _POW10_LOW = _powers_of_ten()
#: the powers of ten that are exact doubles (Clinger's fast path)
_EXACT_POW10 = np.array([10.0**k for k in range(23)])
_TWO53 = np.uint64(1 << 53)
_MAX_DIGITS = 19  # a significand of 19 digits fits in 64 bits
_LOW9 = np.uint64(0x1FF)
_ALL64 = np.uint64(0xFFFFFFFFFFFFFFFF)
_U3 = np.uint64(3)
_U9 = np.uint64(9)
_U53 = np.uint64(53)
_FRACTION = np.uint64((1 << 52) - 1)


@inline
def _leading_zeros(x):
    """The number of leading zero bits of a nonzero uint64."""
    n = 0
    top = _U1 << _U63
    while x & top == _U0:
        x = x << _U1
        n += 1
    return n


@inline
def _eisel_lemire(man, exp10):
    """(ok, value) of the positive number ``man * 10**exp10`` (``man`` nonzero, below
    2**64): ok False where the rounding is not decided or the result is not a normal
    double (the caller then asks :func:`float`)."""
    if exp10 < _MIN_EXP10 or exp10 > _MAX_EXP10:
        return False, 0.0
    clz = _leading_zeros(man)
    man = man << np.uint64(clz)
    ret_exp2 = ((217706 * exp10) >> 16) + 64 + 1023 - clz
    index = exp10 - _MIN_EXP10
    x_hi, x_lo = _mul_64x64(man, _POW10_HIGH[index])
    if x_hi & _LOW9 == _LOW9 and x_lo + man < man:
        # the wider approximation: the next 64 bits of the power
        y_hi, y_lo = _mul_64x64(man, _POW10_LOW[index])
        merged_hi, merged_lo = x_hi, x_lo + y_hi
        if merged_lo < x_lo:
            merged_hi += _U1
        if merged_hi & _LOW9 == _LOW9 and merged_lo + _U1 == _U0 and y_lo + man < man:
            return False, 0.0
        x_hi, x_lo = merged_hi, merged_lo
    msb = x_hi >> _U63
    mantissa = x_hi >> (msb + _U9)
    ret_exp2 -= 1 - int(msb)
    if x_lo == _U0 and x_hi & _LOW9 == _U0 and mantissa & _U3 == _U1:
        return False, 0.0  # half-way between two doubles: not decided here
    mantissa += mantissa & _U1
    mantissa = mantissa >> _U1
    if mantissa >> _U53 > _U0:
        mantissa = mantissa >> _U1
        ret_exp2 += 1
    if ret_exp2 <= 0 or ret_exp2 >= 0x7FF:
        return False, 0.0  # subnormal, or beyond the largest double
    # 53 bits and a power of two: exact
    return True, math.ldexp(float(mantissa), ret_exp2 - 1023 - 52)


@inline
def _digits(data, p, stop, man, digits):
    """(position after them, mantissa, significant digits, digits read) of the decimal
    digits from ``data[p]`` on, appended to the mantissa ``man`` of ``digits``
    significant digits; past _MAX_DIGITS significant digits the mantissa stops growing
    and the count says so (the caller gives up: it would overflow)."""
    count = 0
    while p < stop and _ZERO <= data[p] <= _ZERO + 9:
        d = np.uint64(data[p] - _ZERO)
        if man != _U0 or d != _U0:
            if digits < _MAX_DIGITS:
                man = man * _U10 + d
            digits += 1
        count += 1
        p += 1
    return p, man, digits, count


@inline
def _parse_float(data, start, stop):
    """(ok, value) of the field ``data[start:stop]``: ok False unless it is a plain
    decimal (``-``, digits, ``.`` and digits, ``e`` or ``E``, a sign and digits) whose
    nearest double is decided here."""
    p = start
    negative = False
    if p < stop and data[p] == _MINUS:
        negative = True
        p += 1
    p, man, digits, whole = _digits(data, p, stop, _U0, 0)
    exp10 = 0
    fraction = 0
    if p < stop and data[p] == _DOT:
        p, man, digits, fraction = _digits(data, p + 1, stop, man, digits)
        exp10 = -fraction
    if digits > _MAX_DIGITS:
        return False, 0.0
    if whole + fraction == 0:
        return False, 0.0
    if p < stop and (data[p] == _LOWER_E or data[p] == _UPPER_E):
        p += 1
        sign = 1
        if p < stop and (data[p] == _MINUS or data[p] == _PLUS):
            sign = -1 if data[p] == _MINUS else 1
            p += 1
        if p == stop:
            return False, 0.0
        exponent = 0
        while p < stop and _ZERO <= data[p] <= _ZERO + 9:
            if exponent < 100000:
                exponent = exponent * 10 + (data[p] - _ZERO)
            p += 1
        exp10 += sign * exponent
    if p != stop:
        return False, 0.0
    if man == _U0:
        return True, -0.0 if negative else 0.0
    while man % _U10 == _U0:
        # trailing zeros (repr's "4636013620755838.0"): an exact integer then takes the
        # fast path, where Eisel-Lemire's truncated power could not decide it
        man = man // _U10
        exp10 += 1
    if man <= _TWO53 and -22 <= exp10 <= 22:
        # Clinger: both exact, one rounding
        value = float(man)
        value = value * _EXACT_POW10[exp10] if exp10 >= 0 else value / _EXACT_POW10[-exp10]
        return True, -value if negative else value
    ok, value = _eisel_lemire(man, exp10)
    return ok, -value if negative else value


@inline
def _parse_int(data, start, stop):
    """(ok, value) of an integer field as :func:`str` writes an int: a minus only before
    a nonzero number, no leading zero, at most 18 digits."""
    p = start
    negative = data[p] == _MINUS
    if negative:
        p += 1
    if p == stop or stop - p > 18:
        return False, 0
    if data[p] == _ZERO and (stop - p > 1 or negative):
        return False, 0
    value = 0
    while p < stop:
        c = data[p]
        if c < _ZERO or c > _ZERO + 9:
            return False, 0
        value = value * 10 + (c - _ZERO)
        p += 1
    return True, -value if negative else value


@inline
def _label_code(data, start, stop, labels, label_starts):
    """The index of the label ``data[start:stop]`` among ``labels``, or -1."""
    for k in range(label_starts.size - 1):
        a, b = label_starts[k], label_starts[k + 1]
        if b - a != stop - start:
            continue
        same = True
        for j in range(b - a):
            if data[start + j] != labels[a + j]:
                same = False
                break
        if same:
            return k
    return -1


@jit
def parse_rows(data, kinds, crlf, labels, label_starts, floats, ints, fallback):
    """Parse the whole lines ``data`` (uint8), each of ``kinds.size`` comma-separated
    fields ended by ``\\n`` (``\\r\\n`` when ``crlf``).

    Args:
        kinds: the kind of each column (:data:`FIELD_FLOAT`, :data:`FIELD_INT`,
            :data:`FIELD_WALL`: an int or the word ``lid``, -1; :data:`FIELD_REGIME`: one
            of ``labels``).
        labels, label_starts: the regime labels' bytes, and where each starts (and the
            last ends) in them.
        floats: (rows, columns) float64, filled for the float columns.
        ints: (rows, columns) int64, filled for the others (a regime as its code).
        fallback: (rows * columns, 3) int64: (row * columns + column, start, stop) of each
            float field left to :func:`float`.

    Returns:
        (rows, fallbacks): the rows parsed and the fields listed in ``fallback``; rows -1
        when a line is not of this form (a field count, an empty or malformed integer,
        label or line end: the careful reader decides), or when ``fallback`` is full
        (then fallbacks is its length).
    """
    width = kinds.size
    n = data.size
    row = 0
    listed = 0
    p = 0
    while p < n:
        if row >= floats.shape[0]:
            return -1, listed
        for col in range(width):
            start = p
            while p < n and data[p] != _COMMA and data[p] != _NEWLINE:
                p += 1
            if p == n:
                return -1, listed  # no line end (the caller passes whole lines)
            stop = p
            if col < width - 1:
                if data[p] != _COMMA:
                    return -1, listed  # too few fields
            else:
                if data[p] != _NEWLINE:
                    return -1, listed  # too many fields
                if crlf:
                    if stop == start or data[stop - 1] != _RETURN:
                        return -1, listed
                    stop -= 1
            p += 1
            if stop == start:
                return -1, listed  # an empty field
            kind = kinds[col]
            if kind == FIELD_FLOAT:
                ok, value = _parse_float(data, start, stop)
                if ok:
                    floats[row, col] = value
                else:
                    if listed == fallback.shape[0]:
                        return -1, listed  # the list is full
                    fallback[listed, 0] = row * width + col
                    fallback[listed, 1] = start
                    fallback[listed, 2] = stop
                    listed += 1
            elif kind == FIELD_REGIME:
                code = _label_code(data, start, stop, labels, label_starts)
                if code < 0:
                    return -1, listed
                ints[row, col] = code
            else:
                if (
                    kind == FIELD_WALL
                    and stop - start == 3
                    and data[start] == _LID[0]
                    and data[start + 1] == _LID[1]
                    and data[start + 2] == _LID[2]
                ):
                    ints[row, col] = -1
                    continue
                ok, whole = _parse_int(data, start, stop)
                if not ok:
                    return -1, listed
                ints[row, col] = whole
        row += 1
    return row, listed
