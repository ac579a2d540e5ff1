"""The compiled float formatter (``billiard/kernels/float_text.py``) writes the bytes of
CPython's ``repr(float)``, and the compiled ``collisions.csv`` rows are the bytes of the
``repr`` path of :func:`billiard.runfile.rows.format_rows`. ``repr`` (David Gay's dtoa in
CPython) is the independent reference throughout.
"""

from __future__ import annotations

import importlib
import inspect
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from billiard import jit
from billiard.kernels.layout import LID_LABEL, NCOL, REGIMES
from billiard.runfile import rows

compiled = pytest.mark.skipif(
    not jit.ENABLED, reason=f"the kernels are not compiled: {jit.numba_problem()}"
)

SEP = np.frombuffer(b"\n", dtype=np.uint8)


def _bits(patterns) -> np.ndarray:
    """The doubles with these 64-bit patterns."""
    return np.asarray(patterns, dtype=np.uint64).view(np.float64)


def _format(values: np.ndarray) -> str:
    """The compiled ``repr`` of every value, each followed by a newline: one call."""
    from billiard.kernels import float_text

    values = np.ascontiguousarray(values, dtype=np.float64)
    out = np.empty(values.size * (float_text.MAX_FLOAT_BYTES + SEP.size), dtype=np.uint8)
    size = float_text.format_floats(values, out, SEP)
    return out[:size].tobytes().decode("ascii")


def _assert_repr(values: np.ndarray) -> None:
    """The compiled text of ``values`` is ``repr``'s, value for value."""
    got = _format(values)
    want = "".join(repr(x) + "\n" for x in values.tolist())
    if got != want:
        lines = got.split("\n")
        wrong = [
            (f"{x.view(np.uint64):#018x}", repr(float(x)), text)
            for x, text in zip(values, lines, strict=False)
            if text != repr(float(x))
        ]
        pytest.fail(f"{len(wrong)} values differ from repr (bits, repr, ours): {wrong[:10]}")
    assert got.count("\n") == values.size


def _neighbours(values) -> np.ndarray:
    """Each value with its two adjacent doubles."""
    values = np.asarray(values, dtype=np.float64)
    with np.errstate(over="ignore"):  # the largest double's upper neighbour is inf
        return np.concatenate([values, np.nextafter(values, np.inf), np.nextafter(values, -np.inf)])


def _hard_cases() -> np.ndarray:
    """Zeros, subnormals, extremes, special values, powers of ten and two with their
    neighbours, the bounds of repr's fixed notation, integers around 2**53, exact
    binary fractions (the exact-quotient paths of the digit search), every binary
    exponent with the smallest and largest fractions, and both signs of all."""
    specials = [
        0.0,
        5e-324,
        1e-323,
        2.2250738585072014e-308,  # smallest normal
        2.225073858507201e-308,  # largest subnormal
        1.7976931348623157e308,
        math.inf,
        0.1,
        0.2,
        0.3,
        1 / 3,
        2 / 3,
        1e16,
        9999999999999998.0,
        1e15,
        1234567890123456.0,
        12345678901234568.0,
        1e-4,
        1e-5,
        0.0001,
        0.00001,
        9.999999999999999e-05,
        0.00012345,
        0.001,
        1.5e16,
        1e300,
        1e22,
        1e23,
    ]
    powers_of_ten = [float(f"1e{k}") for k in range(-323, 309)]
    powers_of_two = [math.ldexp(1.0, k) for k in range(-1074, 1024)]
    integers = [float(n) for n in range(0, 10_001)]
    integers += [float(2**53 - k) for k in range(100)] + [float(2**53), float(2**53 + 2)]
    integers += [float(10**k) for k in range(23)] + [float(10**k - 1) for k in range(1, 16)]
    odd = np.arange(1, 2001, 2, dtype=np.float64)
    fractions = np.ldexp(odd[:, None], np.arange(-80, 81)[None, :]).ravel()
    exponents = np.arange(2047, dtype=np.uint64) << np.uint64(52)
    fraction_bits = np.array([0, 1, 2, 3, (1 << 52) - 2, (1 << 52) - 1], dtype=np.uint64)
    per_exponent = _bits((exponents[:, None] | fraction_bits[None, :]).ravel())
    # Ryu's own regressions: values that look like powers of five, long outputs
    ryu = _bits(
        [
            0x4830F0CF064DD592,
            0x4840F0CF064DD592,
            0x4850F0CF064DD592,
            0x44B52D02C7E14AF6,
            0x3FF0000000000001,
            0x7FEFFFFFFFFFFFFF,
        ]
    )
    positive = np.concatenate(
        [
            _neighbours(specials),
            _neighbours(powers_of_ten),
            _neighbours(powers_of_two),
            _neighbours(integers),
            fractions,
            per_exponent,
            ryu,
        ]
    )
    nans = _bits([0x7FF8000000000000, 0x7FF0000000000001, 0x7FFFFFFFFFFFFFFF])
    return np.concatenate([positive, -positive, nans, -nans])


@compiled
def test_write_float_is_repr_on_the_hard_cases():
    values = _hard_cases()
    assert values.size > 100_000
    _assert_repr(values)


@compiled
def test_write_float_is_repr_on_a_million_random_bit_patterns():
    # every 64-bit pattern is a double: subnormals, nans and infinities included
    patterns = np.random.default_rng(20180618).integers(
        0, 2**64, size=1_000_000, dtype=np.uint64, endpoint=False
    )
    values = _bits(patterns)
    assert np.isnan(values).any() and (np.abs(values) < 2.2250738585072014e-308).any()
    _assert_repr(values)


@compiled
@pytest.mark.slow
def test_write_float_is_repr_on_ten_million_random_bit_patterns():
    rng = np.random.default_rng(1074)
    for _ in range(10):
        patterns = rng.integers(0, 2**64, size=1_000_000, dtype=np.uint64, endpoint=False)
        _assert_repr(_bits(patterns))


@compiled
def test_write_float_is_repr_on_the_numbers_a_run_writes():
    rng = np.random.default_rng(2018)
    uniform = rng.uniform(-10.0, 10.0, size=200_000)
    sign = rng.choice([-1.0, 1.0], size=200_000)
    log_uniform = sign * 10.0 ** rng.uniform(-12.0, 3.0, size=200_000)
    single = rng.standard_normal(100_000).astype(np.float32).astype(np.float64)
    _assert_repr(np.concatenate([uniform, log_uniform, single]))


@compiled
def test_write_float_writes_at_the_position_and_returns_the_next():
    from billiard.kernels import float_text

    for x in (-0.0, 1e-05, 1.5e16, -2.2250738585072014e-308, math.nan, -math.inf, 123.0):
        out = np.full(40, ord("#"), dtype=np.uint8)
        end = float_text.write_float(x, out, 7)
        text = out.tobytes().decode("ascii")
        assert text == "#" * 7 + repr(x) + "#" * (40 - 7 - len(repr(x)))
        assert end == 7 + len(repr(x))
        assert len(repr(x)) <= float_text.MAX_FLOAT_BYTES


@compiled
def test_write_int_is_str():
    from billiard.kernels import float_text

    values = [0, 7, -7, 10, -10, 99, 100, 2**53, 2**63 - 1, -(2**63)]
    values += [10**k + d for k in range(19) for d in (-1, 0, 1)]
    values += [-v for v in values if v > -(2**63)]
    for n in values:
        out = np.zeros(float_text.MAX_INT_BYTES + 3, dtype=np.uint8)
        end = float_text.write_int(np.int64(n), out, 2)
        assert out[2:end].tobytes().decode("ascii") == str(n)
        assert end - 2 <= float_text.MAX_INT_BYTES


def _random_block(rng: np.random.Generator, size: int) -> np.ndarray:
    """Rows as the kernels write them: an impact number, codes in the regime and wall
    columns, floats (random bit patterns, numbers of a run's magnitudes) elsewhere."""
    patterns = rng.integers(0, 2**64, size=(size, NCOL), dtype=np.uint64, endpoint=False)
    block = patterns.view(np.float64).copy()
    moderate = rng.uniform(-10.0, 10.0, size=(size, NCOL)) * 10.0 ** rng.integers(-12, 4, (size, 1))
    take = rng.random((size, NCOL)) < 0.7
    block[take] = moderate[take]
    block[:, 0] = rng.integers(-(2**40), 2**62, size=size).astype(np.float64)
    block[: size // 2, 0] = np.arange(1, size // 2 + 1)
    block[:, 10] = rng.integers(0, len(REGIMES), size=size)
    walls = rng.integers(-1, 40, size=size).astype(np.float64)
    block[:, 13] = np.where(walls == -1, LID_LABEL, walls)
    return block


@compiled
@pytest.mark.parametrize("line_end", ["\n", "\r\n"])
def test_format_rows_is_the_repr_path_on_random_rows(line_end):
    block = _random_block(np.random.default_rng(17), 20_000)
    data = rows._format_rows_compiled(block, line_end)
    assert data is not None
    text = rows._format_rows_repr(block, line_end)
    assert bytes(data) == text.encode("ascii")
    assert rows.format_rows(block, line_end) == text
    assert rows.format_rows_bytes(block, line_end) == text.encode("ascii")
    assert text.count(line_end) == len(block)
    assert rows.format_rows(block[:0], line_end) == ""
    assert rows.format_rows_bytes(block[:0], line_end) == b""


@compiled
def test_rows_the_compiled_formatter_leaves_to_repr():
    block = _random_block(np.random.default_rng(5), 3)
    # an impact number beyond int64 and a regime counted from the end, as Python does
    block[0, 0] = 1e20
    block[1, 10] = -1.0
    assert rows._format_rows_compiled(block[:1], "\n") is None
    assert rows.format_rows(block, "\n") == rows._format_rows_repr(block, "\n")
    assert rows.format_rows(block, "\n").startswith("100000000000000000000,")
    assert bytes(rows._format_rows_compiled(block[1:2], "\n")) == (
        rows._format_rows_repr(block[1:2], "\n").encode("ascii")
    )
    assert rows.format_rows_bytes(block, "\n") == rows._format_rows_repr(block, "\n").encode()
    assert f",{REGIMES[-1]}," in rows.format_rows(block[1:2], "\n")
    # a code int() cannot convert raises as it always did
    block[2, 10] = math.nan
    with pytest.raises(ValueError):
        rows.format_rows(block, "\n")
    block[2, 10] = float(len(REGIMES))
    with pytest.raises(IndexError):
        rows.format_rows(block, "\n")


@compiled
def test_format_rows_is_the_repr_path_on_a_run():
    from billiard.run.simulate import simulate
    from billiard.scene.scene import load_scene

    result = simulate(load_scene("wedge-6.6hz"), collisions=2000)
    columns = result.columns
    names = list(columns)
    block = np.array(
        [rows.row_of([columns[name][i] for name in names]) for i in range(len(result))],
        dtype=np.float64,
    )
    assert block.shape == (2000, NCOL)
    data = rows._format_rows_compiled(block, "\n")
    assert data is not None
    assert bytes(data) == rows._format_rows_repr(block, "\n").encode("ascii")


@compiled
def test_billiard_run_writes_the_same_csv_compiled_and_interpreted(tmp_path):
    def run(out, **env):
        subprocess.run(
            [sys.executable, "-m", "billiard.cli", "run", "wedge-6.6hz"]
            + ["--collisions", "2000", "--no-plot", "--out", str(out)],
            env=dict(os.environ, **env),
            check=True,
            capture_output=True,
        )
        return (out / "collisions.csv").read_bytes()

    interpreted = run(tmp_path / "interpreted", NUMBA_DISABLE_JIT="1")
    compiled_bytes = run(tmp_path / "compiled")
    assert interpreted.count(b"\n") == 2001
    assert compiled_bytes == interpreted


def test_the_twin_loads_the_formatter_as_plain_python():
    from billiard.kernels import float_text
    from billiard.kernels import interpreted as twin

    plain = importlib.import_module(f"{twin.PACKAGE}.float_text")
    assert plain.__file__ == float_text.__file__
    assert inspect.isfunction(plain.write_float)
    # interpreted on numpy's uint64 scalars, the same source gives repr's bytes too
    rng = np.random.default_rng(3)
    values = np.concatenate(
        [
            _bits([0x8000000000000000, 1, 0x0010000000000000, 0x7FEFFFFFFFFFFFFF]),
            _bits(rng.integers(0, 2**64, size=300, dtype=np.uint64, endpoint=False)),
            rng.uniform(-10.0, 10.0, size=100),
            [1e16, 9999999999999998.0, 1e-5, 0.0001, 0.1, 2.0**53 + 2, math.inf, math.nan],
        ]
    )
    out = np.empty(plain.MAX_FLOAT_BYTES, dtype=np.uint8)
    for x in values.tolist():
        end = plain.write_float(x, out, 0)
        assert out[:end].tobytes().decode("ascii") == repr(x)


def test_ryu_log10_tables_are_the_digit_counts():
    """The floor(log10) tables of billiard/kernels/ryu.py, stepped past powers of ten,
    equal the plain definition: the number of decimal digits of 2**e and 5**e, less one."""
    from billiard.kernels import ryu

    digits = lambda n: len(str(n)) - 1  # noqa: E731
    assert ryu._LOG10_POW2.tolist() == [digits(1 << e) for e in range(ryu._LOG10_POW2.size)]
    assert ryu._LOG10_POW5.tolist() == [digits(5**e) for e in range(ryu._LOG10_POW5.size)]
    assert ryu._LOG10_POW2.size > 900 and ryu._LOG10_POW5.size > 1000
