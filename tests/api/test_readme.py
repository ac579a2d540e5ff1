"""The README's Python examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_has_a_python_example():
    assert python_blocks()


@pytest.mark.parametrize("index", range(len(python_blocks())))
def test_readme_python_example_runs(index, capsys):
    namespace: dict = {}
    exec(compile(python_blocks()[index], f"README.md block {index}", "exec"), namespace)
    out = capsys.readouterr().out
    assert "impacts" in out


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


@pytest.mark.slow
def test_readme_scene_example_prints_the_summary_shown(tmp_path):
    """The summary the README shows for its scene example is the one a run prints (less
    the wall-clock time and rate, which vary): a full run of the example, 25,000 impacts."""
    from billiard.run.simulate import simulate
    from billiard.scene.scene import load_scene

    text = README.read_text()
    scene = re.search(r"## Scene files\n\n```toml\n(.*?)```", text, re.S).group(1)
    path = tmp_path / "my-scene.toml"
    path.write_text(scene)
    shown = re.search(r"the run prints[^`]*```\n(.*?)\n```", text, re.S).group(1)

    def timeless(line: str) -> str:
        return re.sub(r" in \S+ s \([\d,]+ impacts/s\)", "", line)

    summary = simulate(load_scene(path)).summary()
    assert timeless(shown) == timeless(summary)
    assert timeless(summary) != summary  # the time was there to leave out


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
