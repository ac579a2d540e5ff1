"""One decorator for the compiled kernels: :func:`jit`.

With numba importable and ``NUMBA_DISABLE_JIT`` unset (or ``0``), ``jit`` is
``numba.njit(cache=True, nogil=True, error_model="python")``: no fast-math, so every
operation is the IEEE operation CPython performs, in the same order, and a division by
zero raises as in Python. Otherwise ``jit`` returns the function itself and the kernels
run interpreted: the same source, no second copy. Without numba a one-line notice says
so, once (on first use).

``ENABLED`` tells which of the two is in force.

Caching: numba reuses a cached function when the source file it is defined in is
unchanged, but machine code compiled into it from other modules (a kernel calls
kernels of other modules, the generated ball equations, constants of the engine) is not
checked. The functions of :mod:`billiard.kernels` are therefore stamped with one hash of
every source they compile in (:data:`KERNEL_SOURCES`): an edit or a regenerated
``ball.py`` recompiles all of them. The cache lives beside the sources (``__pycache__``)
when that is writable, else in the user's cache directory (numba's own fallback), or in
``NUMBA_CACHE_DIR`` when set. The wall functions of a curve are not compiled into the
kernels (they are passed by address), so each is stamped by its own module.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

__all__ = [
    "COMPILED_NOTICE",
    "COMPILE_NOTICE",
    "ENABLED",
    "KERNEL_SOURCES",
    "compile_family",
    "jit",
    "kernel_source_hash",
    "numba_problem",
]

_PACKAGE = Path(__file__).resolve().parent
_KERNELS = _PACKAGE / "kernels"
#: The modules compiled into the kernels besides billiard.kernels.*
KERNEL_SOURCES = (
    "billiard.jit",
    "billiard.generated.ball",
    "billiard.generated.contact",
)
_source_hash: bytes | None = None


def kernel_source_hash() -> bytes:
    """sha256 over the kernels' sources and every source compiled into them."""
    global _source_hash
    if _source_hash is None:
        digest = hashlib.sha256()
        files = sorted(_KERNELS.glob("*.py")) + [
            Path(importlib.util.find_spec(name).origin) for name in KERNEL_SOURCES
        ]
        for path in files:
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
        _source_hash = digest.digest()
    return _source_hash


F = TypeVar("F", bound=Callable[..., Any])

_problem: str | None = None
_noticed = False
#: printed when numba starts compiling a function of billiard's that is not in the cache
#: (an empty or outdated cache, or a kind of argument, e.g. a curve's number of walls,
#: not compiled before): what it is and the function; one line per family and curve
COMPILE_NOTICE = "billiard: compiling {family} with numba ({function}); cached for later runs"
#: printed when such a compile ends, if it took a second or more
COMPILED_NOTICE = "billiard: compiled {family} in {seconds:.1f} s"
#: the compiles shorter than this (s) end without a line
COMPILED_NOTICE_AFTER = 1.0
#: what the functions of each module are, for the compile notices
_FAMILIES = {
    "billiard.kernels.loop": "the impact loop",
    "billiard.kernels.locate": "the impact locator",
    "billiard.kernels.flight": "the flight (exact, or with air drag)",
    "billiard.kernels.impact": "the impact law",
    "billiard.kernels.fixed_step": "the rk4 method's fixed steps",
    "billiard.kernels.contact": "the contact phases (rolling, sliding)",
    "billiard.kernels.contact_forces": "the contact phases (rolling, sliding)",
    "billiard.kernels.contact_equations": "the contact phases (rolling, sliding)",
    "billiard.kernels.vertex": "the hold in a vertex",
    "billiard.kernels.rest": "the resting-position scan",
    "billiard.kernels.surfaces": "the walls' offset surfaces",
    "billiard.kernels.float_text": "the CSV number formatting",
    "billiard.kernels.ryu": "the CSV number formatting",
}
#: the functions whose family is not their module's
_FUNCTION_FAMILIES = {
    "billiard.kernels.loop.run_chunk_fixed": "the impact loop of the rk4 method",
}
#: the families (a curve's wall functions among them) announced in this process
_announced: set[str] = set()
#: the compiles in progress, outermost first: (function, family, start time)
_compiling: list[tuple[Any, str | None, float]] = []


def compile_family(function: Any) -> str | None:
    """What a function numba compiles belongs to, in words, for the compile notices
    (None: not billiard's, no notice): a kernel family, or a curve's wall functions."""
    module = getattr(function, "__module__", "") or ""
    if module.startswith(("billiard.generated.curves.", "billiard_user_curves.")):
        names = getattr(function, "__globals__", {})
        name, expression = names.get("NAME", module.rpartition(".")[2]), names.get("EXPRESSION")
        if str(name).startswith("expr_") and expression:
            return f"the wall functions of the curve f(x) = {expression}"
        return f"the wall functions of curve {name!r}"
    if module.startswith("billiard.kernels."):
        where = f"{module}.{getattr(function, '__qualname__', '')}"
        return _FUNCTION_FAMILIES.get(where) or _FAMILIES.get(
            module, f"the engine's kernels ({module})"
        )
    return None


def _disabled() -> bool:
    return os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")


def _import_numba() -> Any:
    """``import numba``, without the two modules its import reads and a run never uses:
    scipy, imported only to check its version (pyproject.toml requires a later one than
    numba does), and yaml, which reads ``.numba_config.yaml`` in the working directory
    (hidden only when there is none; numba looks for it once more, then, on each compile,
    so it gets yaml back, loaded on first use). Either already imported stays."""
    hidden = ["scipy"]
    if not os.path.isfile(".numba_config.yaml"):
        hidden.append("yaml")
    hidden = [name for name in hidden if name not in sys.modules]
    for name in hidden:
        sys.modules[name] = None  # type: ignore[assignment]  (an ImportError)
    try:
        import numba
    finally:
        for name in hidden:
            if name in sys.modules and sys.modules[name] is None:
                del sys.modules[name]
    yaml = _lazy_module("yaml") if "yaml" in hidden else None
    if yaml is not None:
        from numba.core import config

        config.yaml, config._HAVE_YAML = yaml, True
    return numba


def _lazy_module(name: str) -> Any:
    """Module ``name``, executed on its first attribute access (None if not installed)."""
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        return None
    spec.loader = importlib.util.LazyLoader(spec.loader)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


try:
    if _disabled():
        raise ImportError("NUMBA_DISABLE_JIT is set")
    numba = _import_numba()
    from numba.core.errors import NumbaExperimentalFeatureWarning
except ImportError as exc:  # no numba on this platform, or the JIT disabled
    numba = None
    _problem = str(exc)
else:
    # the wall functions are first-class function values (numba.core.types.FunctionType)
    warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)
    from numba.core import caching as _caching

    #: cache folders found writable in this process
    _writable: set[str] = set()

    class _CheckedOnce:
        """A cache locator of billiard's functions that checks its folder once per
        process: numba's check creates and deletes a temporary file in the folder for
        every function (some fifty of them, most never called from Python)."""

        @classmethod
        def from_function(cls, py_func, py_file):
            if not getattr(py_func, "__module__", "").startswith("billiard."):
                return None
            return super().from_function(py_func, py_file)

        def ensure_cache_path(self):
            path = self.get_cache_path()
            if path not in _writable:
                super().ensure_cache_path()
                _writable.add(path)

    @functools.cache
    def _in_kernels(py_file: str) -> bool:
        return Path(py_file).resolve().parent == _KERNELS

    class _KernelStamp(_CheckedOnce):
        """A cache locator for the functions defined in billiard/kernels/: stamped with
        :func:`kernel_source_hash` instead of their own file's hash."""

        @classmethod
        def from_function(cls, py_func, py_file):
            if not _in_kernels(py_file):
                return None
            return super().from_function(py_func, py_file)

        def get_source_stamp(self):
            return kernel_source_hash()

    _bases = (
        _caching.UserProvidedCacheLocator,
        _caching.InTreeCacheLocator,
        _caching.UserWideCacheLocator,
    )
    _locators = [type(f"Kernel{base.__name__}", (_KernelStamp, base), {}) for base in _bases]
    _locators += [type(f"Billiard{base.__name__}", (_CheckedOnce, base), {}) for base in _bases]
    _caching.CacheImpl._locator_classes[:0] = _locators

    from numba.core import event as _event

    class _CompileNotice(_event.Listener):
        """Says what of billiard's is being compiled, and how long a long compile took:
        numba signals "numba:compile" only when a function is compiled, not when it is
        loaded from the cache, so a warm start prints nothing. A compile compiles the
        functions it calls within its own signal: only the outermost one speaks. Its
        family is named once per process (a second compile of it, for other argument
        types, says only how long it took when that was long)."""

        def on_start(self, event):
            function = getattr((event.data or {}).get("dispatcher"), "py_func", None)
            family = compile_family(function) if not _compiling else None
            _compiling.append((function, family, time.perf_counter()))
            if family is not None and family not in _announced:
                _announced.add(family)
                where = f"{function.__module__}.{function.__qualname__}"
                line = COMPILE_NOTICE.format(family=family, function=where)
                print(line, file=sys.stderr, flush=True)

        def on_end(self, event):
            if not _compiling:  # pragma: no cover - a start always comes first
                return
            _, family, started = _compiling.pop()
            seconds = time.perf_counter() - started
            if family is not None and seconds >= COMPILED_NOTICE_AFTER:
                line = COMPILED_NOTICE.format(family=family, seconds=seconds)
                print(line, file=sys.stderr, flush=True)

    _event.register("numba:compile", _CompileNotice())

    import numpy as _np
    from numba.core import types as _types
    from numba.core.typing.typeof import typeof_impl as _typeof_impl
    from numba.np import numpy_support as _numpy_support

    _typeof_array = _typeof_impl.dispatch(_np.ndarray)

    @_typeof_impl.register(_np.ndarray)
    def _typeof_ndarray(val, c):
        """numba's type of an array, without importing numpy.ma (a twentieth of a
        second) to rule out a masked array: none exists before numpy.ma is imported."""
        if "numpy.ma" in sys.modules:
            return _typeof_array(val, c)
        try:
            dtype = _numpy_support.from_dtype(val.dtype)
        except numba.core.errors.NumbaNotImplementedError:
            return _typeof_array(val, c)  # numba's error
        layout = _numpy_support.map_layout(val)
        return _types.Array(dtype, val.ndim, layout, readonly=not val.flags.writeable)


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


@contextlib.contextmanager
def _llvm_lock_unobserved() -> Iterator[None]:
    """llvmlite's calls without numba's "numba:llvm_lock" events: numba has every call
    into LLVM (some 3,000 while cached code is loaded, to list the symbols it defines)
    signal two events, which only the timers of a compilation read. A compilation, on a
    cache miss, runs outside (after) this, with them."""
    from llvmlite.binding import ffi

    callbacks = getattr(getattr(ffi.lib, "_lock", None), "_cblist", None)
    if not isinstance(callbacks, list) or not callbacks:
        yield
        return
    saved = callbacks[:]
    callbacks.clear()
    try:
        yield
    finally:
        callbacks[:0] = saved


def _load_lightly(dispatcher: Any) -> None:
    """Load ``dispatcher``'s cached machine code without numba's full registries.

    numba's cache refreshes the target context before every load: it imports the
    implementations of everything numba can compile (numpy's linear algebra, random,
    typed containers, ...), about 0.35 s and 20 MB, which machine code loaded from the
    cache never uses: it needs only numba's runtime (NRT) linked in, which is loaded
    from the cache too (:func:`_initialize_runtime`). A cache miss compiles, and the
    compiler refreshes the contexts itself.
    """
    cache = dispatcher._cache

    def load_overload(sig: Any, target_context: Any) -> Any:
        with _llvm_lock_unobserved():
            _initialize_runtime(target_context, cache._cache_path)
            with cache._guard_against_spurious_io_errors():
                return cache._load_overload(sig, target_context)

    cache.load_overload = load_overload


def _initialize_runtime(target_context: Any, folder: str) -> None:
    """numba's runtime (NRT) initialized with its machine code read from ``folder``.

    numba compiles the runtime's few LLVM functions (reference counts, atomic
    operations) in every process, 25-30 ms of a warm start. The compiled object is kept
    in ``folder`` (the cache folder of the first function loaded: a curve's or the
    kernels'), named by what numba itself checks before reusing cached machine code:
    its version, llvmlite's, and the target (triple, CPU, CPU features). Unreadable or
    absent, it is compiled, then written (atomically).
    """
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.runtime import nrtdynmod, rtsys

    # numba's own lock (re-entrant, taken by initialize too): no other thread sees the
    # swapped function, or initializes the runtime meanwhile
    with global_compiler_lock:
        if rtsys._init:
            return
        compile_nrt = nrtdynmod.compile_nrt_functions
        nrtdynmod.compile_nrt_functions = functools.partial(_runtime_library, folder=folder)
        try:
            rtsys.initialize(target_context)
        finally:
            nrtdynmod.compile_nrt_functions = compile_nrt


def _runtime_library(ctx: Any, folder: str) -> Any:
    """The runtime's library for ``ctx``: read from ``folder``, or compiled (as
    ``nrtdynmod.compile_nrt_functions`` does) and written there."""
    import pickle

    import llvmlite
    from numba.core.runtime import nrtdynmod

    codegen = ctx.codegen()
    key = repr((numba.__version__, llvmlite.__version__, codegen.magic_tuple()))
    path = Path(folder) / f"nrt-{hashlib.sha256(key.encode()).hexdigest()[:16]}.nbo"
    try:
        state = pickle.loads(path.read_bytes())
        return codegen.unserialize_library(state)
    except Exception:  # absent, unreadable or not numba's: compiled below
        pass
    ir_module, library = nrtdynmod.create_nrt_module(ctx)
    library.enable_object_caching()
    library.add_ir_module(ir_module)
    library.finalize()
    part = path.with_name(f"{path.name}.{os.getpid()}.part")
    try:
        part.write_bytes(pickle.dumps(library.serialize_using_object_code()))
        os.replace(part, path)
    except OSError:  # a read-only cache: compiled in each process, as numba does
        with contextlib.suppress(OSError):
            part.unlink(missing_ok=True)
    return library


def jit(fn: F) -> F:
    """Compile ``fn`` with numba (cached on disk), or return it unchanged."""
    if numba is None:
        return fn
    dispatcher = numba.njit(cache=True, nogil=True, error_model="python")(fn)
    _load_lightly(dispatcher)
    return dispatcher
