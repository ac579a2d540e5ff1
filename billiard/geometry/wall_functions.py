"""A curve's wall functions as the kernels take them: ``walls = (fs, dfs, d2fs)``, one
entry per wall, each compiled by ``numba.cfunc`` for one signature,
``float64(float64, float64[::1])`` (:func:`WallFunction`): a first-class function value
that numba types by its signature alone, so that the kernels are compiled once for
every curve, and cached. Interpreted, the generated functions themselves.
"""

from __future__ import annotations

from typing import Any

from billiard import jit as _jit

__all__ = [
    "WALL_SLOTS",
    "WallFunction",
    "WallTable",
    "near_functions",
    "phase_wall_functions",
    "plain_wall_functions",
    "wall_functions",
]

#: the entries of each row of a :class:`WallTable` at least: a curve with fewer walls
#: has its last wall's functions repeated (never called: the kernels call a wall by its
#: index), so that every curve of up to this many walls gives the kernels one type and
#: they compile once for all of them (the paper's curves have one or two walls)
WALL_SLOTS = 2
_SIGNATURES: dict[int, Any] = {}
_compiled_walls: dict[Any, Any] = {}


def _wall_signature(args: int = 1) -> Any:
    """``float64(float64, float64[::1])`` of a wall function, or with ``args`` = 3 the
    ``float64(float64, float64, float64, float64[::1])`` of a nearest-point function."""
    if args not in _SIGNATURES:
        from numba import types

        _SIGNATURES[args] = types.float64(*([types.float64] * args), types.float64[::1])
    return _SIGNATURES[args]


class WallTable(tuple):
    """Rows of compiled wall functions (``(fs, dfs, d2fs)``, one entry per wall) as the
    kernels take them, with their numba type worked out once: numba types a plain tuple
    item by item on every call of a compiled kernel, some microseconds per function,
    which a contact phase, called once or more per impact, would pay each time. The
    type is given to numba by its documented typing hook
    (``numba.extending.typeof_impl``). Rows shorter than :data:`WALL_SLOTS` are
    padded with their last entry."""

    numba_type: Any

    def __new__(cls, rows: Any) -> WallTable:
        import numba

        rows = [tuple(row) for row in rows]
        rows = [row + row[-1:] * (WALL_SLOTS - len(row)) for row in rows]
        table = super().__new__(cls, rows)
        table.numba_type = numba.typeof(tuple(table))
        return table


if _jit.ENABLED:
    from numba.extending import typeof_impl

    @typeof_impl.register(WallTable)
    def _typeof_wall_table(table: WallTable, context: Any) -> Any:
        return table.numba_type


def WallFunction(fn: Any, args: int = 1) -> Any:  # noqa: N802  (a factory standing for a class)
    """``fn`` as the kernels take it: compiled (``numba.cfunc``, cached) for ``args``
    float arguments and the parameter array, once per process, or ``fn`` itself when
    the kernels run interpreted."""
    if not _jit.ENABLED:
        return fn
    if fn not in _compiled_walls:
        _compiled_walls[fn] = _jit.cfunc(fn, _wall_signature(args))
    return _compiled_walls[fn]


def wall_functions(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f): one tuple per function, one entry per wall of the curve."""
    return _table(sim.boundary.walls, ("f", "df", "d2f"), 1)


def phase_wall_functions(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f, d3f): the rows a contact phase reads (its equations need the third
    derivative)."""
    return _table(sim.boundary.walls, ("f", "df", "d2f", "d3f"), 1)


def near_functions(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(near, dnear): the walls' nearest-point conditions g(s, px, py, p) and dg/ds, for
    the fixed-step detection (method ``rk4``)."""
    return _table(sim.boundary.walls, ("near", "dnear"), 3)


def _table(walls: Any, names: tuple[str, ...], args: int) -> tuple[tuple[Any, ...], ...]:
    """One row per function name, one :func:`WallFunction` of ``args`` floats per wall:
    a :class:`WallTable` when compiled (one per set of functions in a process: typing it
    costs some 0.2 ms, which every run would pay), the interpreted functions as they
    are."""
    functions = tuple(tuple(getattr(w, name) for w in walls) for name in names)
    if not _jit.ENABLED:
        return functions
    key = (functions, args)
    table = _tables.get(key)
    if table is None:
        table = WallTable(tuple(WallFunction(f, args) for f in row) for row in functions)
        _tables[key] = table
    return table


#: the wall tables made in this process, by their functions
_tables: dict[Any, Any] = {}


def plain_wall_functions(walls: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, df, d2f) of ``walls`` as the interpreted kernels take them: the generated
    functions themselves."""
    return tuple(tuple(getattr(w, name) for w in walls) for name in ("f", "df", "d2f"))
