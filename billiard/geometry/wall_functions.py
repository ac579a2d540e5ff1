"""A curve's wall functions as the kernels take them: ``walls = (fs, dfs, d2fs)``, one
entry per wall, each compiled by ``numba.cfunc`` for one signature,
``float64(float64, float64[::1])`` (:func:`WallFunction`): a first-class function value
that numba types by its signature alone, so that the kernels are compiled once for
every curve, and cached. Interpreted, the generated functions themselves.

Compiled, a table (:class:`WallTable`) is a tuple of rows (:class:`WallRow`) that numba
sees as a type of this module (:class:`WallRowType`, through ``numba.extending``): a row
is passed to a kernel as one pointer, to its functions' addresses, and ``row[w]`` gives
the same first-class function value numba's own unboxing of the ``cfunc`` would, so a
call of a wall function compiles to the same indirect call. What changes is the call of
a kernel from Python: numba unboxes a first-class function by an import, an unpickled
signature and two Python calls (some 5 us each, 33-42 us for a table of six or eight),
a row by one attribute lookup (2.5-4.4 us per call for the whole table, typing
included), which a run pays at every chunk, contact phase and pause. This module is
compiled into the kernels (:data:`billiard.jit.KERNEL_SOURCES`).
"""

from __future__ import annotations

from typing import Any

from billiard import jit as _jit

__all__ = [
    "WALL_SLOTS",
    "WallFunction",
    "WallRow",
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


class WallRow(tuple):
    """One row of a :class:`WallTable`: a compiled function per wall slot, and
    ``address``, where the addresses numba calls them at (``cfunc.address``) lie, in a
    buffer the row keeps. numba unboxes a first-class function from Python on every call
    of a kernel (an import, an unpickled signature and two Python calls per function,
    some 5 us each: 40 us for the eight of a contact phase's table); a row reaches the
    kernels as this one pointer (:class:`WallRowType`), read by one attribute lookup."""

    address: int

    def __new__(cls, functions: Any) -> WallRow:
        import numpy as np

        row = super().__new__(cls, functions)
        row._addresses = np.array([f.address for f in row], dtype=np.uintp)
        row.address = row._addresses.ctypes.data
        return row


class WallTable(tuple):
    """Rows of compiled wall functions (``(fs, dfs, d2fs)``, one entry per wall) as the
    kernels take them (:class:`WallRow`), with their numba type worked out once: a tuple
    of :class:`WallRowType`, given to numba by its documented typing hook
    (``numba.extending.typeof_impl``). Rows shorter than :data:`WALL_SLOTS` are padded
    with their last entry."""

    numba_type: Any

    def __new__(cls, rows: Any) -> WallTable:
        from numba import typeof, types

        rows = [tuple(row) for row in rows]
        rows = [WallRow(row + row[-1:] * (WALL_SLOTS - len(row))) for row in rows]
        table = super().__new__(cls, rows)
        row_types = []
        for row in table:
            kinds = {typeof(f) for f in row}
            if len(kinds) != 1:
                raise TypeError(f"the wall functions of a row differ in type: {kinds}")
            row_types.append(WallRowType(kinds.pop().signature, len(row)))
        table.numba_type = types.BaseTuple.from_types(row_types)
        return table


if _jit.ENABLED:
    import operator

    from llvmlite import ir
    from numba import types
    from numba.extending import (
        NativeValue,
        intrinsic,
        models,
        overload,
        register_model,
        typeof_impl,
        unbox,
    )

    class WallRowType(types.Type):
        """numba's type of a :class:`WallRow`: ``slots`` functions of ``signature``,
        passed as the address of their addresses. ``row[w]`` is the first-class
        function ``types.FunctionType(signature)`` of slot ``w``, called as numba calls
        the compiled function itself (its ``cfunc`` address)."""

        def __init__(self, signature: Any, slots: int):
            self.signature = signature
            self.slots = slots
            self.function = types.FunctionType(signature)
            super().__init__(name=f"WallRow({slots} x {signature})")

    register_model(WallRowType)(models.OpaqueModel)

    @typeof_impl.register(WallTable)
    def _typeof_wall_table(table: WallTable, context: Any) -> Any:
        return table.numba_type

    @unbox(WallRowType)
    def _unbox_wall_row(typ: Any, obj: Any, c: Any) -> Any:
        """The row's ``address`` (a Python int) as a pointer; an error where it has none."""
        builder = c.builder
        entry = builder.block
        address = c.pyapi.object_getattr_string(obj, "address")
        found = builder.icmp_unsigned("!=", address, ir.Constant(address.type, None))
        with builder.if_then(found, likely=True):
            pointer = c.pyapi.long_as_voidptr(address)
            c.pyapi.decref(address)
            read = builder.block
        value = builder.phi(pointer.type)
        value.add_incoming(pointer, read)
        value.add_incoming(ir.Constant(pointer.type, None), entry)
        failed = builder.or_(builder.not_(found), c.pyapi.c_api_error())
        return NativeValue(value, is_error=failed)

    @intrinsic
    def _function_at(typingctx, row, w):
        """Slot ``w`` of a row: its address loaded into numba's first-class function
        value (the address of the compiled function; no Python object, no
        numba-convention entry, as numba unboxes a ``cfunc``)."""
        if not isinstance(row, WallRowType) or not isinstance(w, types.Integer):
            return None
        function = row.function

        def codegen(context, builder, signature, args):
            pointer, index = args
            index = context.cast(builder, index, signature.args[1], types.intp)
            slots = builder.bitcast(pointer, pointer.type.as_pointer())
            value = context.make_helper(builder, function)
            value.c_addr = builder.load(builder.gep(slots, [index]))
            value.py_addr = ir.Constant(pointer.type, None)
            value.jit_addr = ir.Constant(pointer.type, None)
            return value._getvalue()

        return function(row, w), codegen

    @overload(operator.getitem, inline="always")
    def _wall_row_item(row, w):  # numba compares its parameters with the lambda's
        if isinstance(row, WallRowType) and isinstance(w, types.Integer):
            return lambda row, w: _function_at(row, w)
        return None


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
