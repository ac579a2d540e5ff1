"""The generated ball equations (:mod:`billiard.generated.ball`) under :func:`billiard.jit.jit`:
the same functions, compiled when numba is there (the functions themselves in the
interpreted twin, :mod:`billiard.kernels.interpreted`)."""

from __future__ import annotations

from billiard.generated import ball as _ball

from .decorators import jit

flight_exact = jit(_ball.flight_exact)
flight_rhs_drag = jit(_ball.flight_rhs_drag)
flight_rhs_magnus = jit(_ball.flight_rhs_magnus)
contact_velocity = jit(_ball.contact_velocity)
frame_velocity = jit(_ball.frame_velocity)
impact_stick = jit(_ball.impact_stick)
impact_slip = jit(_ball.impact_slip)
impact_walton = jit(_ball.impact_walton)
energy = jit(_ball.energy)
