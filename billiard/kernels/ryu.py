"""Ryu's shortest round-trip digits of a double (Ulf Adams, "Ryu: fast float-to-string
conversion", PLDI 2018), compiled: the shortest decimal that reads back as the same
double and, of those, the one nearest to it (ties to an even last digit), with the
bounds of the rounding interval included when the significand is even. That is the
contract of CPython's ``repr`` (``float_repr_style`` 'short', dtoa mode 0), so the
digits are ``repr``'s; :mod:`~billiard.kernels.float_text` lays them out as ``repr``
does.

numba has no 128-bit integers: the products of Ryu's 125-bit powers of five with a
55-bit significand are assembled from 32-bit halves (:func:`_mul_64x64`), without
wrapping around, so the same source also runs interpreted on numpy's uint64 scalars (as
it does in :mod:`billiard.kernels.interpreted`'s twin). Every integer of the digit search is
a ``np.uint64`` and every constant is one too: numba types uint64 mixed with int64 as
float64.

The tables are computed at import with Python's exact integers: the powers of five
(Ryu's ``DOUBLE_POW5_SPLIT`` and ``DOUBLE_POW5_INV_SPLIT``, split into 64-bit words),
their bit lengths, and the floors of ``log10(2**e)`` and ``log10(5**e)`` (Ryu computes
the last three with multiply-and-shift approximations). numba freezes the global
arrays into the compiled code as constants.
"""

from __future__ import annotations

import math

import numpy as np

from .decorators import inline

__all__ = ["shortest"]

# --- the binary64 format and Ryu's parameters -----------------------------------------
_MANTISSA_BITS = 52
_BIAS = 1023
_MAX_EXPONENT = 2046  # the largest biased exponent of a finite double
# e2 below carries two extra bits (4 * m2) for the bounds of the rounding interval
_E2_OFFSET = _BIAS + _MANTISSA_BITS + 2
_POW5_BITCOUNT = 125  # bits kept of each power of five (and of each inverse)

_U0 = np.uint64(0)
_U1 = np.uint64(1)
_U2 = np.uint64(2)
_U5 = np.uint64(5)
_U10 = np.uint64(10)
_U32 = np.uint64(32)
_U52 = np.uint64(52)
_U63 = np.uint64(63)
_U64 = np.uint64(64)
_U100 = np.uint64(100)
_LOW32 = np.uint64(0xFFFFFFFF)
_FRACTION = np.uint64((1 << _MANTISSA_BITS) - 1)
_HIDDEN = np.uint64(1 << _MANTISSA_BITS)
_EXPONENT_MASK = np.uint64(0x7FF)
_SIGN = np.uint64(1 << 63)
_EXPONENT_ALL = np.uint64(0x7FF << 52)
_QUIET = np.uint64(1 << 51)
_SMALLEST_NORMAL = 2.0**-1022
_ZERO_CHAR = np.uint64(ord("0"))


def _floor_log10_powers(base: int, count: int) -> list[int]:
    """floor(log10(base**e)) for e = 0 .. count - 1, exactly: the powers of ten are
    stepped past as the powers grow (the digits of each power's decimal string, the
    plain definition, cost some 10 ms of every start-up)."""
    logs, power, ten, digits = [], 1, 10, 0
    for _ in range(count):
        while power >= ten:
            ten *= 10
            digits += 1
        logs.append(digits)
        power *= base
    return logs


def _split(value: int) -> tuple[int, int]:
    """(low, high) 64-bit words of a value below 2**128."""
    assert 0 <= value < 1 << 128
    return value & ((1 << 64) - 1), value >> 64


def _tables() -> dict[str, np.ndarray]:
    """The exact tables, sized by the exponents of the finite doubles (e2 from
    1 - _E2_OFFSET for the subnormals to _MAX_EXPONENT - _E2_OFFSET)."""
    e2_low, e2_high = 1 - _E2_OFFSET, _MAX_EXPONENT - _E2_OFFSET
    log10_pow2 = _floor_log10_powers(2, e2_high + 1)
    log10_pow5 = _floor_log10_powers(5, -e2_low + 1)

    def q_positive(e2: int) -> int:  # Ryu's q for e2 >= 0
        return log10_pow2[e2] - (1 if e2 > 3 else 0)

    def q_negative(e2: int) -> int:  # Ryu's q for e2 < 0
        return log10_pow5[-e2] - (1 if -e2 > 1 else 0)

    q_max = q_positive(e2_high)
    i_max = max(-e2 - q_negative(e2) for e2 in range(e2_low, 0))
    inverse = [
        _split((1 << ((5**q).bit_length() - 1 + _POW5_BITCOUNT)) // 5**q + 1)
        for q in range(q_max + 1)
    ]
    power = []
    for i in range(i_max + 1):
        shift = (5**i).bit_length() - _POW5_BITCOUNT
        power.append(_split(5**i >> shift if shift >= 0 else 5**i << -shift))
    tables = {
        "inv_lo": np.array([w[0] for w in inverse], dtype=np.uint64),
        "inv_hi": np.array([w[1] for w in inverse], dtype=np.uint64),
        "pow_lo": np.array([w[0] for w in power], dtype=np.uint64),
        "pow_hi": np.array([w[1] for w in power], dtype=np.uint64),
        "pow5_bits": np.array(
            [(5**e).bit_length() for e in range(max(q_max, i_max) + 1)], dtype=np.int64
        ),
        "log10_pow2": np.array(log10_pow2, dtype=np.int64),
        "log10_pow5": np.array(log10_pow5, dtype=np.int64),
        "pow10": np.array([10**k for k in range(20)], dtype=np.uint64),
    }
    # Ryu shifts a 128-bit product right by 64 + a distance in (0, 64); check it for
    # every exponent here, so that the kernel needs no case for 0 or 64 and more
    for e2 in range(e2_low, e2_high + 1):
        if e2 >= 0:
            q = q_positive(e2)
            j = -e2 + q + _POW5_BITCOUNT + int(tables["pow5_bits"][q]) - 1
        else:
            q = q_negative(e2)
            j = q - (int(tables["pow5_bits"][-e2 - q]) - _POW5_BITCOUNT)
        assert 64 < j < 128, (e2, j)
    return tables


_T = _tables()
_INV_LO = _T["inv_lo"]
_INV_HI = _T["inv_hi"]
_POW_LO = _T["pow_lo"]
_POW_HI = _T["pow_hi"]
_POW5_BITS = _T["pow5_bits"]
_LOG10_POW2 = _T["log10_pow2"]
_LOG10_POW5 = _T["log10_pow5"]
_POW10 = _T["pow10"]
del _T


@inline
def _float_bits(x):
    """The 64 bits of a float64 as a uint64, from its value: the sign from
    ``copysign``, the exponent and the fraction from ``frexp`` (exact: a power of two
    and a significand of 53 bits scale without rounding). Every float gives its own
    bits except a nan, which gives the quiet nan of its sign (its payload is not a
    value; :func:`~billiard.kernels.float_text.write_float` reads only that the
    fraction is not zero)."""
    sign = _U0 if math.copysign(1.0, x) > 0.0 else _SIGN
    y = abs(x)
    if y != y:
        return sign | _EXPONENT_ALL | _QUIET
    if y == math.inf:
        return sign | _EXPONENT_ALL
    if y < _SMALLEST_NORMAL:
        # zero and the subnormals: the fraction is the value in units of 2**-1074
        # (scaled in two exact steps: 2.0**1074 is not a float)
        return sign | np.uint64((y * 2.0**1022) * 2.0**52)
    m, e = math.frexp(y)  # y = m * 2**e, 0.5 <= m < 1
    return sign | (np.uint64(e + 1022) << _U52) | np.uint64((m + m - 1.0) * 2.0**52)


@inline
def _mul_64x64(a, b):
    """(high, low) 64-bit words of the 128-bit product ``a * b``, from the four
    products of 32-bit halves; no sum wraps around."""
    a_lo = a & _LOW32
    a_hi = a >> _U32
    b_lo = b & _LOW32
    b_hi = b >> _U32
    lo_lo = a_lo * b_lo
    mid = a_hi * b_lo + (lo_lo >> _U32)
    mid2 = a_lo * b_hi + (mid & _LOW32)
    high = a_hi * b_hi + (mid >> _U32) + (mid2 >> _U32)
    low = ((mid2 & _LOW32) << _U32) | (lo_lo & _LOW32)
    return high, low


@inline
def _mul_shift(m, mul_lo, mul_hi, j):
    """``(m * mul) >> j`` for ``mul = mul_hi * 2**64 + mul_lo`` (125 bits), m below
    2**55 and 64 < j < 128 (checked for every exponent at import)."""
    high1, low1 = _mul_64x64(m, mul_hi)
    high0, _ = _mul_64x64(m, mul_lo)
    # the middle word high0 + low1, its carry added to high1 (below 2**52, no overflow)
    sum_lo = (high0 & _LOW32) + (low1 & _LOW32)
    sum_hi = (high0 >> _U32) + (low1 >> _U32) + (sum_lo >> _U32)
    middle = ((sum_hi & _LOW32) << _U32) | (sum_lo & _LOW32)
    high1 = high1 + (sum_hi >> _U32)
    dist = np.uint64(j - 64)
    return (high1 << (_U64 - dist)) | (middle >> dist)


@inline
def _pow5_multiple(value, p):
    """``value`` (nonzero) is divisible by 5**p."""
    count = 0
    while value % _U5 == _U0:
        value = value // _U5
        count += 1
    return count >= p


@inline
def shortest(fraction, exponent):
    """Ryu's ``d2d``: (digits, e10) with ``digits * 10**e10`` the shortest decimal
    that reads back as the finite nonzero double with these fraction bits (uint64) and
    biased exponent (int64), the nearest such if there are several. ``digits`` may end
    in zeros."""
    if exponent == 0:
        e2 = 1 - _E2_OFFSET
        m2 = fraction
    else:
        e2 = exponent - _E2_OFFSET
        m2 = fraction | _HIDDEN
    # the bounds of the rounding interval read back as this double when m2 is even
    accept_bounds = (m2 & _U1) == _U0
    mv = m2 << _U2
    # the lower gap is half as wide at a power of two (except the smallest normal)
    mm_shift = _U1 if (fraction != _U0 or exponent <= 1) else _U0
    mp = mv + _U2
    mm = mv - _U1 - mm_shift

    vm_trailing_zeros = False
    vr_trailing_zeros = False
    if e2 >= 0:
        q = _LOG10_POW2[e2] - (1 if e2 > 3 else 0)
        e10 = q
        j = -e2 + q + _POW5_BITCOUNT + _POW5_BITS[q] - 1
        mul_lo = _INV_LO[q]
        mul_hi = _INV_HI[q]
        vr = _mul_shift(mv, mul_lo, mul_hi, j)
        vp = _mul_shift(mp, mul_lo, mul_hi, j)
        vm = _mul_shift(mm, mul_lo, mul_hi, j)
        if q <= 21:
            # at most one of mp, mv, mm is a multiple of 5
            if mv % _U5 == _U0:
                vr_trailing_zeros = _pow5_multiple(mv, q)
            elif accept_bounds:
                vm_trailing_zeros = _pow5_multiple(mm, q)
            elif _pow5_multiple(mp, q):
                vp = vp - _U1
    else:
        q = _LOG10_POW5[-e2] - (1 if -e2 > 1 else 0)
        e10 = q + e2
        i = -e2 - q
        j = q - (_POW5_BITS[i] - _POW5_BITCOUNT)
        mul_lo = _POW_LO[i]
        mul_hi = _POW_HI[i]
        vr = _mul_shift(mv, mul_lo, mul_hi, j)
        vp = _mul_shift(mp, mul_lo, mul_hi, j)
        vm = _mul_shift(mm, mul_lo, mul_hi, j)
        if q <= 1:
            # mv has two trailing zero bits, mp one, mm one exactly when mm_shift is 1
            vr_trailing_zeros = True
            if accept_bounds:
                vm_trailing_zeros = mm_shift == _U1
            else:
                vp = vp - _U1
        elif q < 63:
            vr_trailing_zeros = (mv & ((_U1 << np.uint64(q)) - _U1)) == _U0

    # remove the digits that vp and vm share no longer, rounding vr
    removed = 0
    last_removed = _U0
    if vm_trailing_zeros or vr_trailing_zeros:
        # the rare exact cases: track whether the removed digits were all zeros
        while vp // _U10 > vm // _U10:
            vm_digit = vm % _U10
            vm_trailing_zeros = vm_trailing_zeros and vm_digit == _U0
            vr_trailing_zeros = vr_trailing_zeros and last_removed == _U0
            last_removed = vr % _U10
            vr = vr // _U10
            vp = vp // _U10
            vm = vm // _U10
            removed += 1
        if vm_trailing_zeros:
            while vm % _U10 == _U0:
                vr_trailing_zeros = vr_trailing_zeros and last_removed == _U0
                last_removed = vr % _U10
                vr = vr // _U10
                vp = vp // _U10
                vm = vm // _U10
                removed += 1
        if vr_trailing_zeros and last_removed == _U5 and vr % _U2 == _U0:
            # exactly halfway: round to the even digit
            last_removed = np.uint64(4)
        round_up = (vr == vm and (not accept_bounds or not vm_trailing_zeros)) or (
            last_removed >= _U5
        )
    else:
        round_up = False
        if vp // _U100 > vm // _U100:
            round_up = vr % _U100 >= np.uint64(50)
            vr = vr // _U100
            vp = vp // _U100
            vm = vm // _U100
            removed += 2
        while vp // _U10 > vm // _U10:
            round_up = vr % _U10 >= _U5
            vr = vr // _U10
            vp = vp // _U10
            vm = vm // _U10
            removed += 1
        round_up = round_up or vr == vm
    digits = vr + _U1 if round_up else vr
    return digits, e10 + removed
