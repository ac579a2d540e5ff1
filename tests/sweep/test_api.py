"""The sweep as one Python call (``billiard.sweep``): the same sweep as the command line,
its result as a notebook-ready Dataset."""

from __future__ import annotations

import numpy as np
import pytest

import billiard
from billiard.cli import main
from billiard.sweep.api import axis_of
from billiard.sweep.attractor import CLASSES
from billiard.sweep.definition import LinearValues, SweepError, parse_vary
from billiard.sweep.netcdf import read_result

GRID = {"drive.frequency": (5.0, 5.4, 2), "drive.amplitude": [0.015, 0.02543]}


@pytest.fixture(scope="module")
def api_outcome(tmp_path_factory):
    out = tmp_path_factory.mktemp("api") / "sweep"
    return billiard.sweep("parabola-5.4hz", vary=GRID, impacts=60, transient=40, workers=1, out=out)


def test_the_package_is_the_call_even_after_its_modules_are_imported():
    import billiard.sweep.execute  # binds billiard.sweep to the package

    assert callable(billiard.sweep)
    assert billiard.sweep.run_sweep is billiard.sweep.execute.run_sweep


def test_an_axis_from_first_last_count_is_the_command_lines_range():
    axis = axis_of("drive.frequency", (4.0, 7.0, 31))
    assert isinstance(axis.values, LinearValues)
    assert axis == parse_vary("drive.frequency=4:7:31")
    assert axis_of("drive.frequency", (5.4, 5.4, 1)).values == (5.4,)
    listed = axis_of("drive.amplitude", np.array([0.01, 0.02]))
    assert listed.values == (0.01, 0.02) and all(type(v) is float for v in listed.values)
    assert axis_of("air.drag", ["none", "quadratic"]).values == ("none", "quadratic")


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        ({"drive.frequency": (4.0, float("nan"), 3)}, "last value nan is not a finite number"),
        ({"drive.frequency": (4.0, 5.0, 0)}, "count 0 is out of range"),
        ({"drive.frequency": np.zeros((2, 2))}, "one-dimensional"),
        ({"drive.frequency": 5.4}, "expected (first, last, count)"),
        ({}, "give a dict of scene key -> values"),
    ],
)
def test_a_malformed_vary_is_one_line_naming_it(vary, words):
    with pytest.raises(SweepError) as caught:
        billiard.sweep("parabola-5.4hz", vary=vary)
    assert words in str(caught.value) and "\n" not in str(caught.value)


def test_an_unknown_setting_names_the_settings():
    with pytest.raises(SweepError, match="unknown setting 'impact'; the settings are impacts"):
        billiard.sweep("parabola-5.4hz", vary={"drive.frequency": (5, 6, 2)}, impact=3)


def test_the_call_writes_the_command_lines_result_byte_for_byte(api_outcome, tmp_path):
    out = tmp_path / "cli"
    argv = ["sweep", "parabola-5.4hz", "--vary", "drive.frequency=5:5.4:2"]
    argv += ["--vary", "drive.amplitude=0.015,0.02543", "--impacts", "60", "--transient", "40"]
    assert main([*argv, "--workers", "1", "--no-plot", "--out", str(out)]) == 0
    assert (out / "sweep.nc").read_bytes() == api_outcome.result.read_bytes()


def test_the_dataset_names_the_attractors_and_the_axes(api_outcome):
    data = read_result(api_outcome.result)
    with api_outcome.dataset as ds:
        assert ds.attractor.values.tolist() == data["attractor"].tolist()
        assert set(ds.attractor.values.ravel()) <= set(CLASSES)
        codes = ds.attractor_code.values.ravel().tolist()
        assert [CLASSES[c] for c in codes] == ds.attractor.values.ravel().tolist()
        frequency = ds.drive_frequency
        assert frequency.attrs["long_name"] == "drive frequency"
        assert frequency.attrs["units"] == "Hz"
        assert ds.drive_amplitude.attrs["long_name"] == "drive amplitude"


def test_an_ensemble_result_shows_as_a_table():
    result = billiard.run_ensemble(
        "wedge-6.6hz", q1=np.array([-0.01, 0.0, 0.01]), q2=0.09, impacts=20
    )
    page = result._repr_html_()
    assert page.startswith("<table>") and page.endswith("</table>")
    names, counts = np.unique(result.attractor, return_counts=True)
    for name, count in zip(names, counts, strict=True):
        assert f"{name} {count} (" in page
    assert "3 trajectories" in page and "wedge-6.6hz" in page


def test_an_ensemble_without_states_keeps_the_same_measurements():
    """states=False (what the GPU copies back for a sweep): the same columns and kept
    impacts, no final states; an invalid start among them stays invalid."""
    kw = dict(q1=np.array([-0.01, 0.0, 0.5]), q2=0.09, impacts=20, transient=5, keep=6)
    full = billiard.run_ensemble("wedge-6.6hz", **kw)
    lean = billiard.run_ensemble("wedge-6.6hz", states=False, **kw)
    assert full.attractor.tolist()[2] == "invalid" and set(full.final) == {
        "t", "q1", "q2", "v1", "v2", "omega"
    }  # fmt: skip
    for name, column in full.columns.items():
        nan = column.dtype.kind == "f"  # an invalid start's means are NaN
        assert np.array_equal(lean.columns[name], column, equal_nan=nan), name
    assert np.array_equal(lean.last_height, full.last_height, equal_nan=True)
    assert np.array_equal(lean.last_tof, full.last_tof, equal_nan=True)
    assert not np.isnan(full.last_height[:2]).any() and np.isnan(full.last_height[2]).all()
    assert lean.final == {} and lean.ctxs is None
