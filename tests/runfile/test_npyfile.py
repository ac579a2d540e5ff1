"""Binary run files (billiard/runfile/npyfile.py): a run stored as .npy reads back value
for value, dtype for dtype, as the same run stored as CSV (impacts on walls and on the
lid, contact phases and samples); NumPy reads the files itself; the CSV files exported
from them are the bytes a CSV run writes; a damaged file is refused in one line."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import billiard
from billiard.run.simulate import simulate
from billiard.runfile import npyfile
from billiard.runfile.npyfile import COLLISIONS, CONTACTS, TABLES, TRAJECTORY
from billiard.runfile.record import COLUMNS, LID_WALL, ContactRecord, RunDataError
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene, with_values

# (scene, changes, impacts, sampling interval s): the wedge hits the lid from impact 113
RUNS = {
    "wedge": ("wedge-6.6hz", {}, 400, None),
    "parabola-drag": ("parabola-5.4hz", {"air.drag": "fowles"}, 300, None),
    "phases": ("wedge-6.6hz", {"contact.model": "phases"}, 200, 0.01),
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, tuple[Path, Path, object]]:
    """Each run streamed as CSV and as binary rows, and kept in memory."""
    base = tmp_path_factory.mktemp("stores")
    out = {}
    for key, (name, changes, impacts, sample) in RUNS.items():
        scene = with_values(load_scene(name), changes) if changes else load_scene(name)
        folders = []
        for store in ("csv", "npy"):
            folder = base / f"{key}-{store}"
            simulate(scene, collisions=impacts, out_dir=folder, sample=sample, store=store)
            folders.append(folder)
        out[key] = (*folders, simulate(scene, collisions=impacts, sample=sample))
    return out


def assert_same_columns(a: dict, b: dict) -> None:
    assert list(a) == list(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert a[name].shape == b[name].shape, name
        if a[name].dtype.kind == "f":  # bit for bit, -0.0 and all
            assert np.array_equal(a[name].view(np.uint64), b[name].view(np.uint64)), name
        else:
            assert np.array_equal(a[name], b[name]), name


@pytest.mark.parametrize("key", list(RUNS))
def test_binary_and_csv_readers_agree_value_for_value(runs, key):
    csv_dir, npy_dir, memory = runs[key]
    from_csv = read_collisions(csv_dir / "collisions.csv")
    from_npy = billiard.read_collisions(npy_dir / "collisions.npy")
    assert_same_columns(from_csv, from_npy)
    assert_same_columns(from_csv, memory.columns)
    assert list(from_npy) == list(COLUMNS) and len(from_npy["n"]) == RUNS[key][2]
    assert from_npy["n"].dtype == from_npy["wall"].dtype == np.int64
    if key == "wedge":
        assert np.count_nonzero(from_npy["wall"] == LID_WALL) > 0
        assert set(from_npy["wall"].tolist()) == {0, 1, LID_WALL}


def test_the_side_tables_agree_value_for_value(runs):
    csv_dir, npy_dir, memory = runs["phases"]
    for name, read in (
        ("contacts", billiard.read_contacts),
        ("trajectory", billiard.read_trajectory),
    ):
        from_csv = read(csv_dir / f"{name}.csv")
        from_npy = read(npy_dir / f"{name}.npy")
        assert_same_columns(from_csv, from_npy)
        assert_same_columns(from_csv, getattr(memory, name))
        assert len(from_npy["mode"]) > 10
    # the Result of a binary run reads its own side tables
    result = simulate(
        with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"}),
        collisions=50,
        out_dir=npy_dir.parent / "again",
        sample=0.01,
        store="npy",
    )
    assert [p.name for p in result.side_files] == ["contacts.npy", "trajectory.npy"]
    assert result.contacts["t_start"].size and result.trajectory["t"].size


def test_numeric_columns_are_views_of_the_mapped_file(runs):
    _, npy_dir, _ = runs["wedge"]
    columns = read_collisions(npy_dir / "collisions.npy")
    for name in ("n", "t", "q2", "wall"):
        assert not columns[name].flags.writeable and not columns[name].flags.owndata, name
    assert columns["regime"].dtype.kind == "U"


@pytest.mark.parametrize("key", list(RUNS))
def test_numpy_reads_the_files_by_itself(runs, key):
    csv_dir, npy_dir, _ = runs[key]
    rows = np.load(npy_dir / "collisions.npy", mmap_mode="r")
    assert rows.dtype == COLLISIONS.dtype and rows.dtype.itemsize == 137
    from_csv = read_collisions(csv_dir / "collisions.csv")
    assert np.array_equal(rows["q2"], from_csv["q2"])
    assert np.array_equal(rows["wall"], from_csv["wall"])
    codes = {"stick": 0, "slip": 1, "elastic": 2}
    assert rows["regime"].tolist() == [codes[r] for r in from_csv["regime"]]
    if key == "phases":
        contacts = np.load(npy_dir / "contacts.npy")
        assert contacts.dtype == CONTACTS.dtype
        assert contacts["mode"].astype(str).tolist() == from_csv_side(csv_dir, "contacts")


def from_csv_side(folder: Path, name: str) -> list[str]:
    return billiard.read_contacts(folder / f"{name}.csv")["mode"].tolist()


@pytest.mark.parametrize("key", list(RUNS))
def test_exported_csv_files_are_the_bytes_of_a_csv_run(runs, key, tmp_path):
    csv_dir, npy_dir, _ = runs[key]
    for table in TABLES:
        source = npy_dir / table.npy_name
        if not source.exists():
            assert not (csv_dir / table.csv_name).exists()
            continue
        rows = npyfile.export_csv(source, tmp_path / table.csv_name, table)
        assert rows > 0
        assert (tmp_path / table.csv_name).read_bytes() == (csv_dir / table.csv_name).read_bytes()
    assert not list(tmp_path.glob(".*.tmp"))


@pytest.mark.parametrize("rows", [0, 1, 12345, 10**19])
def test_the_header_has_one_size_whatever_the_count(rows):
    for table in TABLES:
        head = npyfile.header_bytes(table.dtype, rows)
        assert len(head) == npyfile.header_size(table.dtype) and len(head) % 64 == 0
        assert npyfile.read_header(head) == (table.dtype, rows, len(head))


def test_an_empty_table_reads_as_empty_columns(tmp_path):
    path = tmp_path / "collisions.npy"
    path.write_bytes(npyfile.header_bytes(COLLISIONS.dtype, 0))
    columns = read_collisions(path)
    assert list(columns) == list(COLUMNS)
    assert all(len(v) == 0 for v in columns.values())
    assert columns["n"].dtype == np.int64 and columns["t"].dtype == np.float64
    assert np.load(path).shape == (0,)
    trajectory = tmp_path / "trajectory.npy"
    trajectory.write_bytes(npyfile.header_bytes(TRAJECTORY.dtype, 0))
    assert billiard.read_trajectory(trajectory)["mode"].dtype.kind == "U"


def damaged(tmp_path: Path, runs, how: str) -> Path:
    source = runs["wedge"][1] / "collisions.npy"
    data = bytearray(source.read_bytes())
    head = npyfile.header_size(COLLISIONS.dtype)
    if how == "cut short":
        data = data[: head + 10 * COLLISIONS.dtype.itemsize + 5]
    elif how == "not npy":
        data = bytearray(b"n,t\n1,0.5\n")
    elif how == "regime code":
        data[head + 8 + 9 * 8] = 7  # the first row's regime (after n and nine floats)
    elif how == "another table":
        data = bytearray(npyfile.header_bytes(TRAJECTORY.dtype, 0))
    path = tmp_path / "collisions.npy"
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize(
    ("how", "message"),
    [
        ("cut short", r"its header counts 400 rows, the file holds 10 \(cut short\?\)"),
        ("regime code", r"regime code 7 is not one of 0 to 2"),
        ("another table", r"missing column\(s\) n, u4, un, tof, regime, z, wall, Rt, Rn, s, q3"),
    ],
)
def test_a_damaged_file_is_refused_in_one_line(tmp_path, runs, how, message):
    path = damaged(tmp_path, runs, how)
    with pytest.raises(RunDataError, match=message) as caught:
        read_collisions(path)
    assert str(caught.value).startswith(f"{path}: ") and "\n" not in str(caught.value)


@pytest.mark.parametrize("name", ["collisions", "contacts", "trajectory"])
def test_a_file_of_the_other_format_is_refused_by_its_name(tmp_path, runs, name):
    """A file is read in the format its name says: another run's CSV text in a .npy
    file (or binary rows in a .csv file) is refused in one line, never read as the
    other format's rows."""
    csv_dir, npy_dir, _ = runs["phases"]
    read = {
        "collisions": read_collisions,
        "contacts": billiard.read_contacts,
        "trajectory": billiard.read_trajectory,
    }[name]
    assert len(read(csv_dir / f"{name}.csv")["t" if name != "contacts" else "t_start"])
    text_in_npy = tmp_path / f"{name}.npy"
    text_in_npy.write_bytes((csv_dir / f"{name}.csv").read_bytes())
    with pytest.raises(RunDataError, match=f"{name}.npy: not a binary run file") as caught:
        read(text_in_npy)
    assert "\n" not in str(caught.value)
    rows_in_csv = tmp_path / f"{name}.csv"
    rows_in_csv.write_bytes((npy_dir / f"{name}.npy").read_bytes())
    with pytest.raises(RunDataError, match=f"{name}.csv: ") as caught:
        read(rows_in_csv)
    assert "\n" not in str(caught.value)


def test_a_text_too_long_for_its_column_is_refused_not_cut():
    record = ContactRecord(0.0, 0.0, 0, "roll", "lift-off", *(0.0,) * 11)
    assert len(record) == len(CONTACTS.columns)
    assert npyfile.rows_of_records([record], CONTACTS)["end"][0] == b"lift-off"
    record = record._replace(end="lift-offs")
    with pytest.raises(ValueError, match="contacts column end: .* is over 8 characters"):
        npyfile.rows_of_records([record], CONTACTS)


def test_bytes_per_impact(runs):
    csv_dir, npy_dir, _ = runs["wedge"]
    head = npyfile.header_size(COLLISIONS.dtype)
    assert os.path.getsize(npy_dir / "collisions.npy") == head + 400 * 137
    assert os.path.getsize(csv_dir / "collisions.csv") > 2 * 400 * 137
