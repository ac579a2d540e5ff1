"""Output folders that cannot be created fail at once in one line (exit status 2), for
every command that writes into a folder it is given."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from billiard.cli import main
from billiard.cli.common import UserError, check_output_folder

# a folder no one can create on Linux, whatever the permissions say (root included)
UNCREATABLE = Path("/proc/nope/figures")
linux_proc = pytest.mark.skipif(
    not sys.platform.startswith("linux") or not Path("/proc/self").exists(),
    reason="needs Linux's /proc",
)


@linux_proc
@pytest.mark.parametrize(
    "args",
    [
        ["reproduce", "--docs", str(UNCREATABLE), "--collisions", "10", "--lyapunov", "0"],
        ["reproduce", "--runs", str(UNCREATABLE), "--collisions", "10", "--lyapunov", "0"],
        ["bench", "--quick", "--out", str(UNCREATABLE)],
        ["run", "wedge-6.6hz", "--collisions", "5", "--no-plot", "--out", str(UNCREATABLE)],
    ],
)
def test_an_uncreatable_output_folder_is_one_line(args, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1, err
    assert "/proc/nope" in err and "No such file or directory" in err
    assert list(tmp_path.iterdir()) == []  # nothing was written anywhere


def test_a_file_in_the_way_is_named(tmp_path):
    blocker = tmp_path / "report.md"
    blocker.write_text("x")
    with pytest.raises(UserError, match=r"^--docs .*report\.md: it is not a folder$"):
        check_output_folder(blocker, "--docs")
    with pytest.raises(UserError, match=r"^--docs .*report\.md/sub: .*report\.md is not a folder$"):
        check_output_folder(blocker / "sub", "--docs")


def test_the_check_leaves_no_folder_behind(tmp_path):
    target = tmp_path / "a" / "b" / "c"
    check_output_folder(target, "--out")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "kept").mkdir()
    check_output_folder(tmp_path / "kept", "--out")
    assert (tmp_path / "kept").is_dir()
