"""Files a user names are read only when they are regular files under a size limit: a
device, a named pipe or a huge file fails in one line, without reading it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from billiard.cli import main
from billiard.run.persist import CHECKPOINT_NAME, SCENE_NAME, resume
from billiard.run.simulate import simulate
from billiard.runfile.checkpoint import MAX_CHECKPOINT_BYTES, CheckpointError, read_checkpoint
from billiard.runfile.sidecsv import read_side_csv
from billiard.scene.scene import SceneError, load_scene
from billiard.scene.userfile import MAX_SCENE_BYTES, FileRefused, read_limited

posix = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1, err
    return err


def padded_scene(size: int) -> bytes:
    """A valid scene file of exactly ``size`` bytes (comments after one key)."""
    head = b'name = "padded"\n[run]\ncollisions = 5\n'
    filler = size - len(head)
    line = b"#" * 63 + b"\n"
    body = line * (filler // len(line))
    return head + body + b"#" * (filler - len(body) - 1) + b"\n"


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_a_device_is_not_read(capsys):
    assert main(["run", "/dev/zero", "--no-plot"]) == 2
    err = one_error_line(capsys)
    assert "scene file '/dev/zero' is not a regular file (a character device)" in err


@posix
def test_a_named_pipe_is_not_opened_for_ever(tmp_path):
    """Opening a pipe without a writer blocks a plain open() for ever: a fresh
    interpreter, which must answer within the timeout."""
    pipe = tmp_path / "scene.toml"
    os.mkfifo(pipe)
    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", str(pipe), "--no-plot"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert proc.returncode == 2, proc.stderr
    expected = f"scene file '{pipe}' is not a regular file (a named pipe)"
    assert proc.stderr == f"billiard: error: {expected}\n"


def test_the_scene_size_limit(tmp_path, capsys):
    at_limit = tmp_path / "at.toml"
    at_limit.write_bytes(padded_scene(MAX_SCENE_BYTES))
    assert at_limit.stat().st_size == MAX_SCENE_BYTES
    assert load_scene(at_limit).run.collisions == 5  # the limit itself is accepted
    over = tmp_path / "over.toml"
    over.write_bytes(padded_scene(MAX_SCENE_BYTES + 1))
    with pytest.raises(SceneError, match=r"is 1,048,577 bytes, over the limit of 1 MiB$"):
        load_scene(over)
    assert main(["run", str(over), "--no-plot"]) == 2
    assert "over.toml' is 1,048,577 bytes, over the limit of 1 MiB" in one_error_line(capsys)


def test_a_folder_is_named_as_such(tmp_path):
    with pytest.raises(SceneError, match=r"is not a regular file \(a folder\)"):
        load_scene(tmp_path)


def test_read_limited_reads_at_most_the_limit(tmp_path):
    path = tmp_path / "f"
    path.write_bytes(b"x" * 100)
    assert read_limited(path, 100) == b"x" * 100
    assert read_limited(path, None) == b"x" * 100
    with pytest.raises(FileRefused, match="is 100 bytes, over the limit of 99 bytes"):
        read_limited(path, 99)


@pytest.fixture(scope="module")
def small_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("run") / "run"
    simulate(load_scene("wedge-6.6hz"), collisions=700, out_dir=out, sample=0.05)
    return out


def copy_of(run: Path, tmp_path: Path) -> Path:
    out = tmp_path / "copy"
    out.mkdir()
    for path in run.iterdir():
        (out / path.name).write_bytes(path.read_bytes())
    return out


def test_a_runs_huge_scene_file_is_not_read(small_run, tmp_path):
    out = copy_of(small_run, tmp_path)
    (out / SCENE_NAME).write_bytes(padded_scene(MAX_SCENE_BYTES + 1))
    refused = r"scene.toml is 1,048,577 bytes, over the limit of 1 MiB"
    with pytest.raises(CheckpointError, match=refused):
        resume(out, collisions=800)


@posix
def test_a_runs_scene_file_that_is_a_pipe_is_not_opened(small_run, tmp_path):
    out = copy_of(small_run, tmp_path)
    (out / SCENE_NAME).unlink()
    os.mkfifo(out / SCENE_NAME)
    with pytest.raises(CheckpointError, match=r"scene.toml is not a regular file \(a named pipe\)"):
        resume(out, collisions=800)


def test_a_huge_checkpoint_is_not_read(small_run, tmp_path):
    out = copy_of(small_run, tmp_path)
    path = out / CHECKPOINT_NAME
    path.write_bytes(path.read_bytes() + b" " * MAX_CHECKPOINT_BYTES)
    refused = r"checkpoint.json is [0-9,]+ bytes, over the limit of 1 MiB"
    with pytest.raises(CheckpointError, match=refused):
        read_checkpoint(path)


@posix
def test_a_side_file_that_is_a_pipe_is_not_read(small_run, tmp_path):
    assert len(read_side_csv(small_run / "trajectory.csv")["t"]) > 10
    pipe = tmp_path / "trajectory.csv"
    os.mkfifo(pipe)
    with pytest.raises(FileRefused, match="named pipe"):
        read_side_csv(pipe)


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_a_runs_csv_that_is_a_device_is_not_read(small_run, tmp_path, capsys):
    """billiard plot DIR whose collisions.csv is a link to /dev/zero read it into memory
    without end; its scene.toml is read under the scene files' limit."""
    out = copy_of(small_run, tmp_path)
    (out / "collisions.csv").unlink()
    (out / "collisions.csv").symlink_to("/dev/zero")
    assert main(["plot", str(out)]) == 2
    err = one_error_line(capsys)
    assert "collisions.csv" in err and "is not a regular file (a character device)" in err
    (tmp_path / "b").mkdir()
    out = copy_of(small_run, tmp_path / "b")
    (out / SCENE_NAME).write_bytes(padded_scene(MAX_SCENE_BYTES + 1))
    assert main(["plot", str(out)]) == 2
    assert "scene.toml: is 1,048,577 bytes, over the limit of 1 MiB" in one_error_line(capsys)
