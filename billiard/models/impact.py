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

from collections.abc import MutableSequence
from dataclasses import dataclass
from typing import Any, Protocol

from billiard.kernels.interpreted import impact as _impact
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.names import copy, new_ctx, read, write

__all__ = [
    "IMPACT_LAWS",
    "Contact",
    "ImpactLaw",
    "ImpactResult",
    "KaneLevinsonImpact",
    "LowVelocityRule",
    "REGIME_RTOL",
    "impact_law",
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

    def __init__(
        self,
        mass: float,
        radius: float,
        inertia_factor: float,
        restitution: float,
        mu_static: float,
        mu_kinetic: float,
        elastic_below: float,
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

    @classmethod
    def from_scene(cls, scene: Any) -> KaneLevinsonImpact:
        return cls(
            scene.ball.mass,
            scene.ball.radius,
            scene.ball.inertia_factor,
            scene.contact.restitution,
            scene.contact.mu_static,
            scene.contact.mu_kinetic,
            scene.contact.elastic_below,
        )

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


#: Impact laws by name: classes built from a scene by their ``from_scene``.
IMPACT_LAWS: dict[str, type] = {
    "kane-levinson": KaneLevinsonImpact,
}


def impact_law(scene: Any, name: str = "kane-levinson") -> ImpactLaw:
    """The impact law ``name`` (a key of :data:`IMPACT_LAWS`) for a scene."""
    try:
        law = IMPACT_LAWS[name]
    except KeyError:
        raise ValueError(
            f"unknown impact law {name!r}: choose from {', '.join(IMPACT_LAWS)}"
        ) from None
    return law.from_scene(scene)
