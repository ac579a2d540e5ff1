"""The command line checks every argument before any work, keeps runs inside their
folders, refuses to replace a run silently, removes plots that no longer match the data,
reports progress in logs, and says what is true after Ctrl-C."""

from __future__ import annotations

import importlib
import io
import math
import os
import sys
from pathlib import Path

import pytest

import billiard.reproduce.paper as reproduce_module
from billiard.cli import main
from billiard.cli.run import ProgressBar
from billiard.plot.run import FIGURE_NAMES
from billiard.run.simulate import CSV_NAME


def one_error_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: error: "), captured.err
    assert "Traceback" not in captured.err
    return lines[0]


@pytest.fixture
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ---------------------------------------------------------------------------------
# run


@pytest.mark.parametrize(
    "value",
    # each refusal starts a process: one in the default suite, the rest with the slow tests
    ["nan", *(pytest.param(v, marks=pytest.mark.slow) for v in ("0", "-1", "inf", "abc", "1/0"))],
)
def test_run_frame_interval_is_checked_before_the_run(in_tmp, capsys, value):
    out = in_tmp / "out"
    code = main(["run", "parabola-5.4hz", "--collisions", "5", "--out", str(out)])
    assert code == 0 and (out / CSV_NAME).exists()
    other = in_tmp / "other"
    args = ["run", "parabola-5.4hz", "--collisions", "5", "--out", str(other)]
    capsys.readouterr()
    assert main([*args, "--frame-interval", value]) == 2
    assert f"frame interval {value!r} must be a positive number of seconds" in one_error_line(
        capsys
    )
    assert not other.exists()


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/absolute-billiard-run", "", ".."])
def test_run_refuses_a_scene_name_that_is_not_one_folder(in_tmp, capsys, name):
    scene = in_tmp / "s.toml"
    scene.write_text(f'name = "{name}"\n[run]\ncollisions = 5\n')
    (in_tmp / "deep" / "down").mkdir(parents=True)
    code = main(["run", str(scene), "--no-plot"])
    assert code == 2
    assert "scene key 'name'" in one_error_line(capsys)
    assert not (in_tmp / "runs").exists()
    assert not Path("/tmp/absolute-billiard-run").exists()
    assert not (in_tmp.parent / "escaped").exists()


@pytest.mark.parametrize(
    "sets, fragment",
    [
        (
            ["contact.law=walten"],
            "scene key 'contact.law' = 'walten' must be one of 'kane-levinson', 'walton', "
            "'power-law', 'viscoelastic', 'energy-dependent', 'angle-dependent', "
            "'point-particle'; did you mean 'walton'?",
        ),
        (
            ["contact.law=power-law", "contact.e_ref=0.5"],
            "scene key 'contact.law' = 'power-law' needs contact.e_ref, contact.v_ref (m/s), "
            "contact.exponent: missing contact.v_ref, contact.exponent",
        ),
        (
            ["contact.law=walton", "contact.beta0=1.5"],
            "scene key 'contact.beta0' = 1.5 is out of range [-1, 1]",
        ),
    ],
)
def test_run_refuses_an_impact_law_misspelled_or_missing_a_parameter(
    in_tmp, capsys, sets, fragment
):
    args = ["run", "parabola-5.4hz", "--collisions", "5", "--no-plot"]
    code = main([*args, *(a for key in sets for a in ("--set", key))])
    assert code == 2
    assert fragment in one_error_line(capsys)
    assert not (in_tmp / "runs").exists()


#: a value of every law's parameters (docs/impact-laws.md)
LAW_SETS = {
    "kane-levinson": [],
    "walton": ["contact.beta0=0.35"],
    "power-law": ["contact.e_ref=0.4", "contact.v_ref=0.5", "contact.exponent=0.2"],
    "viscoelastic": ["contact.viscous=0.5"],
    "energy-dependent": ["contact.energy_scale=2e-5"],
    "angle-dependent": ["contact.angle_slope=0.05"],
    "point-particle": [],
}


@pytest.mark.parametrize("model", ["impacts", "phases"])
@pytest.mark.parametrize("law", LAW_SETS)
def test_run_takes_every_impact_law_under_every_contact_model(in_tmp, capsys, law, model):
    sets = [f"contact.law={law}", f"contact.model={model}", *LAW_SETS[law]]
    out = in_tmp / "out"
    args = ["run", "parabola-5.4hz", "--collisions", "40", "--no-plot", "--out", str(out)]
    assert main([*args, *(a for key in sets for a in ("--set", key))]) == 0
    rows = (out / CSV_NAME).read_text().splitlines()
    assert len(rows) == 41
    assert f'law = "{law}"' in (out / "scene.toml").read_text()


def test_run_refuses_to_replace_a_run_unless_overwrite(in_tmp, capsys):
    args = ["run", "parabola-5.4hz", "--no-plot"]
    assert main([*args, "--collisions", "30"]) == 0
    out = Path("runs") / "parabola-5.4hz"
    before = (out / CSV_NAME).read_bytes()
    capsys.readouterr()
    assert main([*args, "--collisions", "10"]) == 2
    line = one_error_line(capsys)
    assert f"run: {out} already holds a run" in line
    assert "--overwrite" in line and f"billiard run --resume {out}" in line
    assert (out / CSV_NAME).read_bytes() == before
    assert main([*args, "--collisions", "10", "--overwrite"]) == 0
    assert len((out / CSV_NAME).read_text().splitlines()) == 11


def test_overwrite_goes_with_a_scene_not_with_resume(in_tmp, capsys):
    assert main(["run", "--resume", "somewhere", "--overwrite"]) == 2
    assert "give no SCENE" in one_error_line(capsys)


def _fake_plots(folder: Path) -> None:
    for name in FIGURE_NAMES:
        (folder / name).write_bytes(b"old figure")


def test_resume_without_plotting_removes_the_stale_plots(in_tmp, capsys):
    out = in_tmp / "r"
    assert main(["run", "parabola-5.4hz", "--collisions", "20", "--out", str(out)]) == 0
    _fake_plots(out)
    # already complete: the data do not change, the plots stay
    assert main(["run", "--resume", str(out), "--no-plot"]) == 0
    assert all((out / name).read_bytes() == b"old figure" for name in FIGURE_NAMES)
    capsys.readouterr()
    assert main(["run", "--resume", str(out), "--collisions", "30", "--no-plot"]) == 0
    printed = capsys.readouterr().out
    assert not any((out / name).exists() for name in FIGURE_NAMES)
    assert "removed the plots of the earlier data" in printed
    assert f"billiard plot {out}" in printed


def test_resume_with_plotting_redraws(in_tmp, capsys):
    out = in_tmp / "r"
    assert main(["run", "parabola-5.4hz", "--collisions", "20", "--out", str(out)]) == 0
    _fake_plots(out)
    args = ["run", "--resume", str(out), "--collisions", "30", "--no-gif"]
    with pytest.raises(SystemExit):  # run has no --no-gif: checked before any work
        main(args)
    assert main(args[:-1]) == 0
    assert all((out / name).read_bytes() != b"old figure" for name in FIGURE_NAMES)


def test_overwrite_without_plotting_removes_the_stale_plots(in_tmp, capsys):
    out = in_tmp / "r"
    assert main(["run", "parabola-5.4hz", "--collisions", "20", "--out", str(out)]) == 0
    _fake_plots(out)
    args = ["run", "wedge-6.6hz", "--collisions", "10", "--out", str(out), "--no-plot"]
    assert main([*args, "--overwrite"]) == 0
    assert not any((out / name).exists() for name in FIGURE_NAMES)


def test_a_scene_file_that_sets_nothing_gets_a_note(in_tmp, capsys):
    scene = in_tmp / "empty.toml"
    scene.write_text('name = "empty"\n')
    assert main(["run", str(scene), "--collisions", "5", "--no-plot"]) == 0
    out, err = capsys.readouterr()
    assert (
        f"billiard: note: scene file '{scene}' sets no keys; this is the all-defaults scene" in err
    )
    # the all-defaults scene has sustained contact: the ball lies at the bottom for ever
    assert "0 impacts" in out and "at rest on the boundary" in out


def test_the_summary_names_relaunches_of_a_resting_ball(in_tmp, capsys):
    scene = in_tmp / "resting.toml"
    scene.write_text('name = "resting"\n[contact]\nmodel = "impacts"\n[run]\ncollisions = 30\n')
    assert main(["run", str(scene), "--no-plot"]) == 0
    out = capsys.readouterr().out
    assert "30 impacts (0 stick, 0 slip, 30 elastic, of which 30 relaunches of a resting ball)" in (
        out
    )
    assert "lies on the wall nearly all the time" in out and "drive.amplitude, m" in out


# ---------------------------------------------------------------------------------
# progress in logs


def test_progress_lines_when_stderr_is_not_a_terminal():
    stream = io.StringIO()
    clock = iter([0.5, 1.25])
    bar = ProgressBar(stream, interval=0.0, clock=lambda: next(clock))
    assert not bar.enabled
    bar(100, 1000)
    bar(200, 1000)
    bar(1000, 1000)  # the summary follows: no line for the end
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0] == "billiard: 100/1,000 impacts, t = 0.5 s simulated"
    assert lines[1].startswith("billiard: 200/1,000 impacts, t = 1.25 s simulated, ")
    # a rate needs two counts: none on the first line (which may follow a compile)
    assert "impacts/s" not in lines[0] and "left" not in lines[0]
    assert "impacts/s" in lines[1] and "left" in lines[1]


def test_progress_lines_are_a_few_seconds_apart():
    stream = io.StringIO()
    bar = ProgressBar(stream)
    for done in range(0, 1000, 10):
        bar(done, 1000)
    assert stream.getvalue() == ""  # well within the first interval


def test_a_run_in_a_batch_job_logs_its_progress(in_tmp, capsys, monkeypatch):
    monkeypatch.setattr(ProgressBar.__init__, "__defaults__", (None, 30, 0.0, None))
    out = in_tmp / "r"
    assert main(["run", "wedge-6.6hz", "--collisions", "400", "--out", str(out), "--no-plot"]) == 0
    err = capsys.readouterr().err
    assert "/400 impacts, t = " in err and " s simulated, " in err


# ---------------------------------------------------------------------------------
# lyapunov


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--impacts", "0"], "impacts must be a whole number >= 1, got 0"),
        (["--impacts", "-5"], "impacts must be a whole number >= 1, got -5"),
        (["--transient", "-3"], "transient must be a whole number >= 0, got -3"),
        (["--d0", "0"], "d0 = 0.0 m must be small against the scene's lengths"),
        (["--d0", "1"], "between 1e-13 m and 0.000209 m (0.001 of the container's width 0.2094 m)"),
        (["--d0", "nan"], "d0 must be a finite number of metres"),
    ],
)
def test_lyapunov_arguments_are_checked_first(capsys, args, fragment, monkeypatch):
    import billiard.analysis.lyapunov as analysis

    def no_work(*a, **k):  # pragma: no cover - reached only if a check is missing
        raise AssertionError("the computation started")

    monkeypatch.setattr(analysis, "lyapunov_exponent", no_work)
    assert main(["lyapunov", "wedge-6.6hz", *args]) == 2
    assert fragment in one_error_line(capsys)


def test_lyapunov_of_a_resting_ball_is_undefined(in_tmp, capsys):
    scene = in_tmp / "resting.toml"
    scene.write_text('name = "resting"\n[contact]\nmodel = "impacts"\n[run]\ncollisions = 10\n')
    assert main(["lyapunov", str(scene), "--impacts", "100"]) == 3
    out = capsys.readouterr().out
    assert out.startswith("largest Lyapunov exponent undefined: the ball rests on the wall")
    assert "+" not in out.split(":")[0]


def test_lyapunov_of_a_flying_ball_is_a_number(capsys):
    assert main(["lyapunov", "wedge-6.6hz", "--impacts", "100", "--transient", "50"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("largest Lyapunov exponent ") and "per impact" in out
    value = float(out.split()[3])
    assert math.isfinite(value)


# ---------------------------------------------------------------------------------
# reproduce


@pytest.fixture
def no_reproduction(monkeypatch):
    calls = []

    def record(docs, runs, collisions, lyapunov):
        calls.append((docs, runs, collisions, lyapunov))
        return docs / "paper-reproduction.md"

    monkeypatch.setattr(reproduce_module, "reproduce", record)
    return calls


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--collisions", "0"], "--collisions must be >= 1, got 0"),
        (["--collisions", "-3"], "--collisions must be >= 1, got -3"),
        (["--lyapunov", "-1"], "--lyapunov must be >= 0"),
    ],
)
def test_reproduce_arguments_are_checked_first(in_tmp, capsys, no_reproduction, args, fragment):
    assert main(["reproduce", *args]) == 2
    assert fragment in one_error_line(capsys)
    assert no_reproduction == []


def test_only_the_full_reproduction_writes_the_docs(in_tmp, capsys, no_reproduction):
    assert main(["reproduce"]) == 0
    assert no_reproduction[-1] == (Path("docs"), Path("runs/paper"), 25000, 2000)
    assert main(["reproduce", "--collisions", "2000"]) == 0
    assert no_reproduction[-1][0] == Path("runs/paper")
    err = capsys.readouterr().err
    assert "not the full reproduction" in err and "runs/paper/paper-reproduction.md" in err
    assert main(["reproduce", "--collisions", "2000", "--docs", "mine"]) == 0
    assert no_reproduction[-1][0] == Path("mine")


def test_reproduce_refuses_a_docs_folder_it_cannot_write(in_tmp, capsys, no_reproduction):
    (in_tmp / "file").write_text("")
    assert main(["reproduce", "--docs", str(in_tmp / "file" / "docs")]) == 2
    assert "is not a folder" in one_error_line(capsys)
    assert no_reproduction == []


def test_reproduce_refuses_a_read_only_docs_folder(in_tmp, capsys, no_reproduction, monkeypatch):
    docs = in_tmp / "docs"
    docs.mkdir()
    real_access = os.access
    # a read-only folder (root may write anywhere, so the refusal is simulated)
    monkeypatch.setattr(
        reproduce_module.os,
        "access",
        lambda path, mode: False if Path(path) == docs else real_access(path, mode),
    )
    assert main(["reproduce", "--docs", str(docs)]) == 2
    assert f"--docs {docs}: cannot write in {docs} (read-only)" in one_error_line(capsys)
    assert no_reproduction == []


@pytest.mark.skipif(
    sys.platform == "win32" or os.geteuid() == 0, reason="root writes into read-only folders"
)
def test_reproduce_refuses_a_chmod_read_only_docs_folder(in_tmp, capsys, no_reproduction):
    docs = in_tmp / "docs"
    docs.mkdir()
    docs.chmod(0o555)
    try:
        assert main(["reproduce", "--docs", str(docs)]) == 2
    finally:
        docs.chmod(0o755)
    assert "(read-only)" in one_error_line(capsys)


# ---------------------------------------------------------------------------------
# Ctrl-C


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.parametrize(
    ("argv", "module", "name", "message"),
    [
        (
            [
                "calibrate",
                "parabola-5.4hz",
                "--parameter",
                "drive.amplitude",
                "--target-height",
                "0.075",
            ],
            "billiard.analysis.calibrate",
            "calibrate",
            "billiard: interrupted; nothing was written",
        ),
        (
            ["lyapunov", "wedge-6.6hz"],
            "billiard.analysis.lyapunov",
            "lyapunov_exponent",
            "billiard: interrupted; nothing was written",
        ),
        (
            ["plot", "RUN"],
            "billiard.plot",
            "plot_run",
            "billiard: interrupted; the figures in RUN may be missing or partly drawn",
        ),
        (
            ["run", "wedge-6.6hz", "--collisions", "5"],
            "billiard.run.simulate",
            "simulate",
            "billiard: interrupted; no row was lost: a run that started keeps whole rows",
        ),
    ],
)
def test_ctrl_c_says_what_is_true(in_tmp, capsys, monkeypatch, argv, module, name, message):
    monkeypatch.setattr(importlib.import_module(module), name, _interrupt)
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert err.strip() == message or err.startswith(message), err
    assert "rows written so far are kept" not in err
    assert not (in_tmp / "runs").exists()


def test_lyapunov_of_a_ball_at_rest_in_a_contact_phase_is_undefined(in_tmp, capsys):
    scene = in_tmp / "resting.toml"
    scene.write_text('name = "resting"\n[contact]\nmodel = "phases"\n')
    assert main(["lyapunov", str(scene), "--impacts", "100"]) == 3
    out = capsys.readouterr().out
    assert out.startswith("largest Lyapunov exponent undefined: the ball rests on the wall")
