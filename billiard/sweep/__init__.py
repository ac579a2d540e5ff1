"""Parameter sweeps: many scenes, one varied key or more, measured in parallel.

The package is also the sweep's one-call function, ``billiard.sweep(scene, vary=...)``
(:func:`billiard.sweep.api.sweep`)::

    import billiard

    outcome = billiard.sweep("parabola-5.4hz", vary={"drive.frequency": (4, 7, 31)})

The steps it takes, one by one:

>>> from billiard import load_scene
>>> from billiard.sweep import Sweep, parse_vary, run_sweep
>>> sweep = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=4:7:31"),),
...               impacts=2000, transient=500)
>>> outcome = run_sweep(sweep, "runs/my-sweep")  # doctest: +SKIP
>>> outcome.result  # doctest: +SKIP
PosixPath('runs/my-sweep/sweep.nc')

One concept per module: :mod:`~billiard.sweep.definition` (axes, settings, sweep
files), :mod:`~billiard.sweep.attractor` (period and class of one trajectory),
:mod:`~billiard.sweep.measure` (one point, in a worker), :mod:`~billiard.sweep.store`
(the folder and its durable points file), :mod:`~billiard.sweep.execute` (executors,
resume, interruption), :mod:`~billiard.sweep.netcdf` (the result file),
:mod:`~billiard.sweep.basins`, :mod:`~billiard.sweep.categories`,
:mod:`~billiard.sweep.container` and :mod:`~billiard.sweep.plots` (figures). See
docs/sweeps.md; ``run_sweep(...).dataset`` is the result as an ``xarray.Dataset``.
"""

import sys
import types
from typing import Any

from billiard.sweep.api import axis_of, sweep
from billiard.sweep.definition import Axis, Sweep, SweepError, parse_vary, read_sweep_file
from billiard.sweep.execute import (
    StopSweep,
    SweepInterrupted,
    SweepOutcome,
    load_sweep_dir,
    run_sweep,
)
from billiard.sweep.netcdf import RESULT_NAME, read_result

__all__ = [
    "RESULT_NAME",
    "Axis",
    "StopSweep",
    "Sweep",
    "SweepError",
    "SweepInterrupted",
    "SweepOutcome",
    "axis_of",
    "load_sweep_dir",
    "parse_vary",
    "read_result",
    "read_sweep_file",
    "run_sweep",
    "sweep",
]


class _SweepPackage(types.ModuleType):
    """This package, callable: ``billiard.sweep(...)`` is :func:`billiard.sweep.api.sweep`.

    Importing any ``billiard.sweep.*`` module binds the name ``billiard.sweep`` to this
    package, so the one-call function cannot be a separate attribute of ``billiard``; a
    module's ``__class__`` may be set to a subclass of ``ModuleType`` (the language
    reference, "Customizing module attribute access") to give it a ``__call__``.
    """

    def __call__(self, *args: Any, **kwargs: Any) -> SweepOutcome:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _SweepPackage
