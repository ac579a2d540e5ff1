"""The kernels on an NVIDIA GPU, through numba's CUDA target (the ``numba-cuda``
package, optional extra ``[gpu]``): the same source files as the CPU kernels, loaded as
a device twin per curve, and a generic launch of a ``@cuda.jit`` kernel over a batch of
trajectories, one thread each.

* :func:`available`: None where a CUDA GPU and numba-cuda can be used (or numba's CUDA
  simulator, ``NUMBA_ENABLE_CUDASIM=1``), else a one-line reason.
* :func:`device_kernels` / :func:`device_module`: the device twin of
  :mod:`billiard.kernels` for a simulation's curve, package
  ``billiard.kernels_cuda_<n>`` (:mod:`billiard.kernels.twin`), made once per curve
  and process: every ``@jit`` / ``@inline`` kernel is ``numba.cuda.jit(device=True)``
  (``forceinline`` for ``@inline``), and the curve's generated wall functions are
  device functions too, which :func:`billiard.kernels.wallcall.call_wall` calls by
  branches on (function, wall). Any module of ``billiard/kernels`` loads in it by name.
* :func:`launch`: a kernel over ``n`` threads, its array arguments copied to the device
  and back.
* :func:`run_rows_gpu`: the impact rows of a batch of trajectories: thread ``i``
  advances ``ctxs[i]`` (the state vector of :func:`billiard.engine.ctx.state_vector`)
  with the curve parameters ``params[i]`` by :func:`billiard.kernels.loop.run_chunk`,
  writing its rows into ``out[i]`` (the kernel :func:`advance`).
* :func:`advance_ensemble`: the ensemble kernel's measured trajectories
  (:func:`billiard.kernels.ensemble.measure`, one thread each), then, on the device, the
  stop codes and the kept impacts (:func:`reduce_kernel`); what is copied back is what
  the caller asks for: a sweep's chunk takes the statistics and the kept impacts alone.

The seam between the targets, where the device differs from the CPU (the same
physics, not the same bits):

* wall functions: no first-class functions on a device; the twin calls the curve's
  device functions by branches (:mod:`billiard.kernels.wallcall`), so a twin serves one
  curve (any parameters: ``params`` is per trajectory), of at most ``WALL_SLOTS`` walls;
* sin, cos, atan, sqrt, pow and the float remainder are the device's (libdevice), not
  the CPU's libm: some differ in the last bit;
* the device compiler contracts ``a * b + c`` into one fused multiply-add (numba-cuda
  has no switch for it): one rounding instead of two;
* a division by zero does not raise (numba-cuda's error model gives inf or nan);
* a kernel stop (``raise KernelError``) is not reported on the device: the thread ends
  there, its ctx row holding the code in ``EN_STOP`` (and ``EN_ERR_VALUE``); under the
  simulator the exception ends the whole launch instead (numba re-raises it).

Chaotic trajectories therefore leave the CPU's after some hundreds of impacts, while
their statistics agree (measured: docs/design.md, "numba-cuda"; ``bench/gpu_check.py``).
Under the simulator the kernels run as Python on numpy floats (the device functions
are the plain functions: see :class:`_Device`): the rows are the CPU's, bit for bit
(tested). A launch compiles the kernel it calls on its first call, per process (8-11 s
for ``advance`` on an H200; not cached on disk).
"""

from __future__ import annotations

import importlib.util
import threading
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any

import numpy as np

from billiard.engine.ctx import state_vector
from billiard.geometry.wall_functions import WALL_SLOTS
from billiard.kernels import layout as L
from billiard.kernels import twin

__all__ = [
    "INSTALL",
    "PACKAGE",
    "THREADS",
    "BATCH",
    "ROUNDS",
    "advance",
    "advance_ensemble",
    "available",
    "device_kernels",
    "device_module",
    "ensemble_kernel",
    "launch",
    "reduce_kernel",
    "run_rows_gpu",
]

#: how to install the GPU backend
INSTALL = 'pip install "realworld-billiard[gpu]"'
#: the device twins' package names: this and a number per curve
PACKAGE = "billiard.kernels_cuda"
#: threads per block of a launch (the kernels use many registers per thread)
THREADS = 64
#: the rows (f, f', f'') of wall functions a device twin calls
_WALL_ROWS = ("f", "df", "d2f")

#: numba.cuda once :func:`_cuda` has imported it: a module global, so that numba's
#: simulator can swap it for its own in the kernels defined here
cuda: Any = None
_lock = threading.Lock()
#: curve key (its wall functions) -> package name of its device twin
_twins: dict[tuple[Any, ...], str] = {}
#: package name -> the advance kernel compiled for its twin
_advance: dict[str, Any] = {}


def available() -> str | None:
    """None when the GPU backend can run (numba-cuda installed and a CUDA GPU found, or
    numba's CUDA simulator enabled by ``NUMBA_ENABLE_CUDASIM=1``), else why not, in
    one line."""
    if importlib.util.find_spec("numba_cuda") is None:
        return f"no CUDA GPU: numba-cuda is not installed ({INSTALL})"
    try:
        found = _cuda().is_available()
    except Exception as exc:  # a broken driver or toolkit: its first line says what
        lines = str(exc).strip().splitlines() or [type(exc).__name__]
        return f"no CUDA GPU: numba-cuda could not start ({lines[0]})"
    if not found:
        return "no CUDA GPU: numba-cuda found no CUDA GPU"
    return None


def simulated() -> bool:
    """True when numba's CUDA simulator stands for the GPU (``NUMBA_ENABLE_CUDASIM=1``
    when numba.cuda was first imported)."""
    import numba

    return bool(getattr(numba.config, "ENABLE_CUDASIM", 0))


def _cuda() -> Any:
    """numba.cuda (numba-cuda's), imported on first use."""
    global cuda
    if cuda is None:
        from numba import cuda as module

        cuda = module
    return cuda


class _Device:
    """What a device twin's decorators read (``DEVICE`` on its package,
    :mod:`billiard.kernels.decorators`): the compiler and the curve's wall functions."""

    def __init__(self, walls: Any):
        self._simulated = simulated()
        #: rows (f, f', f''), one device function per wall slot
        self.walls = tuple(tuple(self.jit(fn, False) for fn in row) for row in walls)

    def jit(self, fn: Any, inline: bool) -> Any:
        """``fn`` as a device function (``inline``: inlined into its device callers)."""
        if self._simulated:
            # the simulator's device function calls fn with numba.cuda swapped for its
            # own in fn's module, under a lock per call: the kernels do not use
            # numba.cuda, and threads of a block wait on each other's locks for
            # seconds per impact, so they are called as they are
            return fn
        return _cuda().jit(device=True, forceinline=inline)(fn)


def _curve_walls(sim: Any) -> tuple[tuple[Any, ...], ...]:
    """(f, f', f'') of the curve's walls, one generated function per wall slot (a
    curve with fewer walls has its last wall's repeated: never called).

    Raises:
        ValueError: the curve has more walls than the twin's branches cover.
    """
    walls = sim.boundary.walls
    if len(walls) > WALL_SLOTS:
        raise ValueError(
            f"the GPU kernels take curves of at most {WALL_SLOTS} walls; "
            f"{sim.scene.boundary.curve!r} has {len(walls)}"
        )
    rows = tuple(tuple(getattr(w, name) for w in walls) for name in _WALL_ROWS)
    return tuple(row + row[-1:] * (WALL_SLOTS - len(row)) for row in rows)


def device_kernels(sim: Any) -> ModuleType:
    """The device twin of :mod:`billiard.kernels` for the curve of ``sim`` (a
    :class:`billiard.engine.simulation.Simulation`): its package, made once per curve and
    process. Its modules load by name (:func:`device_module`); they compile on the first
    launch of a kernel that calls them."""
    walls = _curve_walls(sim)
    with _lock:
        name = _twins.get(walls)
        if name is None:
            name = f"{PACKAGE}_{len(_twins)}"
            twin.load_package(name, {"DEVICE": _Device(walls)})
            _twins[walls] = name
    return twin.load_package(name)


def device_module(sim: Any, name: str) -> ModuleType:
    """The module ``name`` of ``billiard/kernels`` (``"loop"``, ``"locate"``, any other)
    in the device twin of the curve of ``sim``."""
    package = device_kernels(sim)
    return twin.load_module(package.__name__, name)


def launch(kernel: Any, n: int, *args: Any, back: Sequence[int] = (), threads: int = THREADS):
    """Run ``kernel`` (a ``@cuda.jit`` kernel) over ``n`` threads, ``threads`` per block:
    its numpy array arguments are copied to the device, the others passed as they are;
    the arrays at the positions ``back`` are copied back into the numpy arrays given."""
    gpu = _cuda()
    threads = max(1, min(threads, n))
    blocks = (n + threads - 1) // threads
    device = [gpu.to_device(a) if isinstance(a, np.ndarray) else a for a in args]
    kernel[blocks, threads](*device)
    for i in back:
        device[i].copy_to_host(args[i])
    gpu.synchronize()


def advance(sim: Any) -> Any:
    """The kernel ``advance(ctxs, params, out, impacts, ends)`` of the curve of ``sim``:
    thread ``i`` runs :func:`billiard.kernels.loop.run_chunk` on ``ctxs[i]`` with the
    curve parameters ``params[i]``, up to ``impacts`` rows into ``out[i]`` (``impacts *
    NCOL`` floats), and writes (status, rows written) into ``ends[i]``; a thread that
    stops leaves ``ends[i]`` as it was and its code in ``ctxs[i, EN_STOP]``."""
    return _device_kernel(sim, _advance, "loop", _advance_kernel)


def _device_kernel(
    sim: Any, cache: dict[str, Any], module: str, make: Callable[[ModuleType], Any]
) -> Any:
    """The kernel ``make`` builds from module ``module`` of the device twin of the
    curve of ``sim``, built once per twin (``cache``, by the twin's package)."""
    package = device_kernels(sim).__name__
    with _lock:
        kernel = cache.get(package)
        if kernel is None:
            kernel = cache[package] = make(twin.load_module(package, module))
    return kernel


def _advance_kernel(loop: ModuleType) -> Any:
    run_chunk = loop.run_chunk

    def advance(ctxs, params, out, impacts, ends):
        i = cuda.grid(1)
        if i < ctxs.shape[0]:
            status, rows = run_chunk(ctxs[i], params[i], 0, out[i], impacts)
            ends[i, 0] = status
            ends[i, 1] = rows

    return _cuda().jit(advance)


def run_rows_gpu(
    sims: Sequence[Any], impacts: int, *, threads: int = THREADS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Advance each simulation of ``sims`` (one curve, method ``event``, the impacts
    model; each its own initial state and parameters) by up to ``impacts`` impacts on
    the GPU, one thread each.

    Returns:
        ``(rows, ends, ctxs)``: ``rows[i, r]`` the NCOL columns of impact ``r`` of
        trajectory ``i`` (the columns of collisions.csv, codes for regime and wall);
        ``ends[i]`` its (status, rows written) as ``run_chunk`` returns them, or
        (-1, -1) where it stopped (its ``E_*`` code in ``ctxs[i, EN_STOP]``); ``ctxs``
        the state vectors after the run.

    Raises:
        ValueError: a simulation the kernels cannot run this way, or of another curve.
    """
    if not sims:
        raise ValueError("no simulations to run")
    walls = _curve_walls(sims[0])
    for sim in sims:
        if sim.method != "event" or sim.phases:
            raise ValueError("the GPU kernels run method 'event' with the impacts model only")
        if _curve_walls(sim) != walls:
            raise ValueError("the simulations of one launch share one curve")
    ctxs = np.array([state_vector(sim) for sim in sims], dtype=np.float64)
    params = np.array([sim.boundary.walls[0].p for sim in sims], dtype=np.float64)
    ctxs[:, L.EN_TARGET] = ctxs[:, L.EN_IMPACTS] + impacts
    out = np.zeros((len(sims), impacts * L.NCOL), dtype=np.float64)
    ends = np.full((len(sims), 2), -1, dtype=np.int64)
    launch(advance(sims[0]), len(sims), ctxs, params, out, impacts, ends, back=(0, 2, 4),
           threads=threads)  # fmt: skip
    return out.reshape(len(sims), impacts, L.NCOL), ends, ctxs


#: package name -> the ensemble kernel compiled for its twin
_measure: dict[str, Any] = {}
#: package name -> the end-of-batch kernel (stop codes, kept tails) compiled for its twin
_reduce: dict[str, Any] = {}
#: impacts per trajectory of one launch of :func:`advance_ensemble` (between launches
#: the host sees Ctrl-C and reports progress)
ROUNDS = 2000
#: trajectories per launch batch of :func:`advance_ensemble` (their state vectors and
#: rings on the device: about 24 kB each with a ring of 256 impacts)
BATCH = 1 << 18


def ensemble_kernel(sim: Any) -> Any:
    """The kernel ``measure(ctxs, params, rows, rings, stats, consts, transient, total,
    target)`` of the curve of ``sim``: thread ``i`` runs
    :func:`billiard.kernels.ensemble.measure` on its rows of the arrays (the CPU
    ensemble's per-trajectory function, from the same source)."""
    return _device_kernel(sim, _measure, "ensemble", _measure_kernel)


def _measure_kernel(ensemble: ModuleType) -> Any:
    measure = ensemble.measure

    def run(ctxs, params, rows, rings, stats, consts, transient, total, target):
        i = cuda.grid(1)
        if i < ctxs.shape[0]:
            measure(ctxs[i], params[i], 0, rows[i], rings[i], stats[i], consts[i], transient,
                    total, target)  # fmt: skip

    return _cuda().jit(run)


def reduce_kernel(sim: Any) -> Any:
    """The kernel ``reduce(ctxs, rings, stats, heights, tofs)`` of the curve of
    ``sim``, launched after a batch's last launch of :func:`ensemble_kernel`: thread
    ``i`` puts a kernel stop's code into ``stats[i]``
    (:func:`billiard.kernels.ensemble.settle`) and reads the last ``heights.shape[1]``
    heights and times of flight of its ring into ``heights[i]`` and ``tofs[i]``
    (:func:`billiard.kernels.ensemble.tail`, which the CPU's ``last_impacts`` calls
    too), so that neither state vector nor ring need leave the device."""
    return _device_kernel(sim, _reduce, "ensemble", _reduce_kernel)


def _reduce_kernel(ensemble: ModuleType) -> Any:
    settle, tail = ensemble.settle, ensemble.tail

    def reduce(ctxs, rings, stats, heights, tofs):
        i = cuda.grid(1)
        if i < ctxs.shape[0]:
            settle(ctxs[i], stats[i])
            tail(rings[i], stats[i], heights[i], tofs[i])

    return _cuda().jit(reduce)


def advance_ensemble(
    sim: Any,
    ctxs: np.ndarray,
    params: np.ndarray,
    consts: np.ndarray,
    *,
    transient: int,
    impacts: int,
    width: int,
    keep: int | None = None,
    states: bool = True,
    rounds: int | None = None,
    progress: Any = None,
    threads: int = THREADS,
    clock: dict[str, float] | None = None,
) -> tuple[np.ndarray, Any]:
    """:func:`billiard.engine.ensemble.advance` on the GPU: every trajectory (rows of
    ``ctxs``, of the curve of ``sim``) to ``transient + impacts`` impacts, in launches
    of ``rounds`` (default :data:`ROUNDS`) impacts per trajectory over batches of
    :data:`BATCH` trajectories
    (the arrays stay on the device between the launches of a batch; Ctrl-C is seen
    between launches). A thread that stops in a kernel stop just ends, its code in its
    state vector: it is reported as RUN_FAILED with ST_CODE that code, set on the device
    (by :func:`billiard.kernels.ensemble.measure` in the next launch, which does not
    step it again, or by :func:`reduce_kernel` after the last).

    What comes back per trajectory: ``stats`` (NSTAT floats) always; with ``keep`` None
    its whole ring (``width`` x RCOL floats: 14 kB for 256 impacts), else only the last
    ``keep`` heights and times of flight, read from the ring on the device (16 bytes an
    impact); with ``states`` its state vector (``ctxs`` advanced in place, 11 kB), else
    ``ctxs`` are left as given. The rows of scratch and the rings are made on the device
    (never copied there). ``clock``, when given, gets ``"kernel_s"``: the seconds of the
    launches alone (each synchronised), no set-up or copies.

    Returns:
        ``(stats, rings)`` with ``keep`` None, else ``(stats, (heights, tofs))`` (n x
        keep each, oldest first, NaN-padded at the front; m, s).
    """
    import time

    from billiard.kernels import ensemble as E

    gpu = _cuda()
    kernel, reduce = ensemble_kernel(sim), reduce_kernel(sim)
    n = ctxs.shape[0]
    params = np.array(np.broadcast_to(params, (n, params.shape[-1])), order="C")
    consts = np.array(np.broadcast_to(consts, (n, E.NCONST)), order="C")
    stats = np.zeros((n, E.NSTAT))
    stats[:, E.ST_STATUS] = E.RUN_PENDING
    rings = np.empty((n, width, E.RCOL)) if keep is None else None
    tail = 0 if keep is None else keep
    heights, tofs = np.empty((n, tail)), np.empty((n, tail))
    total = transient + impacts
    rounds = rounds or ROUNDS
    seconds = 0.0
    for lo in range(0, n, BATCH):
        hi = min(n, lo + BATCH)
        count = hi - lo
        up = [gpu.to_device(np.ascontiguousarray(a[lo:hi])) for a in (ctxs, params, stats, consts)]
        d_ctxs, d_params, d_stats, d_consts = up
        d_rows = gpu.device_array((count, L.NCOL))  # each thread's scratch row
        d_rings = gpu.device_array((count, width, E.RCOL))  # read only once written
        blocks = (count + threads - 1) // threads
        target = 0
        while target < total:
            target = min(total, target + rounds)
            began = time.perf_counter()
            kernel[blocks, threads](d_ctxs, d_params, d_rows, d_rings, d_stats, d_consts,
                                    transient, total, target)  # fmt: skip
            gpu.synchronize()
            seconds += time.perf_counter() - began
            if progress is not None:
                progress(lo, count, target)
        # at least one column: a device array of size 0 has no device pointer, which a
        # launch on some numba-cuda versions refuses (numba issues 4140, 6050)
        d_heights = gpu.device_array((count, max(tail, 1)))
        d_tofs = gpu.device_array((count, max(tail, 1)))
        reduce[blocks, threads](d_ctxs, d_rings, d_stats, d_heights, d_tofs)
        d_stats.copy_to_host(stats[lo:hi])
        if keep is None:
            d_rings.copy_to_host(rings[lo:hi])
        elif tail:
            d_heights.copy_to_host(heights[lo:hi])
            d_tofs.copy_to_host(tofs[lo:hi])
        if states:
            ctxs[lo:hi] = d_ctxs.copy_to_host()
    if clock is not None:
        clock["kernel_s"] = seconds
    return stats, (rings if keep is None else (heights, tofs))
