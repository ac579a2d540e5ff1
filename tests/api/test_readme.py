"""The README's Python examples run as written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_has_a_python_example():
    assert python_blocks()


def shown_prints(block: str) -> list[str]:
    """The lines a block shows as printed: ``print(...)  # <...>`` comments (``...``
    stands for text that varies)."""
    return re.findall(r"^print\(.*\)  # (<.*>)$", block, re.M)


@pytest.mark.parametrize("index", range(len(python_blocks())))
def test_readme_python_example_runs(index, capsys):
    """Each block runs, and prints what its comments show it printing."""
    block = python_blocks()[index]
    namespace: dict = {}
    exec(compile(block, f"README.md block {index}", "exec"), namespace)
    out = capsys.readouterr().out
    assert "impacts" in out
    lines = out.splitlines()
    for shown in shown_prints(block):
        pattern = ".*".join(re.escape(part) for part in shown.split("..."))
        assert any(re.fullmatch(pattern, line) for line in lines), (shown, lines)


def test_readme_shows_the_notebook_result():
    """The notebook example's comment is checked above (a Result's repr)."""
    first = next(b for b in python_blocks() if "to_pandas" in b)
    assert shown_prints(first) and shown_prints(first)[0].startswith("<Result ")


def test_readme_scene_example_shows_a_flying_ball(tmp_path, monkeypatch):
    """The "Scene files" example is a scene worth running: the ball is thrown, not left
    lying at the bottom of the bowl (resting relaunches are a small share)."""
    from billiard.run.simulate import simulate
    from billiard.scene.scene import load_scene

    text = re.search(r"## Scene files\n\n```toml\n(.*?)```", README.read_text(), re.S).group(1)
    path = tmp_path / "my-scene.toml"
    path.write_text(text)
    notes: list[str] = []
    scene = load_scene(path, notify=notes.append)
    assert notes == [] and scene.name == "my-scene"
    result = simulate(scene, collisions=2000)
    assert result.stop_reason is None
    assert result.counts["resting"] < 0.5 * len(result)
    assert result.columns["q2"].max() > 0.03  # m: flights of centimetres, not nanometres
    assert "lies on the wall" not in result.summary()


def test_readme_csv_table_lists_every_column():
    from billiard.runfile.record import COLUMNS

    table = README.read_text().split("CSV columns:", 1)[1].split("## ", 1)[0]
    named = set(re.findall(r"\| `([^`]+)`(?:, `([^`]+)`)?(?:, `([^`]+)`)? \|", table))
    listed = {name for row in named for name in row if name}
    assert set(COLUMNS) <= listed, set(COLUMNS) - listed


def _timeless(line: str) -> str:
    """A summary less its wall-clock time and rate, which vary from run to run."""
    return re.sub(r" in \S+ s \([\d,]+ impacts/s\)", "", line)


def _billiard(*args: str, cwd: Path) -> str:
    """The stdout of the ``billiard`` command (the CLI's entry, in a fresh process)."""
    done = subprocess.run(
        [sys.executable, "-m", "billiard.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_readme_scene_example_prints_the_summaries_shown(tmp_path):
    """The two summaries the README shows for its scene example are those the commands it
    names print (less the wall-clock time and rate): `billiard run my-scene.toml`, 25,000
    impacts, and the gentler drive whose ball only rolls."""
    text = README.read_text()
    scene = re.search(r"## Scene files\n\n```toml\n(.*?)```", text, re.S).group(1)
    (tmp_path / "my-scene.toml").write_text(scene)
    command = re.search(r"Run it with `billiard (run my-scene\.toml)`", text).group(1).split()
    shown = re.search(r"the run prints.*?```\n(.*?)\n```", text, re.S).group(1)
    printed = _billiard(*command, "--no-plot", "--out", "thrown", cwd=tmp_path)
    summary = printed.splitlines()[0]
    assert _timeless(summary) != summary  # the time was there to leave out
    assert _timeless(shown) == _timeless(summary)

    gentler = re.search(r"With a gentler drive[^`]*\(`(--set [^`]+)`", text).group(1).split()
    shown = re.search(r"and says why:\n\n```\n(.*?)\n```", text, re.S).group(1)
    printed = _billiard(*command, *gentler, "--no-plot", "--out", "rolls", cwd=tmp_path)
    assert _timeless(shown) == _timeless(printed.splitlines()[0])


def test_readme_plane_example_runs_and_needs_its_start(tmp_path):
    """The plane of "Scene files" runs from the start it gives; without one, the run is
    refused with the message the README quotes."""
    from billiard.errors import GeometryError
    from billiard.run.simulate import simulate
    from billiard.scene.scene import load_scene

    blocks = re.findall(r"```toml\n(.*?)```", README.read_text(), re.S)
    [plane] = [b for b in blocks if 'name = "ramp"' in b]
    path = tmp_path / "ramp.toml"
    path.write_text(plane)
    result = simulate(load_scene(path), collisions=20)
    assert len(result) == 20 and result.stop_reason is None
    path.write_text(plane.split("[initial]")[0])
    with pytest.raises(GeometryError, match="no bottom to rest on.*give initial.q1 and initial.q2"):
        simulate(load_scene(path), collisions=20)
