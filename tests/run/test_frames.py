"""A run's tables as numpy Tables, pandas DataFrames and xarray Datasets: the same
columns, dtypes and values as ``Result.columns``, ``.contacts`` and ``.trajectory``,
with every column's unit; one-line errors for a table that does not exist and for a
missing optional dependency."""

from __future__ import annotations

import pickle
import sys

import numpy as np
import pandas as pd
import pytest

from billiard import load_scene, simulate, with_values
from billiard.run.frames import DATA_HINT, MissingExtraError, Table, TableError
from billiard.runfile.column_units import COLUMN_INFO, TABLE_COLUMNS, TABLES

#: the paper's parabola under contact phases, dropped into a gently shaken bowl: a few
#: impacts, then landing and rolling until the contact span ends the run (one second)
PHASES = {
    "contact.model": "phases",
    "drive.amplitude": 0.005,
    "run.contact_span": 1.0,
    "initial.q1": 0.0,
    "initial.q2": 0.03,
}


@pytest.fixture(scope="module")
def result():
    """A run with all three tables: impacts, contact phases and samples (every 10 ms)."""
    scene = with_values(load_scene("parabola-5.4hz"), PHASES)
    return simulate(scene, collisions=300, sample=0.01)


def _tables(result):
    return {"impacts": result.columns, "contacts": result.contacts, "samples": result.trajectory}


def test_the_run_has_all_three_tables(result):
    for name, table in _tables(result).items():
        assert isinstance(table, Table) and table.name == name
        assert tuple(table) == TABLE_COLUMNS[name]
        assert table.rows > 0 and result.table(name) is table
    assert result.columns.rows == len(result)


@pytest.mark.parametrize("name", TABLES)
def test_to_pandas_holds_each_column_exactly_with_its_unit(result, name):
    table = result.table(name)
    frame = result.to_pandas(name)
    assert list(frame.columns) == list(table) and len(frame) == table.rows
    for column, values in table.items():
        got = frame[column].to_numpy()
        if values.dtype.kind == "U":
            assert list(got) == list(values), column
        else:
            assert got.dtype == values.dtype, column
            assert np.array_equal(got, values, equal_nan=True), column
    units = {column: COLUMN_INFO[name][column][0] for column in table}
    assert frame.attrs["units"] == units and frame.attrs["table"] == name
    assert frame.attrs["scene"] == "parabola-5.4hz" and frame.attrs["status"] == "in_contact"
    assert frame.attrs["final_time_s"] == result.final_time


def test_the_impact_units_are_si():
    units = {column: unit for column, (unit, _) in COLUMN_INFO["impacts"].items()}
    assert units["t"] == "s" and units["q2"] == "m" and units["v1"] == "m/s"
    assert units["omega"] == "rad/s" and units["energy"] == "J" and units["Rn"] == "N s"
    assert set(COLUMN_INFO) == set(TABLES)
    for name in TABLES:
        assert tuple(COLUMN_INFO[name]) == TABLE_COLUMNS[name]


@pytest.mark.parametrize("name", TABLES)
def test_to_xarray_holds_each_column_exactly_with_units_and_names(result, name):
    table = result.table(name)
    dataset = result.to_xarray(name)
    dim = {"impacts": "impact", "contacts": "contact", "samples": "sample"}[name]
    assert dict(dataset.sizes) == {dim: table.rows}
    for column, values in table.items():
        variable = dataset[column]
        assert variable.dims == (dim,)
        assert variable.dtype == values.dtype, column
        assert np.array_equal(variable.values, values), column
        unit, description = COLUMN_INFO[name][column]
        assert variable.attrs["long_name"] == description
        assert variable.attrs.get("units", "") == unit
    assert dataset.attrs["table"] == name and dataset.attrs["status"] == "in_contact"
    assert dataset.attrs["source"].startswith("realworld-billiard ")
    assert "[contact]" in dataset.attrs["scene_toml"]


def test_the_impacts_dataset_is_indexed_by_the_impact_number(result):
    dataset = result.to_xarray()
    n = result.columns["n"]
    assert np.array_equal(dataset["impact"].values, n)
    assert dataset.sel(impact=n[-1])["t"].item() == result.columns["t"][-1]


def test_a_table_is_a_dict_with_attribute_access_and_records(result):
    table = result.contacts
    assert table.t_start is table["t_start"]  # the old dict access keeps working
    assert table.units["t_start"] == "s" and table.units["mode"] == ""
    records = table.to_records()
    assert records.shape == (table.rows,)
    for column, values in table.items():
        assert records[column].dtype == values.dtype
        assert np.array_equal(records[column], values)
    with pytest.raises(AttributeError, match="no column 'q9'"):
        table.q9  # noqa: B018


def test_a_table_and_a_result_survive_pickling(result):
    """As a worker process's return value or a cached object: the same name and arrays."""
    table = pickle.loads(pickle.dumps(result.trajectory))
    assert isinstance(table, Table) and table.name == "samples"
    for column, values in result.trajectory.items():
        assert np.array_equal(table[column], values)
    again = pickle.loads(pickle.dumps(result))
    assert repr(again) == repr(result)
    assert np.array_equal(again.columns.q2, result.columns.q2)


def test_a_table_the_run_lacks_is_a_one_line_error():
    result = simulate(load_scene("parabola-5.4hz"), collisions=5)
    assert result.contacts is None and result.trajectory is None
    with pytest.raises(TableError, match='no contacts table: .*contact.model = "phases"') as info:
        result.to_pandas("contacts")
    assert "\n" not in str(info.value)
    with pytest.raises(TableError, match="no samples table: .*sample=DT"):
        result.to_xarray("samples")
    with pytest.raises(TableError, match="unknown table 'collisions': .*impacts, contacts"):
        result.to_pandas("collisions")


@pytest.mark.parametrize("module, call", [("pandas", "to_pandas"), ("xarray", "to_xarray")])
def test_without_the_data_extra_a_one_line_message_names_it(result, monkeypatch, module, call):
    monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
    with pytest.raises(MissingExtraError) as info:
        getattr(result, call)()
    message = str(info.value)
    assert message == f"{call}() needs {module}: {DATA_HINT}"
    assert 'pip install "realworld-billiard[data]"' in message
    assert isinstance(info.value, ImportError)


def test_a_dataframe_of_impacts_plots(result, tmp_path):
    """The README's notebook path: the DataFrame's columns plot by name."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frame = result.to_pandas()
    axes = frame.plot.scatter("t", "q2", s=2)
    points = axes.collections[0].get_offsets()
    assert np.array_equal(points[:, 1], result.columns["q2"])
    axes.figure.savefig(tmp_path / "q2.png")
    plt.close(axes.figure)
    assert (tmp_path / "q2.png").stat().st_size > 0
    assert isinstance(frame, pd.DataFrame)
