"""``borrow(array)``: the same array without its reference count, for the entry of a
compiled loop.

numba counts references on every array passed to a call it does not inline: an
atomic increment and decrement per array per call, on the hot path of every gap
evaluation. The kernels' arrays are owned by the caller (:mod:`billiard.compiled`) for
the whole call of :func:`billiard.kernels.loop.run_chunk`, so inside it they can be
borrowed: a view with no memory-info pointer, whose reference counting is a test of a
null pointer. Interpreted, ``borrow`` is the identity.
"""

from __future__ import annotations

from billiard import jit as _jit

__all__ = ["borrow"]


def _identity(array):
    return array


if _jit.ENABLED:
    from numba.core import types
    from numba.extending import intrinsic
    from numba.np.arrayobj import make_array, populate_array

    @intrinsic
    def borrow(typingctx, array):
        if not isinstance(array, types.Array):
            return None

        def codegen(context, builder, signature, args):
            source = make_array(array)(context, builder, args[0])
            view = make_array(array)(context, builder)
            populate_array(
                view,
                data=source.data,
                shape=source.shape,
                strides=source.strides,
                itemsize=source.itemsize,
                meminfo=None,
            )
            return view._getvalue()

        return array(array), codegen

else:
    borrow = _identity
