"""The engine: one :class:`Simulation` built from a scene, its state, interrupts and
progress.

:mod:`~billiard.engine.simulation` (the :class:`Simulation`),
:mod:`~billiard.engine.driver` (its chunked calls into the compiled state machine, the
one engine), :mod:`~billiard.engine.state` (the ball and the engine state),
:mod:`~billiard.engine.ctx` (the kernels' state vector from a simulation),
:mod:`~billiard.engine.interrupt` and :mod:`~billiard.engine.progress`;
:mod:`~billiard.engine.compile_all` (every kernel compiled together, once).
"""

from billiard.engine import compile_all as _compile_all  # noqa: F401  (the first-compile hook)
from billiard.engine.simulation import Simulation

__all__ = ["Simulation"]
