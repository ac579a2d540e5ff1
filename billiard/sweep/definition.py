"""What a sweep is: a base scene, the axes it varies and how each point is measured.

An axis is one dotted scene key and its values, from ``KEY=START:STOP:N`` (N values from
START to STOP, both included; a descending range runs downwards) or ``KEY=v1,v2,v3``.
Several axes make a grid (their Cartesian product); point 0 takes every axis' first
value and the last axis varies fastest.

A sweep is written to (and read back from) a sweep file, TOML::

    scene = "parabola-5.4hz"        # a built-in scene, or a scene file relative to this file
    set = ["air.drag=none"]         # optional overrides of the scene, as `--set`
    impacts = 2000                  # impacts measured per point, after the transient
    transient = 500                 # impacts simulated first and not measured
    keep = 100                      # last impact heights and times of flight stored
    lyapunov = false                # largest Lyapunov exponent per point (costs more)
    # duration = 60.0               # s of simulated time per point at most (optional)

    [vary]
    "drive.frequency" = "4:7:31"    # a range START:STOP:N
    "drive.amplitude" = [0.02, 0.025, 0.03]   # or a list
"""

from __future__ import annotations

import itertools
import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from billiard.scene import Scene, SceneError, load_scene

__all__ = [
    "Axis",
    "Sweep",
    "SweepError",
    "parse_vary",
    "read_sweep_file",
    "sweep_to_toml",
]

#: Defaults of the per-point measurement.
DEFAULTS: dict[str, Any] = {
    "impacts": 2000,
    "transient": 500,
    "keep": 100,
    "lyapunov": False,
    "duration": None,
    "tolerance": 1e-5,
    "rest_band": 0.01,
    "max_period": 64,
    "chaos_threshold": 0.01,
    "skip_invalid": False,
}
_SETTINGS = tuple(DEFAULTS)
_FILE_KEYS = ("scene", "set", "vary", *_SETTINGS)


class SweepError(ValueError):
    """A sweep that cannot run; the message is one line and names the key or point."""


@dataclass(frozen=True)
class Axis:
    """One swept scene key.

    Attributes:
        key: dotted scene key, e.g. ``"drive.frequency"`` or ``"initial.q1"``.
        values: the values in sweep order (numbers, or strings for keys such as
            ``air.drag``).
    """

    key: str
    values: tuple[Any, ...]

    @property
    def numeric(self) -> bool:
        return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in self.values)


@dataclass(frozen=True)
class Sweep:
    """A complete sweep definition.

    Attributes:
        scene: the base scene (every ``--set`` applied), fully resolved.
        axes: the swept keys, outermost first.
        impacts: impacts measured per point after the transient (>= 1).
        transient: impacts simulated first and not measured (>= 0).
        keep: last K impact heights and times of flight stored per point (>= 1).
        lyapunov: also estimate the largest Lyapunov exponent per point.
        duration: simulated time per point at most (s), or None.
        tolerance: two post-impact states are the same state when they differ by less
            than this (m, in the scaled state of :mod:`billiard.sweep.attractor`).
        rest_band: a ball that never rises more than this above its resting height (m)
            while most impacts are low-velocity-rule impacts is resting.
        max_period: longest period looked for (impacts).
        chaos_threshold: a non-periodic point with a Lyapunov exponent above this (per
            impact) is chaotic, otherwise quasi-periodic.
        skip_invalid: record points whose scene is invalid as ``invalid`` instead of
            refusing the sweep (kept in the sweep file, so a resumed sweep does the same).
    """

    scene: Scene
    axes: tuple[Axis, ...]
    impacts: int = DEFAULTS["impacts"]
    transient: int = DEFAULTS["transient"]
    keep: int = DEFAULTS["keep"]
    lyapunov: bool = DEFAULTS["lyapunov"]
    duration: float | None = DEFAULTS["duration"]
    tolerance: float = DEFAULTS["tolerance"]
    rest_band: float = DEFAULTS["rest_band"]
    max_period: int = DEFAULTS["max_period"]
    chaos_threshold: float = DEFAULTS["chaos_threshold"]
    skip_invalid: bool = DEFAULTS["skip_invalid"]
    settings_order: tuple[str, ...] = field(default=_SETTINGS, repr=False, compare=False)

    def __post_init__(self) -> None:
        _check_int("impacts", self.impacts, 1)
        _check_int("transient", self.transient, 0)
        _check_int("keep", self.keep, 1)
        _check_int("max_period", self.max_period, 1)
        for name in ("lyapunov", "skip_invalid"):
            if not isinstance(getattr(self, name), bool):
                raise SweepError(
                    f"sweep setting '{name}' must be true or false, got {getattr(self, name)!r}"
                )
        if self.duration is not None:
            _check_positive("duration", self.duration)
        _check_positive("tolerance", self.tolerance)
        _check_positive("rest_band", self.rest_band)
        _check_number("chaos_threshold", self.chaos_threshold)
        if not self.axes:
            raise SweepError("a sweep needs at least one --vary KEY=START:STOP:N")
        keys = [axis.key for axis in self.axes]
        for key in keys:
            if keys.count(key) > 1:
                raise SweepError(f"--vary {key}: the key is swept twice")

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(axis.values) for axis in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def point_values(self, index: int) -> dict[str, Any]:
        """The swept keys' values at point ``index`` (C order: the last axis fastest)."""
        values: dict[str, Any] = {}
        for axis, size in zip(reversed(self.axes), reversed(self.shape), strict=True):
            index, position = divmod(index, size)
            values[axis.key] = axis.values[position]
        return {axis.key: values[axis.key] for axis in self.axes}

    def points(self) -> list[dict[str, Any]]:
        """All points' swept values, in index order."""
        grid = itertools.product(*(axis.values for axis in self.axes))
        return [dict(zip((a.key for a in self.axes), combo, strict=True)) for combo in grid]

    def settings(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in _SETTINGS}

    def with_settings(self, **changes: Any) -> Sweep:
        return replace(self, **{k: v for k, v in changes.items() if v is not None})


def _check_number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(f"sweep setting '{name}' must be a finite number, got {value!r}")
    return float(value)


def _check_positive(name: str, value: Any) -> None:
    if _check_number(name, value) <= 0.0:
        raise SweepError(f"sweep setting '{name}' must be > 0, got {value!r}")


def _check_int(name: str, value: Any, low: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise SweepError(f"sweep setting '{name}' must be an integer >= {low}, got {value!r}")


# ----------------------------------------------------------------------------------------
# axes


def _scalar(text: str) -> Any:
    """A TOML value (``4``, ``0.02``, ``"x"``), or the bare text (``fowles``)."""
    text = text.strip()
    try:
        parsed = tomllib.loads(f"value = {text}")
    except tomllib.TOMLDecodeError:
        return text
    return parsed["value"]


def _range(key: str, spec: str) -> tuple[float, ...]:
    start_text, stop_text, num_text = spec.split(":")
    where = f"--vary {key}={spec}"
    try:
        start, stop = float(start_text), float(stop_text)
    except ValueError:
        raise SweepError(f"{where}: START and STOP must be numbers") from None
    try:
        num = int(num_text)
    except ValueError:
        raise SweepError(f"{where}: N must be a whole number of points") from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise SweepError(f"{where}: START and STOP must be finite")
    if num < 1:
        raise SweepError(f"{where}: N = {num} points; it must be >= 1")
    if num == 1:
        if start != stop:
            raise SweepError(f"{where}: one point cannot span {start:g} to {stop:g}; use N >= 2")
        return (start,)
    if start == stop:
        raise SweepError(f"{where}: empty range (START = STOP) with N = {num} repeats one value")
    step = (stop - start) / (num - 1)
    values = [start + i * step for i in range(num - 1)] + [stop]
    return tuple(values)


def parse_values(key: str, spec: Any) -> tuple[Any, ...]:
    """The values of an axis from ``START:STOP:N``, ``v1,v2,...`` or a TOML list."""
    if isinstance(spec, (list, tuple)):
        values = tuple(spec)
        where = f"vary {key!r}"
    elif isinstance(spec, str):
        where = f"--vary {key}={spec}"
        if not spec.strip():
            raise SweepError(f"{where}: no values (give START:STOP:N or v1,v2,...)")
        if spec.count(":") == 2:
            return _range(key, spec)
        parts = spec.split(",")
        if any(not p.strip() for p in parts):
            raise SweepError(f"{where}: an empty value in the list")
        values = tuple(_scalar(p) for p in parts)
    else:
        raise SweepError(
            f"vary {key!r}: expected 'START:STOP:N', 'v1,v2,...' or a list, got {spec!r}"
        )
    if not values:
        raise SweepError(f"{where}: no values (give START:STOP:N or v1,v2,...)")
    for value in values:
        if isinstance(value, float) and not math.isfinite(value):
            raise SweepError(f"{where}: {value!r} is not a finite number")
        if not isinstance(value, (int, float, str)):
            raise SweepError(f"{where}: {value!r} is neither a number nor a string")
    seen: list[Any] = []
    for value in values:
        if value in seen:
            raise SweepError(f"{where}: the value {value!r} is given twice")
        seen.append(value)
    return values


def parse_vary(text: str) -> Axis:
    """An axis from the command line's ``KEY=START:STOP:N`` or ``KEY=v1,v2,...``."""
    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SweepError(f"--vary {text!r}: expected KEY=START:STOP:N or KEY=v1,v2,...")
    return Axis(key, parse_values(key, spec))


def check_keys(scene: Scene, axes: Sequence[Axis]) -> None:
    """Refuse an axis whose key is not a scene key (with the scene's did-you-mean hint)."""
    from billiard.scene import with_values

    for axis in axes:
        if axis.key in ("name", "description"):
            raise SweepError(f"--vary {axis.key}: only keys of the scene's sections can be swept")
        try:
            with_values(scene, {axis.key: axis.values[0]})
        except SceneError as exc:
            message = str(exc)
            if "unknown scene" in message or "must look like" in message:
                raise SweepError(f"--vary {axis.key}: {message}") from None
            # a bad value is reported later, naming its point


# ----------------------------------------------------------------------------------------
# sweep files


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} in a sweep file")


def sweep_to_toml(sweep: Sweep, scene_file: str = "scene.toml") -> str:
    """The sweep as a sweep file whose scene is ``scene_file`` (written beside it); every
    value is explicit, floats with :func:`repr`, so reading it back gives the same
    sweep bit for bit."""
    lines = [
        "# Sweep definition (SI units); `billiard sweep --resume DIR` continues it and",
        "# `billiard sweep THIS_FILE --out OTHER` runs it again.",
        f"scene = {_toml_value(scene_file)}",
    ]
    for name, value in sweep.settings().items():
        if value is None:
            lines.append(f"# {name}: absent")
        else:
            lines.append(f"{name} = {_toml_value(value)}")
    lines += ["", "[vary]"]
    for axis in sweep.axes:
        lines.append(f"{_toml_value(axis.key)} = {_toml_value(list(axis.values))}")
    return "\n".join(lines) + "\n"


def is_sweep_file(path: str | Path) -> bool:
    """A TOML file with a top-level ``vary`` table is a sweep file (a scene file has none)."""
    path = Path(path)
    if path.suffix != ".toml" or not path.is_file():
        return False
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, OSError, UnicodeDecodeError):
        return False
    return isinstance(data.get("vary"), Mapping)


def read_sweep_file(
    path: str | Path, extra_overrides: Sequence[str] = ()
) -> tuple[Scene, list[Axis], dict[str, Any], list[str]]:
    """A sweep file's base scene, axes and settings, and its ``set`` overrides.

    Args:
        path: the sweep file.
        extra_overrides: more ``"KEY=VALUE"`` overrides, applied after the file's.

    Returns:
        ``(scene, axes, settings, overrides)``; the scene has the overrides applied.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SweepError(f"sweep file '{path}' cannot be read: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SweepError(f"sweep file '{path}': invalid TOML: {exc}") from None
    for key in data:
        if key not in _FILE_KEYS:
            import difflib

            close = difflib.get_close_matches(key, _FILE_KEYS, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise SweepError(f"sweep file '{path}': unknown key '{key}'{hint}")
    if "scene" not in data or not isinstance(data["scene"], str):
        raise SweepError(f"sweep file '{path}': 'scene' (a built-in name or a file) is missing")
    overrides = data.get("set", [])
    if not isinstance(overrides, list) or not all(isinstance(o, str) for o in overrides):
        raise SweepError(f"sweep file '{path}': 'set' must be a list of \"KEY=VALUE\" strings")
    overrides = [*overrides, *extra_overrides]
    scene = load_base_scene(data["scene"], overrides, relative_to=path.parent)
    vary = data.get("vary", {})
    if not isinstance(vary, Mapping):
        raise SweepError(f"sweep file '{path}': 'vary' must be a table of KEY = values")
    axes = [Axis(key, parse_values(key, spec)) for key, spec in vary.items()]
    settings = {k: data[k] for k in _SETTINGS if k in data}
    return scene, axes, settings, list(overrides)


def load_base_scene(name: str, overrides: Sequence[str], relative_to: Path | None = None) -> Scene:
    """A built-in scene or a scene file (relative to ``relative_to`` when given), with
    ``overrides`` (``"KEY=VALUE"``) applied."""
    from billiard.scene import builtin_scene_names

    if relative_to is not None and name not in builtin_scene_names():
        name = str(relative_to / name)
    return load_scene(name, overrides=list(overrides))
