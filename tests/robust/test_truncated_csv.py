"""A CSV file cut short (fewer bytes than its checkpoint describes) is recovered by
resume: the run is recomputed from its start, each recomputed impact checked against
the row on disk, and continued after them; a file that is not a prefix of the run is
refused with the command that starts it again."""

from __future__ import annotations

import shlex

import pytest

from billiard.cli import main
from billiard.engine.interrupt import signal_after
from billiard.run.simulate import (
    CHECKPOINT_NAME,
    CSV_NAME,
    SCENE_NAME,
    RunInterrupted,
    resume,
    simulate,
)
from billiard.runfile.checkpoint import read_checkpoint
from billiard.scene.scene import load_scene

IMPACTS = 400


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("reference")
    simulate(load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out)
    return out


def interrupted_run(out, at=150):
    with pytest.raises(RunInterrupted):
        simulate(
            load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out, on_record=signal_after(at)
        )
    return out


def cut(path, keep):
    data = path.read_bytes()
    path.write_bytes(data[:keep])
    return data[: data.rfind(b"\n", 0, keep) + 1].count(b"\n") - 1


def test_a_csv_cut_short_is_recomputed_and_continued(reference, tmp_path, capsys):
    out = interrupted_run(tmp_path / "run")
    size = (out / CSV_NAME).stat().st_size
    rows = cut(out / CSV_NAME, size // 2)
    assert main(["run", "--resume", str(out), "--no-plot"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(
        f"billiard: {out / CSV_NAME} holds {rows} of the 150 impacts its checkpoint "
        f"describes and an unterminated last line ("
    ), err
    assert (out / CSV_NAME).read_bytes() == (reference / CSV_NAME).read_bytes()
    assert (out / SCENE_NAME).read_bytes() == (reference / SCENE_NAME).read_bytes()


@pytest.mark.parametrize("keep", [0.5, "header", "nothing after the header line"])
def test_a_finished_run_cut_short_is_recomputed(reference, tmp_path, keep):
    out = tmp_path / "run"
    simulate(load_scene("wedge-6.6hz"), collisions=IMPACTS, out_dir=out)
    data = (out / CSV_NAME).read_bytes()
    header = data.index(b"\n") + 1
    size = {"header": header, "nothing after the header line": header + 7}.get(keep)
    cut(out / CSV_NAME, size if size is not None else int(len(data) * keep))
    notes = []
    result = resume(out, notify=notes.append)
    assert not result.already_finished and len(result) == IMPACTS
    assert "recomputing the run from its start" in notes[0]
    assert (out / CSV_NAME).read_bytes() == (reference / CSV_NAME).read_bytes()


def test_a_csv_that_is_not_a_prefix_is_refused_with_the_command_to_restart(
    reference, tmp_path, capsys
):
    out = interrupted_run(tmp_path / "run")
    data = (out / CSV_NAME).read_bytes()
    lines = data.split(b"\n")
    lines[20] = lines[20].replace(b"0", b"1", 1)  # impact 20 edited
    (out / CSV_NAME).write_bytes(b"\n".join(lines[:60]) + b"\n")
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["run", "--resume", str(out), "--no-plot"]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    command = f"billiard run {out / SCENE_NAME} --out {out} --overwrite"
    assert err == (
        f"billiard: error: cannot resume {out}: {out / CSV_NAME}: impact 20 on disk differs "
        f"from the same impact recomputed (was the file edited or replaced?); to start it "
        f"again from the beginning: `{command}`"
    )
    assert {p.name: p.read_bytes() for p in out.iterdir()} == files  # the old checkpoint too
    # the command it gives works
    assert main([*shlex.split(command)[1:], "--no-plot"]) == 0
    assert (out / CSV_NAME).read_bytes() == (reference / CSV_NAME).read_bytes()


def test_a_csv_without_its_header_is_refused(tmp_path, capsys):
    out = interrupted_run(tmp_path / "run")
    (out / CSV_NAME).write_bytes(b"n,t\n")
    assert main(["run", "--resume", str(out), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not start with the header of a run file" in err
    assert f"`billiard run {out / SCENE_NAME} --out {out} --overwrite`" in err


def test_an_interrupted_recomputation_keeps_the_old_checkpoint(reference, tmp_path):
    out = interrupted_run(tmp_path / "run")
    checkpoint = (out / CHECKPOINT_NAME).read_bytes()
    cut(out / CSV_NAME, (out / CSV_NAME).stat().st_size // 2)
    data = (out / CSV_NAME).read_bytes()
    with pytest.raises(RunInterrupted) as caught:
        resume(out, on_record=signal_after(30))
    assert caught.value.rows == data.count(b"\n") - 1
    assert (out / CHECKPOINT_NAME).read_bytes() == checkpoint
    assert (out / CSV_NAME).read_bytes() == data
    assert read_checkpoint(out / CHECKPOINT_NAME)["csv"]["rows"] == 150
    resume(out)
    assert (out / CSV_NAME).read_bytes() == (reference / CSV_NAME).read_bytes()
