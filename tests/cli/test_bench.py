"""``billiard bench`` measures the source checkout's code whichever way the package is
installed, and says in one line what it lacks (exit status 2), never with a traceback."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import pytest

from billiard.cli import bench, main

ROOT = Path(__file__).resolve().parents[2]


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    bench.add_bench_arguments(parser)
    return parser.parse_args(argv)


def test_render_without_saved_results_is_one_line(tmp_path, capsys):
    out = tmp_path / "bench"
    assert main(["bench", "--render", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    saved = out / "figures" / "performance" / "results.json"
    assert err.startswith(f"billiard: error: bench --render: no saved results in {saved}")


@pytest.mark.parametrize(
    "argv",
    [
        [],
        ["--quick"],
        ["--only", "throughput,profile", "--out", "some dir"],
        ["--render", "--quick", "--out", "x"],
    ],
)
def test_the_arguments_are_given_again_unchanged(argv):
    args = parse(argv)
    assert parse(bench.bench_argv(args)) == args


def test_the_checkout_runs_its_own_package_here():
    assert bench.find_checkout(ROOT) == ROOT
    assert bench.runs_checkout(ROOT)


def test_another_copy_of_the_package_starts_the_command_again_on_the_checkout(
    tmp_path, monkeypatch, capsys
):
    """Where the package that runs is not the checkout's (``pip install .``), the
    command is replaced by ``python -m billiard.cli bench ...`` with the checkout first
    on PYTHONPATH, which the measurements' own processes inherit."""
    started = []

    class Replaced(Exception):
        pass

    def execve(path, argv, env):
        started.append((path, argv, env))
        raise Replaced

    monkeypatch.setattr(bench, "runs_checkout", lambda root: False)
    monkeypatch.setattr(os, "execve", execve)
    monkeypatch.delenv("BILLIARD_BENCH_CHECKOUT", raising=False)
    monkeypatch.setenv("PYTHONPATH", "/elsewhere")
    with pytest.raises(Replaced):
        main(["bench", "--quick", "--out", str(tmp_path)])
    [(path, argv, env)] = started
    assert path == sys.executable
    assert argv == [
        sys.executable,
        "-m",
        "billiard.cli",
        "bench",
        "--quick",
        "--out",
        str(tmp_path),
    ]
    assert env["PYTHONPATH"].split(os.pathsep) == [str(ROOT), "/elsewhere"]
    assert env["BILLIARD_BENCH_CHECKOUT"] == str(ROOT)
    assert f"bench measures the source checkout {ROOT}" in capsys.readouterr().err


def test_a_checkout_that_still_does_not_run_its_package_is_one_line(monkeypatch, capsys):
    monkeypatch.setattr(bench, "runs_checkout", lambda root: False)
    monkeypatch.setattr(os, "execve", lambda *a: pytest.fail("started again: a loop"))
    monkeypatch.setenv("BILLIARD_BENCH_CHECKOUT", str(ROOT))
    assert main(["bench", "--quick"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not run its own billiard package" in err, err


def test_no_checkout_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bench, "find_checkout", lambda start=None: None)
    assert main(["bench", "--quick"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bench needs a source checkout" in err, err
