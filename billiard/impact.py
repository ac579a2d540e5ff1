"""Impact laws: the jump of the ball's speeds when it hits the moving boundary.

An impact law takes the ball's speeds just before the impact and a :class:`Contact`
(tangent angle and boundary velocity at the contact point) and returns an
:class:`ImpactResult`. :class:`KaneLevinsonImpact` is the paper's law; another law only
needs the same ``apply(state, contact)`` method.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from billiard.generated import ball as _ball

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

#: Relative tolerance of the friction-cone test |Rt| <= mu_s Rn, in units of the
#: momenta that enter the impulses: 16 ulps. The no-slip impulse Rt is a sum of a few
#: products of the ball's and the boundary's velocity components with the mass, so it
#: carries a rounding error of a few ulps of m (|u1| + |u2| + r |u3| + |vb1| + |vb2|).
#: A purely normal impact (no tangential relative velocity, no spin) has Rt = 0 exactly
#: but computes |Rt| ~ 1e-17 m |u|, which with mu_s = 0 used to exceed mu_s Rn = 0 and
#: label the impact ``slip``. The cone is widened by this much so that rounding alone
#: never decides the regime; an impulse genuinely outside the cone (by more than 1e-14 of
#: the momenta) still slips.
REGIME_RTOL = 16 * 2.0**-52


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
    """

    def __init__(self, threshold: float):
        self.threshold = float(threshold)

    def applies(self, wn: float) -> bool:
        """Does the rule set e = 1 for this relative normal velocity (m/s)?"""
        return abs(wn) < self.threshold

    def lifts(self, wn: float, contact: Contact) -> bool:
        """Is this a lying ball, to be relaunched at the threshold speed?"""
        return contact.pressing and wn > -self.threshold

    def approach_shift(self, wn: float) -> float:
        """Change of the normal velocity (m/s, along c2) that makes a lying ball
        approach at the threshold speed."""
        return -self.threshold - wn


class KaneLevinsonImpact:
    """Kane and Levinson's impact theory with a moving boundary (generated maps).

    Newton restitution on the contact point's normal velocity relative to the boundary.
    The no-slip solution is tried first and kept if its impulse lies in the static
    friction cone, |Rt| <= mu_s Rn (up to rounding: :data:`REGIME_RTOL`); otherwise the
    ball slips with Rt = -mu_k Rn sign(wt).
    Slow impacts follow the :class:`LowVelocityRule` (regime ``"elastic"``).

    Args:
        mass, radius, inertia_factor: the ball (kg, m, I / (m r^2)).
        restitution, mu_static, mu_kinetic: contact coefficients.
        elastic_below: threshold of the low-velocity rule (m/s); 0 disables it.
    """

    regimes: tuple[str, ...] = (STICK, SLIP, ELASTIC)

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
        self.m = float(mass)
        self.r = float(radius)
        self.k = float(inertia_factor)
        self.e = float(restitution)
        self.mu_s = float(mu_static)
        self.mu_k = float(mu_kinetic)
        self.elastic_below = float(elastic_below)
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

    def apply(self, state: Any, contact: Contact) -> ImpactResult:
        """Post-impact speeds for a ball with speeds ``state.u1, state.u2, state.u3``."""
        u1, u2, u3 = state.u1, state.u2, state.u3
        z, vb1, vb2 = contact.z, contact.vb1, contact.vb2
        m, r, k = self.m, self.r, self.k
        wt, wn = _ball.contact_velocity(u1, u2, u3, z, vb1, vb2, r)
        e = self.e
        rule = self.low_velocity
        low = rule.applies(wn)
        resting = False
        v1, v2 = u1, u2
        if low:
            e = 1.0
            if rule.lifts(wn, contact):
                # a lying ball: shift its normal velocity to an approach at the threshold
                shift = rule.approach_shift(wn)
                v1 -= math.sin(z) * shift
                v2 += math.cos(z) * shift
                resting = True
        if wn >= 0.0 and not resting:
            # The contact point is already separating (a locator can report a contact at a
            # rounding-level gap while a ball slides along a curved wall). A contact can
            # only push: Newton's law would need Rn < 0 here, and the slip impulse would
            # then push *with* the slip and create energy. No impulse: the slip law with
            # Rn = 0.
            return ImpactResult(u1, u2, u3, 0.0, 0.0, ELASTIC if low else SLIP, wt, wn, False)
        n1, n2, n3, rt, rn = _ball.impact_stick(v1, v2, u3, z, vb1, vb2, m, r, k, e)
        regime = STICK
        rounding = REGIME_RTOL * m * (abs(v1) + abs(v2) + r * abs(u3) + abs(vb1) + abs(vb2))
        # Friction is bounded by the normal impulse the ball actually receives. For a
        # relaunched ball that is m (threshold - wn) from its true velocity, not the
        # 2 m threshold of the shifted approach the maps see; the shift itself is no
        # impulse of the contact. The normal impulse of a sphere does not depend on the
        # friction (the normal passes through the centre), so scaling mu by the ratio
        # sizes the slip impulse against the applied normal impulse exactly.
        applied = 1.0
        if resting and rn > 0.0:
            c, s = math.cos(z), math.sin(z)
            applied = m * (c * (n2 - u2) - s * (n1 - u1)) / rn
        if abs(rt) > self.mu_s * applied * rn + rounding:
            sgn = math.copysign(1.0, wt)
            n1, n2, n3, rt, rn = _ball.impact_slip(
                v1, v2, u3, z, vb1, vb2, m, r, k, e, self.mu_k * applied, sgn
            )
            regime = SLIP
        if low:
            regime = ELASTIC
        if resting:
            # report the impulse actually applied to the ball's true pre-impact velocity
            c, s = math.cos(z), math.sin(z)
            du1, du2 = n1 - u1, n2 - u2
            rt = m * (c * du1 + s * du2)
            rn = m * (c * du2 - s * du1)
        return ImpactResult(n1, n2, n3, rt, rn, regime, wt, wn, resting)


#: Impact laws by name: each builds the law from a scene.
IMPACT_LAWS: dict[str, Callable[[Any], ImpactLaw]] = {
    "kane-levinson": KaneLevinsonImpact.from_scene,
}


def impact_law(scene: Any, name: str = "kane-levinson") -> ImpactLaw:
    """The impact law ``name`` (a key of :data:`IMPACT_LAWS`) for a scene."""
    try:
        make = IMPACT_LAWS[name]
    except KeyError:
        raise ValueError(
            f"unknown impact law {name!r}: choose from {', '.join(IMPACT_LAWS)}"
        ) from None
    return make(scene)
