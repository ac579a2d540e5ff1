"""What the compiled kernels share at their call boundaries: ``jit(fn)``, a kernel;
``inline(fn)``, a kernel compiled into its compiled callers; ``borrow(array)``, the
same array without its reference count, for the entry of a compiled loop; and
``ulp(x)``, ``math.ulp`` for the compiled kernels.

``borrow``: numba counts references on every array a kernel receives, keeps in a
variable or passes on (an atomic increment and decrement of the array's memory-info
block each), and its pruning of those pairs gives up across the loops, raises and
calls of an inlined impact loop: the optimised ``run_chunk`` kept some 150 increments
and 250 decrements on its three arrays, half the time of a wedge impact. The caller of
an entry kernel (Python, or a compiled loop that itself borrowed) owns its arrays for
the whole call, so the entry borrows them: ``borrow`` gives the same data, shape and
strides with a null memory-info pointer, through numba's documented extension API
(``numba.extending.intrinsic``; the array's fields set through the lowering context's
``make_helper``). numba's counting of a null pointer is a test that LLVM folds away
once the kernels are inlined into the entry, so the counting is gone, not just made
cheap (``tests/kernels/test_loop.py`` counts the calls left in ``run_chunk``'s optimised
IR: none); a kernel the entry calls without inlining it tests a null pointer per count.
A borrowed array must not outlive the call (none is returned or stored). Interpreted
(and in a device twin), ``borrow`` is the identity.

A call between two compiled kernels passes every array as its seven fields and the
wall functions' tuple as twelve words, through memory, and counts references on the
arrays: more than the few operations of a gap, a relative position or a flight state
cost. ``inline`` compiles a kernel with numba's ``forceinline`` option (LLVM's
``alwaysinline``): LLVM inlines it into every compiled caller, so ``run_chunk`` is one
function in which values stay in registers. Inlining moves no operation: the same IEEE
operations run in the same order, without fast-math. Every kernel of ``flight``,
``surfaces``, ``locate``, ``impact`` and ``loop`` except ``run_chunk`` is marked, each
with the option from its own decorator, whichever caller compiles it first. Each
function stays a kernel of its own, callable from Python. Interpreted, ``inline`` is
the identity.

``ulp``: numba has no ``math.ulp``. Compiled, it is computed with floating-point
operations only (:func:`_ulp_compiled`), exactly; interpreted, it is ``math.ulp``.

The same files also load as the interpreted twin :mod:`billiard.kernels_py`
(:mod:`billiard.kernels.interpreted`), whose functions the runtime's classes call one gap at a
time; there every decorator here is the identity (and ``ulp`` is ``math.ulp``) whether
numba is there or not: the kernels import these from their sibling, so the package a
file is loaded in decides.

A device twin (:mod:`billiard.kernels.twin`, loaded for a GPU by
:mod:`billiard.engine.gpu`) carries a ``DEVICE`` object on its package, set by its
loader before any of its modules runs: its ``jit(fn, inline)`` compiles a kernel for
the device (``inline``: inlined into its device callers), and its ``walls`` are the
curve's wall functions compiled for the device, which :mod:`.wallcall` calls (``WALLS``
here; None elsewhere). There ``ulp`` is :func:`_ulp_compiled`.
"""

from __future__ import annotations

import math
import sys

from billiard import jit as _jit

__all__ = ["COMPILED", "DEVICE", "WALLS", "borrow", "inline", "jit", "ulp"]

#: compiled by numba: the package billiard.kernels with numba enabled (never the twin)
COMPILED = _jit.ENABLED and __package__ == "billiard.kernels"
#: the device twin's compiler and wall functions (None: not a device twin)
_DEVICE = None if COMPILED else getattr(sys.modules.get(__package__ or ""), "DEVICE", None)
#: compiled for a device: the package is a device twin
DEVICE = _DEVICE is not None
#: the curve's wall functions compiled for the device, rows (f, f', f''), one function
#: per wall slot (None on the CPU)
WALLS = _DEVICE.walls if DEVICE else None

# the constants of _ulp_compiled: Rump's phi = 2**52 + 1 and 1 - 2**-53, the scalings
# that keep phi * x finite and normal, and the results outside the finite numbers
_PHI = 2.0**52 + 1.0
_ONE_LESS = 1.0 - 2.0**-53
_LARGE = 2.0**970
_SMALL = 2.0**-969
_TINY = 2.0**-1074
_NOT_FINITE = 2.0**972


def jit(fn):
    """:func:`billiard.jit.jit` (the identity in the interpreted twin; compiled for the
    device in a device twin)."""
    if DEVICE:
        return _DEVICE.jit(fn, False)
    return _jit.jit(fn) if COMPILED else fn


def inline(fn):
    """``jit(fn)``, inlined into every compiled caller (numba's ``forceinline``)."""
    if DEVICE:
        return _DEVICE.jit(fn, True)
    return _jit.jit(fn, inline=True) if COMPILED else fn


@inline
def _ufp(x):
    """The unit in the first place of a positive float whose product with 2**52 + 1
    is finite and normal: the power of two 2**e with 2**e <= x < 2**(e + 1), from
    three rounded operations (S. M. Rump, T. Ogita, S. Oishi, "Accurate floating-point
    summation part I", SIAM J. Sci. Comput. 31(1), 2008, Algorithm 3.5)."""
    q = _PHI * x
    return abs(q - _ONE_LESS * q)


@inline
def _ulp_compiled(x):
    """math.ulp(x) of a finite x, exactly, from floating-point operations: the ulp of
    a normal number is its unit in the first place times 2**-52, that of a subnormal
    (and of zero) the smallest subnormal. The scalings by powers of two are exact. A
    non-finite x gives 2**972 (the exponent field of all ones read as a finite one)."""
    y = abs(x)
    if not y <= 1.7976931348623157e308:  # inf, nan
        return _NOT_FINITE
    if y >= _LARGE:
        return _ufp(y * 2.0**-110) * 2.0**58
    if y < _SMALL:
        return max(_ufp(y * 2.0**110) * 2.0**-162, _TINY)
    return _ufp(y) * 2.0**-52


def _ulp(x):
    """math.ulp(x) (interpreted)."""
    return math.ulp(x)


def _identity(array):
    return array


if COMPILED:
    from numba import types as _types
    from numba.extending import intrinsic as _intrinsic

    @_intrinsic
    def borrow(typingctx, array):
        """``array`` with a null memory-info pointer: no reference counting."""
        if not isinstance(array, _types.Array):
            return None

        def codegen(context, builder, signature, args):
            view = context.make_helper(builder, array, value=args[0])
            view.meminfo = context.get_constant_null(_types.MemInfoPointer(array.dtype))
            return view._getvalue()

        return array(array), codegen

else:
    # interpreted: the identity; on a device: the identity compiled for it
    borrow = inline(_identity)


ulp = _ulp_compiled if COMPILED or DEVICE else _ulp
