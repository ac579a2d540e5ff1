"""A driven gravitational billiard with a finite, spinning ball and frictional impacts.

Equations come from a Kane's-method derivation (``billiard.derivation``) and run as
generated code (``billiard.generated``). The Python API::

    from billiard import load_scene, simulate, with_values

    scene = with_values(load_scene("parabola-5.4hz"), {"contact.restitution": 0.5})
    result = simulate(scene, collisions=2000)
    heights = result.columns["q2"]   # numpy array, m

The scene, simulation and calibration API is imported eagerly: ``billiard.simulate`` and
``billiard.calibrate`` are functions named like the modules that define them, and binding
them here, after those modules are imported, keeps them the functions however often the
modules are imported later. Plotting, curves and run files are imported on first use
(none of their names is a module's).
"""

from __future__ import annotations

import gc
import importlib
from typing import Any

# The imports below (numpy, numba and its compiler, the engine) create some 90,000
# objects that live as long as the process (modules, classes, functions, numba's types):
# the cyclic garbage collector, run over them again and again while they are created,
# would find next to nothing to free (a tenth of the import). It is paused while they are
# imported, and they are then handed to its oldest generation without a pass over them
# (gc.freeze then gc.unfreeze: nothing is exempted from collection, and a program that
# froze objects of its own keeps them frozen, untouched). The command line also freezes
# them for good: billiard.cli.main.
_collecting = gc.isenabled()
gc.disable()
try:
    # numba before billiard's own modules: imported after them, numba's set-up of its
    # casting rules (numba.core.typeconv.rules) took 0.11-0.17 s instead of 0.01 s
    # (measured with python -X importtime; the same code, in another order)
    from . import jit  # noqa: F401
    from .calibrate import calibrate
    from .engine import Simulation
    from .scene import (
        Scene,
        SceneError,
        builtin_scenes,
        load_scene,
        scene_from_dict,
        scene_to_toml,
        with_values,
    )
    from .simulate import Result, simulate
    from .status import Status
finally:
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()
    if _collecting:
        gc.enable()

__version__ = "0.1.0"

_EXPORTS = {
    "load_curve": "billiard.curves",
    "read_collisions": "billiard.record",
    "camera_filter": "billiard.camera",
    "plot_run": "billiard.plot",
}

__all__ = [
    "Result",
    "Simulation",
    "Status",
    "Scene",
    "SceneError",
    "builtin_scenes",
    "calibrate",
    "camera_filter",
    "load_curve",
    "load_scene",
    "plot_run",
    "read_collisions",
    "scene_from_dict",
    "scene_to_toml",
    "simulate",
    "with_values",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'billiard' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
