"""Tests of the flight arcs computed as whole arrays (billiard.plot.flights): the same
points as one flight at a time, and a bounded number of them for long windows."""

from __future__ import annotations

import numpy as np
import pytest

from billiard.plot.flights import (
    ARC_POINT_BUDGET,
    MIN_ARC_POINTS,
    arc_count,
    arc_counts,
    arcs,
    flight_positions,
    positions_at,
)
from tests.plot_support import bouncing_ball, scene_of, scene_toml


@pytest.fixture(scope="module")
def bounce():
    return bouncing_ball(120, amplitude=1e-3, frequency=25.0, e=0.5), scene_of(scene_toml())


def one_arc_at_a_time(columns, rows, scene):
    """The arcs as drawn one flight at a time: flight_positions on a linspace of
    arc_count points, each arc followed by NaN, skipping gaps in ``rows``."""
    xs, ys = [], []
    for row, nxt in zip(rows[:-1], rows[1:], strict=True):
        if nxt != row + 1:
            continue
        duration = max(float(columns["tof"][nxt]), 0.0)
        tau = np.linspace(0.0, duration, arc_count(duration))
        x, y = flight_positions(columns, int(row), tau, scene)
        xs += [x, [np.nan]]
        ys += [y, [np.nan]]
    return np.concatenate(xs), np.concatenate(ys)


def test_arcs_as_arrays_equal_the_arcs_one_at_a_time(bounce):
    columns, scene = bounce
    rows = np.concatenate([np.arange(3, 40), np.arange(45, 90)])  # a gap: no arc across it
    x, y = arcs(columns, rows, scene)
    ex, ey = one_arc_at_a_time(columns, rows, scene)
    np.testing.assert_array_equal(x, ex)  # to the last bit, NaN separators included
    np.testing.assert_array_equal(y, ey)
    assert np.isnan(x).sum() == rows.size - 2
    empty = arcs(columns, np.array([5]), scene)
    assert empty[0].size == 0 and empty[1].size == 0


def test_arc_counts_within_the_budget():
    durations = np.array([0.0, 0.001, 0.05, 0.5])
    np.testing.assert_array_equal(arc_counts(durations), [arc_count(d) for d in durations])
    many = np.full(50_000, 0.1)  # 200 points each: 10 million in all
    counts = arc_counts(many)
    assert counts.sum() <= ARC_POINT_BUDGET and counts.min() >= MIN_ARC_POINTS
    assert arc_counts(many, budget=None).sum() == 200 * many.size


def test_long_window_arcs_keep_their_ends(bounce):
    columns, scene = bounce
    rows = np.arange(0, 120)
    x, y = arcs(columns, rows, scene, budget=600)
    ends = np.flatnonzero(np.isnan(x)) - 1
    starts = np.concatenate([[0], ends[:-1] + 2])
    assert np.all(ends - starts + 1 >= MIN_ARC_POINTS)
    assert x.size - ends.size <= 600 + MIN_ARC_POINTS * rows.size
    # each arc still starts at its impact and ends at the next one
    np.testing.assert_allclose(y[starts], columns["q2"][rows[:-1]], atol=1e-15)
    np.testing.assert_allclose(y[ends], columns["q2"][rows[1:]], atol=1e-9)


def test_positions_at_follow_each_flight(bounce):
    columns, scene = bounce
    rows = np.arange(10, 30)
    t = columns["t"]
    times = np.linspace(t[10], t[29], 77)
    x, y, starts = positions_at(columns, rows, times, scene)
    for time, xi, yi, row in zip(times, x, y, starts, strict=True):
        assert t[row] <= time and (row == 29 or time < t[row + 1])
        ex, ey = flight_positions(columns, int(row), np.array([time - t[row]]), scene)
        assert (xi, yi) == (ex[0], ey[0])
