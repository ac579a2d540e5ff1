"""Many starts of one scene at once, measured as a sweep measures a point: the Python
face of the ensemble kernel (:mod:`billiard.kernels.ensemble`).

>>> import numpy as np, billiard
>>> q1, q2 = np.meshgrid(np.linspace(-0.04, 0.04, 50), np.linspace(0.02, 0.12, 50))
>>> result = billiard.run_ensemble("wedge-6.6hz", q1=q1, q2=q2, impacts=200)
>>> result.attractor.shape, result.to_pandas().columns[:4].tolist()

Every start runs the trajectory ``billiard run`` makes from it (bit for bit on the CPU):
``transient`` impacts, then ``impacts`` measured ones, as ``billiard sweep`` measures a
point (:mod:`billiard.sweep.measure`: heights, times of flight, the period of the
post-impact state with the drive phase, the attractor class). A start that overlaps a
wall or the lid is ``invalid``; a run that stops early is ``failed``. Under
``contact.model = "phases"`` a run may also end with the ball on the boundary (at rest,
or in contact for the contact span): its class is then that of the sweep's
(:func:`billiard.sweep.attractor.contact_class`: resting, rolling, sliding, held).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from billiard.kernels import layout as L
from billiard.kernels.names import column
from billiard.sweep.attractor import CLASSES, CONTACT_CLASSES, PERIOD_WINDOW

__all__ = [
    "DEVICES",
    "EnsembleResult",
    "as_scene",
    "check_device",
    "classes_of",
    "run_ensemble",
]

#: what the measured columns hold, with their units (``EnsembleResult.columns``)
COLUMN_UNITS = {
    "q1_start": "m",
    "q2_start": "m",
    "attractor": "",
    "period": "1",
    "drive_periods": "1",
    "impacts": "1",
    "total_impacts": "1",
    "height_mean": "m",
    "height_std": "m",
    "height_max": "m",
    "tof_mean": "s",
    "tof_std": "s",
    "elastic_share": "1",
    "lid_share": "1",
    "run_status": "",
    "final_mode": "",
}


def contact_codes(stats: np.ndarray) -> np.ndarray:
    """The class codes of runs that ended with the ball on the boundary rather than in
    an impact sequence, -1 elsewhere: :func:`billiard.sweep.attractor.contact_class` of
    each trajectory's status, motion state at the end and measured impacts."""
    from billiard.kernels import ensemble as E

    status = stats[:, E.ST_STATUS]
    mode = stats[:, E.ST_MODE].astype(np.int64)
    by_mode = np.array(
        [CLASSES.index(CONTACT_CLASSES[m]) if m in CONTACT_CLASSES else -1 for m in L.MOTION_NAMES]
    )
    contact = by_mode[mode]
    codes = np.full(stats.shape[0], -1, dtype=np.int64)
    settled = (status == E.RUN_TIME_LIMIT) & (stats[:, E.ST_MEASURED] == 0)
    codes[settled] = contact[settled]
    in_contact = status == E.RUN_IN_CONTACT
    codes[in_contact] = np.where(contact >= 0, contact, CLASSES.index("rolling"))[in_contact]
    codes[status == E.RUN_AT_REST] = CLASSES.index("resting")
    return codes


def classes_of(
    stats: np.ndarray, valid: np.ndarray, rest_height: Any, rest_band: float
) -> np.ndarray:
    """The attractor class codes (indices into ``CLASSES``) of measured trajectories,
    by :func:`billiard.sweep.attractor.classify`'s rules (no Lyapunov exponent: a
    trajectory without a period is ``aperiodic``)."""
    from billiard.kernels import ensemble as E

    n = stats.shape[0]
    measured = stats[:, E.ST_MEASURED]
    contact = contact_codes(stats)
    failed = (stats[:, E.ST_STATUS] == E.RUN_FAILED) | (stats[:, E.ST_STATUS] == E.RUN_PENDING)
    failed |= (measured == 0) & (contact < 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        elastic = stats[:, E.ST_ELASTIC] / measured
    rise = stats[:, E.ST_H_MAX] - rest_height
    codes = np.full(n, CLASSES.index("aperiodic"), dtype=np.int8)
    codes[stats[:, E.ST_PERIOD] > 0] = CLASSES.index("periodic")
    codes[(rise <= rest_band) & (elastic >= 0.5)] = CLASSES.index("resting")
    codes[contact >= 0] = contact[contact >= 0]
    codes[failed] = CLASSES.index("failed")
    codes[~valid] = CLASSES.index("invalid")
    return codes


@dataclass
class EnsembleResult:
    """The measurements of an ensemble, one entry per start (arrays shaped as the starts).

    Attributes:
        scene: the scene run.
        columns: name -> array (units in ``COLUMN_UNITS``; ``attractor`` as class names).
        last_height, last_tof: the last K impact heights (m) and times of flight (s) of
            each start, NaN-padded at the front (shape: starts + (K,)).
        final: the ball's state after its last impact, name -> array (``t``, ``q1``,
            ``q2``, ``v1``, ``v2``, ``omega``; s, m, m/s, rad/s); empty when the run
            kept no states (``run_ensemble(..., states=False)``).
        seconds: wall-clock time of the run (s).
    """

    scene: Any
    shape: tuple[int, ...]
    columns: dict[str, np.ndarray]
    last_height: np.ndarray
    last_tof: np.ndarray
    final: dict[str, np.ndarray]
    seconds: float = 0.0
    device: str = "cpu"
    ctxs: Any = field(default=None, repr=False)

    @property
    def attractor(self) -> np.ndarray:
        """The attractor class of each start (strings, ``CLASSES``)."""
        return self.columns["attractor"]

    def __repr__(self) -> str:
        names, counts = np.unique(self.attractor, return_counts=True)
        classes = ", ".join(f"{c} {k}" for c, k in zip(names, counts, strict=True))
        shape = " x ".join(str(n) for n in self.shape) + " starts" if self.shape else "1 start"
        return f"<EnsembleResult {self.scene.name!r}: {shape} on {self.device}: {classes}>"

    def _repr_html_(self) -> str:
        """The scene, the starts and the share of each attractor class as an HTML table."""
        from billiard.scene.display import html_table, scene_rows

        names, counts = np.unique(self.attractor, return_counts=True)
        total = int(counts.sum())
        shares = ", ".join(
            f"{c} {k} ({100.0 * k / total:.3g} %)" for c, k in zip(names, counts, strict=True)
        )
        starts = " x ".join(str(n) for n in self.shape) if self.shape else "1"
        rows = scene_rows(self.scene) + [
            ("starts", f"{starts} ({total} trajectories) on {self.device}"),
            ("attractors", shares or "none"),
            ("wall-clock time", f"{self.seconds:.3g} s"),
        ]
        return html_table(rows, f"EnsembleResult of {self.scene.name!r}")

    def to_pandas(self) -> Any:
        """One row per start, the measured columns.

        Raises:
            MissingExtraError: (an ImportError) pandas is not installed.
        """
        from billiard.run.frames import require_extra

        pd = require_extra("pandas", "EnsembleResult.to_pandas()")

        return pd.DataFrame({k: np.ravel(v) for k, v in self.columns.items()})

    def to_xarray(self) -> Any:
        """An ``xarray.Dataset`` over the starts' dimensions (``start_0``, ...).

        Raises:
            MissingExtraError: (an ImportError) xarray is not installed.
        """
        from billiard.run.frames import require_extra

        xr = require_extra("xarray", "EnsembleResult.to_xarray()")

        dims = tuple(f"start_{i}" for i in range(len(self.shape)))
        data = {
            k: (dims, np.asarray(v), {"units": COLUMN_UNITS.get(k, "")})
            for k, v in self.columns.items()
        }
        data["last_height"] = (dims + ("impact",), self.last_height, {"units": "m"})
        data["last_tof"] = (dims + ("impact",), self.last_tof, {"units": "s"})
        return xr.Dataset(data, attrs={"scene": self.scene.name})


def as_scene(scene: Any) -> Any:
    """A scene, or a built-in scene's name or a scene file's path loaded."""
    if isinstance(scene, str):
        from billiard.scene.scene import load_scene

        return load_scene(scene)
    return scene


def run_ensemble(
    scene: Any,
    *,
    q1: Any,
    q2: Any,
    v1: Any = 0.0,
    v2: Any = 0.0,
    omega: Any = 0.0,
    t: float = 0.0,
    impacts: int = 1000,
    transient: int = 0,
    keep: int = 0,
    duration: float | None = None,
    tolerance: float = 1e-5,
    max_period: int = 64,
    rest_band: float = 0.01,
    threads: int | None = None,
    progress: Callable[[int], None] | None = None,
    device: str = "cpu",
    states: bool = True,
) -> EnsembleResult:
    """Run one trajectory per start (arrays broadcast together: positions in m,
    velocities in m/s, spin in rad/s, all at time t in s) of ``scene`` (a scene or a
    built-in name): ``transient`` impacts, then ``impacts`` measured ones, at most
    ``duration`` s each. ``keep``: the last impacts' heights and times of flight kept
    per start. ``tolerance`` (m), ``max_period`` (impacts) and ``rest_band`` (m) are
    the sweep's period test and resting band (docs/sweeps.md). ``device``: ``"cpu"``
    (all cores, or ``threads``) or ``"gpu"`` (an NVIDIA GPU through numba-cuda: the
    same physics, not the same bits; docs/sweeps.md, "GPU"; the impacts model only).
    ``states`` False: the final state vectors are not kept (``final`` is empty,
    ``ctxs`` None), so that a GPU copies back only the measurements (about 112 bytes
    and 16 per kept impact a start, rather than 11 kB more).

    Raises:
        ValueError: a scene the ensemble kernel does not take (method rk4; contact
            phases on the GPU), or one that cannot be simulated.
    """
    import time

    from billiard.engine import ensemble as EN
    from billiard.kernels import ensemble as E

    scene = as_scene(scene)
    if impacts < 1 or transient < 0 or keep < 0:
        raise ValueError("impacts must be >= 1, transient and keep >= 0")
    check_device(device)
    began = time.perf_counter()
    setup = EN.prepare(scene)
    starts = (q1, q2, v1, v2, omega)
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in starts))
    shape = arrays[0].shape
    ctxs, valid = EN.start(setup, *(a.ravel() for a in arrays), t=t, duration=duration)
    width = max(PERIOD_WINDOW, keep, 1)
    consts = EN.constants(scene, tolerance, max_period, PERIOD_WINDOW)
    n = ctxs.shape[0]
    run = np.nonzero(valid)[0]
    stats = np.zeros((n, E.NSTAT))
    stats[:, E.ST_STATUS] = E.RUN_FAILED
    last_height, last_tof = np.full((n, keep), math.nan), np.full((n, keep), math.nan)
    if run.size:
        whole = run.size == n  # every start valid: advanced where they are
        sub = ctxs if whole else np.ascontiguousarray(ctxs[run])
        s, (h, f) = EN.advance_setup(
            setup, sub, consts, transient=transient, impacts=impacts, width=width,
            device=device, threads=threads, progress=progress, keep=keep, states=states,
        )  # fmt: skip
        stats[run], last_height[run], last_tof[run] = s, h, f
        if states and not whole:
            ctxs[run] = sub
    columns = measured_columns(stats, valid, setup.rest_height, rest_band, scene)
    columns = {"q1_start": arrays[0].ravel(), "q2_start": arrays[1].ravel()} | columns
    final = {
        name: column(ctxs, quantity).reshape(shape)
        for name, quantity in (("t", "engine.t"), ("q1", "engine.q1"), ("q2", "engine.q2"))
        + (("v1", "engine.u1"), ("v2", "engine.u2"), ("omega", "engine.u3"))
        if states
    }
    return EnsembleResult(
        scene=scene,
        shape=shape,
        columns={k: v.reshape(shape) for k, v in columns.items()},
        last_height=last_height.reshape(*shape, keep),
        last_tof=last_tof.reshape(*shape, keep),
        final=final,
        seconds=time.perf_counter() - began,
        device=device,
        ctxs=ctxs if states else None,
    )


#: the devices an ensemble runs on
DEVICES = ("cpu", "gpu")


def check_device(device: str) -> None:
    """Raise ValueError (one line) for a device that is not there: an unknown name, or
    ``gpu`` without numba-cuda or a CUDA GPU."""
    if device not in DEVICES:
        raise ValueError(f"device {device!r}: choose from {', '.join(DEVICES)}")
    if device == "gpu":
        from billiard.engine import gpu

        problem = gpu.available()
        if problem is not None:
            raise ValueError(f"--device gpu: {problem}")


def measured_columns(
    stats: np.ndarray,
    valid: np.ndarray,
    rest_height: Any,
    rest_band: float,
    scene: Any,
    frequency: Any = None,
) -> dict[str, np.ndarray]:
    """The sweep's measurements of each trajectory from the kernel's ``stats``
    (``rest_height`` in m and ``frequency`` in Hz per trajectory or one for all; the
    frequency by default ``scene``'s drive frequency)."""
    from billiard.kernels import ensemble as E

    measured = stats[:, E.ST_MEASURED]
    has = measured > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        height_std = np.sqrt(stats[:, E.ST_H_M2] / measured)
        tof_std = np.sqrt(stats[:, E.ST_TOF_M2] / measured)
        elastic = stats[:, E.ST_ELASTIC] / measured
        lid = stats[:, E.ST_LID] / measured
    codes = classes_of(stats, valid, rest_height, rest_band)
    ok = (codes != CLASSES.index("failed")) & (codes != CLASSES.index("invalid"))
    # a run that ended on the boundary is classed by that, without a period
    period = np.where(ok & (contact_codes(stats) < 0), stats[:, E.ST_PERIOD], 0).astype(np.int64)
    frequency = np.asarray(scene.drive.frequency if frequency is None else frequency, float)
    # as the sweep rounds it: the period's time over the drive period (Python's round
    # and numpy's rint both round half to even); none without a drive
    with np.errstate(invalid="ignore"):  # no period found: its time is not a number
        cycles = np.rint(stats[:, E.ST_PERIOD_TIME] * frequency)
    drive_periods = np.where((period > 0) & (frequency > 0.0), cycles, 0).astype(np.int64)
    nan = np.where(has & ok, 1.0, math.nan)
    status = stats[:, E.ST_STATUS]
    # the run's Status, lower case, as a run reports it ("": stopped)
    run_status = np.full(status.shape, "", dtype=object)
    names = ((E.RUN_COMPLETE, "complete"), (E.RUN_TIME_LIMIT, "time_limit"))
    names += ((E.RUN_AT_REST, "at_rest"), (E.RUN_IN_CONTACT, "in_contact"))
    for code, name in names:
        run_status[status == code] = name
    ran = (run_status != "") & valid
    mode = stats[:, E.ST_MODE].astype(np.int64)
    final_mode = np.where(ran, np.asarray(L.MOTION_NAMES, dtype=object)[mode], "")
    return {
        "attractor": np.asarray(CLASSES, dtype=object)[codes],
        "period": period,
        "drive_periods": drive_periods,
        "impacts": measured.astype(np.int64),
        "total_impacts": stats[:, E.ST_TOTAL].astype(np.int64),
        "height_mean": stats[:, E.ST_H_MEAN] * nan,
        "height_std": height_std * nan,
        "height_max": stats[:, E.ST_H_MAX] * nan,
        "tof_mean": stats[:, E.ST_TOF_MEAN] * nan,
        "tof_std": tof_std * nan,
        "elastic_share": elastic * nan,
        "lid_share": lid * nan,
        "run_status": run_status,
        "final_mode": final_mode,
    }
