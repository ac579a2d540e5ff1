"""``--format``, ``--dpi`` and ``--no-title`` of ``billiard plot`` and ``billiard run``:
the files they write, and bad values refused in one line (exit status 2) before any work."""

from __future__ import annotations

from pathlib import Path

import pytest

from billiard.cli import main
from billiard.cli.run import _remove_plots
from billiard.runfile.figure_files import DEFAULT_DPI, figure_names
from tests.plot_support import bouncing_ball, make_run, scene_toml

HEADS = {".png": b"\x89PNG\r\n\x1a\n", ".pdf": b"%PDF-"}


def assert_format(path: Path) -> None:
    head = path.read_bytes()[:400]
    if path.suffix == ".svg":
        assert head.startswith(b"<?xml") and b"<svg" in head
    else:
        assert head.startswith(HEADS[path.suffix])


@pytest.fixture(scope="module")
def bounce_run(tmp_path_factory) -> Path:
    columns = bouncing_ball(40, amplitude=1e-3, frequency=25.0, e=0.5)
    return make_run(tmp_path_factory.mktemp("runs") / "bounce", columns, scene_toml())


def test_plot_writes_the_format_asked_for(bounce_run, tmp_path, capsys):
    titled, bare = tmp_path / "titled", tmp_path / "bare"
    args = ["plot", str(bounce_run), "--no-gif", "--format", "SVG", "--dpi", "72"]
    assert main([*args, "--out", str(titled)]) == 0
    assert main([*args, "--out", str(bare), "--no-title"]) == 0
    printed = capsys.readouterr().out.splitlines()
    names = figure_names("svg")[:4]
    assert printed == [f"wrote {out / name}" for out in (titled, bare) for name in names]
    for name in names:
        assert_format(titled / name)
        assert_format(bare / name)
        # matplotlib writes each text of an SVG as a comment beside its glyphs
        assert b"<!-- bounce, 40 impacts" in (titled / name).read_bytes()
        assert b"bounce, 40 impacts" not in (bare / name).read_bytes()
    assert not list(titled.glob("*.png")) and not list(bare.glob("*.png"))


@pytest.mark.parametrize("command", ["plot", "run"])
def test_help_names_the_formats_and_the_dpi(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "png, svg, pdf" in text and "(default: png)" in text
    assert f"at the default {DEFAULT_DPI}" in text and "Ignored by SVG and PDF" in text
    assert "--no-title" in text


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (["--format", "gif"], "--format must be one of png, svg, pdf, got 'gif'"),
        (["--format", ""], "--format must be one of png, svg, pdf, got ''"),
        (["--dpi", "0"], "--dpi must be between 20 and 1200 pixels per inch, got '0'"),
        (["--dpi", "300dpi"], "--dpi must be a whole number of pixels per inch, got '300dpi'"),
    ],
)
def test_plot_refuses_bad_values_in_one_line(bounce_run, tmp_path, capsys, extra, problem):
    out = tmp_path / "figures"
    assert main(["plot", str(bounce_run), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err == f"billiard: error: plot: {problem}\n"
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (["--format", "jpg"], "run: --format must be one of png, svg, pdf, got 'jpg'"),
        (["--dpi", "2000"], "run: --dpi must be between 20 and 1200 pixels per inch"),
    ],
)
def test_run_refuses_bad_values_before_running(tmp_path, capsys, extra, problem):
    out = tmp_path / "run"
    assert main(["run", "wedge-6.6hz", "--collisions", "5", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"billiard: error: {problem}") and err.count("\n") == 1
    assert not out.exists()  # nothing simulated


def test_run_draws_its_plots_in_the_format_asked_for(tmp_path, capsys):
    out = tmp_path / "run"
    args = ["run", "wedge-6.6hz", "--collisions", "30", "--out", str(out)]
    assert main([*args, "--format", "pdf", "--dpi", "50", "--no-title"]) == 0
    assert "plots: return_map.pdf, time_map.pdf, phase.pdf, trajectory.pdf, animation.gif" in (
        capsys.readouterr().out
    )
    for name in figure_names("pdf"):
        assert (out / name).is_file()
    for name in figure_names("pdf")[:4]:
        assert_format(out / name)


def test_outdated_figures_of_every_format_are_removed(tmp_path):
    names = ["return_map.svg", "phase.pdf", "trajectory.png", "animation.gif", "time_map.pdf"]
    for name in [*names, "notes.txt", "return_map.jpg"]:
        (tmp_path / name).write_text("x")
    assert sorted(_remove_plots(tmp_path)) == sorted(names)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "return_map.jpg"]
