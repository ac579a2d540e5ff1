"""What the compiled kernels do at their call boundaries: ``borrow(array)``, the same
array without its reference count, for the entry of a compiled loop; ``inline(fn)``,
a kernel compiled into its compiled callers; and ``ulp(x)``, ``math.ulp`` for the
compiled kernels.

numba counts references on every array passed to a call it does not inline: an
atomic increment and decrement per array per call, on the hot path of every gap
evaluation. The kernels' arrays are owned by the caller (:mod:`billiard.run.compiled`) for
the whole call of :func:`billiard.kernels.loop.run_chunk`, so inside it they can be
borrowed: a view with no memory-info pointer, whose reference counting is a test of a
null pointer. Interpreted, ``borrow`` is the identity.

A call between two compiled kernels passes every array as its seven fields and the
wall functions' tuple as twelve words, through memory, and counts references on the
arrays: more than the few operations of a gap, a relative position or a flight state
cost. ``inline`` compiles a kernel with numba's ``forceinline`` option (LLVM's
``alwaysinline``): LLVM inlines it into every compiled caller, so ``run_chunk`` is one
function in which the borrowed arrays' reference counting folds away and values stay in
registers. Inlining moves no operation: the same IEEE operations run in the same order,
without fast-math. Every kernel of ``flight``, ``surfaces``, ``locate``, ``impact`` and
``loop`` except ``run_chunk`` is marked, because numba otherwise inherits the option
from whichever caller compiles a kernel first (a kernel first compiled from Python would
not be inlined later: its cached code would be reused). numba's own
``inline="always"`` (inlining numba IR before typing) ran about as fast but took five
times longer to compile. Each function stays a kernel of its own, callable from Python.
Interpreted, ``inline`` is the identity.

``ulp``: numba has no ``math.ulp``; compiled, it is read from the exponent bits (one
shift and a select, instead of ``frexp`` and ``ldexp`` calls into numba's helpers);
interpreted, it is ``math.ulp``. Both give the exact power of two, so the results agree.

``jit``: :func:`billiard.jit.jit`, for the kernels that are not inlined (``run_chunk``,
the generated ball equations).

The same files also load as the interpreted twin :mod:`billiard.kernels_py`
(:mod:`billiard.kernels.interpreted`), whose functions the runtime's classes call one gap at a
time; there every decorator here is the identity (and ``ulp`` is ``math.ulp``) whether
numba is there or not: the kernels import these from their sibling, so the package a
file is loaded in decides.
"""

from __future__ import annotations

import math

from billiard import jit as _jit

__all__ = ["COMPILED", "borrow", "inline", "jit", "ulp"]

#: compiled by numba: the package billiard.kernels with numba enabled (never the twin)
COMPILED = _jit.ENABLED and __package__ == "billiard.kernels"


def _identity(array):
    return array


def jit(fn):
    """:func:`billiard.jit.jit` (the identity in the interpreted twin)."""
    return _jit.jit(fn) if COMPILED else fn


def inline(fn):
    """``jit(fn)``, inlined into every compiled caller."""
    kernel = jit(fn)
    if COMPILED:
        # the decorator's options, and LLVM's alwaysinline on the compiled function
        kernel.targetoptions["forceinline"] = True
    return kernel


def _ulp(x):
    """math.ulp(x) (interpreted)."""
    return math.ulp(x)


if COMPILED:
    from llvmlite import ir
    from numba.core import types
    from numba.extending import intrinsic

    @intrinsic
    def borrow(typingctx, array):
        if not isinstance(array, types.Array):
            return None

        def codegen(context, builder, signature, args):
            # imported when compiling, not when loading from the cache (30 ms)
            from numba.np.arrayobj import make_array, populate_array

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

    @intrinsic
    def _ulp_bits(typingctx, x):
        """math.ulp of a finite float64, from its exponent field: 2**(e - 1075) for a
        biased exponent e >= 53, the subnormal 2**(e - 1075) = bit e - 1 for
        1 <= e <= 52, and the smallest subnormal for e = 0 (zero and subnormals)."""
        if not isinstance(x, types.Float) or x.bitwidth != 64:
            return None

        def codegen(context, builder, signature, args):
            i64 = ir.IntType(64)
            bits = builder.bitcast(args[0], i64)
            e = builder.and_(builder.lshr(bits, i64(52)), i64(0x7FF))
            normal = builder.shl(builder.sub(e, i64(52)), i64(52))
            low = builder.shl(i64(1), builder.sub(e, i64(1)))
            result = builder.select(
                builder.icmp_unsigned(">=", e, i64(53)),
                normal,
                builder.select(builder.icmp_unsigned("==", e, i64(0)), i64(1), low),
            )
            return builder.bitcast(result, ir.DoubleType())

        return types.float64(types.float64), codegen

    ulp = _ulp_bits

else:
    borrow = _identity
    ulp = _ulp
