"""Which models the compiled kernels run: a model class with a kernel names its kind,
the code its block of the state vector starts with (``IM_KIND``, ``FL_KIND``,
``LOC_KIND``), on which the kernels branch to its kernel function, and writes that block
(``write(ctx)``). :func:`require_kernel` is the one check the engine makes: a model
without a kind (another impact law with only an ``apply`` method, say) is refused with
a one-line :class:`~billiard.scene.checks.SceneError`, rather than run interpreted, tens
of times slower, without a word.

The kind is the model's class's own (``kind`` in the class body): a subclass that does
not name one may compute something else than its parent's kernel, so it has none.
"""

from __future__ import annotations

from collections.abc import Mapping

from billiard.models.flight import FLIGHT_MODELS
from billiard.models.impact import IMPACT_LAWS
from billiard.models.locators import LOCATORS
from billiard.scene.checks import error

__all__ = ["REGISTRIES", "kernel_kind", "require_kernel"]

#: the registries of the models the engine takes, by what the messages call them
REGISTRIES: Mapping[str, Mapping[str, type]] = {
    "impact law": IMPACT_LAWS,
    "flight model": FLIGHT_MODELS,
    "locator": LOCATORS,
}


def _class_kind(cls: type) -> float | None:
    kind = vars(cls).get("kind")
    return kind if type(kind) is float else None


def kernel_kind(model: object) -> float | None:
    """The kernels' code of ``model`` (its class's own ``kind``), or None: no kernel."""
    return _class_kind(type(model))


def require_kernel(model: object, what: str) -> float:
    """The kernels' code of ``model``, a ``what`` (a key of :data:`REGISTRIES`:
    ``"impact law"``, ``"flight model"`` or ``"locator"``).

    Raises:
        SceneError: the model has no compiled kernel (named by its registry name, or its
            class's name when it is in no registry; the message lists those that have).
        KeyError: an unknown ``what``.
    """
    registry = REGISTRIES[what]
    kind = kernel_kind(model)
    if kind is not None:
        return kind
    name = next((key for key, cls in registry.items() if cls is type(model)), None)
    shown = repr(name) if name is not None else type(model).__name__
    choices = ", ".join(key for key, cls in registry.items() if _class_kind(cls) is not None)
    raise error(f"{what} {shown} has no compiled kernel: choose from {choices}")
