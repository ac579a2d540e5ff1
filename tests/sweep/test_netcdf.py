"""The result file as CF-1.8 netCDF: opened by xarray, selected by the values asked for,
the attractor coded with flag_values / flag_meanings, missing values declared by
_FillValue and masked, units on every quantity, and the global attributes CF names.

One small real sweep (12 points of 230 impacts, about 2 s, most of it starting the
worker process): an invalid point (a negative amplitude), a ball at rest, a motion
without a period and the calibrated orbit.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
import xarray as xr
from scipy.io import netcdf_file

import billiard
from billiard import load_scene
from billiard.sweep import Sweep, parse_vary, read_result, run_sweep
from billiard.sweep.attractor import CLASSES
from billiard.sweep.netcdf import INT_FILL
from billiard.sweep.progress import SweepProgress

#: The values asked for, as typed: the grid -0.003:0.03:12 (m).
ASKED = ["-0.003", "0", "0.003", "0.006", "0.009", "0.012", "0.015", "0.018", "0.021"]
ASKED += ["0.024", "0.027", "0.03"]


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    sweep = Sweep(
        load_scene("parabola-5.4hz"),
        (parse_vary("drive.amplitude=-0.003:0.03:12"),),
        impacts=80,
        transient=150,
        keep=4,
        skip_invalid=True,
    )
    directory = tmp_path_factory.mktemp("amplitude")
    progress = SweepProgress(sweep.size, stream=io.StringIO())
    outcome = run_sweep(sweep, directory, workers=1, plots=False, progress=progress)
    return outcome, outcome.records


def test_sel_finds_every_value_asked_for(sweep_file):
    outcome, records = sweep_file
    with xr.open_dataset(outcome.result) as ds:
        point = ds.sel(drive_amplitude=0.027)
        assert int(point.point) == 10
        assert records[10]["values"] == {"drive.amplitude": 0.027}
        assert float(point.height_mean) == records[10]["height_mean"]
        # every value of the grid is the float of its decimal text, as typed
        assert ds.drive_amplitude.values.tolist() == [float(text) for text in ASKED]
        chosen = ds.sel(drive_amplitude=[0.006, 0.015, 0.027])
        assert chosen.point.values.tolist() == [3, 6, 10]


def test_global_attributes_are_cf(sweep_file):
    outcome, _ = sweep_file
    with xr.open_dataset(outcome.result) as ds:
        attrs = ds.attrs
    assert attrs["Conventions"] == "CF-1.8"
    assert "conventions" not in attrs
    assert attrs["source"].startswith(f"realworld-billiard {billiard.__version__}")
    assert attrs["history"].startswith("billiard sweep sweep.toml (")
    assert billiard.__version__ in attrs["history"]
    assert attrs["title"] == "billiard sweep of parabola-5.4hz over drive.amplitude"
    assert '"drive.amplitude" = [-0.003, 0.0, 0.003, 0.006,' in attrs["sweep_definition"]
    assert attrs["points"] == 12
    # read without xarray, through scipy's public API, the same attributes
    assert read_result(outcome.result)["_attributes"] == attrs


def test_every_quantity_has_units(sweep_file):
    outcome, _ = sweep_file
    with xr.open_dataset(outcome.result) as ds:
        numeric = [
            name
            for name, var in ds.variables.items()
            if var.dtype.kind in "fiu" and "flag_values" not in var.attrs
        ]
        assert len(numeric) == 19  # the axis, impact, point and 16 measured quantities
        assert all("units" in ds[name].attrs for name in numeric), numeric
        assert all("long_name" in ds[name].attrs for name in ds.variables)
        assert ds.drive_amplitude.attrs["units"] == "m"
        assert ds.tof_mean.attrs["units"] == "s"


def test_attractor_is_a_coded_integer_named_by_flag_meanings(sweep_file):
    outcome, records = sweep_file
    with xr.open_dataset(outcome.result) as ds:
        attractor = ds.attractor
        assert attractor.dtype == np.int8
        flags = attractor.attrs["flag_values"].tolist()
        meanings = attractor.attrs["flag_meanings"].split()
        assert flags == list(range(len(CLASSES))) and meanings == list(CLASSES)
        names = dict(zip(flags, meanings, strict=True))
        decoded = [names[int(code)] for code in attractor.values]
    expected = [r["attractor"] for r in records]
    assert decoded == expected
    assert {"invalid", "resting", "periodic"} <= set(expected)  # the sweep has several
    assert read_result(outcome.result)["attractor"].tolist() == expected


def test_missing_values_are_declared_and_masked(sweep_file):
    outcome, records = sweep_file
    no_period = [r["period"] == 0 for r in records]
    assert any(no_period) and not all(no_period)
    with xr.open_dataset(outcome.result) as ds:
        period = ds.period.values
        assert np.isnan(period).tolist() == no_period  # masked: no sentinel 0 left
        assert period[~np.isnan(period)].tolist() == [r["period"] for r in records if r["period"]]
        assert ds.period.encoding["_FillValue"] == INT_FILL
        assert np.isnan(ds.height_mean.encoding["_FillValue"])
        assert np.isnan(ds.rest_height.values[0])  # the invalid point: not measured
    with netcdf_file(outcome.result, "r", mmap=False) as f:
        raw = np.array(f.variables["period"].data)
        assert (raw == INT_FILL).tolist() == no_period
        assert f.variables["period"]._FillValue == INT_FILL


def test_read_result_masks_as_xarray_does(sweep_file):
    outcome, _ = sweep_file
    data = read_result(outcome.result)
    with xr.open_dataset(outcome.result) as ds:
        for name in ("period", "drive_periods", "height_mean", "last_height", "impacts"):
            np.testing.assert_array_equal(data[name], ds[name].values)
        assert data["status"].tolist() == ds.status.values.tolist()


def test_read_result_reads_only_the_variables_asked_for(sweep_file):
    outcome, _ = sweep_file
    whole = read_result(outcome.result)
    some = read_result(outcome.result, ["attractor", "period", "drive_amplitude"])
    assert sorted(some) == ["_attributes", "attractor", "drive_amplitude", "period"]
    assert some["attractor"].tolist() == whole["attractor"].tolist()
    np.testing.assert_array_equal(some["period"], whole["period"])
    assert some["_attributes"] == whole["_attributes"]
