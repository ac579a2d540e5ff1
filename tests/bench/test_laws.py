"""bench.laws measures each impact law on the motion of its Kane-Levinson pair: the
laws whose limit is that law exactly make the same impacts, bit for bit, so their cost
compares the laws alone."""

from __future__ import annotations

import numpy as np
import pytest

from bench.laws import PAIRS, _scene
from billiard.run.simulate import simulate


@pytest.mark.parametrize("law", ["power-law", "energy-dependent", "angle-dependent"])
def test_a_law_at_its_kane_levinson_limit_makes_the_same_impacts(law):
    values, kane = PAIRS[law]
    own = simulate(_scene("wedge-6.6hz", values), collisions=300).columns
    pair = simulate(_scene("wedge-6.6hz", kane), collisions=300).columns
    assert _scene("wedge-6.6hz", values).contact.law == law
    for key in ("t", "q1", "q2", "v1", "v2", "omega", "Rt", "Rn"):
        assert np.asarray(own[key]).tobytes() == np.asarray(pair[key]).tobytes(), key


@pytest.mark.parametrize("law", ["walton", "point-particle", "viscoelastic"])
def test_the_other_pairs_start_alike(law):
    # Walton's beta0 = 0, the frictionless ball and e = 1 differ from the law only by
    # rounding: the first impacts agree to within it
    values, kane = PAIRS[law]
    own = simulate(_scene("parabola-5.4hz", values), collisions=5).columns
    pair = simulate(_scene("parabola-5.4hz", kane), collisions=5).columns
    for key in ("t", "q1", "q2", "v1", "v2"):
        assert np.asarray(own[key]) == pytest.approx(np.asarray(pair[key]), rel=1e-9, abs=1e-12)
