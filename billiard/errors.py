"""Exceptions raised by the simulation engine.

Both carry a one-line message meant for the user: the command line prints it without a
traceback.
"""

from __future__ import annotations

from billiard.status import Status

__all__ = ["BallAtRest", "GeometryError", "SimulationError", "UnverifiedDataWarning"]


class GeometryError(ValueError):
    """The scene's geometry cannot be simulated (raised before a run starts).

    Examples: a ball too large for the boundary's curvature (contact would not be at a
    single point), or an initial position that overlaps the wall or the lid.
    """


class SimulationError(RuntimeError):
    """A run cannot continue: the ball escaped, the impacts collapsed, a number became
    non-finite, or a root solve failed. :func:`billiard.run.simulate.simulate` turns it into
    ``Result.status`` and ``Result.stop_reason`` and keeps the impacts recorded so far.

    Attributes:
        status: the :class:`~billiard.status.Status` of the stop.
    """

    def __init__(self, message: str, status: Status = Status.SOLVER_FAILED):
        super().__init__(message)
        self.status = status


class BallAtRest(SimulationError):
    """The ball rests on the boundary, moving with it, and nothing more happens: the run
    ends complete (:attr:`~billiard.status.Status.AT_REST`), not stopped.

    Attributes:
        tau: time (s) into the contact phase from which the ball has been at rest.
    """

    def __init__(self, tau: float):
        super().__init__(
            "the ball rests on the boundary, moving with it: nothing more happens",
            Status.AT_REST,
        )
        self.tau = tau


class UnverifiedDataWarning(UserWarning):
    """Files read without their checksums checked: a run folder without a readable
    checkpoint or with one written before the checksums, a sweep folder written before
    its ``checksums.json``. The message is one line; the command line prints it as
    ``billiard: MESSAGE``."""
