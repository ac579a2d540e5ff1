"""The compiled float parser (``billiard/kernels/float_parse.py``) gives :func:`float`'s
double for every field, bit for bit: the fields it decides itself (Clinger's fast path,
Eisel-Lemire) and those it lists for :func:`float`. CPython's ``float`` (David Gay's
correctly rounded strtod) is the independent reference throughout."""

from __future__ import annotations

import numpy as np
import pytest

from billiard import jit
from billiard.kernels import float_parse as fp

compiled = pytest.mark.skipif(
    not jit.ENABLED, reason=f"the kernels are not compiled: {jit.numba_problem()}"
)
NO_LABELS = (np.zeros(0, dtype=np.uint8), np.zeros(1, dtype=np.int64))


def parse(texts: list[str]) -> tuple[np.ndarray, int]:
    """The doubles of one-field lines ``texts`` (the fields the kernel lists read by
    ``float``, as the reader does), and how many it listed."""
    data = np.frombuffer("".join(t + "\n" for t in texts).encode("ascii"), dtype=np.uint8)
    floats = np.empty((len(texts), 1))
    ints = np.empty((len(texts), 1), dtype=np.int64)
    fallback = np.empty((len(texts), 3), dtype=np.int64)
    kinds = np.array([fp.FIELD_FLOAT], dtype=np.int64)
    rows, listed = fp.parse_rows(data, kinds, False, *NO_LABELS, floats, ints, fallback)
    assert rows == len(texts)
    raw = data.tobytes()
    for index, start, stop in fallback[:listed].tolist():
        floats[index, 0] = float(raw[start:stop])
    return floats[:, 0], listed


def assert_float(texts: list[str]) -> int:
    got, listed = parse(texts)
    want = np.array([float(t) for t in texts])
    bad = np.flatnonzero(got.view(np.uint64) != want.view(np.uint64))
    assert bad.size == 0, [(texts[i], got[i], want[i]) for i in bad[:5]]
    return listed


@compiled
def test_random_doubles_as_repr_writes_them():
    """repr of 300,000 random bit patterns (every exponent, subnormals included): the
    kernel decides nearly all of them itself."""
    rng = np.random.default_rng(39)
    values = rng.integers(0, 2**64, size=300_000, dtype=np.uint64).view(np.float64)
    values = values[np.isfinite(values)]
    listed = assert_float([repr(x) for x in values.tolist()])
    # subnormals (1 in 2048), and exact doubles whose rounding the truncated powers of
    # ten cannot decide (such as 4288368302187648.5): about 0.15 % measured
    assert listed < 0.005 * values.size


@compiled
def test_values_of_a_run_and_other_spellings():
    """Numbers of a run's magnitudes (17 digits, exponents -20 to 3), and the same
    values written otherwise: more digits than the shortest, upper-case E, a plus sign,
    leading zeros, no fraction, 20 and more digits (listed)."""
    rng = np.random.default_rng(7)
    values = rng.standard_normal(100_000) * 10.0 ** rng.integers(-20, 4, 100_000)
    texts = [repr(x) for x in values.tolist()]
    texts += [f"{x:.17e}" for x in values[:20_000].tolist()]
    texts += [f"{x:.20g}".upper() for x in values[:20_000].tolist()]
    texts += [f"{x:.25f}" for x in values[:5000].tolist()]
    texts += ["0", "-0", "00012.50", "1.", ".5", "-.5e-3", "1e+5", "1E5", "7e22", "9e22"]
    assert_float(texts)


@compiled
@pytest.mark.parametrize(
    "text",
    [
        "2.2250738585072014e-308",  # the smallest normal
        "2.2250738585072011e-308",  # just below: a subnormal
        "4.9406564584124654e-324",  # the smallest subnormal
        "2.4703282292062328e-324",  # half of it: rounds up
        "2.4703282292062327e-324",  # below half: zero
        "1.7976931348623157e308",  # the largest double
        "1.7976931348623159e308",  # beyond it: inf
        "9007199254740993",  # 2**53 + 1: half-way, ties to even
        "9007199254740993.0000000001",  # just above half-way
        "1.00000000000000011102230246251565404236316680908203125",  # exactly half-way
        "1.00000000000000011102230246251565404236316680908203124",
        "0.1",
        "5e-324",
        "1e-400",
        "1e400",
        "123456789012345678901234567890",
        "nan",
        "-inf",
        "1_0.5",
    ],
)
def test_hard_cases(text: str):
    assert_float([text])


@compiled
def test_halfway_cases_of_every_binade_region():
    """Exact decimal midpoints between neighbouring doubles (where a parser that rounds
    twice goes wrong), and their neighbours one unit in the 17th digit away."""
    from decimal import Decimal, getcontext

    getcontext().prec = 800
    rng = np.random.default_rng(3)
    values = rng.integers(0, 2**63, size=3000, dtype=np.uint64).view(np.float64)
    texts = []
    for x in values[np.isfinite(values) & (values > 0)].tolist():
        mid = (Decimal(x) + Decimal(np.nextafter(x, np.inf))) / 2
        texts.append(f"{mid:.17e}")
        texts.append(str(mid)[:60])
    assert_float(texts)


@compiled
def test_integer_labels_and_malformed_lines():
    """ints as str writes them, the lid's word, regime labels; a line of another form
    is refused (-1) for the careful reader."""
    labels = np.frombuffer(b"stickslip", dtype=np.uint8)
    starts = np.array([0, 5, 9], dtype=np.int64)
    kinds = np.array([fp.FIELD_INT, fp.FIELD_WALL, fp.FIELD_REGIME, fp.FIELD_FLOAT])

    def run(text: str) -> tuple[int, np.ndarray]:
        data = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
        rows = text.count("\n")
        floats, ints = np.empty((rows, 4)), np.zeros((rows, 4), dtype=np.int64)
        fallback = np.empty((rows * 4, 3), dtype=np.int64)
        done, _ = fp.parse_rows(data, kinds, False, labels, starts, floats, ints, fallback)
        return done, ints

    done, ints = run("1,0,stick,0.5\n12,lid,slip,1.5\n-3,-1,stick,2.0\n")
    assert done == 3 and ints[:, :3].tolist() == [[1, 0, 0], [12, -1, 1], [-3, -1, 0]]
    for bad in ["01,0,stick,0.5\n", "-0,0,stick,0.5\n", "1,0,stack,0.5\n", "1,0,stick\n",
                "1,0,stick,0.5,1\n", "1,,stick,0.5\n", "1,0,stick,0.5", "1.0,0,stick,0.5\n",
                "1,+1,stick,0.5\n", "1, 0,stick,0.5\n"]:  # fmt: skip
        assert run(bad)[0] == -1, bad
