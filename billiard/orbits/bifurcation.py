"""The bifurcations a branch of periodic orbits meets, and the test functions that
change sign at them (Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed.,
sec. 10.2, for maps):

* fold: a multiplier through +1, det(J - I) = 0, where the branch turns back in the
  key; where it goes on instead, a branch point (``branch_point``: a symmetric orbit's
  pitchfork, the parabola's mirror-symmetric orbit losing its symmetry, or a
  transcritical crossing), told apart by the key's component of the branch's tangent;
* period doubling: a multiplier through -1, det(J + I) = 0;
* Neimark-Sacker: a complex pair through the unit circle, prod_{i<j} (m_i m_j - 1) = 0
  (the determinant of the bialternate product's shift; it also vanishes at a neutral
  saddle, m_i m_j = 1 for real m_i, which is no bifurcation and is told apart);
* grazing: the orbit's impact sequence (walls and regimes) changes, where a flight
  touches a wall tangentially, an impact crosses the friction cone or the low-velocity
  threshold: the map is not smooth there, and no test function applies.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BIFURCATIONS", "GRAZING", "NONE", "neimark_sacker_pair", "test_functions"]

#: Codes of the ``bifurcation`` variable of branch.nc, in the order of its
#: ``flag_values`` (0, 1, ...): the names are its ``flag_meanings``.
BIFURCATIONS: tuple[str, ...] = (
    "none",
    "fold",
    "period_doubling",
    "neimark_sacker",
    "grazing",
    "branch_point",
)
NONE = 0
GRAZING = BIFURCATIONS.index("grazing")
#: the smooth bifurcations, in the order of :func:`test_functions`' values
SMOOTH: tuple[str, ...] = ("fold", "period_doubling", "neimark_sacker")


def test_functions(jacobian: np.ndarray) -> np.ndarray:
    """(fold, period doubling, Neimark-Sacker) test functions of an orbit's Jacobian."""
    n = jacobian.shape[0]
    eye = np.eye(n)
    mults = np.linalg.eigvals(jacobian)
    pairs = [mults[i] * mults[j] - 1.0 for i in range(n) for j in range(i + 1, n)]
    ns = np.prod(pairs).real if pairs else 1.0
    return np.array([np.linalg.det(jacobian - eye), np.linalg.det(jacobian + eye), ns], dtype=float)


def neimark_sacker_pair(multipliers: np.ndarray, tol: float = 1e-6) -> bool:
    """Is there a complex pair on the unit circle (within ``tol``): a Neimark-Sacker
    point rather than a neutral saddle?"""
    for m in multipliers:
        if abs(m.imag) > tol and abs(abs(m) - 1.0) < tol:
            return True
    return False
