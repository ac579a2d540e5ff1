"""The kernels of :mod:`billiard.kernels`, interpreted: the same source files loaded a
second time as the package ``billiard.kernels_py``, in which every decorator of
``kernels/decorators.py`` is the identity, so each kernel is the plain Python function
(whether numba is there or not) and the generated equations are the generated functions.

The runtime's classes (:mod:`billiard.models.flight`, :mod:`billiard.geometry.surfaces`,
:mod:`billiard.models.event_locator`, :mod:`billiard.models.impact`, :mod:`billiard.models.contact`,
:mod:`billiard.models.hold`) call these one gap or one step at a
time, over a state vector ``ctx`` that is a list of Python floats: a compiled kernel
called from Python costs tens of microseconds per call (numba types the tuple of wall
functions at each call), a plain function call under a microsecond. One source, run
compiled by :class:`billiard.engine.simulation.Simulation`'s loop and interpreted by the classes.

The twin's functions are never compiled: numba's cache (``billiard/jit.py``) sees only
``billiard.kernels``. The kernel modules import each other relatively, so the twin is
self-contained. A documented stop inside a kernel raises the twin's
:class:`~billiard.kernels.layout.KernelError`; :func:`stop` words it as the classes did.
"""

from __future__ import annotations

from types import ModuleType

from billiard import jit as _jit
from billiard.errors import SimulationError

from . import twin as _twin

__all__ = [
    "PACKAGE",
    "ball",
    "contact",
    "contact_equations",
    "contact_forces",
    "drive",
    "flight",
    "impact",
    "kernel_errors",
    "layout",
    "locate",
    "rest",
    "stop",
    "surfaces",
    "vertex",
]

#: the twin's package name
PACKAGE = "billiard.kernels_py"


def _load(name: str) -> ModuleType:
    return _twin.load_module(PACKAGE, name)


layout = _load("layout")
drive = _load("drive")
ball = _load("ball")
flight = _load("flight")
surfaces = _load("surfaces")
locate = _load("locate")
fixed_step = _load("fixed_step")
samples = _load("samples")
impact = _load("impact")
contact_equations = _load("contact_equations")
contact_forces = _load("contact_forces")
contact = _load("contact")
vertex = _load("vertex")
rest = _load("rest")

#: the documented stops of the kernels the classes call, worded as the engine words them
_TEXTS = {
    layout.E_NO_IMPACT: f"no impact found within {locate.MAX_FLIGHT_TIME:g} s of flight",
    layout.E_ROOT: "the impact time did not converge",
    layout.E_EXTREMUM: "the gap's extremum did not converge",
}


def kernel_errors() -> tuple[type[Exception], ...]:
    """The KernelError of the twin, and of the compiled kernels when there are any (a
    class of their own: the same file loaded as another package)."""
    if not _jit.ENABLED:
        return (layout.KernelError,)
    from billiard.kernels.layout import KernelError

    return (layout.KernelError, KernelError)


def stop_text(code: int, value: float) -> str:
    """The words of the stop ``code`` (a ``KernelError`` code of either package);
    ``value`` is what ``ctx[EN_ERR_VALUE]`` holds (the quantity the message names)."""
    if code == layout.E_STEP_CONTROL:
        return (
            f"the flight's step-size control failed (Dormand-Prince, 200 rejected steps "
            f"from tau = {value!r} s)"
        )
    if code == layout.E_KIND:
        return f"the kernels have no impact law of kind {value:g}"
    if code == layout.E_INVERSION:
        return f"offset-curve inversion did not converge at x = {value!r} m"
    if code == layout.E_DEPARTURES:
        h = value
        finer = float(f"{h / 10:.0e}")
        limit, fraction = fixed_step.DEPARTURE_LIMIT, fixed_step.DEPARTURE_FRACTION
        return (
            f"run.step = {h:g} s is too coarse for this scene (use run.step <= "
            f"{finer:g} s): {limit} impacts in a row were found within "
            f"{fraction * h:.0e} s of the previous one, where the ball had "
            f"just left the wall (it comes back within one step)"
        )
    return _TEXTS.get(code, f"kernel stop {code}")


def stop(exc: Exception, ctx: list) -> SimulationError:
    """The :class:`SimulationError` for a ``KernelError`` out of a twin's kernel."""
    return SimulationError(stop_text(exc.args[0], ctx[layout.EN_ERR_VALUE]))


def engine_modules() -> tuple[ModuleType, ModuleType, ModuleType]:
    """The twin's state machine, impact loop and samples (loaded on first use: only a
    run that asks for the interpreted engine needs them)."""
    return _load("machine"), _load("loop"), _load("samples")
