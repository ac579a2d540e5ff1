"""A run whose report cannot be printed (standard output is a closed pipe or a full
disk) says so in one line, after its files are complete: no traceback and no exit
status 1 after a normal summary."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from billiard.runfile.tables import read_collisions

IMPACTS = 300


def run_cli(out: Path, stdout) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", "wedge-6.6hz", "--collisions",
         str(IMPACTS), "--no-plot", "--out", str(out)],
        stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=120,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip


def check(proc: subprocess.CompletedProcess, out: Path, reason: str) -> None:
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == (
        f"billiard: error: cannot write to standard output ({reason}); the run's files in "
        f"{out} are complete\n"
    )
    assert read_collisions(out / "collisions.csv")["n"].tolist() == list(range(1, IMPACTS + 1))


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_full_disk_under_standard_output(tmp_path):
    with open("/dev/full", "w") as full:
        proc = run_cli(tmp_path / "run", full)
    check(proc, tmp_path / "run", "No space left on device")


def test_a_reader_that_closed_the_pipe(tmp_path):
    read, write = os.pipe()
    os.close(read)  # the reader is gone before the summary: EPIPE on the first line
    try:
        proc = run_cli(tmp_path / "run", write)
    finally:
        os.close(write)
    check(proc, tmp_path / "run", "Broken pipe")
