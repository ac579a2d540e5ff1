"""Numbers that would make a command allocate without bound, and the tracebacks of odd
input: every one is refused (or handled) in one line ``billiard: error: ...`` with exit
status 2, before anything large is allocated.

The refusals are checked to come first: the ensemble set-up (the first step of the
work) is replaced by one that fails the test, the values of a range by ones that cannot
be listed, and the memory the command takes until it refuses is measured.
"""

from __future__ import annotations

import csv
import math
import os
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from billiard.cli import main
from billiard.engine import ensemble as EN
from billiard.run.output_size import MAX_BYTES, OutputSizeError
from billiard.scene.scene import SceneError, load_scene
from billiard.sweep import definition, hysteresis, uncertainty

SCENE = "hyperbola-4.5hz"
BOX = ["--q1", "-0.04:0.04", "--q2", "0.02:0.12"]


def one_line_error(capsys, argv: list[str]) -> str:
    """Run ``billiard ARGV``; it must exit 2 with one line on stderr, nothing on stdout."""
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: error: "), captured.err
    assert captured.out == ""
    return lines[0]


@pytest.fixture
def no_work(monkeypatch):
    """The ensemble's set-up fails the test, and so do listing a range's values and
    making a million eps: a refusal must come before any of them."""

    def prepare(*args, **kwargs):
        raise AssertionError("the work started: the size was not checked first")

    def listed(self):
        raise AssertionError("the range's values were listed before the size check")

    geomspace = np.geomspace

    def few(start, stop, num=50, **kwargs):
        assert num <= 10**6, "the eps were made before the size check"
        return geomspace(start, stop, num, **kwargs)

    monkeypatch.setattr(EN, "prepare", prepare)
    monkeypatch.setattr(definition.LinearValues, "__iter__", listed)
    monkeypatch.setattr(np, "geomspace", few)


@pytest.mark.parametrize(
    "argv, named",
    [
        (
            ["hysteresis", SCENE, "--vary", "drive.frequency=3.8:5.2:71", "--starts", "100000000"],
            "71 values x 100,000,000 starts",
        ),
        (
            ["hysteresis", SCENE, "--vary", "drive.frequency=4:5:100000000"],
            "100,000,000 values x 1 start would",
        ),
        (
            ["uncertainty", SCENE, *BOX, "--samples", "1000000000"],
            "1,000,000,000 starts with 7 eps",
        ),
        (
            ["uncertainty", SCENE, *BOX, "--eps", "1e-6:1e-3:100000000"],
            "2,000 starts with 100,000,000 eps",
        ),
    ],
)
def test_a_size_from_the_users_numbers_is_refused_before_any_work(
    capsys, tmp_path, no_work, argv, named
):
    tracemalloc.start()
    try:
        line = one_line_error(capsys, [*argv, "--out", str(tmp_path / "out")])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert named in line
    assert "of memory" in line and "over the limit of 1 GB" in line and "--yes" in line
    assert peak < 20e6  # nothing of the size estimated was made (measured: under 1 MB)
    assert not (tmp_path / "out").exists()


def test_the_library_refuses_as_the_command_line_does(no_work):
    with pytest.raises(OutputSizeError, match="allow_large=True to go ahead") as info:
        hysteresis.run_hysteresis(SCENE, "drive.frequency", [4.0, 5.0], starts=10**8)
    assert isinstance(info.value, SceneError)
    with pytest.raises(OutputSizeError, match="10,000,000 starts with 2 eps"):
        uncertainty.run_uncertainty(SCENE, (-0.04, 0.04), (0.02, 0.12), samples=10**7,
                                    eps=[1e-6, 1e-3])  # fmt: skip


def test_the_impacts_per_trajectory_are_bounded(capsys, tmp_path, no_work):
    line = one_line_error(
        capsys,
        ["hysteresis", SCENE, "--vary", "drive.frequency=4:5:3", "--impacts", str(10**30),
         "--out", str(tmp_path / "out")],
    )  # fmt: skip
    assert "--transient + --impacts" in line and "at most 1,000,000,000" in line


def peak_bytes(call) -> int:
    tracemalloc.start()
    try:
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_the_estimates_bound_the_memory_measured():
    """Each estimate is at least the memory its work takes (tracemalloc's peak) and not
    far above it, at a size where the per-trajectory terms dominate."""
    scene = load_scene(SCENE)
    values = [4.4, 4.5, 4.6]
    run = lambda: hysteresis.run_hysteresis(  # noqa: E731
        scene, "drive.frequency", values, starts=300, impacts=5, transient=0
    )
    run()  # compiled and warm
    peak = peak_bytes(run)
    memory, table = hysteresis.estimate_size(len(values), 300)
    assert peak <= memory <= 4 * peak, (peak, memory)
    assert table == hysteresis.CSV_ROW_BYTES * (2 * 3 * 300 + 1)
    eps = [1e-5, 1e-4, 1e-3]
    peak = peak_bytes(
        lambda: uncertainty.run_uncertainty(
            scene, (-0.04, 0.04), (0.02, 0.12), samples=100, eps=eps, impacts=5, transient=0
        )
    )
    memory = uncertainty.estimate_size(100, len(eps))
    assert peak <= memory <= 4 * peak, (peak, memory)
    # the limit itself: just under it goes ahead, just over it is refused
    starts = 1
    while hysteresis.estimate_size(2, starts * 2)[0] <= MAX_BYTES:
        starts *= 2
    hysteresis.check_size(2, starts)
    with pytest.raises(OutputSizeError):
        hysteresis.check_size(2, starts * 2)


def test_one_start_is_refused_with_the_reason(capsys, tmp_path):
    line = one_line_error(
        capsys, ["uncertainty", SCENE, *BOX, "--samples", "1", "--out", str(tmp_path / "u")]
    )
    assert "--samples must be >= 2, got 1" in line and "0 < f < 1" in line


def test_an_eps_below_the_resolution_of_q1_is_refused(capsys, tmp_path, no_work):
    line = one_line_error(
        capsys, ["uncertainty", SCENE, *BOX, "--eps", "1e-300:1e-299:2", "--out", str(tmp_path)]
    )
    spacing = np.spacing(0.04)
    assert 0.04 + 1e-300 == 0.04 and 0.04 + spacing == np.nextafter(0.04, 1.0)
    assert "eps 1e-300 m is too small to move a start by eps" in line
    assert f"floats near q1 = 0.04 m are {spacing:.3g} m apart; give eps >= " in line
    # the smallest eps accepted moves every start of the box
    assert uncertainty.smallest_eps((-0.04, 0.04)) == spacing


def test_no_uncertain_start_at_any_eps_still_draws_the_figure(tmp_path):
    """f = 0 at every eps (one attractor in the box): nothing to put on the log axis."""
    eps = np.array([1e-6, 1e-3])
    result = uncertainty.UncertaintyResult(
        scene=load_scene(SCENE), eps=eps, uncertain=np.zeros(2, dtype=int), samples=50,
        alpha=math.nan, alpha_se=math.nan, used=np.zeros(2, dtype=bool), dropped=0,
        drawn=50, labels=["period-1"], counts=[50], q1=np.zeros(50), q2=np.zeros(50),
        center=np.zeros(50, dtype=int), q1_range=(-0.04, 0.04), q2_range=(0.02, 0.12),
    )  # fmt: skip
    path = uncertainty.uncertainty_figure(result, tmp_path / "u.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("command", ["run", "hysteresis", "uncertainty", "view", "plot"])
def test_a_name_longer_than_the_file_system_allows_is_one_line(capsys, tmp_path, command):
    name = "x" * 300
    argv = {
        "run": ["run", "parabola-5.4hz", "--no-plot", "--out", name],
        "hysteresis": ["hysteresis", SCENE, "--vary", "drive.frequency=4:5:2", "--out", name],
        "uncertainty": ["uncertainty", SCENE, *BOX, "--out", name],
        "view": ["view", name],
        "plot": ["plot", name],
    }[command]
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        line = one_line_error(capsys, argv)
    finally:
        os.chdir(cwd)
    assert "a name of 300 bytes in the path" in line and "file name too long" in line
    assert f"at most {os.pathconf(tmp_path, 'PC_NAME_MAX')} per" in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_full_disk_while_the_figure_is_saved_keeps_the_table(capsys, tmp_path):
    """The figure's file is /dev/full, where every write fails with ENOSPC."""
    out = tmp_path / "h"
    out.mkdir()
    (out / "hysteresis.png").symlink_to("/dev/full")
    line = one_line_error(
        capsys,
        ["hysteresis", SCENE, "--vary", "drive.frequency=4.4:4.6:2", "--impacts", "5",
         "--transient", "0", "--out", str(out)],
    )  # fmt: skip
    table = out / "hysteresis.csv"
    assert line == (
        f"billiard: error: hysteresis: cannot write {out / 'hysteresis.png'}: "
        f"{os.strerror(28)}; kept {table}"
    )
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 2 and {r["direction"] for r in rows} == {"up", "down"}
    assert all(math.isfinite(float(r["height_mean_m"])) for r in rows)


@pytest.mark.parametrize("collisions", [2.5, 2.0, float("nan"), 0, True, "3"])
def test_a_count_of_impacts_that_is_no_whole_number_is_refused(collisions):
    from billiard.run.simulate import simulate

    with pytest.raises(SceneError) as info:
        simulate("parabola-5.4hz", collisions=collisions)
    assert str(info.value) == f"collisions must be an integer >= 1, got {collisions!r}"


def test_a_numpy_count_of_impacts_runs_that_many():
    from billiard.run.simulate import simulate

    assert len(simulate("parabola-5.4hz", collisions=np.int64(3))) == 3


@pytest.mark.parametrize("module, call", [("pandas", "to_pandas"), ("xarray", "to_xarray")])
def test_an_ensemble_without_the_data_extra_names_it(monkeypatch, module, call):
    from billiard.run.frames import MissingExtraError
    from billiard.sweep.ensemble import EnsembleResult

    result = EnsembleResult(
        scene=load_scene(SCENE), shape=(2,), columns={"period": np.array([1, 2])},
        last_height=np.zeros((2, 1)), last_tof=np.zeros((2, 1)), final={},
    )  # fmt: skip
    monkeypatch.setitem(__import__("sys").modules, module, None)  # import raises
    with pytest.raises(MissingExtraError) as info:
        getattr(result, call)()
    assert str(info.value) == (
        f'EnsembleResult.{call}() needs {module}: pip install "realworld-billiard[data]"'
    )


def test_a_fractional_power_sympy_cannot_clear_is_refused_at_once(capsys, tmp_path):
    """x**2.0000001 is s**(20000001/10000000): clearing its radical would build a
    polynomial of degree 10^7 (minutes and gigabytes in sympy)."""
    began = time.perf_counter()
    line = one_line_error(
        capsys,
        ["derive", "--name", "near2", "--curve", "x**2.0000001", "--dir", str(tmp_path),
         "--timeout", "60"],
    )  # fmt: skip
    assert time.perf_counter() - began < 30  # measured: 0.2 s
    assert "curve 'x**2.0000001' cannot hold a ball: its height f is not real" in line
    assert list(tmp_path.iterdir()) == []


def test_a_deadline_whose_exception_was_dropped_still_stops_the_derivation():
    # the timer's exception can land where Python ignores exceptions (a garbage
    # collector's callback): the block then runs to its end, and is stopped there
    import time

    from billiard.derivation import build

    with pytest.raises(build._Deadline), build._deadline(0.001):
        end = time.monotonic() + 0.05
        while time.monotonic() < end:
            try:
                time.sleep(0.005)
            except build._Deadline:
                pass  # dropped, as an exception raised in a gc callback is


def test_a_derivation_past_its_time_is_stopped_in_one_line(capsys, tmp_path):
    import signal

    before = signal.getsignal(signal.SIGALRM)
    line = one_line_error(
        capsys,
        ["derive", "--name", "p", "--curve", "x**2", "--dir", str(tmp_path), "--timeout",
         "0.001"],
    )  # fmt: skip
    assert line == (
        "billiard: error: curve 'x**2': the derivation (sympy) did not finish within "
        "0.001 s; write the expression more simply, or allow longer with `billiard derive "
        "--timeout SECONDS`"
    )
    assert signal.getsignal(signal.SIGALRM) == before
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert main(["derive", "--name", "p", "--curve", "x**2", "--dir", str(tmp_path)]) == 0
    assert (Path(tmp_path) / "p.py").exists()
