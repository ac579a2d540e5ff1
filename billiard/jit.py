"""The compiled kernels' use of numba, through its public API only: :func:`jit`,
:func:`cfunc`, the compile notices (:func:`compiling`) and the cache stamp of the
kernels (:func:`refresh_kernel_cache`).

With numba importable and ``NUMBA_DISABLE_JIT`` unset (or ``0``), ``jit`` is
``numba.njit(cache=True, nogil=True, error_model="python")``, with ``forceinline=True``
for a kernel inlined into its compiled callers: no fast-math, so every operation is the
IEEE operation CPython performs, in the same order, and a division by zero raises as in
Python. Otherwise ``jit`` returns the function itself and the kernels run interpreted:
the same source, no second copy. Without numba a one-line notice says so, once (on
first use).

``ENABLED`` tells which of the two is in force.

Caching: numba reuses a cached function while the source file it is defined in is
unchanged, but machine code compiled into it from other modules (a kernel calls
kernels of other modules, the generated ball equations, constants of the engine) is not
checked (numba's documented limit). :func:`refresh_kernel_cache` therefore keeps one
hash of every source compiled into the kernels (:func:`kernel_source_hash` over
``billiard/kernels/*.py`` and :data:`KERNEL_SOURCES`) in a stamp file beside their
cache (``__pycache__`` beside the sources, ``NUMBA_CACHE_DIR`` when set, or the user's
cache folder where the sources' cannot be written); when it differs, that cache is
removed before any kernel is loaded, and the kernels compile anew. The wall functions
of a curve are not compiled into the kernels (they are passed as first-class functions),
so each is stamped by its own module.
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import importlib.util
import os
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

__all__ = [
    "ALL_COMPILED_FILE",
    "COMPILED_NOTICE",
    "COMPILE_NOTICE",
    "ENABLED",
    "KERNEL_SOURCES",
    "STAMP_FILE",
    "all_compiled",
    "cache_stamped",
    "cfunc",
    "compile_family",
    "compiles",
    "compiling",
    "jit",
    "kernel_source_hash",
    "mark_all_compiled",
    "numba_problem",
    "on_first_compile",
    "refresh_kernel_cache",
]

_PACKAGE = Path(__file__).resolve().parent
_KERNELS = _PACKAGE / "kernels"
#: The modules compiled into the kernels besides billiard.kernels.* (the wall table's
#: numba type: how a kernel reads a wall function from its row)
KERNEL_SOURCES = (
    "billiard.jit",
    "billiard.generated.ball",
    "billiard.generated.contact",
    "billiard.geometry.wall_functions",
)
#: the stamp of the kernels' cache: the :func:`kernel_source_hash` (hex) their cache
#: was last invalidated for, in the kernels' ``__pycache__``
STAMP_FILE = "billiard-kernels.sha256"
#: beside the stamp: the stamp's text once every kernel a run can need has been
#: compiled into that cache together (:func:`mark_all_compiled`); removed with the cache
ALL_COMPILED_FILE = "billiard-kernels.compiled"
_source_hash: bytes | None = None


def _source_files() -> list[Path]:
    """``billiard/kernels/*.py`` and the files of :data:`KERNEL_SOURCES`."""
    return sorted(_KERNELS.glob("*.py")) + [
        Path(importlib.util.find_spec(name).origin) for name in KERNEL_SOURCES
    ]


def _hash(files: list[Path]) -> bytes:
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.digest()


def kernel_source_hash() -> bytes:
    """sha256 over the kernels' sources and every source compiled into them."""
    global _source_hash
    if _source_hash is None:
        _source_hash = _hash(_source_files())
    return _source_hash


def refresh_kernel_cache(kernels: Path | None = None, sources: list[Path] | None = None) -> bool:
    """Remove numba's cache of the functions defined in ``kernels`` (a folder, default
    ``billiard/kernels``) when a source compiled into them (``kernels/*.py`` and
    ``sources``, default the files of :data:`KERNEL_SOURCES`) changed since the stamp
    beside that cache was written; returns True when it removed it.

    numba reuses a cached function while its own file is unchanged, so an edit of
    another file it compiles in would go unseen. The cache is where numba keeps it: in
    ``NUMBA_CACHE_DIR`` when that is set, else in ``kernels/__pycache__``, or where that
    cannot be written in the user's cache folder (numba's folder for ``kernels`` in
    each); its files are numba's index (``*.nbi``) and machine code (``*.nbc``) files,
    removed before any kernel is loaded (this runs on ``import billiard``). Where no
    folder can be written, nothing is done."""
    if kernels is None:
        kernels, digest = _KERNELS, kernel_source_hash()
    else:
        digest = _hash(sorted(kernels.glob("*.py")) + list(sources or ()))
    text = digest.hex() + "\n"
    for folder in _cache_folders(kernels):
        try:
            return _refresh(folder, text)
        except OSError:
            continue  # not writable: numba's cache is in the next folder
    return False


def _refresh(folder: Path, text: str) -> bool:
    """The cache files in ``folder`` removed unless its stamp reads ``text``; the stamp
    written. Raises OSError where ``folder`` cannot be written."""
    stamp = folder / STAMP_FILE
    try:
        if stamp.read_text(encoding="ascii") == text:
            return False
    except (OSError, UnicodeDecodeError):
        pass  # none yet, or unreadable: removed below
    folder.mkdir(parents=True, exist_ok=True)
    (folder / ALL_COMPILED_FILE).unlink(missing_ok=True)
    for pattern in ("*.nbi", "*.nbc"):
        for path in folder.glob(pattern):
            path.unlink(missing_ok=True)
    part = stamp.with_name(f"{stamp.name}.{os.getpid()}.part")
    part.write_text(text, encoding="ascii")
    os.replace(part, stamp)
    return True


def cache_stamped() -> bool:
    """True when the kernels' cache has a stamp for these sources: numba can cache
    them (False: no folder could be written, each process compiles what it needs)."""
    return _stamped_folder(_KERNELS) is not None


def _stamped_folder(kernels: Path) -> Path | None:
    """The folder of :func:`_cache_folders` whose stamp reads the kernels' source hash
    (the cache numba uses now), or None."""
    text = kernel_source_hash().hex() + "\n"
    for folder in _cache_folders(kernels):
        try:
            if (folder / STAMP_FILE).read_text(encoding="ascii") == text:
                return folder
        except (OSError, UnicodeDecodeError):
            continue
    return None


def _mark(stamp: str) -> str:
    """The text of the mark for a stamp's text: the stamp and numba's version (a new
    numba compiles anew)."""
    return f"{stamp}numba {getattr(numba, '__version__', '')}\n"


def all_compiled() -> bool:
    """True when every kernel a run can need is in numba's cache for these sources (the
    mark of :func:`mark_all_compiled` beside the stamp reads the stamp's text)."""
    folder = _stamped_folder(_KERNELS)
    if folder is None:
        return False
    try:
        stamp = (folder / STAMP_FILE).read_text(encoding="ascii")
        return (folder / ALL_COMPILED_FILE).read_text(encoding="ascii") == _mark(stamp)
    except (OSError, UnicodeDecodeError):
        return False


def mark_all_compiled() -> None:
    """Record beside the stamp that every kernel a run can need is now in the cache
    (nothing where the folder cannot be written: the next process compiles them again)."""
    folder = _stamped_folder(_KERNELS)
    if folder is None:
        return
    try:
        part = folder / f"{ALL_COMPILED_FILE}.{os.getpid()}.part"
        part.write_text(_mark((folder / STAMP_FILE).read_text(encoding="ascii")), encoding="ascii")
        os.replace(part, folder / ALL_COMPILED_FILE)
    except (OSError, UnicodeDecodeError):
        pass


def _cache_folders(kernels: Path) -> list[Path]:
    """Where numba caches the functions of the files in ``kernels``, in the order it
    tries: its folder for them in ``NUMBA_CACHE_DIR`` when set (the folder's name and a
    sha1 of its path), else their ``__pycache__``, then its folder for them in the
    user's cache folder (``$XDG_CACHE_HOME/numba``, ``~/.cache/numba``; on macOS
    ``~/Library/Caches/numba``)."""
    path = os.path.abspath(kernels)
    name = f"{os.path.basename(path)}_{hashlib.sha1(path.encode()).hexdigest()}"
    root = os.environ.get("NUMBA_CACHE_DIR", "")
    if root:
        return [Path(root) / name]
    if sys.platform == "darwin":
        user = Path.home() / "Library" / "Caches"
    else:
        user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return [kernels / "__pycache__", user / "numba" / name]


F = TypeVar("F", bound=Callable[..., Any])

_problem: str | None = None
_noticed = False
#: printed when numba starts compiling a function of billiard's (one not in the cache:
#: an empty or outdated cache, or a kind of argument, e.g. a curve's number of walls,
#: not compiled before): what it is and the function; one line per family and process
COMPILE_NOTICE = "billiard: compiling {family} with numba ({function}); cached for later runs"
#: printed when such a compile ends, if it took a second or more
COMPILED_NOTICE = "billiard: compiled {family} in {seconds:.1f} s"
#: the compiles shorter than this (s) end without a line
COMPILED_NOTICE_AFTER = 1.0
#: how often a block that may compile asks numba whether it does (s)
COMPILE_POLL_S = 0.05
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
    "billiard.kernels.float_parse": "the CSV number reading",
}
#: the functions whose family is not their module's
_FUNCTION_FAMILIES = {
    "billiard.kernels.loop.run_chunk_fixed": "the impact loop of the rk4 method",
}
#: the families (a curve's wall functions among them) announced in this process
_announced: set[str] = set()
#: the blocks of :func:`compiling` running now (in any thread): only the first speaks
#: (numba compiles one function at a time: the others wait for it, or are within it)
_running = 0
_running_lock = threading.Lock()
#: what compiles every kernel a run can need, together (set by the engine:
#: :func:`on_first_compile`), and whether this process has called it
_compile_all: Callable[[], Any] | None = None
_compile_all_called = False
_compile_all_lock = threading.Lock()


def on_first_compile(hook: Callable[[], Any] | None) -> None:
    """Have ``hook`` called once per process, before the first block of
    :func:`compiling`: it compiles every kernel a run can need at once (one notice, one
    wait) unless they are all in the cache already, so that the blocks that follow load
    them. None: no hook (each block compiles what it needs, with its own notice)."""
    global _compile_all
    _compile_all = hook


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


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


@contextlib.contextmanager
def compiling(function: Any) -> Iterator[None]:
    """The notices of a block that may compile ``function`` (a numba dispatcher, or its
    Python function): its first call. numba is asked, not timed (a load from the cache
    can take seconds on a loaded machine): the block's line names the function's family
    (once per process) as soon as numba counts a miss of its cache for ``function``
    (:func:`compiles`), and gives how long the compile took when that was
    :data:`COMPILED_NOTICE_AFTER` or more. A start from the cache, or a block that only
    runs long, prints nothing. Of the blocks running at the same time (nested, or in
    other threads) only the first speaks."""
    global _running
    python = getattr(function, "py_func", function)
    family = compile_family(python)
    if family is None or numba is None:
        yield
        return
    _ready()
    _first_compile()
    ask = compiles(function)  # before another thread's block can start its compile
    with _running_lock:
        _running += 1
        first = _running == 1
    try:
        if not first:
            yield
            return
        with _notices(python, family, ask):
            yield
    finally:
        with _running_lock:
            _running -= 1


def compiles(function: Any) -> Callable[[], bool | None]:
    """Asks numba whether it compiles ``function`` (a dispatcher) from now on: the
    answer is False while numba has only loaded or reused machine code for it, True
    from the moment it counted a miss of its cache (numba then compiles; without a
    cache every new kind of argument is a miss), and None once the compile's machine
    code is in place (a new overload beside the misses). For what is not a dispatcher
    the answer is always False."""
    stats = getattr(function, "stats", None)
    overloads = getattr(function, "overloads", None)
    if stats is None or overloads is None:
        return lambda: False

    def misses() -> int:
        # a copy first: the compiling thread may add a signature meanwhile
        return sum(list(function.stats.cache_misses.values()))

    missed, loaded = misses(), len(overloads)

    def ask() -> bool | None:
        if misses() == missed:
            return False
        return None if len(function.overloads) > loaded else True

    return ask


@contextlib.contextmanager
def _notices(function: Any, family: str, ask: Callable[[], bool | None]) -> Iterator[None]:
    """The lines of :func:`compiling` for a block that may compile ``function``:
    ``ask`` (:func:`compiles`) is polled from a thread while the block runs."""
    started = time.perf_counter()
    ended: list[float] = []  # when the compile was seen to end
    said: list[bool] = []
    done = threading.Event()

    def watch() -> None:
        while not done.wait(COMPILE_POLL_S):
            if _seen(ask(), function, family, said, ended):
                return

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    try:
        yield
    finally:
        done.set()
        watcher.join()
        _seen(ask(), function, family, said, ended)
        if said:
            seconds = (ended[0] if ended else time.perf_counter()) - started
            if seconds >= COMPILED_NOTICE_AFTER:
                _say(COMPILED_NOTICE.format(family=family, seconds=seconds))


def _seen(
    answer: bool | None, function: Any, family: str, said: list[bool], ended: list[float]
) -> bool:
    """Acts on numba's answer (:func:`compiles`) in a block: a compile is announced
    (its family once per process), and its end noted; True once it ended."""
    if answer is False:
        return False
    if not said:
        said.append(True)
        _announce(function, family)
    if answer is None:
        ended.append(time.perf_counter())
        return True
    return False


def _announce(function: Any, family: str) -> None:
    """The line saying that numba compiles ``function`` (once per family and process)."""
    if family not in _announced:
        _announced.add(family)
        where = f"{function.__module__}.{function.__qualname__}"
        _say(COMPILE_NOTICE.format(family=family, function=where))


def _first_compile() -> None:
    """The hook of :func:`on_first_compile`, once per process (not within a block); a
    block of another thread meanwhile waits for it, so that it loads what the hook
    compiled rather than compile it a second time."""
    global _compile_all_called
    if _compile_all is None or _compile_all_called or _running:
        return
    with _compile_all_lock:
        if _compile_all_called:
            return
        try:
            _compile_all()
        finally:
            _compile_all_called = True


def _disabled() -> bool:
    return os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")


try:
    if _disabled():
        raise ImportError("NUMBA_DISABLE_JIT is set")
    import numba
except ImportError as exc:  # no numba on this platform, or the JIT disabled
    numba = None
    _problem = str(exc)
else:
    # the wall functions are first-class function values, an experimental feature
    warnings.filterwarnings("ignore", message="First-class function type feature is experimental")
    refresh_kernel_cache()


#: True when the kernels are compiled by numba, False when they run interpreted.
ENABLED = numba is not None

#: the options of every kernel: no fast-math (IEEE operations in Python's order), a
#: division by zero raises, the GIL released, cached on disk
_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "python"}


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


def jit(fn: F, *, inline: bool = False) -> F:
    """Compile ``fn`` with numba (cached on disk), or return it unchanged. ``inline``:
    numba's ``forceinline`` (LLVM's ``alwaysinline``), so that LLVM inlines it into
    every compiled caller."""
    if numba is None:
        return fn
    if inline:
        return numba.njit(forceinline=True, **_OPTIONS)(fn)
    return numba.njit(**_OPTIONS)(fn)


def cfunc(fn: Callable[..., Any], signature: Any) -> Any:
    """``fn`` compiled by numba as a C callback of ``signature`` (loaded from its cache
    or compiled, now, with the compile notices): a first-class function value that
    numba types by its signature alone."""
    if numba is None:
        raise RuntimeError("numba is not enabled")
    family = compile_family(fn)
    if family is not None:
        _ready()
        _first_compile()
    started = time.perf_counter()
    made = numba.cfunc(signature, cache=True, error_model="python")(fn)
    # numba compiles a cfunc as it is made: asked afterwards (it loaded it from its
    # cache, or compiled it), the notices come once it is done
    if family is not None and made.cache_hits == 0 and not _running:
        _announce(fn, family)
        seconds = time.perf_counter() - started
        if seconds >= COMPILED_NOTICE_AFTER:
            _say(COMPILED_NOTICE.format(family=family, seconds=seconds))
    return made


def _ready_function() -> int:
    return 0


_ready_kernel: Any = None


def _ready() -> None:
    """numba set up for loading from its cache, before any block of :func:`compiling`:
    its first load in a process imports its implementations (a third of a second),
    which is no part of a kernel's compile. A tiny cached function is loaded (or
    compiled) for that.

    Those implementations are some 60,000 objects that live as long as the process:
    as at ``import billiard``, the cyclic garbage collector is paused while they are
    made, and they are handed to its oldest generation without a pass over them
    (unless the program froze objects of its own: then they are left as they are)."""
    global _ready_kernel
    if _ready_kernel is not None:
        return
    collecting = gc.isenabled()
    gc.disable()
    try:
        kernel = numba.njit(**_OPTIONS)(_ready_function)
        kernel()
        _ready_kernel = kernel
    finally:
        if gc.get_freeze_count() == 0:
            gc.freeze()
            gc.unfreeze()
        if collecting:
            gc.enable()
