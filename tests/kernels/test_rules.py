"""The engine's bookkeeping rules (``billiard/kernels/rules.py``): the compensated clock
gives the correctly rounded sum of its durations (checked against :func:`math.fsum`),
and the compiled loop, the interpreted engine and the docs use the one set of limits."""

from __future__ import annotations

import math
import random
import re

import pytest

from billiard import jit
from billiard.engine import ctx, driver, simulation
from billiard.kernels import loop, rules
from billiard.kernels.rules import (
    COLLAPSE_COUNT,
    COLLAPSE_SPAN,
    ZERO_FLIGHT_LIMIT,
    compensated_add,
)

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


def _durations(seed: int, count: int) -> list[float]:
    """Flight times as a run sees them: log-uniform from 1 ns to 1 s, so that most of
    them lose bits when added to a clock of hundreds of seconds."""
    rng = random.Random(seed)
    return [10.0 ** rng.uniform(-9.0, 0.0) for _ in range(count)]


def _clock(start: float, durations: list[float]) -> tuple[float, float]:
    clock, error = start, 0.0
    for tau in durations:
        clock, error = compensated_add(clock, error, tau)
    return clock, error


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_clock_is_the_correctly_rounded_sum_of_many_durations(seed):
    start = 1234.5  # a clock far from zero: each addition rounds away low bits
    durations = _durations(seed, 100_000)
    clock, error = _clock(start, durations)
    exact = math.fsum([start, *durations])
    assert clock + error == exact
    # the case is one that needs the compensation: plain addition drifts off
    naive = start
    for tau in durations:
        naive += tau
    assert naive != exact
    assert abs(naive - exact) > 10 * math.ulp(exact)


def test_the_clock_keeps_what_cancellation_loses():
    # 1 + 1e100 rounds to 1e100: plain summation returns 0, the exact sum is 2
    values = [1.0, 1e100, 1.0, -1e100]
    assert sum(values) == 0.0
    clock, error = _clock(0.0, values)
    assert clock + error == math.fsum(values) == 2.0


def test_each_step_keeps_the_exact_rounding_error():
    # Neumaier's step: (total, error) with total the rounded sum and the increment of
    # error its exact rounding error, so that total + new error carries every bit
    rng = random.Random(7)
    for _ in range(2000):
        clock = rng.uniform(0.0, 1e4)
        tau = 10.0 ** rng.uniform(-12.0, 2.0) * rng.choice((1.0, -1.0))
        total, error = compensated_add(clock, 0.0, tau)
        assert total == clock + tau
        assert math.fsum([total, error, -clock, -tau]) == 0.0


@compiled
def test_the_compiled_clock_gives_the_same_bits():
    # loop.compensated_add is the same function compiled into the impact loop
    assert loop.compensated_add.py_func is compensated_add
    durations = _durations(11, 2000)
    plain = compiled_ = (987.25, 0.0)
    for tau in durations:
        plain = compensated_add(*plain, tau)
        compiled_ = loop.compensated_add(*compiled_, tau)
        assert compiled_ == plain


def test_the_engines_use_the_one_set_of_limits():
    # one source: the compiled loop and both interpreted steppers read these objects
    for module in (loop, driver, simulation):
        assert module.COLLAPSE_COUNT == COLLAPSE_COUNT, module.__name__
        assert module.COLLAPSE_SPAN == COLLAPSE_SPAN, module.__name__
        assert module.ZERO_FLIGHT_LIMIT == ZERO_FLIGHT_LIMIT, module.__name__
    assert loop._compensated_add is rules.compensated_add
    # the collapse window holds the COLLAPSE_COUNT impact times before the latest one
    assert loop.RING == ctx.RING == COLLAPSE_COUNT + 1


def test_the_documented_limits_are_the_constants():
    # the collapse stop's documentation states the numbers: they must be these
    doc = rules.__doc__
    count = re.search(r"COLLAPSE_COUNT \(([\d,]+)\)", doc)
    span = re.search(r"COLLAPSE_SPAN \(([\d.e+-]+) s\)", doc)
    zero = re.search(r"ZERO_FLIGHT_LIMIT \(([\d,]+)\)", doc)
    assert count and span and zero
    assert int(count.group(1).replace(",", "")) == COLLAPSE_COUNT
    assert float(span.group(1)) == COLLAPSE_SPAN
    assert int(zero.group(1).replace(",", "")) == ZERO_FLIGHT_LIMIT
