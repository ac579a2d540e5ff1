"""A ball at a corner of the boundary, in contact with one surface as it reaches another
(the wedge's vertex, a wall meeting the lid): which contacts are impacts
(``contact.model = "phases"``).

A contact phase on one wall ends where the ball reaches another surface. If the ball is
not approaching that surface there (it touches it to rounding while moving away, or
along it), Newton's law gives no impulse: nothing happens at that contact, so it is no
impact. It is neither recorded in collisions.csv nor counted, and the ball goes on from
its state unchanged. An impact with an impulse, however small, is one.
"""

from __future__ import annotations

from typing import Any

__all__ = ["is_impact"]


def is_impact(res: Any) -> bool:
    """Does the impact result ``res`` (with impulses ``Rt``, ``Rn`` in N s) change the
    ball's motion: a nonzero normal or tangential impulse?"""
    return res.Rn != 0.0 or res.Rt != 0.0
