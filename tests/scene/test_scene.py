"""Tests of scene files: loading, validation, built-in scenes and TOML round trips."""

from __future__ import annotations

import dataclasses
import math
import struct
from importlib import resources
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from billiard.scene.keys import SECTION_KEYS
from billiard.scene.scene import (
    Scene,
    SceneError,
    builtin_scene_names,
    builtin_scenes,
    curve_kind,
    fowles_coefficients,
    key_number,
    key_value,
    load_scene,
    replace,
    scene_from_dict,
    scene_from_toml,
    scene_to_dict,
    scene_to_toml,
    with_values,
)
from billiard.scene.spec import (
    AirSpec,
    BallSpec,
    BoundarySpec,
    ContactSpec,
    DriveSpec,
    InitialSpec,
    RunSpec,
)

BUILTIN_FREQUENCIES = {
    "parabola-5.4hz": ("parabola", 5.4),
    "wedge-6.6hz": ("wedge", 6.6),
    "hyperbola-5.8hz": ("hyperbola", 5.8),
    "hyperbola-4.5hz": ("hyperbola", 4.5),
}


def _float_bits(scene: Scene) -> list[tuple[str, str]]:
    """Every float of a scene as (dotted key, hex of its IEEE bits)."""
    bits = []
    for section, table in scene_to_dict(scene).items():
        if not isinstance(table, dict):
            continue
        for key, value in table.items():
            values = value.items() if isinstance(value, dict) else [(key, value)]
            for name, number in values:
                if isinstance(number, float):
                    bits.append((f"{section}.{name}", struct.pack("<d", number).hex()))
    return bits


def _custom_scene() -> Scene:
    return scene_from_dict(
        {
            "name": 'custom "quoted" name \u00e9',
            "description": "tab\there, back\\slash, unicode \u00e9, newline\nend",
            "boundary": {
                "curve": "a*x**2 + c",
                "parameters": {"a": 26.000000000000004, "c": 0.1 + 0.2},
                "escape_height": 2.5,
            },
            "drive": {
                "amplitude": 1e-3 / 3,
                "frequency": 7,
                "direction": "vertical",
                "phase": -0.0,
            },
            "ball": {"radius": 2e-3, "mass": 2.2e-4, "inertia_factor": 2 / 5},
            "contact": {"restitution": 1, "mu_static": 0.5, "mu_kinetic": 0.5},
            "air": {"drag": "none", "c_lin": 0.0, "magnus": 1.5e-9},
            "initial": {"q1": -1e-300, "q2": 0.02, "v1": 5e-324, "omega": -12.5, "t": 1e5 / 3},
            "run": {"collisions": 12, "method": "rk4", "rtol": 1e-3, "step": 1e-5, "gravity": 9.8},
        }
    )


# ---------------------------------------------------------------------------------
# built-in scenes


def test_builtin_scene_names() -> None:
    assert builtin_scene_names() == sorted(BUILTIN_FREQUENCIES)
    descriptions = builtin_scenes()
    assert sorted(descriptions) == sorted(BUILTIN_FREQUENCIES)
    for description in descriptions.values():
        assert description and "\n" not in description


@pytest.mark.parametrize("name", sorted(BUILTIN_FREQUENCIES))
def test_builtin_scene_loads(name: str) -> None:
    scene = load_scene(name)
    curve, frequency = BUILTIN_FREQUENCIES[name]
    assert scene.name == name
    assert scene.boundary.curve == curve
    assert scene.boundary.kind == "builtin"
    assert scene.boundary.ceiling == 0.2
    # One apparatus: every paper scene shares the parabola's calibrated amplitude.
    amplitude = load_scene("parabola-5.4hz").drive.amplitude
    assert scene.drive == DriveSpec(
        amplitude=amplitude, frequency=frequency, direction="horizontal"
    )
    assert scene.ball == BallSpec(radius=1.55e-3, mass=1.3028e-4, inertia_factor=0.4)
    # the paper's model, set explicitly: a scene that does not say gets "phases"
    assert scene.contact == ContactSpec(
        restitution=0.393, mu_static=0.61, mu_kinetic=0.47, model="impacts"
    )
    # Model ladder (docs/performance.md): drag changes nothing reported in the chaotic
    # scenes, so it is off there; it moves the calibrated orbits, so it is on in the others.
    if name in ("wedge-6.6hz", "hyperbola-5.8hz"):
        assert scene.air.drag == "none" and scene.air.coefficients == (0.0, 0.0)
    else:
        assert scene.air.drag == "fowles"
        assert scene.air.coefficients == fowles_coefficients(1.55e-3)
    assert scene.initial == InitialSpec()
    assert scene.initial.q1 is None and scene.initial.q2 is None
    assert scene.run.collisions == 25000
    assert scene.run.method == "event"


@pytest.mark.parametrize("name", sorted(BUILTIN_FREQUENCIES))
def test_builtin_files_say_where_amplitude_and_lid_come_from(name: str) -> None:
    text = resources.files("billiard.scene.builtin").joinpath(f"{name}.toml").read_text("utf-8")
    assert "billiard calibrate parabola-5.4hz --parameter drive.amplitude" in text
    assert "lid height" in text
    assert "amplitude" in text and "lid" in text


def test_derived_quantities() -> None:
    ball = BallSpec(radius=2e-3, mass=1e-4, inertia_factor=0.4)
    assert ball.inertia == pytest.approx(0.4 * 1e-4 * 4e-6, rel=1e-15)
    assert DriveSpec(amplitude=0.01, frequency=5.0).omega == pytest.approx(10 * math.pi, rel=1e-15)
    assert AirSpec(drag="none").coefficients == (0.0, 0.0)
    assert AirSpec(c_lin=1e-5, c_quad=2e-5).coefficients == (1e-5, 2e-5)
    c_lin, c_quad = fowles_coefficients(1.55e-3)
    assert c_lin == pytest.approx(1.55e-4 * 3.1e-3, rel=1e-15)
    assert c_quad == pytest.approx(0.22 * 3.1e-3**2, rel=1e-15)
    assert AirSpec().coefficients == (c_lin, c_quad)


def test_drag_coefficients_follow_the_ball_diameter() -> None:
    scene = scene_from_dict({"ball": {"radius": 2e-3}})
    assert scene.air.coefficients == fowles_coefficients(2e-3)
    given = scene_from_dict({"ball": {"radius": 2e-3}, "air": {"c_lin": 1e-6}})
    assert given.air.c_lin == 1e-6
    assert given.air.c_quad == fowles_coefficients(2e-3)[1]


def test_defaults() -> None:
    scene = scene_from_dict({})
    assert scene == Scene()
    assert scene.boundary == BoundarySpec(curve="parabola", ceiling=None, escape_height=1.0)
    assert scene.drive == DriveSpec(amplitude=0.0, frequency=0.0, direction="horizontal", phase=0.0)
    assert scene.contact.elastic_below == 0.01
    assert scene.run == RunSpec(
        collisions=25000, method="event", rtol=1e-10, step=1e-4, gravity=9.81
    )
    assert scene.initial == InitialSpec(q1=None, q2=None, v1=0.0, v2=0.0, omega=0.0, t=0.0)


def test_ints_become_floats() -> None:
    scene = scene_from_dict({"drive": {"amplitude": 0, "frequency": 5}, "initial": {"q1": 0}})
    assert type(scene.drive.frequency) is float and scene.drive.frequency == 5.0
    assert type(scene.initial.q1) is float
    assert type(scene.run.collisions) is int


@pytest.mark.parametrize(
    ("curve", "kind"),
    [
        ("parabola", "builtin"),
        ("wedge", "builtin"),
        ("hyperbola", "builtin"),
        ("my-curve_2", "named"),
        ("26*x**2 + 0.0063", "expression"),
        ("sqrt(x**2 + 1)", "expression"),
    ],
)
def test_curve_kind(curve: str, kind: str) -> None:
    assert curve_kind(curve) == kind
    assert BoundarySpec(curve=curve).kind == kind


def test_expression_curve_with_parameters() -> None:
    boundary = BoundarySpec(curve="a*x**2 + c", parameters={"c": 0.0063, "a": 26})
    assert boundary.parameters == (("a", 26.0), ("c", 0.0063))
    assert boundary.parameter_values == {"a": 26.0, "c": 0.0063}
    expression = boundary.expression
    assert expression is not None
    assert expression.evaluate(0.1, **boundary.parameter_values) == pytest.approx(0.2663)
    assert BoundarySpec(curve="parabola").expression is None


# ---------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("name", sorted(BUILTIN_FREQUENCIES))
def test_builtin_toml_round_trip(name: str, tmp_path: Path) -> None:
    scene = load_scene(name)
    text = scene_to_toml(scene)
    path = tmp_path / "copy.toml"
    path.write_text(text, encoding="utf-8")
    again = load_scene(path)
    assert again == scene
    assert scene_to_toml(again) == text
    assert _float_bits(again) == _float_bits(scene)


def test_custom_toml_round_trip_is_bit_for_bit() -> None:
    scene = _custom_scene()
    text = scene_to_toml(scene)
    again = scene_from_toml(text)
    assert again == scene
    assert scene_to_toml(again) == text
    assert _float_bits(again) == _float_bits(scene)
    assert math.copysign(1.0, again.drive.phase) == -1.0
    assert again.initial.v1 == 5e-324
    assert again.boundary.parameter_values["c"] == 0.1 + 0.2
    assert again.description == scene.description


def test_dict_round_trip() -> None:
    scene = _custom_scene()
    assert scene_from_dict(scene_to_dict(scene)) == scene
    data = scene_to_dict(Scene())
    assert data["initial"]["q1"] is None
    assert data["boundary"]["ceiling"] is None
    assert scene_from_dict(data) == Scene()


def test_toml_writes_every_key() -> None:
    text = scene_to_toml(load_scene("parabola-5.4hz"))
    for key in (
        "curve",
        "ceiling",
        "escape_height",
        "amplitude",
        "frequency",
        "direction",
        "phase",
        "radius",
        "mass",
        "inertia_factor",
        "restitution",
        "mu_static",
        "mu_kinetic",
        "elastic_below",
        "drag",
        "c_lin",
        "c_quad",
        "magnus",
        "v1",
        "v2",
        "omega",
        "t",
        "collisions",
        "method",
        "rtol",
        "step",
        "gravity",
    ):
        assert f"\n{key} = " in text
    assert "# q1: absent" in text


FINITE = st.floats(allow_nan=False, allow_infinity=False)
RADIUS = st.floats(min_value=5e-324, max_value=0.1)


@settings(max_examples=100, deadline=None)
@given(
    phase=st.floats(-math.tau, math.tau),
    v2=st.floats(-100.0, 100.0),
    q1=st.none() | st.floats(-10.0, 10.0),
    radius=RADIUS,
    a=FINITE,
)
def test_random_floats_round_trip(phase, v2, q1, radius, a) -> None:
    scene = scene_from_dict(
        {
            "boundary": {"curve": "a*x**2", "parameters": {"a": a}},
            "drive": {"phase": phase},
            "ball": {"radius": radius},
            "initial": {"v2": v2, "q1": q1},
        }
    )
    again = scene_from_toml(scene_to_toml(scene))
    assert again == scene
    assert _float_bits(again) == _float_bits(scene)


# ---------------------------------------------------------------------------------
# overrides and changes


def test_overrides() -> None:
    scene = load_scene(
        "parabola-5.4hz",
        overrides=[
            "drive.amplitude=0.004",
            "drive.direction=vertical",
            "run.collisions = 10",
            "boundary.curve=a*x**2 + c",
            "boundary.parameters.a=26",
            "boundary.parameters.c=6.3e-3",
            'description="changed"',
            "ball.radius=2e-3",
        ],
    )
    assert scene.drive.amplitude == 0.004
    assert scene.drive.direction == "vertical"
    assert scene.run.collisions == 10
    assert scene.boundary.curve == "a*x**2 + c"
    assert scene.boundary.parameter_values == {"a": 26.0, "c": 0.0063}
    assert scene.description == "changed"
    assert scene.air.coefficients == fowles_coefficients(2e-3)
    assert scene.drive.frequency == 5.4


@pytest.mark.parametrize(
    ("override", "fragments"),
    [
        ("contact.restitution=1.5", ["'contact.restitution' = 1.5", "[0, 1]"]),
        (
            "contact.restitutoin=0.3",
            ["'contact.restitutoin'", "did you mean 'contact.restitution'"],
        ),
        ("drive.amplitude", ["must look like 'section.key=value'"]),
        ("drive..amplitude=1", ["must look like 'section.key'"]),
        ("ball.radius.x=1", ["'ball.radius' is not a table"]),
        ("run.collisions=ten", ["'run.collisions'", "integer"]),
        ("boundary.curve=eval(x)", ["'boundary.curve'", "function 'eval'"]),
        ("drive.frequency=0", ["'drive.frequency'", "drive.amplitude"]),
    ],
)
def test_overrides_are_validated(override: str, fragments: list[str]) -> None:
    with pytest.raises(SceneError) as info:
        load_scene("parabola-5.4hz", overrides=[override])
    message = str(info.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message


def test_with_values_and_replace() -> None:
    scene = load_scene("wedge-6.6hz")
    moved = with_values(scene, {"initial.q1": 0.01, "initial.q2": 0.05, "run.collisions": 5})
    assert (moved.initial.q1, moved.initial.q2, moved.run.collisions) == (0.01, 0.05, 5)
    assert moved.drive == scene.drive
    assert moved.name == scene.name
    with pytest.raises(SceneError, match="'initial.q3'"):
        with_values(scene, {"initial.q3": 0.0})
    with pytest.raises(SceneError, match="'run.rtol'"):
        with_values(scene, {"run.rtol": 1.0})
    replaced = replace(scene, initial=InitialSpec(q1=0.0, q2=0.1))
    assert replaced.initial.q2 == 0.1
    assert replaced.boundary == scene.boundary
    with pytest.raises(SceneError, match="'contact.restitution'"):
        replace(scene, contact=dataclasses.replace(scene.contact, restitution=-0.1))
    with pytest.raises(SceneError, match="scene section 'ball'"):
        replace(scene, ball=scene.contact)


def _through_dicts(scene: Scene, changes: dict) -> Scene:
    """``changes`` applied to the scene's nested dicts and built again: the definition
    that with_values' section-by-section path must follow."""
    data = scene_to_dict(scene)
    for dotted, value in changes.items():
        section, key = dotted.split(".")
        data[section][key] = value
    return scene_from_dict(data, name=scene.name)


_KEYS = [f"{section}.{key}" for section, keys in SECTION_KEYS.items() for key in keys]
_VALUES = [0.0, 0.01, 0.25, 0.4, 5.0, 1e-4, 2, -1.0, 1e9, math.nan, None, True, "x",
           "phases", "walton", "vertical", "rk4", [1], {"a": 1}]  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(
    name=st.sampled_from(["parabola-5.4hz", "wedge-6.6hz", "hyperbola-4.5hz"]),
    changes=st.dictionaries(st.sampled_from(_KEYS), st.sampled_from(_VALUES), min_size=1,
                            max_size=3),
)  # fmt: skip
def test_with_values_builds_what_the_dicts_build(name: str, changes: dict) -> None:
    """Changed section by section (a sweep point's path), a scene equals the one built
    from its changed dicts, or both are refused with the same message."""
    scene = load_scene(name)
    try:
        expected = _through_dicts(scene, changes)
    except SceneError as exc:
        with pytest.raises(SceneError) as info:
            with_values(scene, changes)
        assert str(info.value) == str(exc)
        return
    got = with_values(scene, changes)
    assert got == expected
    assert scene_to_toml(got) == scene_to_toml(expected)


# ---------------------------------------------------------------------------------
# validation


def _assert_scene_error(info: pytest.ExceptionInfo, fragments: list[str]) -> None:
    message = str(info.value)
    assert isinstance(info.value, ValueError)
    assert len(message.splitlines()) == 1 and "\r" not in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "nope.toml")
    _assert_scene_error(info, ["nope.toml", "does not exist"])


def test_unknown_scene_name() -> None:
    with pytest.raises(SceneError) as info:
        load_scene("parabola-9hz")
    _assert_scene_error(info, ["'parabola-9hz'", "neither a built-in scene", "parabola-5.4hz"])


def test_directory_is_not_a_scene(tmp_path: Path) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path)
    _assert_scene_error(info, [str(tmp_path), "is not a regular file (a folder)"])


def test_file_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin.toml"
    path.write_bytes(b'name = "caf\xe9"\n')
    with pytest.raises(SceneError) as info:
        load_scene(path)
    _assert_scene_error(info, ["latin.toml", "UTF-8"])


INVALID = [
    # (id, TOML text, fragments expected in the message)
    ("bad-toml", "[drive\namplitude = 1\n", ["bad-toml.toml", "invalid TOML", "line 1"]),
    ("bad-toml-value", "[drive]\namplitude = 1 2\n", ["invalid TOML", "line 2"]),
    (
        "unknown-key",
        "[contact]\nrestitutoin = 0.3\n",
        ["'contact.restitutoin'", "did you mean 'contact.restitution'?"],
    ),
    (
        "key-in-wrong-section",
        "[ball]\nrestitution = 0.3\n",
        ["'ball.restitution'", "did you mean 'contact.restitution'?"],
    ),
    (
        "misspelt-section",
        "[contcat]\nrestitution = 0.3\n",
        ["section 'contcat'", "did you mean 'contact'?"],
    ),
    ("unknown-top-level-key", "colisions = 3\n", ["'colisions'", "'run.collisions'"]),
    ("section-not-table", "drive = 3\n", ["'drive'", "table"]),
    ("name-not-string", "name = 3\n", ["'name'", "string"]),
    ("wrong-type-string", '[ball]\nradius = "big"\n', ["'ball.radius'", "must be a number"]),
    ("wrong-type-bool", "[drive]\namplitude = true\n", ["'drive.amplitude'", "must be a number"]),
    ("wrong-type-array", "[initial]\nv1 = [1, 2]\n", ["'initial.v1'", "must be a number"]),
    ("wrong-type-date", "[initial]\nt = 1979-05-27\n", ["'initial.t'", "must be a number"]),
    ("collisions-float", "[run]\ncollisions = 2.5\n", ["'run.collisions'", "integer >= 1"]),
    ("collisions-zero", "[run]\ncollisions = 0\n", ["'run.collisions'", "integer >= 1"]),
    ("collisions-bool", "[run]\ncollisions = true\n", ["'run.collisions'", "integer >= 1"]),
    ("not-finite-nan", "[initial]\nv1 = nan\n", ["'initial.v1'", "not a finite number"]),
    ("not-finite-inf", "[drive]\nphase = -inf\n", ["'drive.phase'", "not a finite number"]),
    (
        "restitution-high",
        "[contact]\nrestitution = 1.5\n",
        ["scene key 'contact.restitution' = 1.5 is out of range [0, 1]"],
    ),
    ("restitution-low", "[contact]\nrestitution = -0.1\n", ["'contact.restitution'", "[0, 1]"]),
    ("radius-zero", "[ball]\nradius = 0\n", ["'ball.radius' = 0.0 m", "(0, 0.1] m"]),
    ("mass-negative", "[ball]\nmass = -1e-4\n", ["'ball.mass'", "(0, 100] kg"]),
    ("inertia-zero", "[ball]\ninertia_factor = 0\n", ["'ball.inertia_factor'", "(0, 1]"]),
    ("inertia-high", "[ball]\ninertia_factor = 1.01\n", ["'ball.inertia_factor'", "(0, 1]"]),
    ("mu-static-negative", "[contact]\nmu_static = -0.1\n", ["'contact.mu_static'", "[0, 5]"]),
    ("mu-kinetic-negative", "[contact]\nmu_kinetic = -0.1\n", ["'contact.mu_kinetic'"]),
    (
        "mu-kinetic-above-static",
        "[contact]\nmu_static = 0.4\nmu_kinetic = 0.5\n",
        ["'contact.mu_kinetic' = 0.5", "must not exceed contact.mu_static = 0.4"],
    ),
    ("elastic-below-negative", "[contact]\nelastic_below = -0.01\n", ["'contact.elastic_below'"]),
    ("amplitude-negative", "[drive]\namplitude = -0.001\nfrequency = 5\n", ["'drive.amplitude'"]),
    (
        "frequency-negative",
        "[drive]\nfrequency = -5\n",
        ["'drive.frequency' = -5.0 Hz", "[0, 1000] Hz"],
    ),
    (
        "amplitude-without-frequency",
        "[drive]\namplitude = 0.005\n",
        ["'drive.frequency'", "must be > 0 when drive.amplitude"],
    ),
    (
        "direction",
        '[drive]\ndirection = "sideways"\n',
        ["'drive.direction'", "'horizontal', 'vertical'"],
    ),
    ("drag", '[air]\ndrag = "stokes"\n', ["'air.drag'", "'fowles', 'none'"]),
    ("c-lin-negative", "[air]\nc_lin = -1e-7\n", ["'air.c_lin'"]),
    ("magnus-negative", "[air]\nmagnus = -1e-9\n", ["'air.magnus'"]),
    ("method", '[run]\nmethod = "rk45"\n', ["'run.method'", "did you mean 'rk4'?"]),
    ("rtol-zero", "[run]\nrtol = 0\n", ["'run.rtol'", "[1e-14, 0.001]"]),
    ("rtol-large", "[run]\nrtol = 0.01\n", ["'run.rtol'", "[1e-14, 0.001]"]),
    ("step-zero", "[run]\nstep = 0.0\n", ["'run.step'"]),
    ("gravity-negative", "[run]\ngravity = -9.81\n", ["'run.gravity'"]),
    ("ceiling-zero", "[boundary]\nceiling = 0\n", ["'boundary.ceiling' = 0.0 m", "(0, 10] m"]),
    ("ceiling-inf", "[boundary]\nceiling = inf\n", ["'boundary.ceiling'", "finite"]),
    ("escape-height", "[boundary]\nescape_height = -1\n", ["'boundary.escape_height'"]),
    ("curve-not-string", "[boundary]\ncurve = 3\n", ["'boundary.curve'"]),
    ("curve-empty", '[boundary]\ncurve = ""\n', ["'boundary.curve'"]),
    (
        "bad-curve-expression",
        "[boundary]\ncurve = \"__import__('os').system('ls')\"\n",
        ["'boundary.curve'", "not a valid curve expression", "attribute access '.system'"],
    ),
    ("bad-curve-syntax", '[boundary]\ncurve = "26*x**2 +"\n', ["'boundary.curve'", "syntax"]),
    ("bad-curve-unicode", '[boundary]\ncurve = "26*\u0445**2"\n', ["'boundary.curve'", "U+0445"]),
    (
        "missing-curve-parameter",
        '[boundary]\ncurve = "a*x**2 + c"\n[boundary.parameters]\na = 26\n',
        ["'boundary.parameters.c' is missing", "parameter 'c'"],
    ),
    (
        "unused-curve-parameter",
        '[boundary]\ncurve = "a*x**2"\n[boundary.parameters]\na = 26\nb = 1\n',
        ["'boundary.parameters.b' is not used"],
    ),
    (
        "parameter-bad-value",
        '[boundary]\ncurve = "a*x**2"\n[boundary.parameters]\na = "26"\n',
        ["'boundary.parameters.a'", "must be a number"],
    ),
    (
        "parameter-bad-name",
        '[boundary]\ncurve = "wedge"\n[boundary.parameters]\n_b = 1\n',
        ["'boundary.parameters._b'", "not a valid parameter name"],
    ),
    ("parameters-not-table", "[boundary]\nparameters = 3\n", ["'boundary.parameters'", "table"]),
]


@pytest.mark.parametrize(("case", "text", "fragments"), INVALID, ids=[c[0] for c in INVALID])
def test_invalid_scene_files(case: str, text: str, fragments: list[str], tmp_path: Path) -> None:
    path = tmp_path / f"{case}.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    _assert_scene_error(info, fragments)


def test_integer_too_large_for_a_float() -> None:
    with pytest.raises(SceneError) as info:
        scene_from_dict({"initial": {"q1": 10**400}})
    _assert_scene_error(info, ["'initial.q1'", "not a finite number"])


def test_scene_must_be_a_mapping() -> None:
    with pytest.raises(SceneError) as info:
        scene_from_dict([("run", {})])  # type: ignore[arg-type]
    _assert_scene_error(info, ["table of sections"])


def test_valid_edge_values_are_accepted() -> None:
    scene = scene_from_dict(
        {
            "ball": {"inertia_factor": 1},
            "contact": {"restitution": 0, "mu_static": 0, "mu_kinetic": 0, "elastic_below": 0},
            "run": {"rtol": 1e-3, "collisions": 1},
            "drive": {"amplitude": 0, "frequency": 0},
        }
    )
    assert scene.ball.inertia_factor == 1.0
    assert scene.contact.restitution == 0.0
    assert scene.run.rtol == 1e-3
    assert scene.run.collisions == 1


def test_key_number_reads_numeric_keys_only() -> None:
    scene = with_values(load_scene("wedge-6.6hz"), {"run.collisions": 7})
    assert key_number(scene, "drive.frequency") == scene.drive.frequency
    assert key_number(scene, "run.collisions") == 7.0
    assert key_number(scene, "contact.model") is None  # a string
    assert key_value(scene, "contact.model") == scene.contact.model
    with pytest.raises(KeyError):
        key_number(scene, "drive.frequncy")
