"""A point's record as a row of columns and back: codes, counts and shares exact."""

from __future__ import annotations

import numpy as np

from billiard.status import Status
from billiard.sweep.columns import (
    MODES,
    RUN_STATUSES,
    empty_columns,
    record_of_row,
    set_row,
    share,
)


def _record() -> dict:
    return {
        "index": 7,
        "values": {"drive.frequency": 5.4},
        "status": "ok",
        "reason": "",
        "attractor": "periodic",
        "period": 2,
        "drive_periods": 1,
        "impacts": 3,
        "total_impacts": 53,
        "rest_height": 0.00785,
        "height_mean": 0.075,
        "height_std": 1e-9,
        "height_max": 0.0751,
        "tof_mean": 0.0926,
        "tof_std": 0.0,
        "elastic_share": float(np.mean(np.array([True, False, True]))),
        "lid_share": 0.0,
        "lyapunov": None,
        "lyapunov_per_second": None,
        "last_height": [0.074, 0.075, 0.076],
        "last_tof": [0.09, 0.091, 0.092],
        "run_status": "complete",
        "final_mode": "flight",
    }


def test_codes_name_the_statuses_and_modes():
    assert RUN_STATUSES[0] == "" and RUN_STATUSES[1 + Status.AT_REST] == "at_rest"
    assert MODES == ("", "flight", "roll", "slide", "held")


def test_a_record_goes_to_a_row_and_back_unchanged():
    record = _record()
    columns = empty_columns(2, keep=5)
    set_row(columns, 1, record)
    assert columns["elastic_impacts"][1] == 2 and columns["lid_impacts"][1] == 0
    assert np.isnan(columns["last_height"][1, :2]).all()  # padded at the front
    assert columns["last_height"][1, 2:].tolist() == record["last_height"]
    row = {name: column[1] for name, column in columns.items()}
    assert record_of_row(row, record["values"]) == record


def test_shares_are_those_of_numpy_mean():
    flags = np.array([True, False, False, True, True, False, True])
    count, impacts = np.array([flags.sum()]), np.array([len(flags)])
    assert share(count, impacts)[0] == np.mean(flags)
    assert np.isnan(share(np.array([0]), np.array([0]))[0])
