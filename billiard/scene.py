"""Scene files: the description of one simulation, in TOML with SI units.

A scene file has the sections ``[boundary]`` (with an optional
``[boundary.parameters]`` table), ``[drive]``, ``[ball]``, ``[contact]``, ``[air]``,
``[initial]`` and ``[run]``, and the optional top-level keys ``name`` and
``description``. Every key is optional; missing keys take the defaults of the
dataclasses below, which are the values of the real-world billiard experiment
(a 3.1 mm steel ball on aluminium).

Everything is validated before any work is done: unknown sections and keys (with a
"did you mean" hint), wrong types, out-of-range and non-finite values, and curve
expressions. Every problem is reported as a :class:`SceneError` with a one-line
message naming the key. Geometric checks that need the curve itself (the ball's
radius against the curvature, an initial position inside the wall) belong to the
engine.

Scenes shipped with the package live in ``billiard/scenes/<name>.toml`` and are
loaded by name::

    scene = load_scene("parabola-5.4hz", overrides=["drive.amplitude=0.004"])
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from billiard.derivation.expr import (
    BUILTIN_CURVES,
    CurveExpression,
    CurveExpressionError,
    is_curve_name,
    is_parameter_name,
    parse_curve,
)

__all__ = [
    "BUILTIN_CURVES",
    "DRAG_MODELS",
    "DRIVE_DIRECTIONS",
    "METHODS",
    "Air",
    "Ball",
    "Boundary",
    "Contact",
    "Drive",
    "Initial",
    "Run",
    "Scene",
    "SceneError",
    "builtin_scene_names",
    "builtin_scenes",
    "curve_kind",
    "fowles_coefficients",
    "load_scene",
    "replace",
    "scene_from_dict",
    "scene_from_toml",
    "scene_to_dict",
    "scene_to_toml",
    "with_values",
]

#: Accepted values of ``drive.direction``.
DRIVE_DIRECTIONS: tuple[str, ...] = ("horizontal", "vertical")
#: Accepted values of ``air.drag``.
DRAG_MODELS: tuple[str, ...] = ("fowles", "none")
#: Accepted values of ``run.method``.
METHODS: tuple[str, ...] = ("event", "rk4")

_BARE_KEY_RE = re.compile(r"[A-Za-z0-9_-]+")
_MAX_SHOWN = 60

_DEFAULT_RADIUS = 1.55e-3


class SceneError(ValueError):
    """An invalid scene; the message is one line and names the offending key."""


def _error(message: str) -> SceneError:
    return SceneError(message.replace("\r", "\\r").replace("\n", "\\n"))


def _shown(value: Any) -> str:
    text = repr(value)
    if len(text) > _MAX_SHOWN:
        text = text[: _MAX_SHOWN - 3] + "..."
    return text


def fowles_coefficients(radius: float) -> tuple[float, float]:
    """Fowles' still-air drag coefficients for a sphere of the given radius.

    Args:
        radius: sphere radius (m).

    Returns:
        ``(c_lin, c_quad)`` with ``c_lin = 1.55e-4 * D`` (N s/m) and
        ``c_quad = 0.22 * D**2`` (N s^2/m^2), D = 2 * radius in metres.
    """
    diameter = 2.0 * radius
    return 1.55e-4 * diameter, 0.22 * diameter * diameter


def curve_kind(curve: str) -> str:
    """Classify a ``boundary.curve`` string.

    Returns:
        ``"builtin"`` for one of :data:`BUILTIN_CURVES`, ``"named"`` for any other curve
        name (:func:`billiard.derivation.expr.is_curve_name`; a generated curve, looked up
        by the engine) and ``"expression"`` otherwise (to be parsed by
        :func:`billiard.derivation.expr.parse_curve`).
    """
    if curve in BUILTIN_CURVES:
        return "builtin"
    if is_curve_name(curve):
        return "named"
    return "expression"


# ----------------------------------------------------------------------------------
# value checks


def _number(key: str, value: Any) -> float:
    """A finite real number; ints are accepted and converted, bools are not numbers."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _error(
            f"scene key '{key}' must be a number, got {_shown(value)} ({type(value).__name__})"
        )
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise _error(f"scene key '{key}' = {_shown(value)} is not a finite number")
    return number


def _optional_number(key: str, value: Any) -> float | None:
    return None if value is None else _number(key, value)


def _in_range(
    key: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = True,
) -> None:
    below = value <= low if low_open else value < low
    above = value >= high if high_open else value > high
    if below or above:
        left = "(" if low_open or low == -math.inf else "["
        right = ")" if high_open or high == math.inf else "]"
        interval = f"{left}{_bound(low)}, {_bound(high)}{right}"
        raise _error(f"scene key '{key}' = {value!r} is out of range {interval}")


def _bound(value: float) -> str:
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:g}"


def _positive(key: str, value: Any) -> float:
    number = _number(key, value)
    _in_range(key, number, 0.0, low_open=True)
    return number


def _non_negative(key: str, value: Any) -> float:
    number = _number(key, value)
    _in_range(key, number, 0.0)
    return number


def _choice(key: str, value: Any, choices: Sequence[str]) -> str:
    allowed = ", ".join(f"'{choice}'" for choice in choices)
    if not isinstance(value, str) or value not in choices:
        hint = ""
        if isinstance(value, str):
            close = difflib.get_close_matches(value, choices, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
        raise _error(f"scene key '{key}' = {_shown(value)} must be one of {allowed}{hint}")
    return value


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


# ----------------------------------------------------------------------------------
# sections


@dataclass(frozen=True)
class Boundary:
    """The boundary curve y = f(x) (both in metres, in the boundary's own frame).

    Attributes:
        curve: ``"parabola"``, ``"wedge"``, ``"hyperbola"``, the name of a generated curve,
            or an expression in x (m) such as ``"26*x**2 + 0.0063"``.
        ceiling: height (m) of a flat lid, or None for an open container.
        escape_height: height (m) above which a ball in an open container ends the run.
        parameters: values of the curve's named parameters, as sorted ``(name, value)``
            pairs (a mapping is accepted and converted). For an expression they must be
            exactly the parameters it uses; for a named curve they override the generated
            module's defaults and are checked by the engine.
    """

    curve: str = "parabola"
    ceiling: float | None = None
    escape_height: float = 1.0
    parameters: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.curve, str) or not self.curve.strip():
            raise _error(
                f"scene key 'boundary.curve' must be a curve name or an expression in x, "
                f"got {_shown(self.curve)}"
            )
        expression = self.expression  # a bad expression is reported before its parameters
        ceiling = _optional_number("boundary.ceiling", self.ceiling)
        if ceiling is not None:
            _in_range("boundary.ceiling", ceiling, 0.0, low_open=True)
        _set(self, "ceiling", ceiling)
        _set(self, "escape_height", _positive("boundary.escape_height", self.escape_height))
        _set(self, "parameters", self._checked_parameters(expression))

    def _checked_parameters(
        self, expression: CurveExpression | None
    ) -> tuple[tuple[str, float], ...]:
        raw = self.parameters
        pairs: Iterable[Any]
        if isinstance(raw, Mapping):
            pairs = raw.items()
        elif isinstance(raw, (tuple, list)):
            pairs = raw
        else:
            raise _error(
                f"scene key 'boundary.parameters' must be a table of name = value, "
                f"got {_shown(raw)}"
            )
        values: dict[str, float] = {}
        for pair in pairs:
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise _error(
                    f"scene key 'boundary.parameters' must be a table of name = value, "
                    f"got {_shown(raw)}"
                )
            name, value = pair
            if not is_parameter_name(name):
                raise _error(
                    f"scene key 'boundary.parameters.{name}' is not a valid parameter name "
                    "(an ASCII letter, then up to 30 letters, digits or '_'; not x, pi, a "
                    "function name or a Python keyword)"
                )
            if name in values:
                raise _error(f"scene key 'boundary.parameters.{name}' is given twice")
            values[name] = _number(f"boundary.parameters.{name}", value)
        if expression is not None:
            for name in expression.parameters:
                if name not in values:
                    raise _error(
                        f"scene key 'boundary.parameters.{name}' is missing: the curve "
                        f"expression uses the parameter '{name}'"
                    )
            for name in values:
                if name not in expression.parameters:
                    raise _error(
                        f"scene key 'boundary.parameters.{name}' is not used by the curve "
                        f"expression {_shown(self.curve)}"
                    )
        return tuple(sorted(values.items()))

    @property
    def kind(self) -> str:
        """``"builtin"``, ``"named"`` or ``"expression"`` (see :func:`curve_kind`)."""
        return curve_kind(self.curve)

    @property
    def expression(self) -> CurveExpression | None:
        """The parsed curve expression, or None when the curve is a name."""
        if self.kind != "expression":
            return None
        try:
            return parse_curve(self.curve)
        except CurveExpressionError as exc:
            detail = str(exc).removeprefix("curve expression: ")
            raise _error(
                f"scene key 'boundary.curve' = {_shown(self.curve)} is not a valid curve "
                f"expression: {detail}"
            ) from None

    @property
    def parameter_values(self) -> dict[str, float]:
        """The curve parameters as a new dict name -> value."""
        return dict(self.parameters)


@dataclass(frozen=True)
class Drive:
    """Sinusoidal motion of the boundary, D(t) = amplitude * sin(omega t + phase).

    Attributes:
        amplitude: displacement amplitude (m); 0 means a fixed boundary.
        frequency: drive frequency f (Hz).
        direction: ``"horizontal"`` (along n1, the paper's experiments) or ``"vertical"``.
        phase: phase at t = 0 (rad).
    """

    amplitude: float = 0.0
    frequency: float = 0.0
    direction: str = "horizontal"
    phase: float = 0.0

    def __post_init__(self) -> None:
        _set(self, "amplitude", _non_negative("drive.amplitude", self.amplitude))
        _set(self, "frequency", _non_negative("drive.frequency", self.frequency))
        _choice("drive.direction", self.direction, DRIVE_DIRECTIONS)
        _set(self, "phase", _number("drive.phase", self.phase))
        if self.amplitude > 0.0 and self.frequency == 0.0:
            raise _error(
                f"scene key 'drive.frequency' = 0.0 must be > 0 when drive.amplitude = "
                f"{self.amplitude!r} > 0"
            )

    @property
    def omega(self) -> float:
        """Angular frequency 2 pi f (rad/s)."""
        return 2.0 * math.pi * self.frequency


@dataclass(frozen=True)
class Ball:
    """The ball: a uniform sphere by default.

    Attributes:
        radius: radius r (m).
        mass: mass m (kg).
        inertia_factor: k in I = k m r^2 (dimensionless; 0.4 for a solid sphere).
    """

    radius: float = _DEFAULT_RADIUS
    mass: float = 1.3028e-4
    inertia_factor: float = 0.4

    def __post_init__(self) -> None:
        _set(self, "radius", _positive("ball.radius", self.radius))
        _set(self, "mass", _positive("ball.mass", self.mass))
        k = _number("ball.inertia_factor", self.inertia_factor)
        _in_range("ball.inertia_factor", k, 0.0, 1.0, low_open=True, high_open=False)
        _set(self, "inertia_factor", k)

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre, k m r^2 (kg m^2)."""
        return self.inertia_factor * self.mass * self.radius**2


@dataclass(frozen=True)
class Contact:
    """Impact law parameters.

    Attributes:
        restitution: Newton's coefficient of restitution e (dimensionless, in [0, 1]).
        mu_static: static friction coefficient (dimensionless).
        mu_kinetic: kinetic friction coefficient (dimensionless, <= mu_static).
        elastic_below: relative normal speed (m/s) below which impacts are elastic (e = 1),
            which prevents inelastic collapse.
    """

    restitution: float = 0.393
    mu_static: float = 0.61
    mu_kinetic: float = 0.47
    elastic_below: float = 0.01

    def __post_init__(self) -> None:
        e = _number("contact.restitution", self.restitution)
        _in_range("contact.restitution", e, 0.0, 1.0, high_open=False)
        _set(self, "restitution", e)
        _set(self, "mu_static", _non_negative("contact.mu_static", self.mu_static))
        _set(self, "mu_kinetic", _non_negative("contact.mu_kinetic", self.mu_kinetic))
        if self.mu_kinetic > self.mu_static:
            raise _error(
                f"scene key 'contact.mu_kinetic' = {self.mu_kinetic!r} must not exceed "
                f"contact.mu_static = {self.mu_static!r}"
            )
        _set(self, "elastic_below", _non_negative("contact.elastic_below", self.elastic_below))


_DEFAULT_C_LIN, _DEFAULT_C_QUAD = fowles_coefficients(_DEFAULT_RADIUS)


@dataclass(frozen=True)
class Air:
    """Aerodynamic forces on the ball in flight.

    Attributes:
        drag: ``"fowles"`` (linear plus quadratic drag) or ``"none"``.
        c_lin: linear drag coefficient (N s/m).
        c_quad: quadratic drag coefficient (N s^2/m^2).
        magnus: Magnus force coefficient (kg), force ``magnus * w x v``; 0 turns it off.

    When a scene is built from a file or a dict, a missing ``c_lin`` or ``c_quad`` is
    resolved from the ball's diameter with :func:`fowles_coefficients`; the dataclass
    defaults are those of the default ball.
    """

    drag: str = "fowles"
    c_lin: float = _DEFAULT_C_LIN
    c_quad: float = _DEFAULT_C_QUAD
    magnus: float = 0.0

    def __post_init__(self) -> None:
        _choice("air.drag", self.drag, DRAG_MODELS)
        _set(self, "c_lin", _non_negative("air.c_lin", self.c_lin))
        _set(self, "c_quad", _non_negative("air.c_quad", self.c_quad))
        _set(self, "magnus", _non_negative("air.magnus", self.magnus))

    @property
    def coefficients(self) -> tuple[float, float]:
        """``(c_lin, c_quad)`` in effect: (0, 0) when ``drag == "none"``."""
        if self.drag == "none":
            return 0.0, 0.0
        return self.c_lin, self.c_quad


@dataclass(frozen=True)
class Initial:
    """Initial state of the ball in the lab frame.

    Attributes:
        q1, q2: position of the centre (m). None is resolved by the engine; with both
            None the ball starts at rest touching the bottom of the boundary.
        v1, v2: velocity of the centre (m/s).
        omega: spin about n3 (rad/s, counter-clockwise positive).
        t: start time (s).
    """

    q1: float | None = None
    q2: float | None = None
    v1: float = 0.0
    v2: float = 0.0
    omega: float = 0.0
    t: float = 0.0

    def __post_init__(self) -> None:
        _set(self, "q1", _optional_number("initial.q1", self.q1))
        _set(self, "q2", _optional_number("initial.q2", self.q2))
        for name in ("v1", "v2", "omega", "t"):
            _set(self, name, _number(f"initial.{name}", getattr(self, name)))


@dataclass(frozen=True)
class Run:
    """How the run is integrated and when it stops.

    Attributes:
        collisions: number of impacts to simulate (>= 1).
        method: ``"event"`` (event-driven flights) or ``"rk4"`` (fixed-step reference).
        rtol: relative tolerance of the error-controlled flight with drag, in (0, 1e-3].
        step: time step (s) of the ``"rk4"`` method.
        gravity: gravitational acceleration g (m/s^2).
        duration: simulated time (s) after which the run stops, or None for no limit;
            the run ends at whichever of ``collisions`` and ``duration`` comes first.
    """

    collisions: int = 25000
    method: str = "event"
    rtol: float = 1e-10
    step: float = 1e-4
    gravity: float = 9.81
    duration: float | None = None

    def __post_init__(self) -> None:
        collisions = self.collisions
        if isinstance(collisions, bool) or not isinstance(collisions, int) or collisions < 1:
            raise _error(
                f"scene key 'run.collisions' must be an integer >= 1, got {_shown(collisions)}"
            )
        _choice("run.method", self.method, METHODS)
        rtol = _number("run.rtol", self.rtol)
        _in_range("run.rtol", rtol, 0.0, 1e-3, low_open=True, high_open=False)
        _set(self, "rtol", rtol)
        _set(self, "step", _positive("run.step", self.step))
        _set(self, "gravity", _positive("run.gravity", self.gravity))
        if self.duration is not None:
            _set(self, "duration", _positive("run.duration", self.duration))


@dataclass(frozen=True)
class Scene:
    """A complete, validated scene. Build it with :func:`load_scene` or
    :func:`scene_from_dict`; change it with :func:`with_values` or :func:`replace`."""

    name: str = "scene"
    description: str = ""
    boundary: Boundary = field(default_factory=Boundary)
    drive: Drive = field(default_factory=Drive)
    ball: Ball = field(default_factory=Ball)
    contact: Contact = field(default_factory=Contact)
    air: Air = field(default_factory=Air)
    initial: Initial = field(default_factory=Initial)
    run: Run = field(default_factory=Run)

    def __post_init__(self) -> None:
        for key in ("name", "description"):
            value = getattr(self, key)
            if not isinstance(value, str):
                raise _error(f"scene key '{key}' must be a string, got {_shown(value)}")
        for key, cls in _SECTIONS.items():
            value = getattr(self, key)
            if not isinstance(value, cls):
                raise _error(f"scene section '{key}' must be a {cls.__name__}, got {_shown(value)}")


_SECTIONS: dict[str, type] = {
    "boundary": Boundary,
    "drive": Drive,
    "ball": Ball,
    "contact": Contact,
    "air": Air,
    "initial": Initial,
    "run": Run,
}
_TOP_LEVEL_KEYS = ("name", "description")
_SECTION_KEYS: dict[str, tuple[str, ...]] = {
    section: tuple(f.name for f in dataclasses.fields(cls)) for section, cls in _SECTIONS.items()
}
_ALL_KEYS: tuple[str, ...] = _TOP_LEVEL_KEYS + tuple(
    f"{section}.{key}" for section, keys in _SECTION_KEYS.items() for key in keys
)


# ----------------------------------------------------------------------------------
# dict <-> scene


def _hint(candidate: str, options: Sequence[str]) -> str:
    close = difflib.get_close_matches(candidate, options, n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


def _unknown_key_hint(section: str | None, key: str) -> str:
    """Hint for an unknown key, first within its section, then anywhere."""
    if section is not None:
        close = difflib.get_close_matches(key, _SECTION_KEYS[section], n=1, cutoff=0.6)
        if close:
            return f"; did you mean '{section}.{close[0]}'?"
    elsewhere = [
        dotted for dotted in _ALL_KEYS if dotted.rsplit(".", 1)[-1] == key and dotted != key
    ]
    if elsewhere:
        return f"; did you mean '{elsewhere[0]}'?"
    dotted = key if section is None else f"{section}.{key}"
    return _hint(dotted, _ALL_KEYS)


def _check_keys(data: Mapping[str, Any]) -> None:
    for key, value in data.items():
        if key in _TOP_LEVEL_KEYS or key in _SECTIONS:
            continue
        if isinstance(value, Mapping):
            hint = _hint(str(key), tuple(_SECTIONS))
            raise _error(f"unknown scene section '{key}'{hint}")
        raise _error(f"unknown scene key '{key}'{_unknown_key_hint(None, str(key))}")
    for section, keys in _SECTION_KEYS.items():
        table = data.get(section, {})
        if not isinstance(table, Mapping):
            raise _error(
                f"scene key '{section}' must be a table ([{section}]), got {_shown(table)}"
            )
        for key in table:
            if key not in keys:
                hint = _unknown_key_hint(section, str(key))
                raise _error(f"unknown scene key '{section}.{key}'{hint}")


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
        raise _error(f"a scene must be a table of sections, got {_shown(data)}")
    _check_keys(data)
    tables: dict[str, dict[str, Any]] = {
        section: dict(data.get(section, {})) for section in _SECTIONS
    }
    if "parameters" in tables["boundary"]:
        parameters = tables["boundary"]["parameters"]
        if not isinstance(parameters, Mapping):
            raise _error(
                f"scene key 'boundary.parameters' must be a table of name = value, "
                f"got {_shown(parameters)}"
            )
        tables["boundary"]["parameters"] = dict(parameters)
    sections: dict[str, Any] = {}
    for section, cls in _SECTIONS.items():
        table = tables[section]
        if cls is Air:
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
    for section in _SECTIONS:
        table = dataclasses.asdict(getattr(scene, section))
        if section == "boundary":
            table["parameters"] = dict(scene.boundary.parameters)
        data[section] = table
    return data


def _apply(data: dict[str, Any], dotted: str, value: Any, what: str) -> None:
    parts = [part.strip() for part in dotted.split(".")]
    if not all(parts):
        raise _error(f"{what}: key {_shown(dotted)} must look like 'section.key'")
    table = data
    for depth, part in enumerate(parts[:-1]):
        child = table.setdefault(part, {})
        if not isinstance(child, dict):
            prefix = ".".join(parts[: depth + 1])
            raise _error(f"{what}: scene key '{prefix}' is not a table")
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
    data = scene_to_dict(scene)
    for dotted, value in changes.items():
        _apply(data, dotted, value, f"change {dotted!r}")
    return scene_from_dict(data, name=scene.name)


def replace(scene: Scene, **section_changes: Any) -> Scene:
    """``dataclasses.replace`` on the scene, e.g. ``replace(scene, initial=Initial(q1=0.01,
    q2=0.02))``; sections validate themselves when constructed."""
    return dataclasses.replace(scene, **section_changes)


# ----------------------------------------------------------------------------------
# TOML


def _toml_string(text: str) -> str:
    escapes = {
        '"': '\\"',
        "\\": "\\\\",
        "\b": "\\b",
        "\t": "\\t",
        "\n": "\\n",
        "\f": "\\f",
        "\r": "\\r",
    }
    out = []
    for ch in text:
        if ch in escapes:
            out.append(escapes[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    return key if _BARE_KEY_RE.fullmatch(key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):  # pragma: no cover - scenes hold finite numbers only
            raise ValueError(f"cannot write the non-finite number {value!r}")
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    raise TypeError(f"cannot write {type(value).__name__} as a TOML value")


_ABSENT_NOTES = {
    "boundary.ceiling": "ceiling: absent, the container has no lid",
    "initial.q1": "q1: absent, resolved by the engine",
    "initial.q2": "q2: absent, resolved by the engine",
    "run.duration": "duration: absent, no limit on simulated time",
}


def scene_to_toml(scene: Scene) -> str:
    """The fully resolved scene as TOML text, every key written.

    Floats are written with :func:`repr`, so reading the text back gives the same
    scene bit for bit: ``scene_from_toml(scene_to_toml(s)) == s``. Keys whose value is
    None (no lid, engine-resolved start position) are written as comments.
    """
    lines = [
        "# Scene file; SI units (m, kg, s, rad).",
        f"name = {_toml_value(scene.name)}",
        f"description = {_toml_value(scene.description)}",
    ]
    data = scene_to_dict(scene)
    for section in _SECTIONS:
        lines += ["", f"[{section}]"]
        table = data[section]
        for key, value in table.items():
            if section == "boundary" and key == "parameters":
                continue
            if value is None:
                lines.append(f"# {_ABSENT_NOTES[f'{section}.{key}']}")
            else:
                lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
        if section == "boundary" and table["parameters"]:
            lines += ["", "[boundary.parameters]"]
            for key, value in table["parameters"].items():
                lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _parse_toml(text: str, source: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _error(f"scene file {source}: invalid TOML: {exc}") from None


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
    return resources.files("billiard.scenes").joinpath(f"{name}.toml")


def builtin_scene_names() -> list[str]:
    """Names of the scenes shipped with the package, sorted."""
    return sorted(
        entry.name.removesuffix(".toml")
        for entry in resources.files("billiard.scenes").iterdir()
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
            raise _error(
                f"scene {str(name_or_path)!r} is neither a built-in scene ({known}) "
                "nor an existing file"
            )
        raise _error(f"scene file '{path}' does not exist")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _error(f"scene file '{path}' is not UTF-8 text: {exc.reason}") from None
    except OSError as exc:
        raise _error(f"scene file '{path}' cannot be read: {exc.strerror or exc}") from None
    return text, f"'{path}'", path.stem


def load_scene(name_or_path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> Scene:
    """Load and validate a built-in scene (by name) or a scene file (by path).

    Args:
        name_or_path: a name from :func:`builtin_scene_names` or the path of a TOML file.
        overrides: ``"section.key=value"`` strings applied before validation, in order.
            The value is read as a TOML value (``0.004``, ``25``, ``"text"``) and, when
            it is not one, taken as a bare string (``drive.direction=vertical``,
            ``boundary.curve=26*x**2 + 0.0063``).

    Raises:
        SceneError: the file is missing or not valid TOML, an override is malformed, or
            the scene is invalid.
    """
    text, source, default_name = _read_scene(name_or_path)
    data = _parse_toml(text, f"{source}")
    for override in overrides:
        if not isinstance(override, str) or "=" not in override:
            raise _error(f"override {_shown(override)} must look like 'section.key=value'")
        dotted, _, value = override.partition("=")
        _apply(data, dotted, _parse_override_value(value), f"override {override!r}")
    return scene_from_dict(data, name=default_name)
