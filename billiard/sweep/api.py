"""The sweep as one Python call, for scripts and notebooks::

    import billiard

    out = billiard.sweep("parabola-5.4hz", vary={"drive.frequency": (4.5, 6.5, 21)}, impacts=200)
    out.dataset.attractor          # class names per point ("period-1", "chaotic", ...)

It builds the :class:`~billiard.sweep.definition.Sweep` that ``billiard sweep`` builds from
its options and runs it with :func:`~billiard.sweep.execute.run_sweep`: the same folder,
files and results as the command line.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np

from billiard.sweep.definition import (
    DEFAULTS,
    Axis,
    LinearValues,
    Sweep,
    SweepError,
    check_keys,
    parse_values,
)
from billiard.sweep.execute import SweepOutcome, run_sweep

__all__ = ["sweep", "axis_of"]


def axis_of(key: str, spec: Any) -> Axis:
    """One axis from the Python form of a ``vary`` entry: a tuple ``(first, last, count)``
    (``count`` evenly spaced values from ``first`` to ``last``, as ``START:STOP:N`` on
    the command line), a list or numpy array of values, or the command line's text
    (``"4:7:31"``, ``"4.5,5,5.5"``).

    Raises:
        SweepError: a malformed entry, in one line naming the key.
    """
    if not isinstance(key, str) or not key:
        raise SweepError(
            f"vary: a key must be a dotted scene key such as 'drive.frequency', got {key!r}"
        )
    if isinstance(spec, tuple) and len(spec) == 3 and isinstance(spec[2], Integral):
        first, last, count = spec
        for name, value in (("first", first), ("last", last)):
            if not isinstance(value, Real) or isinstance(value, bool) or not math.isfinite(value):
                raise SweepError(f"vary {key!r}: {name} value {value!r} is not a finite number")
        if not 1 <= int(count) <= 10**7:
            raise SweepError(f"vary {key!r}: count {count!r} is out of range [1, 10^7]")
        if int(count) == 1:
            return Axis(key, (float(first),))
        return Axis(key, LinearValues(float(first), float(last), int(count)))
    if isinstance(spec, np.ndarray):
        if spec.ndim != 1:
            raise SweepError(f"vary {key!r}: an array of values must be one-dimensional")
        spec = [v.item() for v in spec]
    if isinstance(spec, (list, tuple, str)):
        return Axis(key, parse_values(key, list(spec) if isinstance(spec, tuple) else spec))
    raise SweepError(
        f"vary {key!r}: expected (first, last, count), a list or array of values, or "
        f"'START:STOP:N', got {spec!r}"
    )


def sweep(
    scene: Any,
    vary: Mapping[str, Any],
    *,
    impacts: int = DEFAULTS["impacts"],
    transient: int = DEFAULTS["transient"],
    workers: int | None = None,
    out: str | os.PathLike[str] | None = None,
    plots: bool = False,
    yes: bool = False,
    device: str = "cpu",
    **settings: Any,
) -> SweepOutcome:
    """Run ``scene`` (a :class:`~billiard.Scene`, a built-in scene's name or a scene
    file's path) over the grid of ``vary`` and return the :class:`SweepOutcome`;
    ``outcome.dataset`` is the result as an ``xarray.Dataset`` (``[data]`` extra).

    Args:
        vary: scene key -> values, outermost axis first: ``(first, last, count)``, a list
            or array of values, or ``"START:STOP:N"``. ``initial.*`` keys give a basin
            map, drive, contact, ball and air keys a parameter map.
        impacts: impacts measured per point, after ``transient`` unmeasured ones.
        workers: local worker processes (default: all cores).
        out: the sweep folder (default ``runs/sweep-SCENE``); everything is written
            inside it and a finished folder is refused, as by ``billiard sweep``.
        plots: also draw the sweep's plots into the folder.
        yes: run a sweep beyond the size that needs confirmation (``--yes``).
        device: ``"cpu"`` or ``"gpu"``.
        settings: the other sweep settings (``keep``, ``duration`` in s, ``tolerance``
            in m, ``rest_band`` in m, ``max_period``, ``lyapunov``, ``skip_invalid``;
            docs/sweeps.md).

    Raises:
        SweepError: bad ``vary`` or settings, in one line.
        SceneError: an unknown scene or key.
    """
    from billiard.sweep.ensemble import as_scene

    if not isinstance(vary, Mapping) or not vary:
        raise SweepError(
            "vary: give a dict of scene key -> values, e.g. {'drive.frequency': (4.5, 6.5, 21)}"
        )
    unknown = sorted(set(settings) - set(DEFAULTS))
    if unknown:
        raise SweepError(
            f"sweep: unknown setting {unknown[0]!r}; the settings are {', '.join(DEFAULTS)}"
        )
    base = as_scene(scene)
    axes = tuple(axis_of(key, spec) for key, spec in vary.items())
    check_keys(base, axes)
    definition = Sweep(base, axes, impacts=impacts, transient=transient, **settings)
    directory = Path(out) if out is not None else Path("runs") / f"sweep-{base.name}"
    return run_sweep(definition, directory, workers=workers, plots=plots, yes=yes, device=device)
