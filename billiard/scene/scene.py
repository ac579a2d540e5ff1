"""Scene files: the description of one simulation, in TOML with SI units.

A scene file has the sections ``[boundary]`` (with an optional
``[boundary.parameters]`` table), ``[drive]``, ``[ball]``, ``[contact]``, ``[air]``,
``[initial]`` and ``[run]``, and the optional top-level keys ``name`` and
``description``. Every key is optional; missing keys take the defaults of the section
specifications in :mod:`billiard.scene.spec` (:class:`BoundarySpec` and the others), which are
the values of the real-world billiard experiment (a 3.1 mm steel ball on aluminium).

Everything is validated before any work is done: unknown sections and keys (with a
"did you mean" hint), wrong types, non-finite values and values outside their physically
sensible range (:data:`billiard.scene.checks.LIMITS`, unit in the message), curve expressions,
and the scene's name, which names its run folder (``runs/<name>``) and must therefore be
a single safe path component. Every problem is reported as a :class:`SceneError` with a
one-line message naming the key.

This module holds the :class:`Scene`, its conversion from and to dicts and TOML,
overrides (:func:`with_values`, ``--set``) and the built-in scenes, which live in
``billiard/scenes/<name>.toml`` and are loaded by name::

    scene = load_scene("parabola-5.4hz", overrides=["drive.amplitude=0.004"])
"""

from __future__ import annotations

import dataclasses
import os
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from billiard.scene.checks import SceneError, check_name, error, shown
from billiard.scene.display import html_table, scene_line, scene_rows
from billiard.scene.keys import SECTION_KEYS, check_keys, sets_keys
from billiard.scene.spec import (
    BUILTIN_CURVES,
    DRAG_MODELS,
    DRIVE_DIRECTIONS,
    METHODS,
    SECTIONS,
    AirSpec,
    BallSpec,
    BoundarySpec,
    ContactSpec,
    DriveSpec,
    InitialSpec,
    RunSpec,
    curve_kind,
    fowles_coefficients,
)
from billiard.scene.toml_text import toml_key, toml_value
from billiard.scene.userfile import MAX_SCENE_BYTES, FileRefused, read_limited

__all__ = [
    "PAPER_SCENES",
    "BUILTIN_CURVES",
    "DRAG_MODELS",
    "DRIVE_DIRECTIONS",
    "METHODS",
    "AirSpec",
    "BallSpec",
    "BoundarySpec",
    "ContactSpec",
    "DriveSpec",
    "InitialSpec",
    "RunSpec",
    "Scene",
    "SceneError",
    "builtin_scene_names",
    "builtin_scenes",
    "check_name",
    "curve_kind",
    "fowles_coefficients",
    "load_scene",
    "replace",
    "key_number",
    "key_value",
    "scene_from_dict",
    "scene_from_toml",
    "scene_to_dict",
    "scene_to_toml",
    "sets_keys",
    "with_values",
]


@dataclass(frozen=True)
class Scene:
    """A complete, validated scene. Build it with :func:`load_scene` or
    :func:`scene_from_dict`; change it with :func:`with_values` or :func:`replace`."""

    name: str = "scene"
    description: str = ""
    boundary: BoundarySpec = field(default_factory=BoundarySpec)
    drive: DriveSpec = field(default_factory=DriveSpec)
    ball: BallSpec = field(default_factory=BallSpec)
    contact: ContactSpec = field(default_factory=ContactSpec)
    air: AirSpec = field(default_factory=AirSpec)
    initial: InitialSpec = field(default_factory=InitialSpec)
    run: RunSpec = field(default_factory=RunSpec)

    def __post_init__(self) -> None:
        check_name(self.name)
        if not isinstance(self.description, str):
            raise error(f"scene key 'description' must be a string, got {shown(self.description)}")
        for key, cls in SECTIONS.items():
            value = getattr(self, key)
            if not isinstance(value, cls):
                raise error(f"scene section '{key}' must be a {cls.__name__}, got {shown(value)}")

    def __repr__(self) -> str:
        """One line: name, curve, drive, restitution, contact model, impacts (SI units);
        ``scene_to_toml(scene)`` gives every value exactly."""
        return scene_line(self)

    def _repr_html_(self) -> str:
        """The scene's main settings as a small HTML table (shown by notebooks)."""
        return html_table(scene_rows(self), f"Scene {self.name!r}")


def scene_from_dict(data: Mapping[str, Any], name: str = "scene") -> Scene:
    """Build and validate a scene from nested mappings shaped like a scene file.

    Args:
        data: ``{"boundary": {...}, "drive": {...}, ...}`` plus optional top-level
            ``name`` and ``description``; missing sections and keys take defaults.
        name: the scene's name when *data* has no ``name`` key.

    Raises:
        SceneError: on any invalid section, key or value.
    """
    if not isinstance(data, Mapping):
        raise error(f"a scene must be a table of sections, got {shown(data)}")
    check_keys(data)
    tables: dict[str, dict[str, Any]] = {
        section: dict(data.get(section, {})) for section in SECTIONS
    }
    if "parameters" in tables["boundary"]:
        parameters = tables["boundary"]["parameters"]
        if not isinstance(parameters, Mapping):
            raise error(
                f"scene key 'boundary.parameters' must be a table of name = value, "
                f"got {shown(parameters)}"
            )
        tables["boundary"]["parameters"] = dict(parameters)
    sections: dict[str, Any] = {}
    for section, cls in SECTIONS.items():
        table = tables[section]
        if cls is AirSpec:
            c_lin, c_quad = fowles_coefficients(sections["ball"].radius)
            if table.get("c_lin") is None:
                table["c_lin"] = c_lin
            if table.get("c_quad") is None:
                table["c_quad"] = c_quad
        sections[section] = cls(**table)
    return Scene(
        name=data.get("name", name),
        description=data.get("description", ""),
        **sections,
    )


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """The fully resolved scene as nested plain dicts, every key present (None for an
    absent ``boundary.ceiling``, ``initial.q1`` or ``initial.q2``).
    ``scene_from_dict(scene_to_dict(s)) == s``."""
    data: dict[str, Any] = {"name": scene.name, "description": scene.description}
    for section in SECTIONS:
        table = dataclasses.asdict(getattr(scene, section))
        if section == "boundary":
            table["parameters"] = dict(scene.boundary.parameters)
        data[section] = table
    return data


def _apply(data: dict[str, Any], dotted: str, value: Any, what: str) -> None:
    parts = [part.strip() for part in dotted.split(".")]
    if not all(parts):
        raise error(f"{what}: key {shown(dotted)} must look like 'section.key'")
    table = data
    for depth, part in enumerate(parts[:-1]):
        child = table.setdefault(part, {})
        if not isinstance(child, dict):
            prefix = ".".join(parts[: depth + 1])
            raise error(f"{what}: scene key '{prefix}' is not a table")
        table = child
    table[parts[-1]] = value


def with_values(scene: Scene, changes: Mapping[str, Any]) -> Scene:
    """A new validated scene with some keys changed.

    Args:
        scene: the scene to start from.
        changes: dotted keys and new values, e.g. ``{"initial.q1": 0.01,
            "boundary.parameters.a": 26.0}``.

    Note that the drag coefficients of *scene* are already resolved: changing
    ``ball.radius`` here keeps ``air.c_lin`` and ``air.c_quad`` unless they are changed
    too (a load-time override of ``ball.radius`` does re-derive them).
    """
    sections = _section_changes(changes)
    if sections is not None:
        # the common case (a sweep point, a parameter-map point): only the changed
        # sections are built again, each validating itself as scene_from_dict would;
        # the round trip through nested dicts took most of a patched map point's set-up
        return dataclasses.replace(
            scene,
            **{
                section: dataclasses.replace(getattr(scene, section), **keys)
                for section, keys in sections.items()
            },
        )
    data = scene_to_dict(scene)
    for dotted, value in changes.items():
        _apply(data, dotted, value, f"change {dotted!r}")
    return scene_from_dict(data, name=scene.name)


def _section_changes(changes: Mapping[str, Any]) -> dict[str, dict[str, Any]] | None:
    """``changes`` as {section: {key: value}} where every change is a plain key of a
    section whose new value needs nothing from another section, else None (then the
    changes take the path through :func:`scene_from_dict`: nested keys, unknown keys and
    their hints, drag coefficients derived again from the ball)."""
    out: dict[str, dict[str, Any]] = {}
    for dotted, value in changes.items():
        if not isinstance(dotted, str):
            return None
        section, _, key = dotted.partition(".")
        if key not in SECTION_KEYS.get(section, ()) or (section, key) == ("boundary", "parameters"):
            return None
        if section == "air" and value is None:  # resolved from the ball by scene_from_dict
            return None
        out.setdefault(section, {})[key] = value
    # built (and so validated) in the sections' order, as scene_from_dict does: the
    # same error first
    return {section: out[section] for section in SECTIONS if section in out}


def key_value(scene: Scene, key: str) -> Any:
    """The value of scene key ``key`` (``"section.name"``), as the scene holds it.

    Raises:
        KeyError: the scene has no such key.
    """
    section, _, name = key.partition(".")
    try:
        return getattr(getattr(scene, section), name)
    except AttributeError:
        raise KeyError(key) from None


def key_number(scene: Scene, key: str) -> float | None:
    """:func:`key_value` as a float, None when it is not a number (a string, a bool,
    an absent value).

    Raises:
        KeyError: the scene has no such key.
    """
    value = key_value(scene, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def replace(scene: Scene, **section_changes: Any) -> Scene:
    """``dataclasses.replace`` on the scene, e.g. ``replace(scene, initial=InitialSpec(q1=0.01,
    q2=0.02))``; sections validate themselves when constructed."""
    return dataclasses.replace(scene, **section_changes)


# ----------------------------------------------------------------------------------
# TOML


_ABSENT_NOTES = {
    "boundary.ceiling": "ceiling: absent, the container has no lid",
    "initial.q1": "q1: absent, resolved by the engine",
    "initial.q2": "q2: absent, resolved by the engine",
    "run.duration": "duration: absent, no limit on simulated time",
    "contact.beta0": "beta0: absent (contact.law = 'walton' needs it)",
    "contact.e_ref": "e_ref: absent (contact.law = 'power-law' needs it)",
    "contact.v_ref": "v_ref: absent, m/s (contact.law = 'power-law' needs it)",
    "contact.exponent": "exponent: absent (contact.law = 'power-law' needs it)",
    "contact.viscous": "viscous: absent, (s/m)^(1/5) (contact.law = 'viscoelastic' needs it)",
    "contact.energy_scale": "energy_scale: absent, J (contact.law = 'energy-dependent' needs it)",
    "contact.angle_slope": "angle_slope: absent (contact.law = 'angle-dependent' needs it)",
}


def scene_to_toml(scene: Scene) -> str:
    """The fully resolved scene as TOML text, every key written.

    Floats are written with :func:`repr`, so reading the text back gives the same
    scene bit for bit: ``scene_from_toml(scene_to_toml(s)) == s``. Keys whose value is
    None (no lid, engine-resolved start position) are written as comments.
    """
    lines = [
        "# Scene file; SI units (m, kg, s, rad).",
        f"name = {toml_value(scene.name)}",
        f"description = {toml_value(scene.description)}",
    ]
    data = scene_to_dict(scene)
    for section in SECTIONS:
        lines += ["", f"[{section}]"]
        table = data[section]
        for key, value in table.items():
            if section == "boundary" and key == "parameters":
                continue
            if value is None:
                lines.append(f"# {_ABSENT_NOTES[f'{section}.{key}']}")
            else:
                lines.append(f"{toml_key(key)} = {toml_value(value)}")
        if section == "boundary" and table["parameters"]:
            lines += ["", "[boundary.parameters]"]
            for key, value in table["parameters"].items():
                lines.append(f"{toml_key(key)} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


def _parse_toml(text: str, source: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"scene file {source}: invalid TOML: {exc}") from None


def scene_from_toml(text: str, name: str = "scene", source: str = "<string>") -> Scene:
    """Build and validate a scene from TOML text.

    Args:
        text: the TOML document.
        name: the scene's name when the document has no ``name`` key.
        source: how to refer to the document in error messages.
    """
    return scene_from_dict(_parse_toml(text, source), name=name)


def _parse_override_value(text: str) -> Any:
    """A TOML value, or the bare text when it is not one (``parabola``, ``26*x**2``)."""
    text = text.strip()
    try:
        parsed = tomllib.loads(f"value = {text}")
    except tomllib.TOMLDecodeError:
        return text
    return parsed["value"] if set(parsed) == {"value"} else text


def _scene_resource(name: str) -> Any:
    return resources.files("billiard.scene.builtin").joinpath(f"{name}.toml")


#: The paper's four experiments, in the paper's order (all built in).
PAPER_SCENES: tuple[str, ...] = (
    "parabola-5.4hz",
    "wedge-6.6hz",
    "hyperbola-5.8hz",
    "hyperbola-4.5hz",
)


def builtin_scene_names() -> list[str]:
    """Names of the scenes shipped with the package, sorted."""
    return sorted(
        entry.name.removesuffix(".toml")
        for entry in resources.files("billiard.scene.builtin").iterdir()
        if entry.name.endswith(".toml")
    )


def builtin_scenes() -> dict[str, str]:
    """Built-in scene name -> its one-line description."""
    return {name: load_scene(name).description for name in builtin_scene_names()}


def _read_scene(name_or_path: str | os.PathLike[str]) -> tuple[str, str, str]:
    """Text, display name and default scene name of a built-in scene or a file."""
    if isinstance(name_or_path, str) and name_or_path in builtin_scene_names():
        text = _scene_resource(name_or_path).read_text(encoding="utf-8")
        return text, f"'{name_or_path}' (built-in)", name_or_path
    path = Path(name_or_path)
    if not path.exists():
        if isinstance(name_or_path, str) and path.suffix != ".toml" and len(path.parts) == 1:
            known = ", ".join(builtin_scene_names())
            raise error(
                f"scene {str(name_or_path)!r} is neither a built-in scene ({known}) "
                "nor an existing file"
            )
        raise error(f"scene file '{path}' does not exist")
    try:
        text = read_limited(path, MAX_SCENE_BYTES).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"scene file '{path}' is not UTF-8 text: {exc.reason}") from None
    except FileRefused as exc:
        raise error(f"scene file '{path}' {exc.reason}") from None
    except OSError as exc:
        raise error(f"scene file '{path}' cannot be read: {exc.strerror or exc}") from None
    return text, f"'{path}'", path.stem


def load_scene(
    name_or_path: str | os.PathLike[str],
    overrides: Sequence[str] = (),
    *,
    notify: Callable[[str], None] | None = None,
) -> Scene:
    """Load and validate a built-in scene (by name) or a scene file (by path).

    Args:
        name_or_path: a name from :func:`builtin_scene_names` or the path of a TOML file.
        overrides: ``"section.key=value"`` strings applied before validation, in order.
            The value is read as a TOML value (``0.004``, ``25``, ``"text"``) and, when
            it is not one, taken as a bare string (``drive.direction=vertical``,
            ``boundary.curve=26*x**2 + 0.0063``).
        notify: called with a one-line note when the file and the overrides set no key
            besides ``name`` and ``description`` (the scene is then the all-defaults
            scene, which is rarely what was meant).

    Raises:
        SceneError: the file is missing or not valid TOML, an override is malformed, or
            the scene is invalid.
    """
    text, source, default_name = _read_scene(name_or_path)
    data = _parse_toml(text, f"{source}")
    for override in overrides:
        if not isinstance(override, str) or "=" not in override:
            raise error(f"override {shown(override)} must look like 'section.key=value'")
        dotted, _, value = override.partition("=")
        _apply(data, dotted, _parse_override_value(value), f"override {override!r}")
    scene = scene_from_dict(data, name=default_name)
    if notify is not None and not sets_keys(data):
        notify(
            f"scene file {source} sets no keys; this is the all-defaults scene: {_DEFAULTS_SUMMARY}"
        )
    return scene


#: What the all-defaults scene is, in words.
_DEFAULTS_SUMMARY = (
    f"a fixed parabola (drive.amplitude = 0 m) with the ball at rest at its bottom, "
    f"{RunSpec().collisions} impacts"
)
