"""A continued branch of periodic orbits (``billiard orbits``, DIR/branch.png): the height
q2 just after the orbit's first impact against the continued key, solid where the orbit
is stable, dashed where not, its bifurcations marked, the period-2N branches switched
onto at period doublings in their own colours; optionally over a sweep's
brute-force bifurcation diagram (the last impact heights of each swept value)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from billiard.orbits.bifurcation import BIFURCATIONS
from billiard.plot.common import new_figure, save

__all__ = ["plot_branch"]

#: marker of each bifurcation (code >= 1)
_MARKERS = {
    "fold": "s",
    "period_doubling": "D",
    "neimark_sacker": "o",
    "grazing": "^",
    "branch_point": "v",
}
#: line colour of each branch (0 the continued one, then those switched onto)
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:purple")


def plot_branch(
    arrays: Mapping[str, np.ndarray],
    key: str,
    path: str | os.PathLike[str],
    label: str = "",
    over: tuple[np.ndarray, np.ndarray] | None = None,
    title: str = "",
) -> Path:
    """Draw the branch ``arrays`` (:meth:`billiard.orbits.continuation.Branch.arrays`)
    to ``path``. ``label``: the key's axis label; ``over``: (values of the key (n,),
    impact heights (n, k) in m) of a sweep, drawn as grey dots beneath."""
    x = np.asarray(arrays[key.replace(".", "_")], dtype=float)
    y = np.asarray(arrays["q2"], dtype=float) * 1e3
    stable = np.asarray(arrays["stable"]).astype(bool)
    codes = np.asarray(arrays["bifurcation"])
    fig = new_figure((7.0, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    if over is not None:
        xs, heights = over
        heights = np.asarray(heights, dtype=float)
        xs = np.repeat(np.asarray(xs, dtype=float), heights.shape[1])
        keep = np.isfinite(heights.ravel())
        ax.scatter(
            xs[keep],
            heights.ravel()[keep] * 1e3,
            s=1.5,
            color="0.6",
            linewidths=0,
            label="sweep: last impact heights",
        )
    # each branch its own colour (a period-2N branch switched onto at a period doubling
    # after the one continued), one line piece per run of equal stability, joined at the
    # shared point
    segments = np.asarray(arrays.get("branch", np.zeros(len(x), dtype=int)))
    periods = np.asarray(arrays.get("period", np.ones(len(x), dtype=int)))
    labelled = set()
    for k in np.unique(segments):
        rows = np.flatnonzero(segments == k)
        colour = _COLOURS[int(k) % len(_COLOURS)]
        named = f"period {int(periods[rows[0]])}" if len(np.unique(segments)) > 1 else ""
        start = 0
        for i in range(1, len(rows) + 1):
            if i == len(rows) or stable[rows[i]] != stable[rows[start]]:
                piece = rows[start : min(i + 1, len(rows))]
                kind = " ".join(
                    filter(None, ["stable" if stable[rows[start]] else "unstable", named])
                )
                ax.plot(
                    x[piece],
                    y[piece],
                    linestyle="-" if stable[rows[start]] else "--",
                    color=colour,
                    label=None if kind in labelled else f"{kind} orbit",
                )
                labelled.add(kind)
                start = i
    for code, name in enumerate(BIFURCATIONS):
        mask = codes == code
        if code == 0 or not mask.any():
            continue
        ax.plot(
            x[mask],
            y[mask],
            linestyle="none",
            marker=_MARKERS[name],
            color="tab:red",
            label=name.replace("_", " "),
        )
    ax.set_xlabel(label or key)
    ax.set_ylabel("height q2 after the first impact (mm)")
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize="small")
    return save(fig, path)
