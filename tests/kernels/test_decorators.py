"""The two kernels that read a float's binary format, computed from its value alone:
``ulp`` (``billiard/kernels/decorators.py``, for the event locator's tolerances) and the
bits that the CSV formatter reads (``_float_bits``, ``billiard/kernels/ryu.py``). The
references are ``math.ulp`` and the float's own bits (a numpy view), on every binade's
edges, the subnormals and a million random bit patterns. Also ``borrow``, an array
without its reference count: the same array to the kernel that reads it."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from billiard import jit
from billiard.kernels import interpreted as kernels_python

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

#: what ulp gives for inf and nan: the exponent field of all ones read as a finite one
NOT_FINITE_ULP = 2.0**972


def _values() -> np.ndarray:
    """Finite doubles of both signs: zero, every power of two and its neighbours, the
    subnormals' edges, the largest double, random bit patterns."""
    powers = np.ldexp(1.0, np.arange(-1074, 1024))
    edges = np.concatenate(
        [
            [0.0, 5e-324, 2.2250738585072014e-308, 2.225073858507201e-308],
            [1.7976931348623157e308, 1.0, 1.5, 0.1],
            powers,
            np.nextafter(powers, 0.0),
            np.nextafter(powers, np.inf),
            1.5 * powers[:-1],
        ]
    )
    patterns = np.random.default_rng(52).integers(0, 2**63, size=1_000_000, dtype=np.uint64)
    random = patterns.view(np.float64)
    values = np.concatenate([edges, random[np.isfinite(random)]])
    values = values[np.isfinite(values)]
    return np.concatenate([values, -values])


def _loop(kernel, dtype):
    """A compiled loop of ``kernel`` over an array (one call for many values)."""
    import numba

    @numba.njit
    def apply(xs, out):
        for k in range(xs.size):
            out[k] = kernel(xs[k])

    def run(xs: np.ndarray) -> np.ndarray:
        out = np.empty(xs.size, dtype=dtype)
        apply(xs, out)
        return out

    return run


@compiled
def test_compiled_ulp_is_math_ulp():
    from billiard.kernels import decorators

    values = _values()
    got = _loop(decorators.ulp, np.float64)(values)
    expected = np.array([math.ulp(x) for x in values])
    assert np.array_equal(got.view(np.uint64), expected.view(np.uint64))
    special = np.array([math.inf, -math.inf, math.nan, -math.nan])
    assert (_loop(decorators.ulp, np.float64)(special) == NOT_FINITE_ULP).all()


def test_the_ulp_arithmetic_is_exact_in_python_too():
    """The compiled ulp's source, run by CPython (the same IEEE operations), on the
    binades' edges: the algorithm, not numba, gives the exact result."""
    twin = importlib.import_module(f"{kernels_python.PACKAGE}.decorators")
    ulp = getattr(twin._ulp_compiled, "py_func", twin._ulp_compiled)
    values = _values()[:20_000]
    assert all(ulp(x) == math.ulp(x) for x in values.tolist())
    assert ulp(math.inf) == ulp(math.nan) == NOT_FINITE_ULP
    assert twin.ulp(0.1) == math.ulp(0.1)  # the twin's ulp is math.ulp


@compiled
def test_compiled_float_bits_are_the_floats_bits():
    from billiard.kernels import ryu

    values = _values()
    got = _loop(ryu._float_bits, np.uint64)(values)
    assert np.array_equal(got, values.view(np.uint64))
    assert _loop(ryu._float_bits, np.uint64)(np.array([-0.0]))[0] == 1 << 63


def _nan_bits_ok(bits: int, negative: bool) -> bool:
    """A nan's bits: the exponent field all ones, a fraction that is not zero, its sign."""
    return (
        (bits >> 52) & 0x7FF == 0x7FF
        and bits & ((1 << 52) - 1) != 0
        and (bits >> 63 == int(negative))
    )


@compiled
def test_compiled_float_bits_of_infinities_and_nans():
    from billiard.kernels import ryu

    nans = np.array([0x7FF8000000000000, 0x7FF0000000000001, 0xFFFFFFFFFFFFFFFF], np.uint64)
    values = np.concatenate([[math.inf, -math.inf], nans.view(np.float64)])
    got = [int(b) for b in _loop(ryu._float_bits, np.uint64)(values)]
    assert got[:2] == [0x7FF0000000000000, 0xFFF0000000000000]
    signs = (False, False, True)
    assert all(_nan_bits_ok(b, neg) for b, neg in zip(got[2:], signs, strict=True))


def test_interpreted_float_bits_are_the_floats_bits():
    twin = importlib.import_module(f"{kernels_python.PACKAGE}.ryu")
    values = _values()[::50]
    got = np.array([twin._float_bits(x) for x in values.tolist()], dtype=np.uint64)
    assert np.array_equal(got, values.view(np.uint64))
    assert int(twin._float_bits(-math.inf)) == 0xFFF0000000000000
    assert _nan_bits_ok(int(twin._float_bits(-math.nan)), True)


@compiled
def test_a_borrowed_array_is_the_array_itself():
    """``borrow`` drops the reference count, nothing else: a compiled kernel reads and
    writes the caller's array through it, every element and the length."""
    import numba

    from billiard.kernels.decorators import borrow

    @numba.njit
    def double_in_place(values):
        view = borrow(values)
        for i in range(len(view)):
            view[i] = 2.0 * view[i]
        return len(view)

    values = np.arange(7.0)
    assert double_in_place(values) == 7
    assert values.tolist() == [2.0 * i for i in range(7)]


def test_borrow_is_the_identity_interpreted():
    values = [1.0, 2.0]
    twin = importlib.import_module(f"{kernels_python.PACKAGE}.decorators")
    assert twin.borrow(values) is values
