"""The uncertainty exponent of a basin boundary (Grebogi, McDonald, Ott and Yorke,
Phys. Lett. A 99 (1983) 415), from the ensemble kernel.

Random starts (q1, q2) are drawn in a box; a start is eps-uncertain when the attractor
it reaches differs from that of (q1 + eps, q2) or of (q1 - eps, q2). The fraction f(eps)
of uncertain starts scales as eps^alpha; a boundary of box-counting dimension d in the
plane has alpha = 2 - d (alpha = 1 for a smooth boundary, smaller for a fractal one).
alpha is the least-squares slope of log f against log eps over the eps with
0 < f < 1, its standard error the slope's from the residuals.

Attractors are told apart as a basin map tells them (:func:`billiard.sweep.basins.
attractor_labels`: class, then period and mean impact height within 1 mm), over every
trajectory of the estimate together, so that a start and its neighbours are labelled
by one rule. All trajectories (the starts and their 2 K neighbours for K values of eps)
run on the ensemble kernel in a few calls of :func:`billiard.engine.ensemble.advance`.

The estimator (:func:`uncertain_counts`, :func:`fit_exponent`) takes labels from
anywhere: the tests check it on label functions whose exponent is known in closed form.
"""

from __future__ import annotations

import csv
import json
import math
import textwrap
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "MIN_SAMPLES",
    "SAMPLES_WHY",
    "UncertaintyResult",
    "check_size",
    "estimate_size",
    "fit_exponent",
    "run_uncertainty",
    "smallest_eps",
    "uncertain_counts",
    "uncertainty_figure",
    "write_results",
]

#: trajectories per call of the kernel: bounds the memory of the rings (256 impacts x 7
#: floats each, about 14 kB per trajectory) and of the state vectors (about 11 kB each)
CHUNK = 8192

# Memory of an estimate, for :func:`estimate_size` (measured with tracemalloc on
# hyperbola-4.5hz, 5 impacts each: 700 trajectories peak at 17 MB, 7,000 at 174 MB,
# 60,000 at 333 MB, 120,000 at 348 MB).
#: bytes per trajectory of a chunk while the kernel runs (state vector, ring, the checks
#: of the starts), counted up to CHUNK trajectories: 25 kB while the chunk fills, 39 kB
#: at the peak of a full one
TRAJECTORY_BYTES = 39_000
#: bytes per trajectory kept to the end (its start, its attractor's record and label)
RECORD_BYTES = 300

#: fewest starts, and why
MIN_SAMPLES = 2
SAMPLES_WHY = (
    "with one start the uncertain fraction f is 0 or 1 at every eps, and alpha is fitted "
    "over the eps with 0 < f < 1"
)


def uncertain_counts(center: np.ndarray, plus: np.ndarray, minus: np.ndarray) -> np.ndarray:
    """Per eps the number of uncertain starts: ``center`` (n labels) differs from
    ``plus[k]`` or ``minus[k]`` (K x n labels, start moved by +eps_k and -eps_k)."""
    center = np.asarray(center)
    differs = (np.asarray(plus) != center[None, :]) | (np.asarray(minus) != center[None, :])
    return differs.sum(axis=1)


def fit_exponent(
    eps: Sequence[float], fraction: Sequence[float]
) -> tuple[float, float, np.ndarray]:
    """The least-squares slope alpha of log f against log eps and its standard error,
    over the eps with 0 < f < 1 (``used``, returned as a mask). With two usable points
    the error is NaN; with fewer, alpha is NaN too."""
    x = np.log(np.asarray(eps, dtype=np.float64))
    f = np.asarray(fraction, dtype=np.float64)
    used = (f > 0.0) & (f < 1.0)
    m = int(used.sum())
    if m < 2:
        return math.nan, math.nan, used
    x, y = x[used], np.log(f[used])
    xm = x.mean()
    sxx = float(((x - xm) ** 2).sum())
    alpha = float(((x - xm) * (y - y.mean())).sum() / sxx)
    if m == 2:
        return alpha, math.nan, used
    intercept = y.mean() - alpha * xm
    residual = y - (intercept + alpha * x)
    se = math.sqrt(float((residual**2).sum()) / (m - 2) / sxx)
    return alpha, se, used


@dataclass
class UncertaintyResult:
    """An estimate of the uncertainty exponent.

    Attributes:
        scene: the scene.
        eps: the displacements (m), increasing.
        uncertain: per eps the uncertain starts; ``samples`` the starts kept.
        alpha, alpha_se: the exponent and its standard error (NaN: too few usable eps).
        used: per eps whether it entered the fit (0 < f < 1).
        dropped: starts drawn valid but dropped for a neighbour (q1 +- eps) that is not.
        drawn: starts drawn in the box in all; the rest overlapped a wall or the lid.
        labels: the attractors' names (:func:`billiard.sweep.basins.attractor_labels`);
            ``counts`` how many of the kept starts reach each.
        q1, q2: the kept starts (m); ``center`` their attractor numbers.
    """

    scene: Any
    eps: np.ndarray
    uncertain: np.ndarray
    samples: int
    alpha: float
    alpha_se: float
    used: np.ndarray
    dropped: int
    drawn: int
    labels: list[str]
    counts: list[int]
    q1: np.ndarray
    q2: np.ndarray
    center: np.ndarray
    q1_range: tuple[float, float] = (0.0, 0.0)
    q2_range: tuple[float, float] = (0.0, 0.0)
    impacts: int = 0
    transient: int = 0
    seed: int = 0
    seconds: float = 0.0
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def fraction(self) -> np.ndarray:
        """f(eps): the share of uncertain starts."""
        return self.uncertain / max(self.samples, 1)

    @property
    def dimension(self) -> float:
        """The boundary's box-counting dimension d = 2 - alpha."""
        return 2.0 - self.alpha


def smallest_eps(q1: tuple[float, float]) -> float:
    """The smallest displacement (m) that moves every start of the box's q1 range: the
    spacing of floats at its largest magnitude (a smaller eps leaves q1 + eps = q1 for
    the starts there)."""
    return float(np.spacing(max(abs(q1[0]), abs(q1[1]))))


def estimate_size(samples: int, eps: int) -> float:
    """Bytes of memory an estimate from ``samples`` starts and ``eps`` displacements
    takes at most, about: every start runs with its 2 ``eps`` neighbours. A float: it
    may exceed every integer type."""
    trajectories = float(samples) * (2.0 * float(eps) + 1.0)
    return TRAJECTORY_BYTES * min(trajectories, CHUNK) + RECORD_BYTES * trajectories


def check_size(samples: int, eps: int, allow: str = "allow_large=True") -> None:
    """Refuse, before anything is allocated, an estimate whose memory
    (:func:`estimate_size`) is over :data:`billiard.run.output_size.MAX_BYTES`, unless
    confirmed.

    Raises:
        OutputSizeError: one line naming the estimate, the starts and the eps, and
            ``allow`` as the way to go ahead.
    """
    from billiard.run.output_size import check_size as check

    trajectories = samples * (2 * eps + 1)
    check(
        {"memory": estimate_size(samples, eps)},
        what=(
            f"{samples:,} starts with {eps:,} eps each ({trajectories:,} trajectories: "
            "every start and its 2 neighbours per eps)"
        ),
        fewer="give fewer --samples or eps (--eps LO:HI:N)",
        allow=allow,
    )


def _draw(
    setup: Any,
    rng: np.random.Generator,
    q1_range: tuple[float, float],
    q2_range: tuple[float, float],
    eps: np.ndarray,
    samples: int,
    t: float,
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """``samples`` starts whose centre and 2 K neighbours the set-up all accepts;
    also the starts drawn and those dropped for a neighbour."""
    from billiard.engine.ensemble import start

    shifts = np.concatenate(([0.0], eps, -eps))
    drawn1: list[np.ndarray] = []
    drawn2: list[np.ndarray] = []
    centre: list[np.ndarray] = []  # the start itself is valid
    whole: list[np.ndarray] = []  # ... and so are its 2 K neighbours
    have = 0
    for _ in range(200):
        batch = max(64, 2 * (samples - have))
        q1 = rng.uniform(q1_range[0], q1_range[1], batch)
        q2 = rng.uniform(q2_range[0], q2_range[1], batch)
        moved = (q1[None, :] + shifts[:, None]).ravel()
        same = np.tile(q2, shifts.size)
        ok = np.concatenate(
            [start(setup, moved[i : i + CHUNK], same[i : i + CHUNK], t=t)[1]
             for i in range(0, moved.size, CHUNK)]
        ).reshape(shifts.size, batch)  # fmt: skip
        drawn1.append(q1)
        drawn2.append(q2)
        centre.append(ok[0])
        whole.append(ok.all(axis=0))
        have += int(whole[-1].sum())
        if have >= samples:
            break
        if have == 0 and len(whole) >= 4:  # nothing in 4 rounds: hardly ever anything
            break
    if have < samples:
        raise ValueError(
            f"found {have} valid starts of {samples} in the box in "
            f"{sum(a.size for a in drawn1)} draws: is the box inside the container?"
        )
    good = np.concatenate(whole)
    # the draws up to the last start needed count, those after it are not used
    last = int(np.nonzero(good)[0][samples - 1])
    good = good[: last + 1]
    dropped = int((np.concatenate(centre)[: last + 1] & ~good).sum())
    q1 = np.concatenate(drawn1)[: last + 1][good]
    q2 = np.concatenate(drawn2)[: last + 1][good]
    return q1, q2, last + 1, dropped


def run_uncertainty(
    scene: Any,
    q1: tuple[float, float],
    q2: tuple[float, float],
    *,
    samples: int = 2000,
    eps: Sequence[float] = tuple(np.geomspace(1e-6, 1e-3, 7)),
    impacts: int = 300,
    transient: int = 300,
    seed: int = 0,
    tolerance: float = 1e-5,
    max_period: int = 64,
    rest_band: float = 0.01,
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    allow_large: bool = False,
) -> UncertaintyResult:
    """Estimate the uncertainty exponent of the basin boundaries of ``scene`` (a scene or
    a built-in name) in the box
    ``q1`` x ``q2`` (m; each (low, high)) from ``samples`` random starts at rest (random
    generator seeded with ``seed``), displaced by each of ``eps`` (m) along q1, each
    trajectory ``transient`` impacts then ``impacts`` measured ones.
    ``progress(done, total)`` counts trajectories. ``allow_large``: go ahead when the
    memory would be over 1 GB (:func:`check_size`).

    Raises:
        ValueError: an empty box, samples < 2, fewer than 2 eps, an eps <= 0 or one too
            small to move a start (below the spacing of floats at the box's largest
            q1), a scene the ensemble kernel does not take, or no valid starts in the box.
        OutputSizeError: (a ``SceneError``) the estimate would take more than 1 GB of
            memory and ``allow_large`` is False; checked before anything is drawn.
    """
    from billiard.engine import ensemble as EN
    from billiard.sweep.attractor import PERIOD_WINDOW
    from billiard.sweep.basins import attractor_labels
    from billiard.sweep.ensemble import as_scene, measured_columns

    if samples < MIN_SAMPLES:
        raise ValueError(f"samples must be >= {MIN_SAMPLES}, got {samples}: {SAMPLES_WHY}")
    if not allow_large:  # first: nothing is drawn before
        check_size(samples, len(eps))
    scene = as_scene(scene)
    began = time.perf_counter()
    eps = np.sort(np.asarray(eps, dtype=np.float64))
    for name, (lo, hi) in (("q1", q1), ("q2", q2)):
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"--{name} {lo:g}:{hi:g}: give LO:HI with LO < HI (m)")
    if eps.size < 2 or not np.all(np.isfinite(eps)) or eps[0] <= 0.0:
        raise ValueError("eps: give at least 2 displacements, all > 0 (m)")
    resolution = smallest_eps(q1)
    if eps[0] < resolution:
        raise ValueError(
            f"eps {eps[0]:.3g} m is too small to move a start by eps: floats near q1 = "
            f"{max(abs(q1[0]), abs(q1[1])):g} m are {resolution:.3g} m apart; give eps >= "
            f"{resolution:.3g} m"
        )
    if np.any(np.diff(eps) == 0.0):
        raise ValueError("eps: a displacement is given twice")
    if impacts < 1 or transient < 0:
        raise ValueError("impacts must be >= 1 and transient >= 0")
    why = EN.supports(scene)
    if why is not None:
        raise ValueError(f"the ensemble kernel does not take this scene: {why}")
    setup = EN.prepare(scene)
    rng = np.random.default_rng(seed)
    t = scene.initial.t
    c1, c2, drawn, dropped = _draw(setup, rng, q1, q2, eps, samples, t)
    k = eps.size
    shifts = np.concatenate(([0.0], eps, -eps))
    all1 = (c1[None, :] + shifts[:, None]).ravel()  # centres, then +eps_k, then -eps_k
    all2 = np.tile(c2, shifts.size)
    ini = scene.initial
    window = PERIOD_WINDOW
    consts = EN.constants(scene, tolerance, max_period, window)
    records: list[dict[str, Any]] = []
    total = all1.size
    for lo in range(0, total, CHUNK):
        hi = min(total, lo + CHUNK)
        ctxs, ok = EN.start(setup, all1[lo:hi], all2[lo:hi], ini.v1, ini.v2, ini.omega, t=t)
        if not ok.all():  # _draw checked each of them: a start is accepted or not
            raise AssertionError("a start checked valid was refused")
        stats, rings = EN.advance(
            ctxs, setup.params, setup.walls, consts, transient=transient, impacts=impacts,
            width=window, threads=threads, nears=setup.nears,
        )  # fmt: skip
        cols = measured_columns(stats, ok, setup.rest_height, rest_band, scene)
        records += [
            {"attractor": a, "period": p, "height_mean": h}
            for a, p, h in zip(cols["attractor"], cols["period"], cols["height_mean"], strict=True)
        ]
        if progress is not None:
            progress(hi, total)
    numbers, labels = attractor_labels(records)
    grid = np.asarray(numbers).reshape(shifts.size, samples)
    center, plus, minus = grid[0], grid[1 : 1 + k], grid[1 + k :]
    uncertain = uncertain_counts(center, plus, minus)
    alpha, se, used = fit_exponent(eps, uncertain / samples)
    counts = np.bincount(center, minlength=len(labels)).tolist()
    return UncertaintyResult(
        scene=scene,
        eps=eps,
        uncertain=uncertain,
        samples=samples,
        alpha=alpha,
        alpha_se=se,
        used=used,
        dropped=dropped,
        drawn=drawn,
        labels=labels,
        counts=counts,
        q1=c1,
        q2=c2,
        center=center,
        q1_range=(float(q1[0]), float(q1[1])),
        q2_range=(float(q2[0]), float(q2[1])),
        impacts=impacts,
        transient=transient,
        seed=seed,
        seconds=time.perf_counter() - began,
    )


def write_results(result: UncertaintyResult, directory: Path) -> list[Path]:
    """``uncertainty.csv`` (per eps: eps_m, uncertain, samples, fraction, used_in_fit)
    and ``uncertainty.json`` (alpha, its standard error, d, the counts and settings)."""
    directory.mkdir(parents=True, exist_ok=True)
    table = directory / "uncertainty.csv"
    with open(table, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(("eps_m", "uncertain", "samples", "fraction", "used_in_fit"))
        for e, u, frac, used in zip(
            result.eps, result.uncertain, result.fraction, result.used, strict=True
        ):
            writer.writerow((repr(float(e)), int(u), result.samples, repr(float(frac)), int(used)))
    summary = directory / "uncertainty.json"

    def number(x: float) -> float | None:
        return None if not math.isfinite(x) else x

    summary.write_text(
        json.dumps(
            {
                "scene": result.scene.name,
                "alpha": number(result.alpha),
                "alpha_standard_error": number(result.alpha_se),
                "boundary_dimension": number(result.dimension),
                "samples": result.samples,
                "drawn": result.drawn,
                "dropped_for_invalid_neighbour": result.dropped,
                "q1_range_m": list(result.q1_range),
                "q2_range_m": list(result.q2_range),
                "impacts": result.impacts,
                "transient": result.transient,
                "seed": result.seed,
                "attractors": dict(zip(result.labels, result.counts, strict=True)),
                "seconds": round(result.seconds, 3),
            },
            indent=2,
        )
        + "\n"
    )
    return [table, summary]


def uncertainty_figure(result: UncertaintyResult, path: Path) -> Path:
    """log-log f(eps) with binomial error bars, the fitted line, alpha and d."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = result.fraction
    n = max(result.samples, 1)
    err = np.sqrt(f * (1.0 - f) / n)
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    shown = f > 0.0
    ax.errorbar(result.eps[shown], f[shown], yerr=err[shown], fmt="o", ms=4, capsize=2,
                color="tab:blue", label="uncertain fraction f")  # fmt: skip
    if math.isfinite(result.alpha):
        x = result.eps[result.used]
        logf = np.log(f[result.used])
        intercept = float(np.mean(logf - result.alpha * np.log(x)))
        line = np.geomspace(result.eps[0], result.eps[-1], 50)
        se = "" if not math.isfinite(result.alpha_se) else f" ± {result.alpha_se:.3f}"
        label = f"fit: alpha = {result.alpha:.3f}{se}, d = {result.dimension:.3f}"
        ax.plot(line, np.exp(intercept) * line**result.alpha, "-", color="tab:red", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    # fixed limits: f is 0 or at least 1/n, at most 1, so the frame holds every f > 0;
    # where no start is uncertain at any eps there is nothing to scale the axes by
    ax.set_xlim(result.eps[0] / 2.0, result.eps[-1] * 2.0)
    ax.set_ylim(0.5 / n, 1.5)
    if not shown.any():
        ax.text(0.5, 0.5, "no start is uncertain at these eps (f = 0)", ha="center",
                va="center", transform=ax.transAxes)  # fmt: skip
    ax.set_xlabel("displacement eps along q1 (m)")
    ax.set_ylabel("uncertain fraction f (1)")
    text = (
        f"{result.scene.name}: uncertainty exponent, {result.samples} starts in "
        f"q1 {result.q1_range[0]:g}:{result.q1_range[1]:g} m, "
        f"q2 {result.q2_range[0]:g}:{result.q2_range[1]:g} m, "
        f"{result.transient} + {result.impacts} impacts each"
    )
    ax.set_title("\n".join(textwrap.wrap(text, 70)), fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
