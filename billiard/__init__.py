"""A driven gravitational billiard with a finite, spinning ball and frictional impacts.

Equations come from a Kane's-method derivation (``billiard.derivation``) and run as
generated code (``billiard.generated``). The Python API::

    from billiard import load_scene, simulate, with_values

    scene = with_values(load_scene("parabola-5.4hz"), {"contact.restitution": 0.5})
    result = simulate(scene, collisions=2000)
    heights = result.columns["q2"]   # numpy array, m

The scene and simulation API is imported eagerly (``billiard.simulate`` the function must
shadow the module of the same name); plotting and calibration on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

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

__version__ = "0.1.0"

_EXPORTS = {
    "load_curve": "billiard.curves",
    "read_collisions": "billiard.record",
    "camera_filter": "billiard.camera",
    "calibrate": "billiard.calibrate",
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
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
