"""The Illinois variant of regula falsi (Dowell and Jarratt 1971), the root search of a
phase's end and of a hold's release: a secant point of the bracket [a, b] (its middle
when the secant leaves it), and the bracket kept around the sign change, halving the
value kept at the end that stays twice in a row so that the search does not stall on
one side. The loop that evaluates the function is the caller's: the function is a
kernel of the caller's state, not a value."""

from __future__ import annotations

from .decorators import inline


@inline
def secant_point(a, b, fa, fb):
    """The secant's zero in (a, b), else the middle of [a, b]."""
    m = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
    if not a < m < b:
        m = 0.5 * (a + b)
    return m


@inline
def narrow(a, b, fa, fb, m, fm, side):
    """The bracket after the value fm at m: (a, b, fa, fb, side), the root staying where
    the function falls to zero or below."""
    if fm > 0.0:
        a, fa = m, fm
        if side == -1:
            fb *= 0.5
        side = -1
    else:
        b, fb = m, fm
        if side == 1:
            fa *= 0.5
        side = 1
    return a, b, fa, fb, side
