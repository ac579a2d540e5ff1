"""``open_run(DIR)``: the folder ``billiard run`` wrote, as the Result of the same run in
memory, value for value; nothing of the tables read before they are asked for; the
binary impact table preferred to the CSV; one-line errors for a folder without a run."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import billiard.run.result as result_module
from billiard import load_scene, open_run, simulate, with_values
from billiard.cli import _user_errors, main
from billiard.run.load import NotARunError
from billiard.run.persist import CHECKPOINT_NAME, CSV_NAME, SCENE_NAME
from billiard.run.verify import UnverifiedRunWarning
from billiard.runfile.checkpoint import read_checkpoint, write_checkpoint
from billiard.runfile.record import RunDataError
from billiard.status import Status

PHASES = [
    "contact.model=phases",
    "drive.amplitude=0.005",
    "run.contact_span=1.0",
    "initial.q1=0.0",
    "initial.q2=0.03",
]


def _same_tables(a, b) -> None:
    for name in ("impacts", "contacts", "samples"):
        have = (a.columns, a.contacts, a.trajectory)[("impacts", "contacts", "samples").index(name)]
        if have is None:
            assert name != "impacts"
            assert (b.contacts if name == "contacts" else b.trajectory) is None
            continue
        other = b.table(name)
        assert list(other) == list(have), name
        for column, values in have.items():
            assert other[column].dtype == values.dtype, (name, column)
            assert np.array_equal(other[column], values), (name, column)


def _same_outcome(a, b) -> None:
    assert b.scene == a.scene
    assert b.status is a.status and b.stop_reason == a.stop_reason
    assert b.counts == a.counts and b.regimes == a.regimes
    assert b.final_time == a.final_time and b.final_mode == a.final_mode
    assert b.mode_times == a.mode_times
    assert len(b) == len(a) and b.message == a.message


@pytest.mark.parametrize(
    "options, sets",
    [
        (["--collisions", "300"], []),  # the paper's impact-only model
        (["--collisions", "300", "--sample", "0.01"], PHASES),  # contacts and samples
        (["--collisions", "300", "--duration", "0.5"], PHASES),  # ends at run.duration
    ],
    ids=["impacts", "phases-sampled", "duration"],
)
def test_open_run_of_a_cli_run_equals_the_run_in_memory(tmp_path, capsys, options, sets):
    out = tmp_path / "run"
    argv = ["run", "parabola-5.4hz", *options, "--out", str(out), "--no-plot"]
    assert main(argv + [arg for value in sets for arg in ("--set", value)]) == 0
    capsys.readouterr()
    scene = load_scene("parabola-5.4hz", overrides=sets)
    sample = float(options[options.index("--sample") + 1]) if "--sample" in options else None
    duration = float(options[options.index("--duration") + 1]) if "--duration" in options else None
    memory = simulate(scene, collisions=300, sample=sample, duration=duration)
    opened = open_run(out)
    _same_outcome(memory, opened)
    _same_tables(memory, opened)
    assert opened.path == out / CSV_NAME and math.isnan(opened.wall_time)
    assert repr(opened) == repr(memory)
    # the same summary, less the wall-clock time and rate a folder does not keep
    assert opened.summary() == re.sub(r" in \S+ s \(\S+ impacts/s\)", "", memory.summary())


def test_open_run_equals_the_streamed_result(tmp_path):
    scene = with_values(load_scene("parabola-5.4hz"), {"run.collisions": 200})
    streamed = simulate(scene, out_dir=tmp_path)
    opened = open_run(tmp_path)
    _same_outcome(streamed, opened)
    _same_tables(streamed, opened)
    assert opened.to_pandas().equals(streamed.to_pandas())


def test_open_run_reads_no_table_until_asked(tmp_path, monkeypatch):
    simulate(load_scene("parabola-5.4hz"), collisions=200, out_dir=tmp_path)
    reads = []
    real = result_module.read_collisions
    monkeypatch.setattr(
        result_module, "read_collisions", lambda path: reads.append(path) or real(path)
    )
    opened = open_run(tmp_path)
    text = repr(opened) + opened._repr_html_() + opened.summary()
    assert "200 impacts" in text and len(opened) == 200 and opened.status is Status.COMPLETE
    assert reads == []
    assert opened.columns["n"][-1] == 200 and opened.to_pandas()["n"].iloc[-1] == 200
    assert reads == [tmp_path / CSV_NAME]  # once, then kept


def test_open_run_prefers_the_binary_table(tmp_path, monkeypatch):
    """With the CSV copy `billiard export DIR --csv` writes beside collisions.npy, the
    impacts are read from the .npy file, through the one reader of impact tables."""
    simulate(load_scene("parabola-5.4hz"), collisions=50, out_dir=tmp_path, store="npy")
    assert main(["export", str(tmp_path), "--csv"]) == 0
    reads = []
    real = result_module.read_collisions
    monkeypatch.setattr(
        result_module, "read_collisions", lambda path: reads.append(path) or real(path)
    )
    opened = open_run(tmp_path)
    assert opened.path == tmp_path / "collisions.npy"
    assert len(opened.columns["t"]) == 50 and reads == [tmp_path / "collisions.npy"]


def test_a_binary_table_beside_a_csv_run_is_not_read_as_its_impacts(tmp_path):
    """A collisions.npy in a folder whose checkpoint describes a CSV run is not the run's
    (a run of one store removes the other's files): refused in one line, not read."""
    simulate(load_scene("parabola-5.4hz"), collisions=50, out_dir=tmp_path)
    simulate(load_scene("wedge-6.6hz"), collisions=20, out_dir=tmp_path / "other", store="npy")
    (tmp_path / "collisions.npy").write_bytes((tmp_path / "other/collisions.npy").read_bytes())
    with pytest.raises(
        RunDataError, match="collisions.npy is not part of the run in .*stored as collisions.csv"
    ):
        open_run(tmp_path)


def test_an_interrupted_run_opens_with_its_rows_and_how_to_continue(tmp_path):
    simulate(load_scene("parabola-5.4hz"), collisions=100, out_dir=tmp_path)
    body = read_checkpoint(tmp_path / CHECKPOINT_NAME)
    body["status"] = "interrupted"
    for key in ("format", "version", "outcome"):
        body.pop(key)
    write_checkpoint(tmp_path / CHECKPOINT_NAME, body)
    opened = open_run(tmp_path)
    assert opened.status is None and opened.unfinished == "interrupted"
    assert len(opened) == 100 and opened.columns["n"][-1] == 100
    assert f"billiard run --resume {tmp_path}" in opened.message
    assert repr(opened).startswith("<Result 'parabola-5.4hz': interrupted, 100 impacts")
    assert "interrupted before its end" in opened.summary()


def test_a_folder_without_a_checkpoint_still_opens(tmp_path):
    memory = simulate(load_scene("parabola-5.4hz"), collisions=60, out_dir=tmp_path)
    (tmp_path / CHECKPOINT_NAME).unlink()
    with pytest.warns(UnverifiedRunWarning, match="checkpoint.json is missing: the run's files"):
        opened = open_run(tmp_path)
    assert opened.status is None and opened.unfinished == "unknown" and opened.counts == {}
    assert "not known" in opened.message
    _same_tables(memory, opened)


def test_a_checkpoint_without_the_outcome_gives_the_last_impact_time(tmp_path):
    """A run written before checkpoints kept the outcome: its final time is the time of
    its last state, the last impact for a run that did all its impacts."""
    memory = simulate(load_scene("parabola-5.4hz"), collisions=60, out_dir=tmp_path)
    body = read_checkpoint(tmp_path / CHECKPOINT_NAME)
    for key in ("format", "version", "outcome"):
        body.pop(key)
    write_checkpoint(tmp_path / CHECKPOINT_NAME, body)
    opened = open_run(tmp_path)
    assert opened.final_time == memory.final_time == memory.columns["t"][-1]
    assert opened.status is Status.COMPLETE and opened.counts == memory.counts


@pytest.mark.parametrize(
    "make, expected",
    [
        (lambda d: d / "missing", "missing does not exist: open_run() takes a run folder"),
        (lambda d: d, "holds no run: no collisions.npy or collisions.csv"),
        (lambda d: _without_scene(d), "scene.toml is missing"),
    ],
    ids=["no-folder", "empty-folder", "no-scene"],
)
def test_a_folder_without_a_run_is_a_one_line_error(tmp_path, make, expected):
    with pytest.raises(NotARunError) as info:
        open_run(make(tmp_path))
    message = str(info.value)
    assert expected in message and "\n" not in message
    # a RunDataError: the command line reports it in one line with exit status 2
    assert isinstance(info.value, RunDataError) and isinstance(info.value, _user_errors())


def _without_scene(folder):
    simulate(load_scene("parabola-5.4hz"), collisions=5, out_dir=folder)
    (folder / SCENE_NAME).unlink()
    return folder
