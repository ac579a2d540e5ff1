"""``billiard run --store`` and ``billiard export DIR --csv``: a run stored as binary
rows, its CSV files written afterwards with the bytes of a CSV run, the choice of
``--store auto`` said in one line, and bad input refused in one line (exit 2)."""

from __future__ import annotations

import importlib

import pytest

from billiard.cli import main
from billiard.runfile.tables import read_collisions

store = importlib.import_module("billiard.run.store")

RUN = ["run", "wedge-6.6hz", "--collisions", "300", "--no-plot"]
PHASES = [*RUN, "--set", "contact.model=phases", "--sample", "0.01"]


def test_a_binary_run_exports_the_bytes_of_a_csv_run(tmp_path, capsys):
    assert main([*PHASES, "--store", "npy", "--out", str(tmp_path / "npy")]) == 0
    assert main([*PHASES, "--store", "csv", "--out", str(tmp_path / "csv")]) == 0
    out = capsys.readouterr().out
    assert (
        f"wrote {tmp_path / 'npy' / 'collisions.npy'}, {tmp_path / 'npy' / 'contacts.npy'}" in out
    )
    names = sorted(p.name for p in (tmp_path / "npy").iterdir())
    assert names == [
        "checkpoint.json",
        "collisions.npy",
        "contacts.npy",
        "scene.toml",
        "trajectory.npy",
    ]
    assert (
        main(["export", str(tmp_path / "npy"), "--csv", "--out", str(tmp_path / "exported")]) == 0
    )
    assert "(300 rows)" in capsys.readouterr().out
    for name in ("collisions.csv", "contacts.csv", "trajectory.csv", "scene.toml"):
        exported = (tmp_path / "exported" / name).read_bytes()
        assert exported == (tmp_path / "csv" / name).read_bytes(), name
    # into the run's own folder: its binary files stay the run's
    assert main(["export", str(tmp_path / "npy"), "--csv"]) == 0
    assert (tmp_path / "npy" / "collisions.csv").read_bytes() == (
        tmp_path / "csv" / "collisions.csv"
    ).read_bytes()
    assert main(["run", "--resume", str(tmp_path / "npy"), "--no-plot"]) == 0
    assert "already complete (300 impacts)" in capsys.readouterr().out


def test_a_binary_run_is_plotted_from_its_files(tmp_path):
    from billiard.plot.run import load_run, load_sides

    assert main([*PHASES, "--store", "npy", "--out", str(tmp_path)]) == 0
    columns, scene = load_run(tmp_path)
    contacts, samples = load_sides(tmp_path)
    assert len(columns["t"]) == 300 and scene.name == "wedge-6.6hz"
    assert contacts is not None and len(contacts["mode"]) > 0
    assert samples is not None and samples["t"][1] - samples["t"][0] == pytest.approx(0.01)


def test_overwriting_with_another_store_removes_the_old_files(tmp_path):
    assert main([*PHASES, "--store", "csv", "--out", str(tmp_path)]) == 0
    assert main([*PHASES, "--store", "npy", "--out", str(tmp_path), "--overwrite"]) == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [
        "checkpoint.json",
        "collisions.npy",
        "contacts.npy",
        "scene.toml",
        "trajectory.npy",
    ]
    assert main([*RUN, "--store", "csv", "--out", str(tmp_path), "--overwrite"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "checkpoint.json",
        "collisions.csv",
        "scene.toml",
    ]


def test_auto_says_when_it_stores_binary_rows(tmp_path, capsys, monkeypatch):
    assert main([*RUN, "--out", str(tmp_path / "small")]) == 0
    assert "binary" not in capsys.readouterr().err
    assert (tmp_path / "small" / "collisions.csv").is_file()
    monkeypatch.setattr(store, "AUTO_BINARY_BYTES", 50_000)  # as if 300 impacts were many
    assert main([*RUN, "--out", str(tmp_path / "large")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith("billiard: the run's CSV files would take about 0 MB (over 0 MB)")
    assert "--store csv writes CSV instead" in err[0]
    assert len(read_collisions(tmp_path / "large" / "collisions.npy")["n"]) == 300
    assert not (tmp_path / "large" / "collisions.csv").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["export", "{tmp}/missing", "--csv"], "export: {tmp}/missing is not a folder"),
        (
            ["export", "{tmp}", "--csv"],
            "export: {tmp} holds no run (collisions.npy not found; "
            "`billiard run SCENE --store npy --out {tmp}` writes one)",
        ),
        (
            ["run", "--resume", "{tmp}", "--store", "npy"],
            "run --resume DIR continues a run as it was set up: give no SCENE, --out, --set, "
            "--method, --duration, --sample, --store or --overwrite with it",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, message):
    assert main([a.format(tmp=tmp_path) for a in args]) == 2
    err = capsys.readouterr().err
    assert err == f"billiard: error: {message.format(tmp=tmp_path)}\n"


def test_export_of_a_csv_run_has_nothing_to_do(tmp_path, capsys):
    assert main([*RUN, "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main(["export", str(tmp_path), "--csv"]) == 0
    assert "holds a CSV run already (collisions.csv): nothing to export" in capsys.readouterr().out
