"""Ensembles of trajectories on the compiled kernels: one parameter set of a scene, many
starts, advanced together by :func:`billiard.kernels.ensemble.run_batch` on all cores.

:func:`prepare` builds, once per parameter set (every scene key but the ball's start
``initial.*``), what the engine's set-up builds for a run: the state vector's constants
(one :class:`~billiard.engine.simulation.Simulation` of the scene with the ball at rest
on the bottom, which also gives the resting height), the curve's parameters and wall
functions. :func:`start` then puts each start into a state vector as a run's set-up does
(ball state, fresh event count, the warm starts the start check moves) and reports the
starts that overlap a wall, the lid or the escape height; :func:`advance` runs them.
A trajectory's state vector after :func:`start` is the one ``billiard run`` builds for
that start, slot for slot, and its impacts are the run's, bit for bit.

Under ``contact.model = "phases"`` the state vector is the one such a run hands the state
machine (:mod:`billiard.kernels.machine`: its contact constants, the motion state a
start lying on a wall starts in) and the trajectories run on it
(:func:`billiard.kernels.ensemble.run_batch_phases`).

Plain Python around the kernels; nothing here runs per impact.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass
from typing import Any

import numpy as np

from billiard import jit as _jit
from billiard.engine.ctx import engine_state, state_vector, write_motion
from billiard.kernels import layout as L

__all__ = [
    "BALL_KEYS",
    "EnsembleSetup",
    "advance",
    "advance_setup",
    "at_rest_scene",
    "last_impacts",
    "patch",
    "PATCH_KEYS",
    "prepare",
    "start",
    "start_at_rest",
    "start_verdicts",
    "supports",
    "VERDICTS",
]

#: why the GPU does not run a contact-phases scene, and where it runs instead (the
#: state machine, with its third derivatives and nearest-point functions, has no device
#: twin; a sweep on the GPU runs such points on the CPU)
GPU_PHASES = (
    "contact.model = 'phases' runs on the CPU only: the GPU kernels have the impacts "
    "model, not the contact state machine (use device 'cpu')"
)
#: the scene keys of a start: what may differ between the trajectories of one set-up
BALL_KEYS = (
    "initial.q1",
    "initial.q2",
    "initial.v1",
    "initial.v2",
    "initial.omega",
    "initial.t",
)
#: a start this far (m) inside a wall, the lid or above the escape height is refused,
#: as the engine's set-up refuses it (Boundary.check_initial_position)
_OVERLAP = 1e-12


def supports(scene: Any) -> str | None:
    """None when trajectories of ``scene`` run on the ensemble kernel, else why not."""
    if scene.run.method != "event":
        return f"run.method = {scene.run.method!r} (the ensemble kernel has method 'event')"
    if not _jit.ENABLED:
        return "numba is not enabled (the ensemble kernel runs compiled only)"
    return None


@dataclass
class EnsembleSetup:
    """What the trajectories of one parameter set share.

    Attributes:
        scene: the scene (its ``initial.*`` keys are the template's, not used).
        template: the state vector of a run's set-up, warm starts fresh (SIZE floats).
        params: the curve's parameters.
        walls: the curve's wall functions as the kernels take them.
        offsets: surfaces checked at the start (the offset walls, which come first).
        rest_height: centre height (m) of the ball at rest on the bottom.
        drive: the boundary's drive.
        lid_level, escape_level: the highest centre height under the lid, the escape
            height (m; inf: none).
        at_rest: the state vector of a run whose ball starts at rest on the bottom (no
            ``initial.q1``, ``initial.q2``) at time ``t`` (s).
        phases: ``contact.model = "phases"``: the trajectories run on the state
            machine, ``walls`` holds f, f', f'' and the third derivative, ``nears`` the
            walls' nearest-point functions (its flights' other locator's).
        sim: the Simulation of the ball at rest (under contact phases, the engine whose
            set-up finds the motion state of a start lying on a wall).
    """

    scene: Any
    template: np.ndarray
    params: np.ndarray
    walls: Any
    offsets: int
    rest_height: float
    drive: Any
    lid_level: float
    escape_level: float
    at_rest: np.ndarray
    t: float
    sim: Any = None
    phases: bool = False
    nears: Any = None
    #: the ball at rest in the boundary frame, (x, y) (m), and the warm starts the
    #: search for it left (found on the first :func:`patch`, for the set-ups patched
    #: from this one: it depends on the geometry alone)
    rest: Any = None


def at_rest_scene(scene: Any) -> Any:
    """``scene`` with the ball at rest on the bottom (no start position, no velocity) and
    no end in time: what a Simulation needs to give the resting height and the state
    vector of a ball that starts on the bottom."""
    from billiard.scene.scene import with_values

    return with_values(
        scene,
        {"initial.q1": None, "initial.q2": None, "initial.v1": 0.0, "initial.v2": 0.0}
        | {"initial.omega": 0.0, "run.duration": None},
    )


def prepare(scene: Any) -> EnsembleSetup:
    """The set-up of ``scene``'s parameter set (a Simulation of it, ball at rest).

    Raises:
        ValueError: the scene cannot be simulated (SceneError, GeometryError), or the
            ensemble kernel does not take it (see :func:`supports`).
    """
    from billiard.engine.simulation import Simulation
    from billiard.geometry.wall_functions import (
        near_functions,
        phase_wall_functions,
        wall_functions,
    )

    why = supports(scene)
    if why is not None:
        raise ValueError(f"the ensemble kernel does not take this scene: {why}")
    sim = Simulation(at_rest_scene(scene))
    phases = bool(sim.phases)
    if phases:
        at_rest_ctx = machine_vector(sim)
    else:
        at_rest_ctx = np.array(state_vector(sim), dtype=np.float64)
    template = at_rest_ctx.copy()
    # the warm starts as a run's set-up has them before its start check moves them
    for j, (s, slope) in enumerate(sim.boundary.initial_warm()):
        base = L.SURF + j * L.SURF_STRIDE
        template[base + L.S_WS] = s
        template[base + L.S_WSLOPE] = slope
    if phases:
        # a start in flight (one lying on a wall: see start); no time in phases yet
        template[L.MC_MODE] = L.M_FLIGHT
        template[L.MC_CONTACT : L.MC_CONTACT + 6] = 0.0
        template[L.MC_PHASE_TIME : L.MC_PHASE_TIME + len(L.MOTION_NAMES) - 1] = 0.0
    boundary = sim.boundary
    return EnsembleSetup(
        scene=scene,
        template=template,
        params=np.array(boundary.walls[0].p, dtype=np.float64),
        walls=phase_wall_functions(sim) if phases else wall_functions(sim),
        offsets=len(boundary.offsets),
        rest_height=float(sim.initial.q2),
        drive=sim.drive,
        lid_level=math.inf if boundary.lid is None else float(boundary.lid.level),
        escape_level=math.inf if boundary.escape is None else float(boundary.escape.level),
        at_rest=at_rest_ctx,
        t=float(scene.initial.t),
        sim=sim,
        phases=phases,
        nears=near_functions(sim) if phases else None,
    )


#: The scene keys that reach a set-up's state vectors only through the blocks the
#: models write (the locator's drive, the flight's air drag, the impact law's constants)
#: and through the ball put at rest: a parameter set that differs from another in these
#: alone is :func:`patch`-ed from the other's set-up. The others (the curve, the ball's
#: radius, the lid, gravity, ...) change the geometry or more, and need their own set-up.
PATCH_KEYS = frozenset(
    {
        "drive.amplitude",
        "drive.frequency",
        "drive.phase",
        "contact.restitution",
        "contact.mu_static",
        "contact.mu_kinetic",
        "contact.elastic_below",
        "contact.law",
        "contact.beta0",
        "contact.e_ref",
        "contact.v_ref",
        "contact.exponent",
        "contact.viscous",
        "contact.energy_scale",
        "contact.angle_slope",
        "air.c_lin",
        "air.c_quad",
        "air.magnus",
        "ball.mass",
        "ball.inertia_factor",
    }
)


def patch(setup: EnsembleSetup, scene: Any) -> EnsembleSetup:
    """The set-up of ``scene``, which differs from ``setup.scene`` in :data:`PATCH_KEYS`
    alone, made from ``setup`` without a Simulation of its own (the set-up of a point of
    a parameter map: 0.1 ms rather than 12 ms): the locator, flight model and impact law
    of ``scene`` write their blocks into copies of ``setup``'s state vectors, over the
    same geometry, and the ball at rest is put on the bottom as
    ``Simulation.initial_state`` puts it. Its vectors equal :func:`prepare`'s of
    ``scene``, slot for slot (tested over every key of PATCH_KEYS).

    Raises:
        ValueError: a contact-phases set-up (its ball at rest is classified by the
            engine's set-up: use :func:`prepare`).
    """
    import copy

    from billiard.engine.ctx import write_ball
    from billiard.engine.state import BallState
    from billiard.geometry.drive import Drive
    from billiard.models.flight import flight_model
    from billiard.models.impact import impact_law
    from billiard.models.kinds import require_kernel
    from billiard.models.locators import LOCATORS

    if setup.phases:
        raise ValueError("a contact-phases set-up is not patched: prepare it")
    sim = setup.sim
    drive = Drive.from_scene(scene.drive)
    boundary = copy.copy(sim.boundary)  # the same geometry, moved by this drive
    boundary.drive = drive
    flight = flight_model(scene, sim.method)
    locator = LOCATORS[sim.method](boundary, flight, scene.run.gravity, boundary.initial_warm())
    impact = impact_law(scene)
    template = setup.template.copy()
    for model, what in ((locator, "locator"), (flight, "flight model"), (impact, "impact law")):
        require_kernel(model, what)
        model.write(template)
    if setup.rest is None:
        warm = boundary.initial_warm()
        setup.rest = (*boundary.resting_position(warm), [list(w) for w in warm])
    x, y, rest_warm = setup.rest
    warm = [list(w) for w in rest_warm]
    t = float(scene.initial.t)
    theta = drive.angle(t)
    q1, q2 = drive.to_lab_frame(theta, x, y)
    boundary.check_initial_position(q1, q2, theta, warm)
    # both vectors hold the ball at rest (the template's warm starts are fresh ones)
    write_ball(template, BallState(t, theta, q1, q2, 0.0, 0.0, 0.0, 0.0))
    at_rest = template.copy()
    for j, (s, slope) in enumerate(warm):
        base = L.SURF + j * L.SURF_STRIDE
        at_rest[base + L.S_WS] = s
        at_rest[base + L.S_WSLOPE] = slope
    return EnsembleSetup(
        scene=scene,
        template=template,
        params=setup.params,
        walls=setup.walls,
        offsets=setup.offsets,
        rest_height=float(q2),
        drive=drive,
        lid_level=setup.lid_level,
        escape_level=setup.escape_level,
        at_rest=at_rest,
        t=t,
        sim=sim,
        rest=setup.rest,
    )


def machine_vector(sim: Any) -> np.ndarray:
    """The state vector a run of ``sim`` (contact phases, method event, in its present
    engine state) hands the state machine: its constants, the engine state and motion
    state, the run's end so far."""
    ctx = np.array(state_vector(sim), dtype=np.float64)
    ctx[L.MC_FINAL] = sim.final_time
    return ctx


#: a start whose centre is farther than this (m) from every wall's offset curve does not
#: lie on one (the engine's test: within 1e-12 m; the compiled gap and the engine's
#: agree to rounding)
_APART = 1e-9


def _lying(setup: EnsembleSetup, ctxs: np.ndarray, rows: Any) -> None:
    """The motion state of the starts ``rows`` of ``ctxs`` (state vectors of a
    contact-phases set-up), as a run's set-up finds it: a ball lying on a wall that
    presses it starts rolling or sliding on it (or held by two walls), else in flight
    (``Simulation._start_in_contact``, asked of the set-up's Simulation with each
    start's ball and warm starts; its own engine state is put back after)."""
    sim = setup.sim
    walls = len(setup.sim.boundary.offsets)
    regimes = sim.impact.regimes
    saved = [list(w) for w in sim.warm]
    try:
        for i in rows:
            ctx = ctxs[i]
            for j, warm in enumerate(sim.warm):
                base = L.SURF + j * L.SURF_STRIDE
                warm[0], warm[1] = float(ctx[base + L.S_WS]), float(ctx[base + L.S_WSLOPE])
            sim.reset(engine_state(ctx, regimes, walls).ball)
            write_motion(ctx, sim.state)
            # held by two walls, the ball moves with the boundary
            ctx[L.EN_U1], ctx[L.EN_U2] = sim.ctx[L.EN_U1], sim.ctx[L.EN_U2]
    finally:
        for warm, values in zip(sim.warm, saved, strict=True):
            warm[:] = values
        sim.reset()


def _boundary_frame(
    setup: EnsembleSetup, q1: np.ndarray, q2: np.ndarray, t: float
) -> tuple[np.ndarray, np.ndarray]:
    """The centres (m) relative to the boundary at time t (s), as
    Drive.to_boundary_frame computes them."""
    drive = setup.drive
    d = drive.displacement(drive.angle(t))
    return (q1 - d, q2) if drive.horizontal else (q1, q2 - d)


def start(
    setup: EnsembleSetup,
    q1: Any,
    q2: Any,
    v1: Any = 0.0,
    v2: Any = 0.0,
    omega: Any = 0.0,
    t: float = 0.0,
    duration: float | None = None,
    out: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """State vectors of the starts (arrays broadcast together; m, m/s, rad/s) at time t
    (s), each run ending at t + ``duration`` (s; None: no end in time); written into
    ``out`` (n x SIZE, C order) when given.

    Returns:
        (ctxs, ok): the state vectors (n x SIZE) and, per start, whether a run's set-up
        accepts it (False: the ball overlaps a wall or the lid, or starts above the
        escape height; its row is not to be run).
    """
    q1, q2, v1, v2, omega = np.broadcast_arrays(
        *(np.asarray(x, dtype=np.float64) for x in (q1, q2, v1, v2, omega))
    )
    n = q1.size
    theta = setup.drive.angle(t)
    px, py = _boundary_frame(setup, q1, q2, t)
    balls = np.empty((n, 7))
    balls[:, 0] = t
    balls[:, 1] = theta
    for column, values in enumerate((q1, q2, v1, v2, omega), start=2):
        balls[:, column] = values.ravel()
    ctxs = np.empty((n, setup.template.size)) if out is None else out
    gaps = np.empty(n)
    # a copy: a broadcast view is read-only (and stays one when it is already
    # contiguous, as for one trajectory), which the kernels' wall functions refuse
    params = np.array(np.broadcast_to(setup.params, (n, setup.params.size)), order="C")
    px = np.ascontiguousarray(px, dtype=np.float64).ravel()
    py = np.ascontiguousarray(py, dtype=np.float64).ravel()
    _start_all(ctxs, params, setup, balls, px, py, gaps)
    ctxs[:, L.EN_UNTIL] = math.inf if duration is None else t + duration
    ctxs[:, L.SM_T0] = t
    ok = (py <= setup.lid_level + _OVERLAP) & (py < setup.escape_level) & (gaps >= -_OVERLAP)
    if setup.phases:
        ctxs[:, L.MC_LAST_IMPACT] = t
        ctxs[:, L.MC_FINAL] = t
        _lying(setup, ctxs, np.nonzero(ok & ~(gaps > _APART))[0])
    return ctxs, ok


#: starts per slice of :func:`_start_all` (below this many, one thread sets them up)
START_SLICE = 8192


def _start_all(
    ctxs: np.ndarray,
    params: np.ndarray,
    setup: EnsembleSetup,
    balls: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    gaps: np.ndarray,
) -> None:
    """``start_batch`` over all the starts, in slices on every core this process may
    use (the kernel runs without the GIL; each row is set up alone, so the slicing
    changes no bit): a 10^6-start ensemble spent 11-31 s setting its starts up on one
    thread."""
    from billiard.kernels.ensemble import start_batch

    n = ctxs.shape[0]
    args = (setup.walls, setup.template)

    def run(lo: int, hi: int) -> None:
        start_batch(
            ctxs[lo:hi], params[lo:hi], *args, balls[lo:hi], px[lo:hi], py[lo:hi],
            setup.offsets, gaps[lo:hi],
        )  # fmt: skip

    threads = min(threads_default(), -(-n // START_SLICE))
    if threads <= 1:
        run(0, n)
        return
    with _jit.compiling(start_batch):
        run(0, 1)  # compiled (or loaded) once, before the threads start
    with ThreadPoolExecutor(max_workers=threads) as pool:
        for future in [
            pool.submit(run, lo, min(n, lo + START_SLICE)) for lo in range(1, n, START_SLICE)
        ]:
            future.result()


#: what :func:`start_verdicts` finds wrong with a start, by its code
VERDICTS = ("", "into the lid", "above the escape height", "into the wall")


def start_verdicts(setup: EnsembleSetup, q1: Any, q2: Any, t: float = 0.0) -> np.ndarray:
    """Per start (m, at time t in s) 0 where a run's set-up accepts it, else the code of
    :data:`VERDICTS` it fails on first (the lid, the escape height, a wall: the order of
    the set-up's checks). Made in blocks: no state vector is kept."""
    q1, q2 = (np.ravel(np.asarray(x, dtype=np.float64)) for x in np.broadcast_arrays(q1, q2))
    codes = np.zeros(q1.size, dtype=np.int8)
    block = 4096  # state vectors of 11 kB each
    out = np.empty((min(block, q1.size), setup.template.size))
    for lo in range(0, q1.size, block):
        hi = min(q1.size, lo + block)
        _, ok = start(setup, q1[lo:hi], q2[lo:hi], t=t, out=out[: hi - lo])
        bad = np.nonzero(~ok)[0]
        if not bad.size:
            continue
        py = _boundary_frame(setup, q1[lo:hi][bad], q2[lo:hi][bad], t)[1]
        code = np.full(bad.size, 3, dtype=np.int8)
        code[py >= setup.escape_level] = 2
        code[py > setup.lid_level + _OVERLAP] = 1
        codes[lo + bad] = code
    return codes


def start_at_rest(
    setup: EnsembleSetup,
    n: int,
    v1: Any = 0.0,
    v2: Any = 0.0,
    omega: Any = 0.0,
    duration: float | None = None,
) -> np.ndarray:
    """State vectors of ``n`` runs whose ball starts on the bottom, as a scene without
    ``initial.q1`` and ``initial.q2`` puts it, at the set-up's time ``setup.t``, with
    velocities (m/s) and spin (rad/s) ``v1``, ``v2``, ``omega`` (arrays of n, or
    numbers), each ending at ``setup.t + duration`` (s; None: no end in time)."""
    ctxs = np.tile(setup.at_rest, (n, 1))
    ctxs[:, L.EN_U1] = v1
    ctxs[:, L.EN_U2] = v2
    ctxs[:, L.EN_U3] = omega
    ctxs[:, L.EN_UNTIL] = math.inf if duration is None else setup.t + duration
    ctxs[:, L.SM_T0] = setup.t
    if setup.phases:
        # the set-up's ball lies on the bottom at rest: moving, it may start otherwise
        moving = (ctxs[:, L.EN_U1] != 0.0) | (ctxs[:, L.EN_U2] != 0.0) | (ctxs[:, L.EN_U3] != 0.0)
        _lying(setup, ctxs, np.nonzero(moving)[0])
    return ctxs


def constants(scene: Any, tolerance: float, max_period: int, window: int) -> np.ndarray:
    """The period test's per-trajectory constants (``billiard.kernels.ensemble`` C_*)."""
    from billiard.kernels import ensemble as E

    consts = np.empty(E.NCONST)
    consts[E.C_FREQUENCY] = scene.drive.frequency
    consts[E.C_PHASE] = scene.drive.phase
    consts[E.C_RADIUS] = scene.ball.radius
    consts[E.C_GRAVITY] = scene.run.gravity
    consts[E.C_TOLERANCE] = tolerance
    consts[E.C_MAX_PERIOD] = max_period
    consts[E.C_WINDOW] = window
    return consts


#: impacts per trajectory of one round of :func:`advance` (a round's calls return to
#: Python, where Ctrl-C and the progress report are seen)
ROUND_IMPACTS = 2000
#: trajectories per call of the kernel in a round, at most
SLICE = 256


def threads_default() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def advance(
    ctxs: np.ndarray,
    params: np.ndarray,
    walls: Any,
    consts: np.ndarray,
    *,
    transient: int,
    impacts: int,
    width: int,
    threads: int | None = None,
    progress: Callable[[int], None] | None = None,
    nears: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run every trajectory (rows of ``ctxs``, advanced in place) to ``transient +
    impacts`` impacts, measuring the last ``impacts``; ``width`` impacts are kept in
    each trajectory's ring. Returns (stats, rings) (``billiard.kernels.ensemble``).
    State vectors of a contact-phases set-up (landings watched, ``EN_LAND_ON``) run on
    the state machine, and ``walls`` are then its wall functions and ``nears`` the
    walls' nearest-point functions (``EnsembleSetup.walls``, ``EnsembleSetup.nears``).

    The trajectories run in rounds of :data:`ROUND_IMPACTS` impacts, each round in
    slices of at most :data:`SLICE` trajectories spread over ``threads`` threads
    (default: every core this process may use; the kernel runs without the GIL).
    Between two slices the calling thread sees Ctrl-C (KeyboardInterrupt: the slices
    running finish first, nothing is returned) and ``progress(impacts so far)`` is
    called. The result does not depend on the rounds, slices or threads."""
    from billiard.kernels import ensemble as E

    n = ctxs.shape[0]
    # writable C-ordered copies (see start)
    params = np.array(np.broadcast_to(params, (n, params.shape[-1])), order="C")
    consts = np.array(np.broadcast_to(consts, (n, E.NCONST)), order="C")
    rows = np.empty((n, L.NCOL))
    # not filled: a ring's slots are read only once written (find_period, last_impacts)
    rings = np.empty((n, width, E.RCOL))
    stats = np.zeros((n, E.NSTAT))
    stats[:, E.ST_STATUS] = E.RUN_PENDING
    total = transient + impacts
    threads = max(1, min(threads or threads_default(), n))
    size = max(1, min(SLICE, -(-n // (4 * threads))))
    slices = [(lo, min(n, lo + size)) for lo in range(0, n, size)]

    phases = n > 0 and bool(ctxs[0, L.EN_LAND_ON] == 1.0)
    kernel = E.run_batch_phases if phases else E.run_batch
    if phases and nears is None:
        raise ValueError("contact phases need the walls' nearest-point functions (nears)")

    def call(target: int, lo: int, hi: int) -> None:
        if phases:
            E.run_batch_phases(
                ctxs, params, walls, nears, rings, stats, consts, transient, total, target,
                lo, hi,
            )  # fmt: skip
            return
        E.run_batch(
            ctxs, params, walls, rows, rings, stats, consts, transient, total, target, lo, hi
        )

    if n == 0:
        return stats, rings
    with _jit.compiling(kernel):
        call(min(total, 1), 0, 1)  # compiled (or loaded) once, before the threads start
    target = 0
    pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
    try:
        while target < total:
            target = min(total, target + ROUND_IMPACTS)
            if pool is None:
                for lo, hi in slices:
                    call(target, lo, hi)
                    if progress is not None:
                        progress(int(stats[:, E.ST_TOTAL].sum()))
                continue
            pending = {pool.submit(call, target, lo, hi) for lo, hi in slices}
            while pending:
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                for future in done:
                    future.result()
                if progress is not None:
                    progress(int(stats[:, E.ST_TOTAL].sum()))
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    return stats, rings


def advance_setup(
    setup: EnsembleSetup,
    ctxs: np.ndarray,
    consts: np.ndarray,
    *,
    transient: int,
    impacts: int,
    width: int,
    device: str = "cpu",
    threads: int | None = None,
    progress: Callable[[int], None] | None = None,
    keep: int | None = None,
    states: bool = True,
) -> tuple[np.ndarray, Any]:
    """:func:`advance` of trajectories of ``setup`` on ``device``: ``"cpu"`` (``threads``
    threads) or ``"gpu"`` (:func:`billiard.engine.gpu.advance_ensemble`).

    ``keep`` None: returns (stats, rings), as :func:`advance`. ``keep`` K: returns
    (stats, (heights, tofs)), the last K measured heights (m) and times of flight (s) of
    each trajectory (n x K each, oldest first, NaN-padded at the front;
    :func:`billiard.kernels.ensemble.tail`, on the device on a GPU), and no ring leaves
    the GPU. ``states`` False: the GPU does not copy the state vectors back (``ctxs``
    are then left as given there; the CPU advances them in place either way). What a
    sweep stores needs neither ring nor state vector (docs/sweeps.md, "On a GPU").

    Raises:
        ValueError: ``"gpu"`` for a contact-phases set-up (the GPU kernels have the
            impacts model).
    """
    if device == "gpu" and setup.phases:
        raise ValueError(GPU_PHASES)
    if device == "gpu":
        from billiard.engine import gpu

        return gpu.advance_ensemble(
            setup.sim, ctxs, setup.params, consts, transient=transient, impacts=impacts,
            width=width, keep=keep, states=states,
        )  # fmt: skip
    stats, rings = advance(
        ctxs, setup.params, setup.walls, consts, transient=transient, impacts=impacts,
        width=width, threads=threads, progress=progress, nears=setup.nears,
    )  # fmt: skip
    return stats, (rings if keep is None else last_impacts(stats, rings, keep))


def last_impacts(stats: np.ndarray, rings: np.ndarray, keep: int) -> tuple[np.ndarray, ...]:
    """The last ``keep`` measured heights (m) and times of flight (s) of each
    trajectory, oldest first, NaN-padded at the front (n x keep each): the kernels'
    :func:`~billiard.kernels.ensemble.tail`, which the GPU runs on the device."""
    from billiard.kernels.ensemble import tails

    n = rings.shape[0]
    heights, tofs = np.empty((n, keep)), np.empty((n, keep))
    if n and keep:
        tails(np.ascontiguousarray(rings), np.ascontiguousarray(stats), heights, tofs)
    return heights, tofs
