"""Scene values outside their physically sensible range, scene names that are not one
safe folder name, and scene files that set nothing."""

from __future__ import annotations

import math

import pytest

from billiard.scene.checks import LIMITS
from billiard.scene.scene import (
    SceneError,
    load_scene,
    scene_from_dict,
    scene_from_toml,
    with_values,
)
from billiard.scene.spec import SECTIONS

# key -> (a value out of range, fragment of the message with the unit)
OUT_OF_RANGE = {
    "drive.frequency": (1e9, "'drive.frequency' = 1000000000.0 Hz is out of range [0, 1000] Hz"),
    "drive.amplitude": (25.0, "'drive.amplitude' = 25.0 m is out of range [0, 1] m"),
    "drive.phase": (90.0, "'drive.phase' = 90.0 rad is out of range [-6.28319, 6.28319] rad"),
    "initial.v1": (1e6, "'initial.v1' = 1000000.0 m/s is out of range [-100, 100] m/s"),
    "initial.v2": (-101.0, "'initial.v2' = -101.0 m/s is out of range [-100, 100] m/s"),
    "initial.omega": (1e6, "'initial.omega' = 1000000.0 rad/s is out of range"),
    "initial.q1": (11.0, "'initial.q1' = 11.0 m is out of range [-10, 10] m"),
    "initial.q2": (-20.0, "'initial.q2' = -20.0 m is out of range [-10, 10] m"),
    "initial.t": (1e20, "'initial.t' = 1e+20 s is out of range [-1e+06, 1e+06] s"),
    "ball.radius": (0.2, "'ball.radius' = 0.2 m is out of range (0, 0.1] m"),
    "ball.mass": (1000.0, "'ball.mass' = 1000.0 kg is out of range (0, 100] kg"),
    "contact.mu_static": (50.0, "'contact.mu_static' = 50.0 is out of range [0, 5]"),
    "contact.elastic_below": (5.0, "'contact.elastic_below' = 5.0 m/s is out of range [0, 1]"),
    "air.c_lin": (2.0, "'air.c_lin' = 2.0 N s/m is out of range [0, 1] N s/m"),
    "air.c_quad": (2.0, "'air.c_quad' = 2.0 N s^2/m^2 is out of range [0, 1] N s^2/m^2"),
    "air.magnus": (2.0, "'air.magnus' = 2.0 kg is out of range [0, 1] kg"),
    "boundary.ceiling": (50.0, "'boundary.ceiling' = 50.0 m is out of range (0, 10] m"),
    "boundary.escape_height": (1e4, "'boundary.escape_height' = 10000.0 m is out of range"),
    "run.gravity": (1000.0, "'run.gravity' = 1000.0 m/s^2 is out of range (0, 100] m/s^2"),
    "run.rtol": (1e-16, "'run.rtol' = 1e-16 is out of range [1e-14, 0.001]"),
    "run.step": (1.0, "'run.step' = 1.0 s is out of range [1e-07, 0.1] s"),
    "run.duration": (1e12, "'run.duration' = 1000000000000.0 s is out of range (0, 1e+09] s"),
}


@pytest.mark.parametrize("key", sorted(OUT_OF_RANGE))
def test_value_out_of_range_is_refused_with_its_unit(key):
    value, fragment = OUT_OF_RANGE[key]
    section, name = key.split(".")
    with pytest.raises(SceneError) as info:
        scene_from_dict({section: {name: value}})
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


def test_every_number_key_has_a_range():
    """Every float key of every section has limits (or is a choice or a table)."""
    import dataclasses

    # text, a table of free curve parameters, and the impact count (its own check)
    unbounded = {"boundary.curve", "boundary.parameters", "drive.direction", "air.drag"}
    unbounded |= {"run.method", "run.collisions", "contact.model", "contact.law"}
    for section, cls in SECTIONS.items():
        for field in dataclasses.fields(cls):
            key = f"{section}.{field.name}"
            assert key in LIMITS or key in unbounded, key


@pytest.mark.parametrize("key", sorted(LIMITS))
def test_the_defaults_and_the_builtin_scenes_are_inside_the_limits(key):
    section, name = key.split(".")
    for scene_name in ("parabola-5.4hz", "wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz"):
        value = getattr(getattr(load_scene(scene_name), section), name)
        limit = LIMITS[key]
        if value is not None:
            assert limit.low <= value <= limit.high


def test_bounds_are_inclusive_where_they_say_so():
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {"drive.frequency": 1000.0, "drive.phase": -math.tau, "initial.v1": 100.0},
    )
    assert scene.drive.frequency == 1000.0
    with pytest.raises(SceneError, match=r"\(0, 100\] m/s\^2"):
        with_values(scene, {"run.gravity": 0.0})


def test_too_many_collisions():
    with pytest.raises(SceneError, match=r"'run.collisions' = 10000000000 is out of range"):
        scene_from_dict({"run": {"collisions": 10**10}})


# ---------------------------------------------------------------------------------
# names: one safe folder name


@pytest.mark.parametrize(
    ("name", "problem"),
    [
        ("../../x", "contains a path separator"),
        ("/tmp/abs", "contains a path separator"),
        ("a\\b", "contains a path separator"),
        ("", "is empty"),
        (".", "is a reference to a folder"),
        ("..", "is a reference to a folder"),
        (" x", "starts or ends with a blank"),
        ("x\ty", "contains a control character"),
        ("x" * 101, "is longer than 100 characters"),
    ],
)
def test_unsafe_names_are_refused(name, problem):
    with pytest.raises(SceneError) as info:
        scene_from_dict({"name": name})
    message = str(info.value)
    assert message.startswith("scene key 'name' = ")
    assert problem in message and "runs/NAME" in message
    assert "\n" not in message


@pytest.mark.parametrize("name", ["my-scene", "bowl_5mm", "parabola-5.4hz", "été 2", "a+b"])
def test_ordinary_names_are_accepted(name):
    assert scene_from_toml(f'name = "{name}"\n').name == name


# ---------------------------------------------------------------------------------
# a scene file that sets nothing


@pytest.mark.parametrize(
    "text",
    ["", 'name = "empty"\ndescription = "nothing"\n', "[drive]\n[boundary.parameters]\n"],
)
def test_a_file_that_sets_no_keys_gets_a_note(tmp_path, text):
    path = tmp_path / "empty.toml"
    path.write_text(text)
    notes: list[str] = []
    scene = load_scene(path, notify=notes.append)
    assert scene == scene_from_dict({"name": scene.name, "description": scene.description})
    assert len(notes) == 1
    assert notes[0].startswith(f"scene file '{path}' sets no keys; this is the all-defaults scene")
    assert "drive.amplitude = 0 m" in notes[0]


def test_a_file_or_override_that_sets_a_key_gets_no_note(tmp_path):
    path = tmp_path / "empty.toml"
    path.write_text("")
    notes: list[str] = []
    load_scene(path, overrides=["drive.amplitude=0.01", "drive.frequency=5"], notify=notes.append)
    path.write_text("[run]\ncollisions = 10\n")
    load_scene(path, notify=notes.append)
    load_scene("parabola-5.4hz", notify=notes.append)
    assert notes == []
