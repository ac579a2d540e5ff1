"""Why a run ended: a status code plus a one-line message, as scipy's solvers report.

A run that simulated everything it was asked for ends with :attr:`Status.COMPLETE` (the
impact count) or :attr:`Status.TIME_LIMIT` (``run.duration``); every other status is a
documented stop of the model or the numerics, with its message in
``Result.stop_reason``. A programming error is none of these: it surfaces as the
exception it is.
"""

from __future__ import annotations

from enum import IntEnum

__all__ = ["Status"]


class Status(IntEnum):
    """How a run ended (``Result.status``)."""

    #: the requested number of impacts was simulated
    COMPLETE = 0
    #: the requested simulated time (``run.duration``) was reached
    TIME_LIMIT = 1
    #: the ball left an open container above ``boundary.escape_height``
    ESCAPED = 2
    #: inelastic collapse: impacts piled up in a vanishing span of time
    COLLAPSE = 3
    #: a quantity of the state became infinite or NaN
    NON_FINITE = 4
    #: a root or step-size search did not converge
    SOLVER_FAILED = 5
    #: an arithmetic fault (overflow, a math domain error) in the equations
    NUMERICAL_FAULT = 6
    #: the ball rests on the boundary, moving with it, through a whole drive period (or
    #: on a static boundary): nothing more happens, so the run ends early but complete
    AT_REST = 7
    #: a run that asked for impacts (no ``run.duration``) and whose ball stayed in contact
    #: with the boundary (rolling, sliding or held) without an impact for
    #: ``run.contact_span`` seconds of simulated time: it ends early but complete; a
    #: ``run.duration`` (``--duration``) follows the contact motion further
    IN_CONTACT = 8

    @property
    def finished(self) -> bool:
        """True when the run did all it was asked for, or all that can happen (no early
        stop by a fault of the model or the numerics)."""
        return self in (Status.COMPLETE, Status.TIME_LIMIT, Status.AT_REST, Status.IN_CONTACT)
