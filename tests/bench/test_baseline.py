"""``billiard bench --only throughput --baseline REF`` (bench/baseline.py): this checkout
and a commit of it measured alternately in one run, each process running its own tree's
code, the ratio taken from the two measured columns; a REF that cannot be measured is a
one-line error before anything runs.

The processes run interpreted (NUMBA_DISABLE_JIT=1): the commit's worktree is new, and
compiling its kernels would take a minute. What is tested is the machinery, not the
speed: no time is asserted beyond what holds by construction."""

from __future__ import annotations

import argparse
import statistics
import subprocess
from pathlib import Path

import pytest

from bench import baseline, page, report_throughput
from billiard.cli import bench, main

ROOT = Path(__file__).resolve().parents[2]
IMPACTS, REPEATS, ROUNDS = 30, 2, 2


def _git(*args: str) -> str:
    return subprocess.run(
        ["git", *args], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.strip()


@pytest.fixture(scope="module")
def measured() -> dict:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("NUMBA_DISABLE_JIT", "1")
        commit = baseline.resolve(ROOT, "HEAD")
        return baseline.measure(
            ROOT, commit, ("wedge-6.6hz",), IMPACTS, REPEATS, ROUNDS, 1, drags=("none",)
        )


def test_both_trees_are_measured_and_the_ratio_is_of_the_two(measured):
    assert measured["commit"] == _git("rev-parse", "HEAD")
    assert measured["ref"] == "HEAD" and measured["engine"]["compiled"] is False
    [rate] = measured["rates"]
    assert (rate["scene"], rate["drag"], rate["impacts"]) == ("wedge-6.6hz", "none", IMPACTS)
    for name in (baseline.NEW, baseline.OLD):
        column = rate[name]
        assert len(column["loops"]) == len(column["cpus"]) == ROUNDS * REPEATS
        assert all(x > 0 for x in column["loops"] + column["cpus"])
        assert column["per_impact"] == pytest.approx(statistics.median(column["loops"]) / IMPACTS)
    assert rate["ratio"] == pytest.approx(
        rate[baseline.NEW]["per_impact"] / rate[baseline.OLD]["per_impact"]
    )
    assert len(rate["round_ratios"]) == ROUNDS


def test_start_up_is_measured_for_both_trees(measured):
    rows = {r["what"]: r for r in measured["startup"]}
    assert list(rows) == list(baseline.STARTUP)
    for row in rows.values():
        for name in (baseline.NEW, baseline.OLD):
            assert len(row[name]["times"]) == 1 and row[name]["median"] > 0
        assert row["ratio"] == pytest.approx(
            row[baseline.NEW]["median"] / row[baseline.OLD]["median"]
        )
    # the first impact is timed inside the process whose whole life is the other figure
    for name in (baseline.NEW, baseline.OLD):
        inside = rows[baseline.FIRST][name]["median"]
        assert inside < rows[baseline.PROCESS][name]["median"]


def test_the_temporary_worktree_is_gone(measured):
    assert "billiard-baseline-" not in _git("worktree", "list", "--porcelain")


def test_a_process_that_imports_another_billiard_is_refused(tmp_path, monkeypatch):
    """A folder without a billiard package: its process imports the installed one (this
    checkout, through the editable install), which is not the tree it measures."""
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    with pytest.raises(baseline.TreeError, match="imported billiard from elsewhere"):
        baseline.first_impact(tmp_path, "wedge-6.6hz")
    own = str(ROOT / "billiard" / "__init__.py")
    baseline.check_files(ROOT, [own])
    with pytest.raises(baseline.TreeError):
        baseline.check_files(ROOT, [])


def test_each_tree_runs_its_own_package(tmp_path):
    """A tree whose billiard cannot be imported: its process fails with that tree's
    error (not the checkout's package, which imports), reported in one line."""
    package = tmp_path / "billiard"
    package.mkdir()
    (package / "__init__.py").write_text('raise ImportError("this tree\'s own billiard")\n')
    with pytest.raises(baseline.TreeError, match="this tree's own billiard") as caught:
        baseline.rate(tmp_path, "wedge-6.6hz", "none", 10, 1)
    assert "\n" not in str(caught.value) and str(tmp_path) in str(caught.value)


def test_the_page_the_tables_and_the_terminal_show_both_columns(measured):
    [rate] = measured["rates"]
    short = page.section_baseline(measured)
    for value in (rate["new"]["per_impact"], rate["old"]["per_impact"]):
        assert f"| {value * 1e6:.2f} |" in short
    assert f"| {rate['ratio']:.2f}x |" in short
    assert f"--baseline {measured['ref']}" in short and measured["short"] in short
    full = report_throughput.section_baseline(measured)
    for name in ("new", "old"):
        runs = ", ".join(report_throughput._us(x / IMPACTS) for x in rate[name]["loops"])
        assert runs in full
    lo, hi = min(rate["round_ratios"]), max(rate["round_ratios"])
    assert f"{lo:.2f}x to {hi:.2f}x" in full
    terminal = baseline.summary(measured)
    assert f"new/old {rate['ratio']:.2f}x" in terminal
    assert f"old {rate['old']['per_impact'] * 1e6:7.2f}" in terminal


def test_a_ref_that_is_no_commit_is_one_line(tmp_path, capsys):
    ref = "no-such-ref-3f9c"
    assert main(["bench", "--only", "throughput", "--baseline", ref, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"bench --baseline: '{ref}' is not a commit of the repository at {ROOT}" in err
    assert list(tmp_path.iterdir()) == []  # nothing measured, nothing written


def test_without_git_it_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PATH", str(tmp_path))  # no git on it
    argv = ["bench", "--only", "throughput", "--baseline", "HEAD", "--out", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bench --baseline: git is needed" in err, err


def test_a_folder_outside_git_and_a_section_without_throughput(tmp_path, capsys):
    with pytest.raises(baseline.TreeError, match="is not a git repository"):
        baseline.resolve(tmp_path, "HEAD")
    assert main(["bench", "--only", "ladder", "--baseline", "HEAD", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "compares the throughput section" in err, err


def test_the_baseline_is_given_again_when_the_command_restarts():
    parser = argparse.ArgumentParser()
    bench.add_bench_arguments(parser)
    args = parser.parse_args(["--only", "throughput", "--baseline", "main~3"])
    assert bench.bench_argv(args) == ["--only", "throughput", "--baseline", "main~3"]
    assert parser.parse_args(bench.bench_argv(args)) == args
