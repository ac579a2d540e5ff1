"""The contact phases' table (billiard/runfile/tables.py ``read_contacts``): ``wall`` is
an integer column in every run, a run where two walls hold the ball too, with the second
wall in ``wall_other``; files of either format written before (``a+b`` text) still read,
as the files of now."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import billiard
from billiard.geometry.curves import load_curve
from billiard.geometry.drive import Drive
from billiard.run.simulate import simulate
from billiard.runfile import npyfile
from billiard.runfile.npyfile import CONTACTS, header_bytes
from billiard.runfile.record import CONTACT_COLUMNS, LID_WALL, NO_WALL, RunDataError
from billiard.scene.scene import load_scene, with_values

pd = pytest.importorskip("pandas")

FREQUENCY, AMPLITUDE = 5.0, 0.0239  # A w^2 = 1.3 g tan(beta): the wedge holds, then lets go
W = 2 * math.pi * FREQUENCY
DURATION = 0.3  # s: a held phase, then rolling and sliding on each wall (9 impacts)


def held_scene():
    """The paper's wedge shaken sideways, the ball at rest in its vertex at t = 0."""
    return with_values(
        load_scene("wedge-6.6hz"),
        {
            "contact.model": "phases",
            "drive.frequency": FREQUENCY,
            "drive.amplitude": AMPLITUDE,
            "initial.v1": AMPLITUDE * W,  # moving with the wedge
        },
    )


# (store, sampling interval): the state machine writes the phases, with samples and
# without
CASES = [("csv", None), ("csv", 0.01), ("npy", None), ("npy", 0.01)]


@pytest.fixture(scope="module")
def held_runs(tmp_path_factory) -> dict[tuple[str, float | None], Path]:
    base = tmp_path_factory.mktemp("held")
    out = {}
    for store, sample in CASES:
        folder = base / f"{store}-{sample}"
        simulate(held_scene(), collisions=1000, duration=DURATION, out_dir=folder, store=store,
                 sample=sample)  # fmt: skip
        out[store, sample] = folder
    return out


@pytest.mark.parametrize(("store", "sample"), CASES)
def test_the_walls_of_a_run_with_a_hold_are_integers(held_runs, store, sample):
    folder = held_runs[store, sample]
    contacts = billiard.read_contacts(folder / f"contacts.{store}")
    assert list(contacts) == list(CONTACT_COLUMNS)
    wall, other, mode = contacts["wall"], contacts["wall_other"], contacts["mode"]
    assert wall.dtype == other.dtype == np.int64
    held = mode == "held"
    assert held.any() and (~held).any()
    # held by the wedge's two walls from t = 0 to the release, asin(1/Gamma) / w
    assert set(zip(wall[held].tolist(), other[held].tolist(), strict=True)) == {(0, 1)}
    assert contacts["t_start"][0] == 0.0 and held[0] and contacts["end"][0] == "release"
    assert contacts["t_end"][0] == pytest.approx(math.asin(1 / 1.3) / W, abs=1e-3)
    # every other phase on one wall, no second: the wall on whose interval the centre
    # lies, relative to the wedge, at the phase's start and end (wall 0 left of the
    # vertex, wall 1 right; the sideways push after the release is to the right)
    assert set(other[~held].tolist()) == {NO_WALL} and wall[1] == 1
    scene = held_scene()
    walls = load_curve(scene.boundary.curve, dict(scene.boundary.parameters)).walls
    drive = Drive.from_scene(scene.drive)
    for k in np.flatnonzero(~held):
        for end in ("start", "end"):
            t = contacts["t_start" if end == "start" else "t_end"][k]
            state = (contacts[f"{q}_{end}"][k] for q in ("q1", "q2", "v1", "v2"))
            px = drive.to_boundary_frame(drive.angle(t), *state)[0]
            assert walls[wall[k]].lo <= px <= walls[wall[k]].hi, (k, end, px)
    # pandas reads the file's columns as int64 whatever the run (no a+b text)
    if store == "csv":
        frame = pd.read_csv(folder / "contacts.csv")
    else:
        frame = pd.DataFrame(np.load(folder / "contacts.npy"))
    assert frame["wall"].dtype == frame["wall_other"].dtype == np.int64
    assert frame["wall"].tolist() == wall.tolist()
    assert frame["wall_other"].tolist() == other.tolist()


def test_result_contacts_and_to_pandas_have_integer_walls(held_runs):
    in_memory = simulate(held_scene(), collisions=1000, duration=DURATION)
    opened = billiard.open_run(held_runs["csv", None])
    for result in (in_memory, opened):
        contacts = result.contacts
        assert contacts["wall"].dtype == contacts["wall_other"].dtype == np.int64
        frame = result.to_pandas("contacts")
        assert frame["wall"].dtype == frame["wall_other"].dtype == np.int64
        assert frame.attrs["units"]["wall_other"] == ""
    memory, disk = in_memory.contacts, opened.contacts
    assert memory["wall"].tolist() == disk["wall"].tolist()
    assert memory["wall_other"].tolist() == disk["wall_other"].tolist()


#: contacts.csv as an earlier version wrote it: ``wall`` text, ``a+b`` for two walls
OLD_HEADER = ",".join(name for name in CONTACT_COLUMNS if name != "wall_other")
OLD_ROWS = [
    ("0.0", "0.1", "0+1", "held", "release"),
    ("0.1", "0.2", "1", "roll", "slip"),
    ("0.2", "0.3", "lid", "slide", "cut"),
    ("0.3", "0.4", "11+12", "held", "cut"),
]
OLD_WALLS = [(0, 1), (1, NO_WALL), (LID_WALL, NO_WALL), (11, 12)]


def old_csv(path: Path) -> Path:
    floats = ",".join(["0.5"] * 10)
    lines = [OLD_HEADER] + [",".join(row[:2]) + f",{','.join(row[2:])},0.25,{floats}"
                            for row in OLD_ROWS]  # fmt: skip
    path.write_text("\n".join(lines) + "\n")
    return path


def old_npy(path: Path) -> Path:
    """contacts.npy as an earlier version wrote it: ``wall`` ``S15``, no ``wall_other``."""
    names = [name for name in CONTACT_COLUMNS if name != "wall_other"]
    kinds = {"wall": "S15", "mode": "S5", "end": "S8"}
    dtype = np.dtype([(name, kinds.get(name, "<f8")) for name in names])
    rows = np.array(
        [(float(r[0]), float(r[1]), r[2], r[3], r[4], 0.25, *[0.5] * 10) for r in OLD_ROWS],
        dtype=dtype,
    )
    path.write_bytes(header_bytes(dtype, len(rows)) + rows.tobytes())
    assert np.load(path)["wall"].tolist() == [r[2].encode() for r in OLD_ROWS]
    return path


@pytest.mark.parametrize("make", [old_csv, old_npy])
def test_a_contacts_file_written_before_reads_as_one_of_now(tmp_path, make):
    path = make(tmp_path / ("contacts.csv" if make is old_csv else "contacts.npy"))
    contacts = billiard.read_contacts(path)
    assert list(contacts) == list(CONTACT_COLUMNS)
    assert contacts["wall"].dtype == contacts["wall_other"].dtype == np.int64
    walls = list(zip(contacts["wall"].tolist(), contacts["wall_other"].tolist(), strict=True))
    assert walls == OLD_WALLS
    assert contacts["mode"].tolist() == [r[3] for r in OLD_ROWS]
    assert contacts["t_end"].tolist() == [0.1, 0.2, 0.3, 0.4]
    assert contacts["omega_end"].tolist() == [0.5] * 4


def test_an_old_binary_contacts_file_exports_the_csv_of_now(tmp_path):
    exported = tmp_path / "contacts.csv"
    rows = npyfile.export_csv(old_npy(tmp_path / "contacts.npy"), exported, CONTACTS)
    assert rows == len(OLD_ROWS)
    lines = exported.read_text().splitlines()
    assert lines[0] == ",".join(CONTACT_COLUMNS)
    frame = pd.read_csv(exported)
    assert frame["wall"].dtype == frame["wall_other"].dtype == np.int64
    assert list(zip(frame["wall"], frame["wall_other"], strict=True)) == OLD_WALLS


@pytest.mark.parametrize("cell", ["0+", "+1", "x", "0+1+2", ""])
def test_an_old_wall_that_names_no_wall_is_refused_in_one_line(tmp_path, cell):
    path = old_csv(tmp_path / "contacts.csv")
    text = path.read_text().replace(",0+1,", f",{cell},", 1)
    path.write_text(text)
    with pytest.raises(RunDataError) as caught:
        billiard.read_contacts(path)
    assert str(caught.value).startswith(f"{path}: ") and "\n" not in str(caught.value)
