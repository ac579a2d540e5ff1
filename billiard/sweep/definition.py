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
    # changes = ["..."]             # written by the sweep: the `set` already in scene.toml

    [vary]
    "drive.frequency" = "4:7:31"    # a range START:STOP:N
    "drive.amplitude" = [0.02, 0.025, 0.03]   # or a list
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any

from billiard.scene.scene import Scene, SceneError, load_scene
from billiard.scene.userfile import FileRefused, read_limited

__all__ = [
    "Axis",
    "LinearValues",
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
_FILE_KEYS = ("scene", "set", "changes", "vary", *_SETTINGS)

#: Most points a sweep may have at all: the result file numbers them with 32-bit integers,
#: and a billion points of even a millisecond each is eleven days of one core.
MAX_POINTS = 10**9
#: Largest sweep file read (bytes): a list of 100,000 values is about 2 MB.
MAX_FILE_BYTES = 64 * 2**20
#: The period test looks at the last 256 impacts (attractor.find_period's window), so a
#: period can be at most half of that.
MAX_PERIOD = 128


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
        if isinstance(self.values, LinearValues):
            return True
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
        changes: the ``--set`` overrides already applied to ``scene`` (``"KEY=VALUE"``),
            kept to name them in plot titles and the sweep file.
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
    changes: tuple[str, ...] = field(default=(), compare=False)
    settings_order: tuple[str, ...] = field(default=_SETTINGS, repr=False, compare=False)

    def __post_init__(self) -> None:
        from billiard.scene.spec import MAX_COLLISIONS

        # every number is checked here, before any point runs: a value no point can run
        # with (a duration of 1e300 s) would otherwise fail every point one by one
        _check_int("impacts", self.impacts, 1, MAX_COLLISIONS, "impacts")
        _check_int("transient", self.transient, 0, MAX_COLLISIONS, "impacts")
        if self.impacts + self.transient > MAX_COLLISIONS:
            raise SweepError(
                f"sweep settings 'impacts' + 'transient' = {self.impacts + self.transient} "
                f"impacts per point is out of range [1, {MAX_COLLISIONS}] impacts"
            )
        _check_int("keep", self.keep, 1, MAX_COLLISIONS, "impacts")
        _check_int("max_period", self.max_period, 1, MAX_PERIOD, "impacts")
        for name in ("lyapunov", "skip_invalid"):
            if not isinstance(getattr(self, name), bool):
                raise SweepError(
                    f"sweep setting '{name}' must be true or false, got {getattr(self, name)!r}"
                )
        if self.duration is not None:
            from billiard.scene.checks import LIMITS

            limit = LIMITS["run.duration"]  # the scene's own limit on simulated time
            _check_range("duration", self.duration, limit.low, limit.high, limit.unit)
        _check_range("tolerance", self.tolerance, 0.0, 1.0, "m")
        _check_range("rest_band", self.rest_band, 0.0, 10.0, "m")
        _check_range("chaos_threshold", self.chaos_threshold, -100.0, 100.0, "1/impact", True)
        if isinstance(self.changes, list):
            object.__setattr__(self, "changes", tuple(self.changes))
        if not isinstance(self.changes, tuple) or not all(isinstance(c, str) for c in self.changes):
            raise SweepError(f"sweep 'changes' must be \"KEY=VALUE\" strings, got {self.changes!r}")
        if not self.axes:
            raise SweepError("a sweep needs at least one --vary KEY=START:STOP:N")
        keys = [axis.key for axis in self.axes]
        for key in keys:
            if keys.count(key) > 1:
                raise SweepError(f"--vary {key}: the key is swept twice")
        if self.size > MAX_POINTS:
            sizes = " x ".join(f"{n:,}" for n in self.shape)
            raise SweepError(
                f"the sweep has {self.size:,} points ({sizes}); at most {MAX_POINTS:,} can be "
                "swept (and far fewer in reasonable time): use fewer values per --vary"
            )

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

    def points(self) -> Iterator[dict[str, Any]]:
        """All points' swept values, in index order, one at a time (a grid is never held
        in memory whole)."""
        for index in range(self.size):
            yield self.point_values(index)

    def settings(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in _SETTINGS}

    def with_settings(self, **changes: Any) -> Sweep:
        return replace(self, **{k: v for k, v in changes.items() if v is not None})


def _check_number(name: str, value: Any, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(f"sweep setting '{name}' must be a finite number ({unit}), got {value!r}")
    return float(value)


def _check_range(
    name: str, value: Any, low: float, high: float, unit: str, low_closed: bool = False
) -> None:
    """A finite number in (low, high] (or [low, high]) of ``unit``."""
    number = _check_number(name, value, unit)
    if (number < low if low_closed else number <= low) or number > high:
        left = "[" if low_closed else "("
        raise SweepError(
            f"sweep setting '{name}' = {value!r} {unit} is out of range "
            f"{left}{low:g}, {high:g}] {unit}"
        )


def _check_int(name: str, value: Any, low: int, high: int, unit: str) -> None:
    if isinstance(value, bool) or not isinstance(value, int):
        raise SweepError(f"sweep setting '{name}' must be an integer >= {low}, got {value!r}")
    if value < low:
        raise SweepError(f"sweep setting '{name}' must be an integer >= {low}, got {value!r}")
    if value > high:
        raise SweepError(
            f"sweep setting '{name}' = {value} {unit} is out of range [{low}, {high:,}] {unit}"
        )


class LinearValues(Sequence[float]):
    """The values of ``START:STOP:N`` computed when asked for, never all held (a
    million-point axis costs nothing until its points run).

    Value i is the float nearest to the exact decimal ``START + i (STOP - START) / (N - 1)``
    of the decimals START and STOP stand for (their shortest ``repr``, the text typed):
    the grid's own values, so ``0.02:0.03:11`` holds ``0.027`` (``float("0.027")``), not
    ``0.02 + 7 * 0.001 = 0.027000000000000003``, and a result selected by the value asked
    for finds it. The first value is START and the last STOP exactly.
    """

    def __init__(self, start: float, stop: float, num: int):
        self.start, self.stop, self.num = float(start), float(stop), int(num)
        a, b = Fraction(repr(self.start)), Fraction(repr(self.stop))
        steps = max(self.num - 1, 1)
        # value i = (first + i * rise) / over, in integers: Python's int / int is the
        # correctly rounded quotient, so each value is the float nearest the exact one
        self._over = a.denominator * b.denominator * steps
        self._first = a.numerator * b.denominator * steps
        self._rise = b.numerator * a.denominator - a.numerator * b.denominator

    def __len__(self) -> int:
        return self.num

    def _value(self, i: int) -> float:
        return (self._first + i * self._rise) / self._over

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return tuple(self._value(k) for k in range(*i.indices(self.num)))
        i = int(i)
        if i < 0:
            i += self.num
        if not 0 <= i < self.num:
            raise IndexError("axis value index out of range")
        return self._value(i)

    def __array__(self, dtype: Any = None, copy: Any = None) -> Any:
        import numpy as np

        out = np.fromiter(map(self._value, range(self.num)), dtype=float, count=self.num)
        return out if dtype is None else out.astype(dtype)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, LinearValues):
            return (self.start, self.stop, self.num) == (other.start, other.stop, other.num)
        if isinstance(other, Sequence) and not isinstance(other, str):
            return len(other) == self.num and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    def __hash__(self) -> int:  # equal to the tuple it equals, so hashed as that tuple
        return hash(tuple(self))

    def __repr__(self) -> str:
        return f"LinearValues({self.start!r}, {self.stop!r}, {self.num})"


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


def _range(key: str, spec: str) -> tuple[float, ...] | LinearValues:
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
    if num > MAX_POINTS:
        raise SweepError(f"{where}: N = {num:,} points; at most {MAX_POINTS:,} can be swept")
    if num == 1:
        if start != stop:
            raise SweepError(f"{where}: one point cannot span {start:g} to {stop:g}; use N >= 2")
        return (start,)
    if start == stop:
        raise SweepError(f"{where}: empty range (START = STOP) with N = {num} repeats one value")
    return LinearValues(start, stop, num)


def parse_values(key: str, spec: Any) -> tuple[Any, ...] | LinearValues:
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
    seen: set[Any] = set()  # 4 and 4.0 are the same value here, as they compare equal
    for value in values:
        if value in seen:
            raise SweepError(f"{where}: the value {value!r} is given twice")
        seen.add(value)
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
    from billiard.scene.scene import with_values

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
    if sweep.changes:
        lines += [
            "# the --set changes of the base scene, already applied in the scene file",
            f"changes = {_toml_value(list(sweep.changes))}",
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
        data = tomllib.loads(_read_text(path))
    except (tomllib.TOMLDecodeError, OSError, UnicodeDecodeError, SweepError):
        return False
    return isinstance(data.get("vary"), Mapping)


def _read_text(path: Path) -> str:
    """A regular file's text, refused (SweepError) beyond MAX_FILE_BYTES: never read an
    endless or huge file (``/dev/zero``, a FIFO) into memory."""
    try:
        data = read_limited(path, MAX_FILE_BYTES)
    except FileRefused as exc:
        raise SweepError(f"sweep file '{path}' {exc.reason}: not a sweep file") from None
    return data.decode("utf-8")


def read_sweep_file(
    path: str | Path, extra_overrides: Sequence[str] = ()
) -> tuple[Scene, list[Axis], dict[str, Any], list[str]]:
    """A sweep file's base scene, axes and settings, and its ``set`` overrides.

    Args:
        path: the sweep file.
        extra_overrides: more ``"KEY=VALUE"`` overrides, applied after the file's.

    Returns:
        ``(scene, axes, settings, overrides)``; the scene has the overrides applied;
        ``overrides`` starts with the file's ``changes`` (overrides already applied to
        its scene file, by the sweep that wrote it), which are not applied again.
    """
    path = Path(path)
    try:
        data = tomllib.loads(_read_text(path))
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
    changes = data.get("changes", [])
    if not isinstance(changes, list) or not all(isinstance(o, str) for o in changes):
        raise SweepError(f"sweep file '{path}': 'changes' must be a list of \"KEY=VALUE\" strings")
    overrides = [*overrides, *extra_overrides]
    scene = load_base_scene(data["scene"], overrides, relative_to=path.parent)
    vary = data.get("vary", {})
    if not isinstance(vary, Mapping):
        raise SweepError(f"sweep file '{path}': 'vary' must be a table of KEY = values")
    axes = [Axis(key, parse_values(key, spec)) for key, spec in vary.items()]
    settings = {k: data[k] for k in _SETTINGS if k in data}
    return scene, axes, settings, [*changes, *overrides]


def load_base_scene(name: str, overrides: Sequence[str], relative_to: Path | None = None) -> Scene:
    """A built-in scene or a scene file (relative to ``relative_to`` when given), with
    ``overrides`` (``"KEY=VALUE"``) applied."""
    from billiard.scene.scene import builtin_scene_names

    if relative_to is not None and name not in builtin_scene_names():
        name = str(relative_to / name)
    return load_scene(name, overrides=list(overrides))
