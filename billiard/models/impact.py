"""Impact laws: the jump of the ball's speeds when it hits the moving boundary.

An impact law takes the ball's speeds just before the impact and a :class:`Contact`
(tangent angle and boundary velocity at the contact point) and returns an
:class:`ImpactResult`. :class:`KaneLevinsonImpact` is the paper's law.

A law runs compiled because the kernels have it: a kernel function chosen by its kind
(``IM_KIND``, :func:`billiard.kernels.impact.impact_law`), and here a class that names
that ``kind``, writes its block of the state vector (``write``) and is built from a
scene (``from_scene``), registered in :data:`IMPACT_LAWS`. A law with an ``apply``
method alone has no kernel: :func:`billiard.models.kinds.require_kernel` refuses it.
"""

from __future__ import annotations

from collections.abc import Mapping, MutableSequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Protocol

from billiard.kernels.interpreted import impact as _impact
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.names import copy, new_ctx, read, write
from billiard.scene.scene import with_values
from billiard.scene.spec import LAW_PARAMETERS

__all__ = [
    "IMPACT_LAWS",
    "Contact",
    "ImpactLaw",
    "ImpactResult",
    "AngleDependentImpact",
    "EnergyDependentImpact",
    "KaneLevinsonImpact",
    "PointParticleImpact",
    "PowerLawImpact",
    "ViscoelasticImpact",
    "WaltonImpact",
    "LowVelocityRule",
    "REGIME_RTOL",
    "impact_law",
    "with_law",
]

STICK = "stick"
SLIP = "slip"
ELASTIC = "elastic"

#: Relative tolerance of the friction-cone test |Rt| <= mu_s Rn (see
#: billiard/kernels/impact.py): 16 ulps of the momenta that enter the impulses.
REGIME_RTOL = _impact.REGIME_RTOL


@dataclass(frozen=True, slots=True)
class Contact:
    """Where and how the ball touches the boundary.

    Attributes:
        z: tangent angle of the boundary at the contact point (rad); pi for the lid.
        vb1, vb2: lab-frame velocity of the boundary (m/s).
        pressing: the ball's acceleration relative to the boundary points into the
            surface (it would stay in contact rather than fly off on its own).
    """

    z: float
    vb1: float
    vb2: float
    pressing: bool = False


@dataclass(frozen=True, slots=True)
class ImpactResult:
    """Speeds just after an impact and the impulse that produced them.

    Attributes:
        u1, u2: lab velocity of the centre (m/s); u3: spin (rad/s).
        Rt, Rn: impulse on the ball along c1 and c2 (N s).
        regime: ``"stick"``, ``"slip"`` or ``"elastic"`` (the low-velocity rule).
        wt, wn: velocity of the ball's contact point relative to the boundary just
            before the impact, along c1 and c2 (m/s; wn < 0 when approaching).
        resting: the low-velocity rule met a ball lying on the surface (see
            :class:`KaneLevinsonImpact`).
    """

    u1: float
    u2: float
    u3: float
    Rt: float
    Rn: float
    regime: str
    wt: float
    wn: float
    resting: bool = False


class ImpactLaw(Protocol):
    """What the engine needs of an impact law: the regimes it reports (an open set; the
    summary, plots and audits read them from here) and the jump of the speeds."""

    regimes: tuple[str, ...]

    def apply(self, state: Any, contact: Contact) -> ImpactResult: ...


class LowVelocityRule:
    """The paper's low-velocity rule, a policy of the impact law (after Luding): an
    impact whose relative normal speed |wn| is below ``threshold`` (m/s) is elastic
    (e = 1), which prevents inelastic collapse.

    A ball *lying* on the surface (|wn| below the threshold while its relative
    acceleration presses it into the surface, e.g. at rest at the bottom of a shaken
    container) cannot be lifted by any restitution, as there is nothing to reflect. For
    it the impact is evaluated as if the ball approached at ``threshold``: it leaves at
    that speed, and the ensuing micro-bounces, each carrying its friction impulse, stand
    in for the rolling or sliding contact that the impact-only model lacks. The paper's
    fixed time step plays the same role implicitly. ``threshold = 0`` disables the rule.
    Applied by :func:`billiard.kernels.impact.kane_levinson`.
    """

    def __init__(self, threshold: float):
        self.threshold = float(threshold)


def _slot(name: str, doc: str) -> property:
    """An attribute of the law kept in its state vector's quantity ``name``."""

    def get(self: KaneLevinsonImpact) -> float:
        return read(self.ctx, name)

    def set(self: KaneLevinsonImpact, value: float) -> None:
        write(self.ctx, name, float(value))

    return property(get, set, doc=doc)


class KaneLevinsonImpact:
    """Kane and Levinson's impact theory with a moving boundary (generated maps).

    Newton restitution on the contact point's normal velocity relative to the boundary.
    The no-slip solution is tried first and kept if its impulse lies in the static
    friction cone, |Rt| <= mu_s Rn (up to rounding: :data:`REGIME_RTOL`); otherwise the
    ball slips with Rt = -mu_k Rn sign(wt).
    Slow impacts follow the :class:`LowVelocityRule` (regime ``"elastic"``).

    The law is :func:`billiard.kernels.impact.kane_levinson` (run interpreted), its
    coefficients the slots of a state vector ``ctx`` in the kernels' layout.

    Args:
        mass, radius, inertia_factor: the ball (kg, m, I / (m r^2)).
        restitution, mu_static, mu_kinetic: contact coefficients.
        elastic_below: threshold of the low-velocity rule (m/s); 0 disables it.
        parameters: the law's own, by their ``[contact]`` keys
            (:data:`billiard.scene.spec.LAW_PARAMETERS`; none for this law).
    """

    regimes: tuple[str, ...] = (STICK, SLIP, ELASTIC)
    #: the kernels' code of this law (``IM_KIND``)
    kind: float = _L.KANE_LEVINSON

    m = _slot("impact.mass", "mass (kg)")
    r = _slot("impact.radius", "radius (m)")
    k = _slot("impact.inertia_factor", "inertia factor I / (m r^2)")
    e = _slot("impact.restitution", "restitution")
    mu_s = _slot("impact.mu_static", "static friction")
    mu_k = _slot("impact.mu_kinetic", "kinetic friction")
    elastic_below = _slot("impact.elastic_below", "threshold of the low-velocity rule (m/s)")
    beta0 = _slot("impact.beta0", "Walton's tangential restitution")
    e_ref = _slot("impact.e_ref", "power law: restitution at v_ref")
    v_ref = _slot("impact.v_ref", "power law: reference normal speed (m/s)")
    exponent = _slot("impact.exponent", "power law: exponent p")
    viscous = _slot("impact.viscous", "viscoelastic A alpha^(2/5) ((s/m)^(1/5))")
    energy_scale = _slot("impact.energy_scale", "energy-dependent E0 (J); 0: constant e")
    angle_slope = _slot("impact.angle_slope", "rise of e with tan(incidence)")

    #: the law's name in :data:`IMPACT_LAWS` (``contact.law``)
    name = "kane-levinson"
    #: the ``[contact]`` key that ``billiard calibrate --law`` fits: the law's main parameter
    main = "restitution"
    #: the range ``billiard calibrate --law`` scans the main parameter over
    main_range: tuple[float, float] = (0.1, 0.95)
    #: values of its other parameters where a scene has none (docs/impact-laws.md)
    defaults: Mapping[str, float] = MappingProxyType({})

    def __init__(
        self,
        mass: float,
        radius: float,
        inertia_factor: float,
        restitution: float,
        mu_static: float,
        mu_kinetic: float,
        elastic_below: float,
        **parameters: float,
    ):
        #: the law's block of a state vector (slots up to the block's end; the rest unused)
        self.ctx = new_ctx("impact")
        write(self.ctx, "impact.kind", self.kind)
        self.m = mass
        self.r = radius
        self.k = inertia_factor
        self.e = restitution
        self.mu_s = mu_static
        self.mu_k = mu_kinetic
        self.elastic_below = elastic_below
        self.low_velocity = LowVelocityRule(elastic_below)
        required, optional = LAW_PARAMETERS[self.name]
        unknown = set(parameters) - set(required) - set(optional)
        missing = set(required) - set(parameters)
        if unknown or missing:
            raise TypeError(
                f"impact law {self.name!r} takes {', '.join(required + optional) or 'no'} "
                f"parameters (needs {', '.join(required) or 'none'}); got {', '.join(parameters)}"
            )
        # absent optional parameters stay 0.0, which the kernels read as "none"
        for key, value in parameters.items():
            setattr(self, key, value)

    @classmethod
    def from_scene(cls, scene: Any) -> KaneLevinsonImpact:
        required, optional = LAW_PARAMETERS[cls.name]
        parameters = {key: getattr(scene.contact, key) for key in required + optional}
        return cls(
            scene.ball.mass,
            scene.ball.radius,
            scene.ball.inertia_factor,
            scene.contact.restitution,
            scene.contact.mu_static,
            scene.contact.mu_kinetic,
            scene.contact.elastic_below,
            **{key: value for key, value in parameters.items() if value is not None},
        )

    def restitution(self, wt: float, wn: float) -> float:
        """Newton's e of an impact whose contact point approaches the boundary with the
        relative velocity (wt, wn) (m/s), before the low-velocity rule."""
        return _impact.restitution(self.ctx, self.kind, wt, wn)

    def write(self, ctx: MutableSequence[float]) -> None:
        """Write the law's block (its kind and coefficients) into a state vector."""
        copy(ctx, self.ctx, "impact")

    def apply(self, state: Any, contact: Contact) -> ImpactResult:
        """Post-impact speeds for a ball with speeds ``state.u1, state.u2, state.u3``."""
        u1, u2, u3 = state.u1, state.u2, state.u3
        z, vb1, vb2 = contact.z, contact.vb1, contact.vb2
        # with the relative velocity before the impact, which the record reports
        n1, n2, n3, rt, rn, regime, resting, wt, wn = _impact.impact_law(
            self.ctx, u1, u2, u3, z, vb1, vb2, contact.pressing
        )
        return ImpactResult(n1, n2, n3, rt, rn, _L.REGIMES[int(regime)], wt, wn, resting)


class WaltonImpact(KaneLevinsonImpact):
    """Walton's three-parameter law (O. R. Walton, 1993; S. F. Foerster, M. Y. Louge,
    H. Chang and K. Allia, Phys. Fluids 6, 1108, 1994): Newton's e, Coulomb's mu
    (``contact.mu_kinetic``) and the tangential restitution ``beta0`` of the contact
    point, wt+ = -beta0 wt-, in a sticking impact; an impact whose sticking impulse lies
    outside mu Rn slides (Kane and Levinson's slip). Regime ``stick`` is the beta0
    branch."""

    kind: float = _L.WALTON
    name = "walton"
    #: within the 0.3-0.45 Foerster et al. measured for hard spheres
    defaults = MappingProxyType({"beta0": 0.35})


class PowerLawImpact(KaneLevinsonImpact):
    """Kane and Levinson's law with e(v) = min(1, e_ref (v / v_ref)^-exponent), v the
    contact point's normal speed (m/s) relative to the boundary."""

    kind: float = _L.POWER_LAW
    name = "power-law"
    main = "e_ref"
    #: e ~ v^(-1/4): Johnson's elastic-plastic impact (K. L. Johnson, Contact Mechanics,
    #: 1985, section 11.4); e_ref at 1 m/s, the paper's e
    defaults = MappingProxyType({"e_ref": 0.393, "v_ref": 1.0, "exponent": 0.25})


class ViscoelasticImpact(KaneLevinsonImpact):
    """Kane and Levinson's law with the viscoelastic e(v) of Brilliantov, Spahn,
    Hertzsch and Poeschel (Phys. Rev. E 53, 5382, 1996) to second order (Ramirez et
    al., Phys. Rev. E 60, 4465, 1999): e = 1 - C1 x + C2 x^2, x = viscous v^(1/5)
    (:func:`billiard.kernels.impact.viscoelastic_restitution`)."""

    kind: float = _L.VISCOELASTIC
    name = "viscoelastic"
    main = "viscous"
    main_range = (0.02, 5.0)
    defaults = MappingProxyType({"viscous": 0.5})


class EnergyDependentImpact(KaneLevinsonImpact):
    """Kane and Levinson's law with e falling from 1 for a slow impact to
    ``restitution`` for an energetic one: e = restitution + (1 - restitution)
    exp(-E / energy_scale), E = m wn^2 / 2 the impact's normal energy (J); the form
    stands for Gorski and Srokowski's energy-dependent e (docs/impact-laws.md)."""

    kind: float = _L.ENERGY_DEPENDENT
    name = "energy-dependent"
    #: E0 of the order of the ball's kinetic energy relative to the wall at the paper's
    #: period-one orbit on the parabola (3e-4 J)
    defaults = MappingProxyType({"energy_scale": 1e-4})


class AngleDependentImpact(KaneLevinsonImpact):
    """Kane and Levinson's law with e rising with the angle of incidence, as Louge and
    Adams measured (Phys. Rev. E 65, 021303, 2002): e = min(1, restitution +
    angle_slope |wt| / |wn|), |wt| / |wn| the tangent of the contact point's angle of
    incidence."""

    kind: float = _L.ANGLE_DEPENDENT
    name = "angle-dependent"
    defaults = MappingProxyType({"angle_slope": 0.1})


class PointParticleImpact(KaneLevinsonImpact):
    """A point particle: no friction, no change of spin; Newton's e on the normal
    velocity relative to the boundary, constant (``restitution``) or energy-dependent
    (with ``energy_scale``, as :class:`EnergyDependentImpact`). The model of Gorski
    and Srokowski. Regime ``slip`` (frictionless) or ``elastic``."""

    kind: float = _L.POINT_PARTICLE
    name = "point-particle"


#: Impact laws by name (``contact.law``): classes built from a scene by their ``from_scene``.
IMPACT_LAWS: dict[str, type] = {
    cls.name: cls
    for cls in (
        KaneLevinsonImpact,
        WaltonImpact,
        PowerLawImpact,
        ViscoelasticImpact,
        EnergyDependentImpact,
        AngleDependentImpact,
        PointParticleImpact,
    )
}


def impact_law(scene: Any, name: str | None = None) -> ImpactLaw:
    """The impact law ``name`` (a key of :data:`IMPACT_LAWS`; the scene's
    ``contact.law`` by default) for a scene."""
    if name is None:
        name = scene.contact.law
    try:
        law = IMPACT_LAWS[name]
    except KeyError:
        raise ValueError(
            f"unknown impact law {name!r}: choose from {', '.join(IMPACT_LAWS)}"
        ) from None
    return law.from_scene(scene)


def with_law(scene: Any, name: str) -> Any:
    """The scene under the impact law ``name``: ``contact.law`` set, and each parameter
    the law needs that the scene lacks at the law's default (its class's ``defaults``).

    Raises:
        SceneError: ``name`` is no law (one line naming the choices).
    """
    changes: dict[str, Any] = {"contact.law": name}
    law = IMPACT_LAWS.get(name)
    if law is not None:
        for key, value in law.defaults.items():
            if getattr(scene.contact, key) is None:
                changes[f"contact.{key}"] = value
    return with_values(scene, changes)
