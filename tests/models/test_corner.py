"""Which contacts at a corner are impacts: those with an impulse."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from billiard.models.corner import is_impact
from billiard.models.impact import Contact, KaneLevinsonImpact

M, R, K = 1.3028e-4, 1.55e-3, 0.4


@pytest.mark.parametrize("e", [0.0, 0.393])
def test_a_contact_left_at_once_gives_no_impulse_and_is_no_impact(e):
    law = KaneLevinsonImpact(M, R, K, e, 0.61, 0.47, 0.001)
    # the wall's normal is +y (z = 0); the ball moves away from it at 2 mm/s, sliding
    leaving = law.apply(SimpleNamespace(u1=0.01, u2=0.002, u3=3.0), Contact(0.0, 0.0, 0.0))
    assert leaving.wn > 0.0
    assert (leaving.Rt, leaving.Rn) == (0.0, 0.0) and not is_impact(leaving)
    # the same ball approaching the wall: an impact, with a normal impulse
    hitting = law.apply(SimpleNamespace(u1=0.01, u2=-0.002, u3=3.0), Contact(0.0, 0.0, 0.0))
    assert hitting.Rn > 0.0 and is_impact(hitting)


def test_a_tangential_impulse_alone_makes_an_impact():
    assert is_impact(SimpleNamespace(Rt=1e-12, Rn=0.0))
    assert not is_impact(SimpleNamespace(Rt=0.0, Rn=0.0))
