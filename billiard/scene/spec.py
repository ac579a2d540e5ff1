"""The sections of a scene file, as validated specifications.

One frozen dataclass per section: :class:`BoundarySpec`, :class:`DriveSpec`,
:class:`BallSpec`, :class:`ContactSpec`, :class:`AirSpec`, :class:`InitialSpec` and
:class:`RunSpec`. They *specify* a run; the engine builds its runtime objects from them
(:class:`billiard.geometry.boundary.Boundary`, :class:`billiard.geometry.boundary.Drive`,
:class:`billiard.models.impact.Contact`). Each checks its values when constructed (type,
finiteness, the physically sensible ranges of :data:`billiard.scene.checks.LIMITS`, choices,
relations between keys) and raises :class:`~billiard.scene.checks.SceneError` with a one-line
message naming the key. Geometric checks that need the curve itself (the ball's radius
against the curvature, an initial position inside the wall) belong to the engine.

The defaults are the values of the real-world billiard experiment (a 3.1 mm steel ball
on aluminium), with a fixed parabola and the ball at rest at its bottom.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from billiard.derivation.expr import (
    BUILTIN_CURVES,
    CurveExpression,
    CurveExpressionError,
    is_curve_name,
    is_parameter_name,
    parse_curve,
)
from billiard.scene.checks import (
    LIMITS,
    check_choice,
    check_number,
    check_optional_number,
    error,
    limited,
    shown,
)

__all__ = [
    "BUILTIN_CURVES",
    "DRAG_MODELS",
    "DRIVE_DIRECTIONS",
    "LAW_KEYS",
    "LAW_PARAMETERS",
    "MAX_COLLISIONS",
    "METHODS",
    "SECTIONS",
    "AirSpec",
    "BallSpec",
    "BoundarySpec",
    "ContactSpec",
    "DriveSpec",
    "InitialSpec",
    "RunSpec",
    "check_collisions",
    "curve_kind",
    "fowles_coefficients",
]

#: Curves whose generated modules ship with the package.
#: Accepted values of ``drive.direction``.
DRIVE_DIRECTIONS: tuple[str, ...] = ("horizontal", "vertical")
#: Accepted values of ``air.drag``.
DRAG_MODELS: tuple[str, ...] = ("fowles", "none")
#: Accepted values of ``run.method``.
METHODS: tuple[str, ...] = ("event", "rk4")
#: Largest ``run.collisions``: about a day of computing at the engine's usual rate.
MAX_COLLISIONS = 10**9

_DEFAULT_RADIUS = 1.55e-3


def check_collisions(value: Any, name: str = "collisions") -> int:
    """``value`` as a number of impacts: an integer (Python's or numpy's, not a bool) in
    [1, :data:`MAX_COLLISIONS`]; a float, even a whole one, is refused rather than cut
    (``2.5`` must not run 2 impacts).

    Raises:
        SceneError: one line naming ``name`` and the value.
    """
    try:
        count = None if isinstance(value, bool) else operator.index(value)
    except TypeError:
        count = None
    if count is None or count < 1:
        raise error(f"{name} must be an integer >= 1, got {shown(value)}")
    if count > MAX_COLLISIONS:
        raise error(
            f"{name} = {count} is out of range [1, {MAX_COLLISIONS}] (a longer run: extend "
            "it with `billiard run --resume`)"
        )
    return count


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


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class BoundarySpec:
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
            raise error(
                f"scene key 'boundary.curve' must be a curve name or an expression in x, "
                f"got {shown(self.curve)}"
            )
        expression = self.expression  # a bad expression is reported before its parameters
        _set(self, "ceiling", check_optional_number("boundary.ceiling", self.ceiling))
        _set(self, "escape_height", limited("boundary.escape_height", self.escape_height))
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
            raise error(
                f"scene key 'boundary.parameters' must be a table of name = value, got {shown(raw)}"
            )
        values: dict[str, float] = {}
        for pair in pairs:
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise error(
                    f"scene key 'boundary.parameters' must be a table of name = value, "
                    f"got {shown(raw)}"
                )
            name, value = pair
            if not is_parameter_name(name):
                raise error(
                    f"scene key 'boundary.parameters.{name}' is not a valid parameter name "
                    "(an ASCII letter, then up to 30 letters, digits or '_'; not x, pi, a "
                    "function name or a Python keyword)"
                )
            if name in values:
                raise error(f"scene key 'boundary.parameters.{name}' is given twice")
            values[name] = check_number(f"boundary.parameters.{name}", value)
        if expression is not None:
            for name in expression.parameters:
                if name not in values:
                    raise error(
                        f"scene key 'boundary.parameters.{name}' is missing: the curve "
                        f"expression uses the parameter '{name}'"
                    )
            for name in values:
                if name not in expression.parameters:
                    raise error(
                        f"scene key 'boundary.parameters.{name}' is not used by the curve "
                        f"expression {shown(self.curve)}"
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
            raise error(
                f"scene key 'boundary.curve' = {shown(self.curve)} is not a valid curve "
                f"expression: {detail}"
            ) from None

    @property
    def parameter_values(self) -> dict[str, float]:
        """The curve parameters as a new dict name -> value."""
        return dict(self.parameters)


@dataclass(frozen=True)
class DriveSpec:
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
        _set(self, "amplitude", limited("drive.amplitude", self.amplitude))
        _set(self, "frequency", limited("drive.frequency", self.frequency))
        check_choice("drive.direction", self.direction, DRIVE_DIRECTIONS)
        _set(self, "phase", limited("drive.phase", self.phase))
        if self.amplitude > 0.0 and self.frequency == 0.0:
            raise error(
                f"scene key 'drive.frequency' = 0.0 must be > 0 when drive.amplitude = "
                f"{self.amplitude!r} > 0"
            )

    @property
    def omega(self) -> float:
        """Angular frequency 2 pi f (rad/s)."""
        return 2.0 * math.pi * self.frequency


@dataclass(frozen=True)
class BallSpec:
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
        _set(self, "radius", limited("ball.radius", self.radius))
        _set(self, "mass", limited("ball.mass", self.mass))
        _set(self, "inertia_factor", limited("ball.inertia_factor", self.inertia_factor))

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre, k m r^2 (kg m^2)."""
        return self.inertia_factor * self.mass * self.radius**2


@dataclass(frozen=True)
class ContactSpec:
    """Impact law parameters.

    Attributes:
        restitution: Newton's coefficient of restitution e (dimensionless, in [0, 1]);
            for the energy-dependent laws e at high impact energy, for the angle-dependent
            law e at normal incidence; the e of the landing test and of the chatter sum
            (``model = "phases"``) under every law.
        mu_static: static friction coefficient (dimensionless).
        mu_kinetic: kinetic friction coefficient (dimensionless, <= mu_static); Walton's
            mu (both his cone and his sliding impulse).
        elastic_below: relative normal speed (m/s) below which impacts are elastic (e = 1),
            which prevents inelastic collapse. With ``model = "phases"`` it is also the
            landing speed: an impact on a wall that presses the ball, whose rebound
            speed e |wn| would be below it, starts a rolling or sliding phase instead
            (the ball also lands where its chatter series is summed, whatever this is;
            under phases a slow impact is elastic, never a relaunch).
        model: ``"impacts"`` (impacts only, with the paper's low-velocity rule) or
            ``"phases"`` (impacts plus rolling and sliding phases on a wall, see
            :mod:`billiard.models.contact`).
        law: the impact law, a key of :data:`LAW_PARAMETERS` (docs/impact-laws.md);
            ``"kane-levinson"``, the paper's, by default.
        beta0: Walton's tangential restitution of the contact point in a sticking
            impact, in [-1, 1] (``law = "walton"``).
        e_ref: the power law's restitution at the speed v_ref (dimensionless): e(v) =
            min(1, e_ref (v / v_ref)^-exponent), v the normal impact speed
            (``law = "power-law"``).
        v_ref: the power law's reference speed (m/s).
        exponent: the power law's exponent (dimensionless).
        viscous: ((s/m)^(1/5)) the viscoelastic dissipation A alpha^(2/5)
            (``law = "viscoelastic"``).
        energy_scale: E0 (J) of the energy-dependent restitution
            e = restitution + (1 - restitution) exp(-E / E0), E = m wn^2 / 2
            (``law = "energy-dependent"``; optional for ``"point-particle"``).
        angle_slope: the rise of e with the tangent of the angle of incidence,
            e = min(1, restitution + angle_slope |wt| / |wn|) (``law = "angle-dependent"``).
        The parameters of a law other than the scene's are kept and unused.
    """

    restitution: float = 0.393
    mu_static: float = 0.61
    mu_kinetic: float = 0.47
    elastic_below: float = 0.01
    model: str = "phases"
    law: str = "kane-levinson"
    beta0: float | None = None
    e_ref: float | None = None
    v_ref: float | None = None
    exponent: float | None = None
    viscous: float | None = None
    energy_scale: float | None = None
    angle_slope: float | None = None

    def __post_init__(self) -> None:
        _set(self, "restitution", limited("contact.restitution", self.restitution))
        _set(self, "mu_static", limited("contact.mu_static", self.mu_static))
        _set(self, "mu_kinetic", limited("contact.mu_kinetic", self.mu_kinetic))
        if self.mu_kinetic > self.mu_static:
            raise error(
                f"scene key 'contact.mu_kinetic' = {self.mu_kinetic!r} must not exceed "
                f"contact.mu_static = {self.mu_static!r}"
            )
        _set(self, "elastic_below", limited("contact.elastic_below", self.elastic_below))
        check_choice("contact.model", self.model, CONTACT_MODELS)
        check_choice("contact.law", self.law, tuple(LAW_PARAMETERS))
        for key in LAW_KEYS:
            _set(self, key, check_optional_number(f"contact.{key}", getattr(self, key)))
        required, _ = LAW_PARAMETERS[self.law]
        missing = [key for key in required if getattr(self, key) is None]
        if missing:
            needs = ", ".join(_law_key(key) for key in required)
            raise error(
                f"scene key 'contact.law' = {self.law!r} needs {needs}: "
                f"missing {', '.join(f'contact.{key}' for key in missing)}"
            )


def _law_key(key: str) -> str:
    unit = LIMITS[f"contact.{key}"].unit
    return f"contact.{key} ({unit})" if unit else f"contact.{key}"


#: Contact models (``contact.model``).
CONTACT_MODELS = ("impacts", "phases")

#: Impact laws (``contact.law``, docs/impact-laws.md): the [contact] keys each needs
#: and those it may take, beyond restitution, friction and elastic_below
LAW_PARAMETERS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "kane-levinson": ((), ()),
    "walton": (("beta0",), ()),
    "power-law": (("e_ref", "v_ref", "exponent"), ()),
    "viscoelastic": (("viscous",), ()),
    "energy-dependent": (("energy_scale",), ()),
    "angle-dependent": (("angle_slope",), ()),
    "point-particle": ((), ("energy_scale",)),
}
#: every law's own keys, in their order in ContactSpec
LAW_KEYS = ("beta0", "e_ref", "v_ref", "exponent", "viscous", "energy_scale", "angle_slope")


_DEFAULT_C_LIN, _DEFAULT_C_QUAD = fowles_coefficients(_DEFAULT_RADIUS)


@dataclass(frozen=True)
class AirSpec:
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
        check_choice("air.drag", self.drag, DRAG_MODELS)
        _set(self, "c_lin", limited("air.c_lin", self.c_lin))
        _set(self, "c_quad", limited("air.c_quad", self.c_quad))
        _set(self, "magnus", limited("air.magnus", self.magnus))

    @property
    def coefficients(self) -> tuple[float, float]:
        """``(c_lin, c_quad)`` in effect: (0, 0) when ``drag == "none"``."""
        if self.drag == "none":
            return 0.0, 0.0
        return self.c_lin, self.c_quad


@dataclass(frozen=True)
class InitialSpec:
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
        _set(self, "q1", check_optional_number("initial.q1", self.q1))
        _set(self, "q2", check_optional_number("initial.q2", self.q2))
        for name in ("v1", "v2", "omega", "t"):
            _set(self, name, limited(f"initial.{name}", getattr(self, name)))


@dataclass(frozen=True)
class RunSpec:
    """How the run is integrated and when it stops.

    Attributes:
        collisions: number of impacts to simulate (>= 1).
        method: ``"event"`` (event-driven flights) or ``"rk4"`` (fixed-step reference).
        rtol: relative tolerance of the error-controlled flight with drag, in [1e-14, 1e-3].
        step: time step (s) of the ``"rk4"`` method.
        gravity: gravitational acceleration g (m/s^2).
        duration: simulated time (s) after which the run stops, or None for no limit;
            the run ends at whichever of ``collisions`` and ``duration`` comes first.
        contact_span: without ``duration``, simulated time (s) the ball may stay in
            contact with the boundary (rolling, sliding or held) without an impact before
            the run ends (status ``IN_CONTACT``): a run that asks for impacts always ends.
    """

    collisions: int = 25000
    method: str = "event"
    rtol: float = 1e-10
    step: float = 1e-4
    gravity: float = 9.81
    duration: float | None = None
    contact_span: float = 10.0

    def __post_init__(self) -> None:
        _set(self, "collisions", check_collisions(self.collisions, "scene key 'run.collisions'"))
        check_choice("run.method", self.method, METHODS)
        _set(self, "rtol", limited("run.rtol", self.rtol))
        _set(self, "step", limited("run.step", self.step))
        _set(self, "gravity", limited("run.gravity", self.gravity))
        _set(self, "duration", check_optional_number("run.duration", self.duration))
        _set(self, "contact_span", limited("run.contact_span", self.contact_span))


#: Section name -> its dataclass, in file order.
SECTIONS: dict[str, type] = {
    "boundary": BoundarySpec,
    "drive": DriveSpec,
    "ball": BallSpec,
    "contact": ContactSpec,
    "air": AirSpec,
    "initial": InitialSpec,
    "run": RunSpec,
}
