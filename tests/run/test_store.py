"""Where a run keeps its rows (billiard/run/store.py): CSV unless asked, or unless
``auto`` finds the run's CSV files would be large; the choice is said in one line."""

from __future__ import annotations

import pytest

from billiard.run.output_size import SampleEstimate
from billiard.run.store import AUTO_BINARY_BYTES, CSV_IMPACT_BYTES, choose_store


def test_explicit_stores_are_kept():
    assert choose_store("csv", 10**9) == ("csv", None)
    assert choose_store("npy", 1) == ("npy", None)


def test_auto_picks_binary_only_for_a_large_run():
    limit = AUTO_BINARY_BYTES // CSV_IMPACT_BYTES
    assert choose_store("auto", limit) == ("csv", None)
    store, why = choose_store("auto", limit + 1)
    assert store == "npy"
    assert why is not None and "\n" not in why and "--store csv" in why
    assert "about 100 MB (over 100 MB)" in why


def test_auto_counts_the_trajectory_samples():
    samples = SampleEstimate(rows=AUTO_BINARY_BYTES / 140, span=1.0, why="a test", row_bytes=140)
    assert choose_store("auto", 1000)[0] == "csv"
    store, why = choose_store("auto", 1000, samples)
    assert store == "npy" and "about 100 MB" in why


def test_an_unknown_store_is_refused():
    with pytest.raises(ValueError, match="store must be one of auto, csv, npy, got 'parquet'"):
        choose_store("parquet", 10)
