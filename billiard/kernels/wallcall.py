"""The one call by which the impact path's kernels reach a curve's wall functions:
``call_wall(walls, k, w, x, p)``, function ``k`` (0: f, 1: f', 2: f'') of wall ``w`` at
abscissa ``x`` (m), ``p`` the curve's parameter array.

On the CPU (compiled or interpreted) it is ``walls[k][w](x, p)``: ``walls`` is the
table of :mod:`billiard.geometry.wall_functions` (first-class compiled functions, or the
generated functions themselves). A GPU has no first-class functions: in a device twin
of the kernels (:mod:`billiard.engine.gpu`) ``walls`` is a placeholder and the call
branches on ``(k, w)`` to the curve's generated functions compiled for the device,
which its loader hands to :mod:`.decorators` (``WALLS``: rows f, f', f'', one function
per wall slot, :data:`billiard.geometry.wall_functions.WALL_SLOTS` = 2 of them). This is
the seam between the two targets; the kernels that call it are the same source.
"""

from __future__ import annotations

from .decorators import WALLS, inline

__all__ = ["call_wall"]

if WALLS is None:

    @inline
    def call_wall(walls, k, w, x, p):
        """``walls[k][w](x, p)``: function k of wall w at x (the row by a constant
        index in each branch, as the kernels indexed it before this seam)."""
        if k == 0:
            return walls[0][w](x, p)
        if k == 1:
            return walls[1][w](x, p)
        return walls[2][w](x, p)

else:
    (_F0, _F1), (_DF0, _DF1), (_D2F0, _D2F1) = WALLS

    @inline
    def call_wall(walls, k, w, x, p):
        """Function k of wall w at x, by branches (``walls`` is not read)."""
        if k == 0:
            return _F0(x, p) if w == 0 else _F1(x, p)
        if k == 1:
            return _DF0(x, p) if w == 0 else _DF1(x, p)
        return _D2F0(x, p) if w == 0 else _D2F1(x, p)
