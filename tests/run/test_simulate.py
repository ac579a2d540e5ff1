"""``simulate()`` takes a built-in scene's name or a scene file's path as well as a
Scene: the same run as ``simulate(load_scene(...))``; anything else is a one-line error."""

from __future__ import annotations

import numpy as np
import pytest

from billiard import SceneError, load_scene, scene_to_toml, simulate, with_values


def _same_run(a, b) -> None:
    assert a.scene == b.scene and a.status is b.status and a.counts == b.counts
    assert a.final_time == b.final_time and len(a) == len(b) > 0
    for column, values in a.columns.items():
        assert np.array_equal(b.columns[column], values), column


def test_by_name_equals_by_scene():
    _same_run(
        simulate("wedge-6.6hz", collisions=200),
        simulate(load_scene("wedge-6.6hz"), collisions=200),
    )


@pytest.mark.parametrize("as_text", [False, True], ids=["Path", "str"])
def test_by_path_equals_by_scene(tmp_path, as_text):
    scene = with_values(load_scene("parabola-5.4hz"), {"name": "my-bowl", "drive.frequency": 5.0})
    path = tmp_path / "my-bowl.toml"
    path.write_text(scene_to_toml(scene))
    by_path = simulate(str(path) if as_text else path, collisions=200)
    assert by_path.scene.name == "my-bowl"
    _same_run(by_path, simulate(load_scene(path), collisions=200))


def test_an_unknown_name_is_a_one_line_error():
    with pytest.raises(SceneError) as info:
        simulate("parabola-5.4")
    message = str(info.value)
    assert "'parabola-5.4' is neither a built-in scene" in message and "parabola-5.4hz" in message
    assert "\n" not in message


def test_a_missing_file_is_a_one_line_error(tmp_path):
    with pytest.raises(SceneError, match=r"scene file '.*nowhere\.toml' does not exist"):
        simulate(tmp_path / "nowhere.toml")


def test_something_else_is_a_one_line_error():
    with pytest.raises(SceneError, match="simulate\\(\\) takes a Scene, .* got dict"):
        simulate({"drive": {"frequency": 5.0}})
