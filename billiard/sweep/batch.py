"""The points of a sweep chunk that the ensemble kernel takes, measured together.

Points are grouped by their parameter set (every swept key but the ball's start,
``initial.*``); each group is set up once (:func:`billiard.engine.ensemble.prepare`,
cached for the worker's next chunks) and its starts run as one ensemble on this worker's
core. A point's trajectory is bit for bit the one ``billiard run`` makes, and its
measurements are the sweep's (:mod:`billiard.sweep.measure`): the class, period and
impact counts equal the per-point path's, the means and spreads agree to the last bits
(running sums instead of numpy's pairwise ones).

Scenes under ``contact.model = "phases"`` run on the state machine (on the CPU also
when the sweep's device is the GPU, whose kernels have the impacts model only); a run
that ends with the ball on the boundary (at rest, in contact) is classed as the
per-point path classes it.

Left to the per-point path (:func:`billiard.sweep.measure.measure_point`): points with
``--lyapunov``, scenes the kernel does not take (method rk4), starts with one of
``initial.q1``, ``initial.q2`` given and not the other, and points whose run stops
early (measured again one by one, for the engine's own words of why).
"""

from __future__ import annotations

import math
import os
from collections import OrderedDict
from typing import Any

import numpy as np

from billiard.engine import ensemble as EN
from billiard.sweep.attractor import CLASSES, PERIOD_WINDOW
from billiard.sweep.columns import MODES, RUN_STATUSES, STATUSES
from billiard.sweep.ensemble import measured_columns

__all__ = ["measure_batch"]

#: the set-ups a worker keeps for its next chunks (one per parameter set)
_SETUPS: OrderedDict[Any, Any] = OrderedDict()
_KEEP_SETUPS = 64
#: set to "0" in the environment, every parameter set is set up on its own (the
#: benchmark's baseline: ``billiard bench --only ensemble`` measures both paths)
PATCH_ENV = "BILLIARD_PATCH_SETUPS"
#: a start's keys -> their names in the starts (q1, q2, v1, v2, omega, t)
_BALL = {key: key.removeprefix("initial.") for key in EN.BALL_KEYS}


def _setup(scene: Any) -> Any:
    """The set-up of ``scene`` (its parameter set), made once per worker."""
    key = scene  # a frozen dataclass: equal scenes, one set-up
    if key in _SETUPS:
        _SETUPS.move_to_end(key)
        return _SETUPS[key]
    setup = EN.prepare(scene)
    _SETUPS[key] = setup
    if len(_SETUPS) > _KEEP_SETUPS:
        _SETUPS.popitem(last=False)
    return setup


def _groups(sweep: Any, indices: Any) -> dict[Any, list[tuple[int, dict[str, Any]]]]:
    """Points by parameter set: (the set's values) -> [(index, the start's values)]."""
    groups: dict[Any, list[tuple[int, dict[str, Any]]]] = {}
    for index in indices:
        values = sweep.point_values(int(index))
        params = tuple((k, v) for k, v in values.items() if k not in _BALL)
        start = {_BALL[k]: v for k, v in values.items() if k in _BALL}
        groups.setdefault(params, []).append((int(index), start))
    return groups


def _families(
    groups: dict[Any, list[tuple[int, dict[str, Any]]]],
) -> dict[Any, list[tuple[Any, list[tuple[int, dict[str, Any]]]]]]:
    """Parameter sets by family: the sets that differ in :data:`~billiard.engine.
    ensemble.PATCH_KEYS` alone (the points of a drive, contact or air parameter map),
    which share one set-up's geometry and run as one ensemble."""
    families: dict[Any, list[tuple[Any, list[tuple[int, dict[str, Any]]]]]] = {}
    for params, points in groups.items():
        fixed = tuple((k, v) for k, v in params if k not in EN.PATCH_KEYS)
        families.setdefault(fixed, []).append((params, points))
    return families


def measure_batch(
    sweep: Any, indices: Any, settings: dict[str, Any], device: str = "cpu"
) -> tuple[dict[str, np.ndarray] | None, list[int]]:
    """Measure the points ``indices`` of ``sweep`` that the ensemble kernel takes, on
    this core or (``device = "gpu"``) on the GPU.

    The parameter sets of a family (:func:`_families`) under the impacts model run as one
    ensemble (on the CPU or the GPU): the first set is set up (:func:`_setup`), the others are
    patched from it (:func:`billiard.engine.ensemble.patch`, no Simulation of their own),
    each trajectory with its own state vector and constants.

    Returns:
        (columns, rest): the columns of the points measured here (``billiard.sweep.
        columns``, ``index`` first; None when there are none) and the indices left to
        the per-point path (in groups of parameter sets).
    """
    from billiard.scene.scene import with_values

    if settings["lyapunov"]:
        return None, [int(i) for i in indices]
    keep = int(settings["keep"])
    parts: list[dict[str, np.ndarray]] = []
    rest: list[int] = []
    for sets in _families(_groups(sweep, indices)).values():
        scenes = []
        for params, points in sets:
            try:
                scene = with_values(sweep.scene, dict(params))
            except ValueError:
                rest += [i for i, _ in points]
                continue
            if EN.supports(scene) is not None:
                rest += [i for i, _ in points]
                continue
            scenes.append((scene, points))
        if not scenes:
            continue
        patched = scenes[0][0].contact.model == "impacts"
        patched = patched and os.environ.get(PATCH_ENV, "1") != "0"
        family = [scenes] if patched else [[one] for one in scenes]
        for members in family:
            part, left = _measure_family(members, settings, keep, device)
            rest += left
            if part is not None:
                parts.append(part)
    if not parts:
        return None, rest
    columns = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    return columns, rest


def _setups(
    scenes: list[tuple[Any, list[tuple[int, dict[str, Any]]]]],
) -> tuple[list[tuple[Any, Any, list[tuple[int, dict[str, Any]]]]], list[int]]:
    """(set-up, scene, points) of each parameter set that can be set up (the first
    prepared, the others patched from it), and the points of those that cannot (left
    to the per-point path, which says why)."""
    try:
        base = _setup(scenes[0][0])
    except ValueError:  # a scene the engine cannot set up: the per-point path says why
        return [], [i for _, points in scenes for i, _ in points]
    out = [(base, scenes[0][0], scenes[0][1])]
    left: list[int] = []
    for scene, points in scenes[1:]:
        try:
            out.append((EN.patch(base, scene), scene, points))
        except ValueError:
            left += [i for i, _ in points]
    return out, left


def _start_rows(
    setup: Any, points: list[tuple[int, dict[str, Any]]], duration: float | None
) -> tuple[np.ndarray, np.ndarray, list[int], list[int]]:
    """The state vectors of the points' starts: (ctxs, valid, rows, left): ``rows`` the
    points (positions in ``points``) given a vector, ``valid`` whether the set-up
    accepts each, ``left`` the indices of points left to the per-point path (a start
    with one of q1 and q2 given, or at rest at another time)."""
    init = setup.scene.initial
    base = {"q1": init.q1, "q2": init.q2, "v1": init.v1, "v2": init.v2}
    base |= {"omega": init.omega, "t": init.t}
    starts = [base | start for _, start in points]
    placed = [s["q1"] is not None and s["q2"] is not None for s in starts]
    resting = [s["q1"] is None and s["q2"] is None and s["t"] == setup.t for s in starts]
    rows = [k for k in range(len(points)) if placed[k] or resting[k]]
    left = [points[k][0] for k in range(len(points)) if not (placed[k] or resting[k])]
    ctxs = np.empty((len(rows), setup.template.size))
    valid = np.ones(len(rows), dtype=bool)
    by_time: dict[float, list[int]] = {}
    for r, k in enumerate(rows):
        if placed[k]:
            by_time.setdefault(float(starts[k]["t"]), []).append(r)
    for t, rs in by_time.items():
        pick = [starts[rows[r]] for r in rs]
        whole = len(rs) == len(rows)  # the common case: one start time, nothing at rest
        c, ok = EN.start(
            setup,
            *(np.array([float(s[name]) for s in pick]) for name in ("q1", "q2", "v1", "v2")),
            np.array([float(s["omega"]) for s in pick]),
            t=t,
            duration=duration,
            out=ctxs if whole else None,
        )
        if not whole:
            ctxs[rs] = c
        valid[rs] = ok
    lying = [r for r, k in enumerate(rows) if resting[k]]
    if lying:
        pick = [starts[rows[r]] for r in lying]
        ctxs[lying] = EN.start_at_rest(
            setup,
            len(lying),
            *(np.array([float(s[name]) for s in pick]) for name in ("v1", "v2", "omega")),
            duration=duration,
        )
    return ctxs, valid, rows, left


def _measure_family(
    scenes: list[tuple[Any, list[tuple[int, dict[str, Any]]]]],
    settings: dict[str, Any],
    keep: int,
    device: str = "cpu",
) -> tuple[dict[str, np.ndarray] | None, list[int]]:
    """Measure the points of parameter sets that share one set-up's geometry (one set,
    or a family of the impacts model) as one ensemble."""
    from billiard.kernels import ensemble as E

    setups, left = _setups(scenes)
    if not setups:
        return None, left
    duration = settings["duration"]
    duration = setups[0][1].run.duration if duration is None else duration
    blocks, consts, index, rest_height, frequency = [], [], [], [], []
    for setup, scene, points in setups:
        ctxs, valid, rows, not_here = _start_rows(setup, points, duration)
        left += not_here
        # invalid starts (refused before the sweep ran, so rare here) go to the
        # per-point path
        left += [points[rows[r]][0] for r in np.nonzero(~valid)[0]]
        run = np.nonzero(valid)[0]
        if not run.size:
            continue
        blocks.append(ctxs if run.size == len(rows) else ctxs[run])
        one = EN.constants(scene, settings["tolerance"], settings["max_period"], PERIOD_WINDOW)
        consts.append(np.broadcast_to(one, (run.size, one.size)))
        index += [points[rows[r]][0] for r in run]
        rest_height.append(np.full(run.size, setup.rest_height))
        frequency.append(np.full(run.size, scene.drive.frequency))
    if not blocks:
        return None, left
    ctxs = blocks[0] if len(blocks) == 1 else np.concatenate(blocks)
    setup, scene = setups[0][0], setups[0][1]
    transient, impacts = int(settings["transient"]), int(settings["impacts"])
    width = max(PERIOD_WINDOW, keep, 1)
    # only what the sweep stores: no ring or state vector leaves a GPU
    stats, (heights, tofs) = EN.advance_setup(
        setup, ctxs, np.concatenate(consts), transient=transient, impacts=impacts,
        width=width, device="cpu" if setup.phases else device, threads=1, keep=keep,
        states=False,
    )  # fmt: skip
    heights_at_rest = np.concatenate(rest_height)
    columns = measured_columns(
        stats,
        np.ones(len(index), dtype=bool),
        heights_at_rest,
        settings["rest_band"],
        scene,
        frequency=np.concatenate(frequency),
    )
    # a run that stopped early, or one without a measured impact (that did not end on
    # the boundary): measured again one by one, for the engine's words of why
    ok = columns["attractor"] != "failed"
    keep_rows = np.nonzero(ok)[0]
    left += [index[r] for r in np.nonzero(~ok)[0]]
    if not keep_rows.size:
        return None, left
    n = keep_rows.size
    attractor = np.array([CLASSES.index(c) for c in columns["attractor"][keep_rows]], np.int8)
    run_status = np.array(
        [RUN_STATUSES.index(s) for s in columns["run_status"][keep_rows]], dtype=np.int8
    )
    part = {
        "index": np.array([index[r] for r in keep_rows], dtype=np.int64),
        "status": np.full(n, STATUSES.index("ok"), dtype=np.int8),
        "attractor": attractor,
        "run_status": run_status,
        "final_mode": np.array(
            [MODES.index(m) for m in columns["final_mode"][keep_rows]], dtype=np.int8
        ),
        "period": columns["period"][keep_rows].astype(np.int32),
        "drive_periods": columns["drive_periods"][keep_rows].astype(np.int32),
        "impacts": columns["impacts"][keep_rows].astype(np.int64),
        "total_impacts": columns["total_impacts"][keep_rows].astype(np.int64),
        "elastic_impacts": stats[keep_rows, E.ST_ELASTIC].astype(np.int64),
        "lid_impacts": stats[keep_rows, E.ST_LID].astype(np.int64),
        "rest_height": heights_at_rest[keep_rows],
        "height_mean": columns["height_mean"][keep_rows],
        "height_std": columns["height_std"][keep_rows],
        "height_max": columns["height_max"][keep_rows],
        "tof_mean": columns["tof_mean"][keep_rows],
        "tof_std": columns["tof_std"][keep_rows],
        "lyapunov": np.full(n, math.nan),
        "lyapunov_per_second": np.full(n, math.nan),
        "last_height": heights[keep_rows],
        "last_tof": tofs[keep_rows],
    }
    return part, left
