"""Tests of billiard.analysis.camera as the plots use it: reading a run's CSV and the
camera filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard.analysis.camera import camera_filter
from billiard.runfile.record import write_collisions
from billiard.runfile.tables import read_collisions
from tests.plot_support import COLUMN_NAMES, bouncing_ball


@pytest.fixture(scope="module")
def bounce_columns() -> dict[str, np.ndarray]:
    return bouncing_ball(160, amplitude=1e-3, frequency=25.0, e=0.5)


# --- camera ------------------------------------------------------------------------------


def hand_columns(times):
    t = np.asarray(times, dtype=float)
    tof = np.diff(t, prepend=-0.05)
    return {
        "n": np.arange(1.0, t.size + 1),
        "t": t,
        "q2": 0.01 + t,
        "tof": tof,
        "regime": np.array(["stick"] * t.size),
    }


def test_camera_filter_keeps_first_and_drops_rapid_impacts():
    kept = camera_filter(hand_columns([0, 0.001, 0.1, 0.1005, 0.3]), 1 / 30)
    np.testing.assert_array_equal(kept["t"], [0.0, 0.1, 0.3])
    np.testing.assert_array_equal(kept["n"], [1, 3, 5])
    np.testing.assert_allclose(kept["q2"], [0.01, 0.11, 0.31])
    # tof: time since the previous kept impact; the first keeps its own tof.
    np.testing.assert_allclose(kept["tof"], [0.05, 0.1, 0.2])
    assert list(kept["regime"]) == ["stick"] * 3


def test_camera_filter_measures_from_the_last_kept_impact():
    # A burst every 10 ms seen with a 25 ms frame: every third impact is kept, measured
    # from the previous *kept* one (not from the previous impact).
    kept = camera_filter(hand_columns(np.arange(10) * 0.01), 0.025)
    np.testing.assert_allclose(kept["t"], [0.0, 0.03, 0.06, 0.09])
    np.testing.assert_allclose(kept["tof"][1:], [0.03, 0.03, 0.03])


def test_camera_filter_is_strict_at_one_frame():
    kept = camera_filter(hand_columns([0.0, 0.5, 1.0, 1.75]), 0.5)
    np.testing.assert_array_equal(kept["t"], [0.0, 1.0, 1.75])


def test_camera_filter_edge_cases():
    empty = camera_filter(hand_columns([]), 0.1)
    assert all(v.size == 0 for v in empty.values())
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError):
            camera_filter(hand_columns([0, 1]), bad)
    with pytest.raises(ValueError):
        camera_filter(hand_columns([0.2, 0.1]), 0.01)
    # Without rapid impacts, everything is kept and tof is unchanged.
    columns = hand_columns([0, 0.2, 0.4])
    kept = camera_filter(columns, 1 / 30)
    np.testing.assert_allclose(kept["tof"], columns["tof"])


def test_read_collisions_round_trip(tmp_path, bounce_columns):
    path = write_collisions(tmp_path / "c.csv", bounce_columns)
    back = read_collisions(path)
    assert list(back) == COLUMN_NAMES
    assert back["regime"].dtype.kind == "U"
    assert set(back["regime"]) <= {"stick", "elastic"}
    for name in COLUMN_NAMES:
        if name not in ("regime", "wall"):
            assert back[name].dtype == (np.int64 if name == "n" else float)
            np.testing.assert_array_equal(back[name], bounce_columns[name])


def test_read_collisions_skips_a_row_cut_short_by_a_kill(tmp_path):
    header = "n,t,q1,q2,v1,v2,omega,u4,un,tof,regime,z,energy"
    row = "{n},{t},0.0,0.01,0.1,0.2,0.0,0.1,0.2,0.1,stick,0.0,1e-5"
    complete = "\n".join([header, row.format(n=1, t=0.1), row.format(n=2, t=0.2)]) + "\n"
    (tmp_path / "collisions.csv").write_text(complete + "3,0.3,0.0,0.0")
    cols = read_collisions(tmp_path / "collisions.csv")
    assert list(cols["n"]) == [1.0, 2.0]
    (tmp_path / "collisions.csv").write_text(complete)
    assert list(read_collisions(tmp_path / "collisions.csv")["t"]) == [0.1, 0.2]
