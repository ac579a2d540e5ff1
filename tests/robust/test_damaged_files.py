"""Damaged run files are refused, never read as good: another run's file in a run's
place, bytes overwritten in the middle of a table, bytes after a finished run's rows.
``open_run`` raises a one-line ``RunDataError`` naming the file, ``billiard run
--resume`` exits with status 2 in one line and changes nothing; an intact run opens
without a notice, and a run whose checkpoint predates the checksums opens with one.
"""

from __future__ import annotations

import shutil
import warnings

import numpy as np
import pytest

from billiard import load_scene, open_run, read_collisions, simulate
from billiard.cli import main
from billiard.run.verify import DamagedRunError, UnverifiedRunWarning
from billiard.runfile import checkpoint as checkpoint_module
from billiard.runfile.checkpoint import read_checkpoint, write_checkpoint
from billiard.runfile.npyfile import COLLISIONS, header_bytes, header_size, read_header
from billiard.runfile.record import RunDataError

#: a phases run of the parabola, sampled, that ends by its duration in a contact phase
#: (the run's end cuts it)
PHASES = [
    "contact.model=phases",
    "drive.amplitude=0.005",
    "run.contact_span=1.0",
    "initial.q1=0.0",
    "initial.q2=0.03",
]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Finished runs, one per store, impacts only and with contacts and samples."""
    root = tmp_path_factory.mktemp("runs")
    wedge, parabola = load_scene("wedge-6.6hz"), load_scene("parabola-5.4hz", overrides=PHASES)
    simulate(wedge, collisions=5000, out_dir=root / "npy", store="npy")
    simulate(wedge, collisions=2000, out_dir=root / "csv", store="csv")
    for store in ("npy", "csv"):
        out = root / f"phases-{store}"
        simulate(parabola, collisions=300, sample=0.01, duration=0.5, out_dir=out, store=store)
    return root


def _copy(runs, name, tmp_path):
    return shutil.copytree(runs / name, tmp_path / name)


def _files(folder) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(folder.iterdir())}


def _refused(folder, name: str, why: str, capsys) -> None:
    """open_run and `billiard run --resume` refuse the run in one line naming the file;
    the resume changes no file."""
    with pytest.raises(DamagedRunError) as info:
        open_run(folder)
    message = str(info.value)
    assert str(folder / name) in message and why in message and "\n" not in message
    assert isinstance(info.value, RunDataError)  # what reading a run raises
    before = _files(folder)
    capsys.readouterr()
    assert main(["run", "--resume", str(folder)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"billiard: error: cannot resume {folder}: {folder / name}")
    assert why in err and err.count("\n") == 1
    assert _files(folder) == before


def test_another_runs_csv_text_in_collisions_npy_is_refused(runs, tmp_path, capsys):
    """A finished binary run of 5000 impacts whose collisions.npy holds the CSV text of
    a 2000-impact run: refused by its format, never read as that run's rows."""
    folder = _copy(runs, "npy", tmp_path)
    (folder / "collisions.npy").write_bytes((runs / "csv" / "collisions.csv").read_bytes())
    _refused(folder, "collisions.npy", "does not start with the header of a binary", capsys)
    with pytest.raises(RunDataError, match="collisions.npy: not a binary run file"):
        read_collisions(folder / "collisions.npy")


def test_a_row_with_n_minus_1_written_mid_file_is_refused(runs, tmp_path, capsys):
    """8 bytes overwritten in the middle of collisions.npy: the middle row's impact
    number becomes -1."""
    folder = _copy(runs, "npy", tmp_path)
    path = folder / "collisions.npy"
    row = 2500
    with open(path, "r+b") as handle:
        handle.seek(header_size(COLLISIONS.dtype) + row * COLLISIONS.dtype.itemsize)
        handle.write(np.int64(-1).tobytes())
    assert np.load(path, mmap_mode="r")["n"][row] == -1  # what a reader would get
    _refused(folder, "collisions.npy", "CRC-32 differs", capsys)


@pytest.mark.parametrize(
    "run, name",
    [
        ("csv", "collisions.csv"),
        ("phases-npy", "contacts.npy"),
        ("phases-npy", "trajectory.npy"),
        ("phases-csv", "contacts.csv"),
        ("phases-csv", "trajectory.csv"),
    ],
)
def test_eight_bytes_overwritten_in_the_middle_are_found(runs, tmp_path, capsys, run, name):
    folder = _copy(runs, run, tmp_path)
    path = folder / name
    data = bytearray(path.read_bytes())
    start = read_header(bytes(data))[2] if name.endswith(".npy") else 0  # the rows
    middle = (start + len(data)) // 2
    data[middle : middle + 8] = bytes(b ^ 0x01 for b in data[middle : middle + 8])
    path.write_bytes(bytes(data))
    _refused(folder, name, "CRC-32 differs", capsys)


@pytest.mark.parametrize("store", ["npy", "csv"])
def test_the_phase_the_end_cut_is_covered(runs, tmp_path, store):
    """The contact phase a run's end cut is written after the sizes a resume cuts back
    to; the last checkpoint covers it all the same."""
    folder = _copy(runs, f"phases-{store}", tmp_path)
    assert open_run(folder).contacts["end"][-1] == "cut"
    path = folder / f"contacts.{store}"
    data = bytearray(path.read_bytes())
    data[-20] ^= 0x01  # in the last row: the cut phase's
    path.write_bytes(bytes(data))
    with pytest.raises(DamagedRunError, match="its last rows were changed"):
        open_run(folder)


@pytest.mark.parametrize("store", ["npy", "csv"])
def test_rows_after_a_finished_run_are_refused(runs, tmp_path, store):
    """A finished run's files end where its last checkpoint says: a row appended to it
    (and counted in a binary file's header) is not the run's."""
    folder = _copy(runs, store, tmp_path)
    path = folder / f"collisions.{store}"
    data = path.read_bytes()
    if store == "npy":
        rows = len(np.load(path, mmap_mode="r"))
        extra = data[-COLLISIONS.dtype.itemsize :]
        data = (
            header_bytes(COLLISIONS.dtype, rows + 1)
            + data[len(header_bytes(COLLISIONS.dtype, 0)) :]
        )
    else:
        extra = data[data.rindex(b"\n", 0, len(data) - 1) + 1 :]
    path.write_bytes(data + extra)
    with pytest.raises(DamagedRunError, match=f"holds {len(extra)} bytes after the"):
        open_run(folder)


@pytest.mark.parametrize("run", ["npy", "csv", "phases-npy", "phases-csv"])
def test_an_intact_run_opens_verified_and_without_a_notice(runs, tmp_path, capsys, run):
    folder = _copy(runs, run, tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        opened = open_run(folder)
        assert len(opened.columns["n"]) == len(opened)
    assert main(["run", "--resume", str(folder)]) == 0
    assert "the run is already complete" in capsys.readouterr().out


def test_a_header_of_another_table_is_refused(runs, tmp_path):
    """trajectory.npy in contacts.npy's place: another table's rows."""
    folder = _copy(runs, "phases-npy", tmp_path)
    shutil.copyfile(folder / "trajectory.npy", folder / "contacts.npy")
    with pytest.raises(DamagedRunError, match="contacts.npy does not start with the header"):
        open_run(folder)


def test_a_run_written_before_the_checksums_opens_with_a_notice(runs, tmp_path, monkeypatch):
    """A checkpoint of version 2 has no checksums: the run opens, and a warning says
    that its files are not verified."""
    folder = _copy(runs, "csv", tmp_path)
    body = read_checkpoint(folder / "checkpoint.json")
    for key in ("format", "version", "side_crc32", "scene_toml_sha256"):
        body.pop(key, None)
    body["csv"].pop("crc32")
    monkeypatch.setattr(checkpoint_module, "CHECKPOINT_VERSION", 2)
    write_checkpoint(folder / "checkpoint.json", body)
    with pytest.warns(UnverifiedRunWarning, match="without the checksums"):
        opened = open_run(folder)
    assert len(opened.columns["n"]) == 2000


@pytest.mark.parametrize(
    "argv", [["plot", "{dir}"], ["view", "{dir}"], ["export", "{dir}", "--csv"]]
)
def test_commands_that_read_a_run_refuse_a_damaged_one(runs, tmp_path, capsys, argv):
    """`billiard plot`, `view` and `export` check the files as open_run does: nothing
    drawn or written from a damaged file."""
    folder = _copy(runs, "npy", tmp_path)
    path = folder / "collisions.npy"
    with open(path, "r+b") as handle:
        handle.seek(header_size(COLLISIONS.dtype) + 100 * COLLISIONS.dtype.itemsize + 9)
        handle.write(np.float64(1.0).tobytes())  # impact 101's time
    before = _files(folder)
    assert main([arg.format(dir=folder) for arg in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"billiard: error: {path} does not match the checkpoint")
    assert err.count("\n") == 1 and _files(folder) == before


def test_a_side_file_row_with_an_extra_field_is_refused(runs, tmp_path):
    """A contacts.csv row with one field too many (a damaged copy, the checksums not
    consulted: the reader alone) is refused in one line naming the file and the line,
    not read with its fields shifted or dropped."""
    from billiard.runfile.sidecsv import read_side_csv

    path = _copy(runs, "phases-csv", tmp_path) / "contacts.csv"
    lines = path.read_text().splitlines(keepends=True)
    lines[1] = lines[1].replace(",", ",0,", 1)
    path.write_text("".join(lines))
    with pytest.raises(RunDataError) as info:
        read_side_csv(path)
    assert f"{path}: line 2 has" in str(info.value) and "\n" not in str(info.value)
