"""Checks of scene values: types, finiteness, physically sensible ranges, choices.

Every failed check raises :class:`SceneError` with a one-line message that names the
dotted scene key, the value, and (for ranges) the accepted interval with its unit, e.g.
``scene key 'drive.frequency' = 1000000000.0 Hz is out of range (0, 1000] Hz``.

The bounds themselves, and why a physicist would accept them for this tabletop billiard,
are in :data:`LIMITS`.
"""

from __future__ import annotations

import difflib
import math
import os
from collections.abc import Sequence
from typing import Any, NamedTuple

__all__ = [
    "LIMITS",
    "Limit",
    "SceneError",
    "check_choice",
    "check_name",
    "check_number",
    "check_optional_number",
    "error",
    "limited",
    "shown",
]

_MAX_SHOWN = 60


class SceneError(ValueError):
    """An invalid scene; the message is one line and names the offending key."""


def error(message: str) -> SceneError:
    """A :class:`SceneError` whose message is kept on one line."""
    return SceneError(message.replace("\r", "\\r").replace("\n", "\\n"))


def shown(value: Any) -> str:
    """``repr(value)``, shortened for a one-line message."""
    text = repr(value)
    if len(text) > _MAX_SHOWN:
        text = text[: _MAX_SHOWN - 3] + "..."
    return text


class Limit(NamedTuple):
    """Accepted interval of a scene key, with its unit ("" for a dimensionless one)."""

    low: float
    high: float
    unit: str
    low_open: bool = False
    high_open: bool = False


# The ball is a few millimetres across, the container a few centimetres to decimetres,
# the drive a few hertz and centimetres. The bounds below are generous for any tabletop
# version of the experiment and still catch unit mistakes (millimetres typed as metres,
# degrees as radians, a frequency in rad/s typed as Hz) and values that cannot be meant.
LIMITS: dict[str, Limit] = {
    # lengths of the container: a tabletop apparatus is well under a metre tall;
    # 10 m leaves room for exploration, an escape height up to 100 m for thrown balls
    "boundary.ceiling": Limit(0.0, 10.0, "m", low_open=True),
    "boundary.escape_height": Limit(0.0, 100.0, "m", low_open=True),
    # a shaker (loudspeaker, motor, vibration table) moves by at most about a metre,
    # at no more than about a kilohertz; above that the ball no longer bounces in a
    # rigid container (the walls' own vibrations take over)
    "drive.amplitude": Limit(0.0, 1.0, "m"),
    "drive.frequency": Limit(0.0, 1000.0, "Hz"),
    # one turn either way gives every phase; 90 is degrees typed as radians
    "drive.phase": Limit(-math.tau, math.tau, "rad"),
    # up to 0.1 m (a bowling ball), down to the point-particle limit (validation runs
    # compare a 0.1 um ball with the billiard map of a point); the heaviest 0.1 m ball
    # (tungsten) has 80 kg
    "ball.radius": Limit(0.0, 0.1, "m", low_open=True),
    "ball.mass": Limit(0.0, 100.0, "kg", low_open=True),
    # I = k m r^2: 0 < k <= 1 (all the mass on the surface of a sphere is 2/3; a ring 1)
    "ball.inertia_factor": Limit(0.0, 1.0, "", low_open=True),
    # Newton's restitution is between 0 (plastic) and 1 (elastic); Coulomb friction of
    # hard contacts stays below about 1.5, soft rubber reaches 2-3: 5 is ample
    "contact.restitution": Limit(0.0, 1.0, ""),
    "contact.mu_static": Limit(0.0, 5.0, ""),
    "contact.mu_kinetic": Limit(0.0, 5.0, ""),
    # the low-velocity rule is for micro-bounces (mm/s to cm/s); at 1 m/s and above it
    # would make ordinary impacts elastic
    "contact.elastic_below": Limit(0.0, 1.0, "m/s"),
    # the impact laws' own parameters (docs/impact-laws.md): Walton's beta0 runs from a
    # smooth sphere (-1) to a perfectly rough one (1); a power law's exponent is 1/4 and
    # less for metals (0 is constant e); the viscoelastic A alpha^(2/5) of steel is about
    # 0.1 (s/m)^(1/5); a 3 mm steel ball at 1 m/s carries 6.5e-5 J
    "contact.beta0": Limit(-1.0, 1.0, ""),
    "contact.e_ref": Limit(0.0, 1.0, ""),
    "contact.v_ref": Limit(0.0, 100.0, "m/s", low_open=True),
    "contact.exponent": Limit(0.0, 1.0, ""),
    "contact.viscous": Limit(0.0, 10.0, "(s/m)^(1/5)"),
    "contact.energy_scale": Limit(0.0, 1.0, "J", low_open=True),
    "contact.angle_slope": Limit(0.0, 10.0, ""),
    # Fowles' coefficients of a 0.2 m sphere are c_lin 3e-5 N s/m and c_quad 9e-3
    # N s^2/m^2 and its Magnus coefficient (~ air density r^3) 1e-3 kg: 1 allows a
    # hundred times more (a denser fluid) and catches unit slips
    "air.c_lin": Limit(0.0, 1.0, "N s/m"),
    "air.c_quad": Limit(0.0, 1.0, "N s^2/m^2"),
    "air.magnus": Limit(0.0, 1.0, "kg"),
    # the start: inside a container of at most 10 m, thrown at most at 100 m/s (a bullet
    # is faster, a thrown ball is not), spinning at most at 1e5 rad/s (1 million rpm; r
    # omega of a 3 mm ball is then 155 m/s); a start time within about 11 days
    "initial.q1": Limit(-10.0, 10.0, "m"),
    "initial.q2": Limit(-10.0, 10.0, "m"),
    "initial.v1": Limit(-100.0, 100.0, "m/s"),
    "initial.v2": Limit(-100.0, 100.0, "m/s"),
    "initial.omega": Limit(-1e5, 1e5, "rad/s"),
    "initial.t": Limit(-1e6, 1e6, "s"),
    # a tolerance below 1e-14 is below double rounding (2.2e-16) times the error
    # estimate's own noise: the step control would never accept a step
    "run.rtol": Limit(1e-14, 1e-3, ""),
    # the rk4 step: a flight lasts milliseconds to a second; a step above 0.1 s skips
    # whole flights, one below 1e-7 s needs millions of steps per flight
    "run.step": Limit(1e-7, 0.1, "s"),
    # from a small asteroid's surface to ten times the Earth's
    "run.gravity": Limit(0.0, 100.0, "m/s^2", low_open=True),
    # simulated time: up to about 30 years
    "run.duration": Limit(0.0, 1e9, "s", low_open=True),
    # time without an impact after which a run that asked for impacts ends (the ball
    # rolls, slides or is held): from a millisecond to a day
    "run.contact_span": Limit(1e-3, 86400.0, "s"),
}


def check_number(key: str, value: Any) -> float:
    """A finite real number; ints are accepted and converted, bools are not numbers."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(
            f"scene key '{key}' must be a number, got {shown(value)} ({type(value).__name__})"
        )
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise error(f"scene key '{key}' = {shown(value)} is not a finite number")
    return number


def check_optional_number(key: str, value: Any) -> float | None:
    """None, or :func:`limited` of the value."""
    return None if value is None else limited(key, value)


def _bound(value: float) -> str:
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:g}"


def limited(key: str, value: Any) -> float:
    """A finite number inside the key's :data:`LIMITS` interval."""
    number = check_number(key, value)
    limit = LIMITS[key]
    below = number <= limit.low if limit.low_open else number < limit.low
    above = number >= limit.high if limit.high_open else number > limit.high
    if below or above:
        left = "(" if limit.low_open else "["
        right = ")" if limit.high_open else "]"
        unit = f" {limit.unit}" if limit.unit else ""
        interval = f"{left}{_bound(limit.low)}, {_bound(limit.high)}{right}"
        raise error(f"scene key '{key}' = {number!r}{unit} is out of range {interval}{unit}")
    return number


def check_choice(key: str, value: Any, choices: Sequence[str]) -> str:
    """One of ``choices``, with a "did you mean" hint for a near miss."""
    allowed = ", ".join(f"'{choice}'" for choice in choices)
    if not isinstance(value, str) or value not in choices:
        hint = ""
        if isinstance(value, str):
            close = difflib.get_close_matches(value, choices, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
        raise error(f"scene key '{key}' = {shown(value)} must be one of {allowed}{hint}")
    return value


_MAX_NAME = 100


def check_name(name: Any) -> str:
    """A scene name: it names the run folder ``runs/<name>``, so it must be one safe
    path component (not empty, not ``.`` or ``..``, no ``/`` or ``\\``, no control
    characters, no leading or trailing blanks, at most 100 characters)."""
    if not isinstance(name, str):
        raise error(f"scene key 'name' must be a string, got {shown(name)}")
    problem = None
    if not name:
        problem = "is empty"
    elif name in (".", ".."):
        problem = "is a reference to a folder"
    elif "/" in name or "\\" in name or (os.altsep and os.altsep in name):
        problem = "contains a path separator"
    elif any(ord(ch) < 0x20 or ord(ch) == 0x7F for ch in name):
        problem = "contains a control character"
    elif name != name.strip():
        problem = "starts or ends with a blank"
    elif len(name) > _MAX_NAME:
        problem = f"is longer than {_MAX_NAME} characters"
    if problem is not None:
        raise error(
            f"scene key 'name' = {shown(name)} {problem}; it names the run folder "
            "runs/NAME and must be a single folder name such as 'my-scene'"
        )
    return name
