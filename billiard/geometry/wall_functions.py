"""A curve's wall functions as the kernels take them: ``walls = (fs, dfs, d2fs)``, one
entry per wall, each a first-class function value of one numba type,
``float64(float64, float64[::1])`` (:class:`WallFunction`), so that the kernels are
compiled once for every curve, and cached. Interpreted, the generated functions
themselves.
"""

from __future__ import annotations

from typing import Any

from billiard import jit as _jit

__all__ = ["WallFunction", "near_functions", "plain_wall_functions", "wall_functions"]

_SIGNATURES: dict[int, Any] = {}
_compiled_walls: dict[Any, Any] = {}


def _wall_signature(args: int = 1) -> Any:
    """``float64(float64, float64[::1])`` of a wall function, or with ``args`` = 3 the
    ``float64(float64, float64, float64, float64[::1])`` of a nearest-point function."""
    if args not in _SIGNATURES:
        from numba import types

        _SIGNATURES[args] = types.float64(*([types.float64] * args), types.float64[::1])
    return _SIGNATURES[args]


def _wall_function_class() -> type:
    import numba.experimental.function_type  # noqa: F401  (typeof of the protocol)
    from numba.core.types import WrapperAddressProtocol

    class _WallFunction(WrapperAddressProtocol):
        """A generated wall function, compiled for its signature, as a first-class
        function value: numba types it by its signature alone, so a kernel taking it is
        compiled (and cached) once for every curve."""

        def __init__(self, fn: Any, args: int):
            self.sig = _wall_signature(args)
            self.dispatcher = _jit.jit(fn)
            self.dispatcher.compile(self.sig.args)
            result = self.dispatcher.get_compile_result(self.sig)
            self.address = result.library.get_pointer_to_function(
                result.fndesc.llvm_cfunc_wrapper_name
            )

        def __wrapper_address__(self) -> int:
            return self.address

        def signature(self) -> Any:
            return self.sig

    return _WallFunction


_WallFunctionClass: type | None = None


def WallFunction(fn: Any, args: int = 1) -> Any:  # noqa: N802  (a factory standing for a class)
    """``fn`` as the kernels take it: a compiled first-class function value of ``args``
    float arguments and the parameter array, or ``fn`` itself when the kernels run
    interpreted."""
    global _WallFunctionClass
    if not _jit.ENABLED:
        return fn
    if fn not in _compiled_walls:
        if _WallFunctionClass is None:
            _WallFunctionClass = _wall_function_class()
        _compiled_walls[fn] = _WallFunctionClass(fn, args)
    return _compiled_walls[fn]


def wall_functions(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f): one tuple per function, one entry per wall of the curve."""
    walls = sim.boundary.walls
    return (
        tuple(WallFunction(w.f) for w in walls),
        tuple(WallFunction(w.df) for w in walls),
        tuple(WallFunction(w.d2f) for w in walls),
    )


def near_functions(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(near, dnear): the walls' nearest-point conditions g(s, px, py, p) and dg/ds, for
    the fixed-step detection (method ``rk4``)."""
    walls = sim.boundary.walls
    return (
        tuple(WallFunction(w.near, 3) for w in walls),
        tuple(WallFunction(w.dnear, 3) for w in walls),
    )


def plain_wall_functions(walls: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f) of ``walls`` as the interpreted kernels take them: the generated
    functions themselves."""
    return (
        tuple(w.f for w in walls),
        tuple(w.df for w in walls),
        tuple(w.d2f for w in walls),
    )
