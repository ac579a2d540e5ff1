"""The state vector ``ctx`` by name, for the wings outside the kernels and the engine:
they read and write its quantities through these functions, by the names
:mod:`billiard.kernels.layout` declares (``"engine.q1"``; a surface's ``"warm_s"``), and
never subscript it with a slot (a test scans the package for that), so that a change
of the layout is made in the layout alone.

``ctx`` is one vector (a list of floats or a float64 array), ``ctxs`` an array of them,
one row per trajectory; ``write`` and the columns take quantities of one slot,
``read_slots`` and ``write_slots`` quantities of several. A model sets its block's
quantities with ``write_block(ctx, "phase", mass=m, radius=r)`` and hands its block on
with ``copy(to, ctx, "impact")`` (a block, or the slots from one name through another).
A surface's block is addressed by the surface's number ``j`` and a quantity of
:data:`~billiard.kernels.layout.SURFACE` (``"kind"``, ``"a"`` .. ``"e"``, ``"warm_s"``, ...).
"""

from __future__ import annotations

from collections.abc import MutableSequence, Sequence
from typing import Any

from billiard.kernels.layout import CTX, S_WS, S_WSLOPE, SIZE, SURF, SURF_STRIDE, SURFACE

__all__ = [
    "column",
    "columns",
    "copy",
    "new_ctx",
    "put_surface_block",
    "put_warm_s",
    "read",
    "read_slots",
    "read_surface",
    "set_columns",
    "surface_block",
    "surface_constants",
    "surface_ctx",
    "warm_start",
    "write",
    "write_block",
    "write_slots",
    "write_surface",
    "write_surface_slots",
]


def _index(name: str) -> int:
    """The slot of ``ctx``'s one-slot quantity ``name``."""
    slot = CTX.slot(name)
    if slot.size != 1:
        raise ValueError(f"{name} has {slot.size} slots, not one")
    return slot.index


# a surface's quantities: offset from its block's start (by name, without "surface.")
_OFFSET = {s.name.removeprefix("surface."): s.index for s in SURFACE.slots}


def _offset(name: str) -> int:
    try:
        return _OFFSET[name]
    except KeyError:
        raise KeyError(f"no quantity {name!r} in a surface's block") from None


#: ``read(ctx, name)``: the value of ``ctx``'s quantity ``name`` (a tuple when it has
#: more than one slot)
read = CTX.read


def write(ctx: MutableSequence[float], name: str, value: float) -> None:
    """Set ``ctx``'s quantity ``name`` to ``value``."""
    ctx[_index(name)] = value


def read_slots(ctx: Sequence[float], name: str, count: int | None = None) -> tuple[float, ...]:
    """The values of the slots of ``ctx``'s quantity ``name``: its first ``count`` (all
    by default)."""
    slot = CTX.slot(name)
    if count is None:
        count = slot.size
    elif not 0 <= count <= slot.size:
        raise ValueError(f"{name} has {slot.size} slots, not {count}")
    return tuple(float(x) for x in ctx[slot.index : slot.index + count])


def write_slots(
    ctx: MutableSequence[float], name: str, values: Sequence[float], at: int = 0
) -> None:
    """Set the slots of ``ctx``'s quantity ``name`` from its ``at``-th (its first by
    default) to ``values``, one each; the slots after them keep their values."""
    slot = CTX.slot(name)
    start, stop = slot.index + at, slot.index + at + len(values)
    if at < 0 or stop > slot.stop:
        raise ValueError(f"{name} has {slot.size} slots: {len(values)} from slot {at} do not fit")
    ctx[start:stop] = values


def write_block(ctx: MutableSequence[float], block: str, **values: float) -> None:
    """Set the one-slot quantities of ``block`` named by the keywords
    (``write_block(ctx, "hold", za=0.1, zb=-0.1)``)."""
    for name, value in values.items():
        ctx[_index(f"{block}.{name}")] = value


# a block's slots, by its name
_BLOCKS = {name: (start, stop) for name, start, stop in CTX.blocks}


def _span(name: str) -> tuple[int, int]:
    """The slots (start, stop) of the block or the quantity ``name``."""
    if name in _BLOCKS:
        return _BLOCKS[name]
    slot = CTX.slot(name)
    return slot.index, slot.stop


def copy(to: MutableSequence[float], source: Sequence[float], first: str, last: str = "") -> None:
    """Copy the slots of ``source`` from the block or quantity ``first`` through the
    block or quantity ``last`` (default ``first``) into the same slots of ``to``
    (``copy(ctx, flight_ctx, "flight.kind", "flight.step")``: the flight's constants and
    step proposal)."""
    start, stop = _span(first)[0], _span(last or first)[1]
    if stop <= start:
        raise ValueError(f"{last} comes before {first} in the state vector")
    to[start:stop] = source[start:stop]


def new_ctx(through: str = "") -> list[float]:
    """A state vector of zeros: every slot, or the slots through the block ``through``
    alone (the vector of a model that keeps nothing after its block)."""
    return [0.0] * (_BLOCKS[through][1] if through else SIZE)


def column(ctxs: Any, name: str) -> Any:
    """The quantity ``name`` of each row of ``ctxs`` (a view of the array)."""
    return ctxs[:, _index(name)]


def columns(ctxs: Any, names: Sequence[str]) -> Any:
    """The quantities ``names`` of each row of ``ctxs``: a new array, one column each."""
    return ctxs[:, [_index(name) for name in names]]


def set_columns(ctxs: Any, names: Sequence[str], values: Any) -> None:
    """Set the quantities ``names`` of each row of ``ctxs`` to the columns of ``values``
    (or to one value for all)."""
    ctxs[:, [_index(name) for name in names]] = values


def surface_ctx(surfaces: int) -> list[float]:
    """A state vector of zeros long enough for the blocks of ``surfaces`` surfaces (the
    slots before them unused): what a surface's own kernel calls take."""
    return [0.0] * (SURF + surfaces * SURF_STRIDE)


def read_surface(ctx: Sequence[float], j: int, name: str) -> float:
    """The quantity ``name`` of surface ``j``'s block."""
    return ctx[SURF + j * SURF_STRIDE + _offset(name)]


def write_surface(ctx: MutableSequence[float], j: int, **values: float) -> None:
    """Set the quantities of surface ``j``'s block named by the keywords."""
    base = SURF + j * SURF_STRIDE
    for name, value in values.items():
        ctx[base + _offset(name)] = value


# the warm start is copied in and out around every query of a surface: positional, the
# fastest of these accessors (a tenth of a microsecond)
def write_surface_slots(
    ctx: MutableSequence[float], j: int, name: str, values: Sequence[float]
) -> None:
    """Set the first slots of surface ``j``'s quantity ``name`` (one of several slots, as
    a chain's joins) to ``values``."""
    base = SURF + j * SURF_STRIDE + _offset(name)
    ctx[base : base + len(values)] = [float(v) for v in values]


def warm_start(ctx: Sequence[float], j: int) -> tuple[float, float]:
    """Surface ``j``'s warm start ``(s, slope)``: its quantities ``warm_s`` and
    ``warm_slope``."""
    base = SURF + j * SURF_STRIDE
    return ctx[base + S_WS], ctx[base + S_WSLOPE]


def put_warm_s(ctx: MutableSequence[float], j: int, s: float) -> None:
    """Set surface ``j``'s ``warm_s``: where the next inversion of its offset curve
    starts."""
    ctx[SURF + j * SURF_STRIDE + S_WS] = s


def surface_block(ctx: Sequence[float], j: int) -> list[float]:
    """A copy of surface ``j``'s whole block (:func:`put_surface_block` writes it)."""
    base = SURF + j * SURF_STRIDE
    return list(ctx[base : base + SURF_STRIDE])


def put_surface_block(ctx: MutableSequence[float], j: int, block: Sequence[float]) -> None:
    """Write ``block`` (a whole block, or its first slots) as surface ``j``'s block."""
    base = SURF + j * SURF_STRIDE
    ctx[base : base + len(block)] = block


def surface_constants(ctx: Sequence[float], j: int, **values: float) -> list[float]:
    """A copy of the constants of surface ``j``'s block (its slots before the warm
    start, which the engine's state vectors take from a surface), the quantities named
    by the keywords replaced."""
    base = SURF + j * SURF_STRIDE
    block = list(ctx[base : base + S_WS])
    for name, value in values.items():
        offset = _offset(name)
        if offset >= S_WS:
            raise KeyError(f"{name!r} is no constant of a surface's block")
        block[offset] = value
    return block
