"""What the orbits wing raises: one line, for the user."""

from __future__ import annotations

__all__ = ["OrbitError", "SequenceChange"]


class OrbitError(ValueError):
    """No orbit can be computed here: bad input (a scene outside the method's scope, a
    guess that is no post-impact state) or a search that failed. One line, for the user."""


class SequenceChange(OrbitError):
    """The orbit's impacts hit other walls than the branch's, or, through contact
    phases, its lift-offs come other drive periods apart or not at all: past a grazing."""
