"""``billiard hysteresis`` and ``billiard uncertainty``: bad input is one line and exit
status 2; a short run writes its table, summary and figure."""

from __future__ import annotations

import csv
import json

import pytest

from billiard.cli import main


def one_error_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: error: "), captured.err
    assert "Traceback" not in captured.err
    return lines[0]


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--vary", "drive.frequency=5:5:1"], "needs >= 2 values"),
        (["--vary", "drive.frequency=5.5"], "needs >= 2 values"),
        (["--vary", "air.drag=none,linear"], "must be numbers"),
        (["--vary", "drive.frequency=a:6:3"], "START and STOP must be numbers"),
        (["--vary", "drive.frequncy=5:6:3"], "did you mean 'drive.frequency'"),
        (["--vary", "initial.q1=0:0.01:3"], "ball's start cannot be swept"),
        (["--vary", "drive.phase=0:1:3"], "the phase has no effect"),
        (["--vary", "run.collisions=10,20"], "--impacts and --transient"),
        (["--vary", "drive.frequency=-1:1:3"], "drive.frequency"),
        (["--vary", "drive.frequency=5:6:3", "--set", "contact.model=phases"], "phases"),
        (["--vary", "drive.frequency=5:6:3", "--set", "run.method=rk4"], "'rk4'"),
        (["--vary", "drive.frequency=5:6:3", "--starts", "0"], "--starts must be >= 1"),
        (["--vary", "drive.frequency=5:6:3", "--impacts", "0"], "--impacts must be >= 1"),
    ],
)
def test_hysteresis_refuses_bad_input(argv, says, capsys, tmp_path):
    code = main(["hysteresis", "parabola-5.4hz", "--out", str(tmp_path / "h"), *argv])
    assert code == 2
    assert says in one_error_line(capsys)
    assert not (tmp_path / "h").exists()


def test_hysteresis_writes_its_table_and_figure(capsys, tmp_path):
    out = tmp_path / "h"
    argv = ["hysteresis", "parabola-5.4hz", "--vary", "drive.frequency=5.3:5.5:3"]
    code = main(
        [*argv, "--starts", "2", "--impacts", "50", "--transient", "100", "--out", str(out)]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "3 values, 2 start(s)" in printed and "hysteresis.png" in printed
    with open(out / "hysteresis.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 3 * 2
    assert [r["direction"] for r in rows[::2]] == ["up"] * 3 + ["down"] * 3
    at_54 = [float(r["height_mean_m"]) for r in rows if float(r["value"]) == 5.4]
    assert len(at_54) == 4 and all(abs(h - 0.075) < 1e-3 for h in at_54)
    assert (out / "hysteresis.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--q1", "0.01:-0.01", "--q2", "0.03:0.05"], "LO < HI"),
        (["--q1", "x", "--q2", "0.03:0.05"], "give LO:HI in metres"),
        (["--q1", "-0.01:0.01", "--q2", "0.03:0.05", "--eps", "1e-3:1e-2"], "LO:HI:N"),
        (["--q1", "-0.01:0.01", "--q2", "0.03:0.05", "--eps", "0:1e-2:3"], "0 < LO < HI"),
        (["--q1", "-0.01:0.01", "--q2", "0.03:0.05", "--eps", "1e-3:1e-2:1"], "N >= 2"),
        (["--q1", "-0.01:0.01", "--q2", "0.03:0.05", "--samples", "0"], "--samples"),
        (["--q1", "-0.01:0.01", "--q2", "0.03:0.05", "--set", "run.method=rk4"], "'rk4'"),
        (["--q1", "-0.01:0.01", "--q2", "5:6", "--samples", "5"], "inside the container"),
    ],
)
def test_uncertainty_refuses_bad_input(argv, says, capsys, tmp_path):
    code = main(["uncertainty", "wedge-6.6hz", "--out", str(tmp_path / "u"), *argv])
    assert code == 2
    assert says in one_error_line(capsys)
    assert not (tmp_path / "u").exists()


def test_uncertainty_writes_its_results(capsys, tmp_path):
    out = tmp_path / "u"
    argv = ["uncertainty", "wedge-6.6hz", "--q1", "-0.04:0.04", "--q2", "0.02:0.12"]
    more = ["--samples", "30", "--eps", "1e-4:1e-2:3", "--impacts", "30", "--transient", "50"]
    assert main([*argv, *more, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "uncertainty.json").read_text())
    assert summary["samples"] == 30 and summary["scene"] == "wedge-6.6hz"
    assert f"alpha = {summary['alpha']:.3f}" in printed
    with open(out / "uncertainty.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 and all(int(r["samples"]) == 30 for r in rows)
    assert (out / "uncertainty.png").stat().st_size > 10_000
