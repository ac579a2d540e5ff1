"""One decorator for the compiled kernels: :func:`jit`.

With numba importable and ``NUMBA_DISABLE_JIT`` unset (or ``0``), ``jit`` is
``numba.njit(cache=True, nogil=True, error_model="python")``: no fast-math, so every
operation is the IEEE operation CPython performs, in the same order, and a division by
zero raises as in Python. Otherwise ``jit`` returns the function itself and the kernels
run interpreted: the same source, no second copy. Without numba a one-line notice says
so, once (on first use).

``ENABLED`` tells which of the two is in force.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["ENABLED", "jit", "numba_problem"]

F = TypeVar("F", bound=Callable[..., Any])

_problem: str | None = None
_noticed = False


def _disabled() -> bool:
    return os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")


try:
    if _disabled():
        raise ImportError("NUMBA_DISABLE_JIT is set")
    import numba
    from numba.core.errors import NumbaExperimentalFeatureWarning
except ImportError as exc:  # no numba on this platform, or the JIT disabled
    numba = None
    _problem = str(exc)
else:
    # the wall functions are first-class function values (numba.core.types.FunctionType)
    warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)

#: True when the kernels are compiled by numba, False when they run interpreted.
ENABLED = numba is not None


def numba_problem() -> str | None:
    """Why the kernels run interpreted (None when they are compiled)."""
    return _problem


def notice() -> None:
    """Print, once per process, that the kernels run interpreted because numba is
    missing (not when NUMBA_DISABLE_JIT asked for it)."""
    global _noticed
    if _noticed or ENABLED or _disabled():
        return
    _noticed = True
    print(f"billiard: numba unavailable ({_problem}); the engine runs interpreted", file=sys.stderr)


def jit(fn: F) -> F:
    """Compile ``fn`` with numba (cached on disk), or return it unchanged."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True, error_model="python")(fn)
