"""The generated contact equations (:mod:`billiard.generated.contact`) under
:func:`billiard.jit.jit`: the same functions, compiled when numba is there (the functions
themselves in the interpreted twin, :mod:`billiard.kernels.interpreted`)."""

from __future__ import annotations

from billiard.generated import contact as _contact

from .decorators import jit

roll_rhs = jit(_contact.roll_rhs)
roll_spin = jit(_contact.roll_spin)
slide_rhs = jit(_contact.slide_rhs)
slip_velocity = jit(_contact.slip_velocity)
centre_state = jit(_contact.centre_state)
s_dot_of_velocity = jit(_contact.s_dot_of_velocity)
