"""A driven gravitational billiard with a finite, spinning ball and frictional impacts.

Equations come from a Kane's-method derivation (``billiard.derivation``) and run as
generated code (``billiard.generated``). The Python API::

    from billiard import load_scene, open_run, simulate, view, with_values

    scene = with_values(load_scene("parabola-5.4hz"), {"contact.restitution": 0.5})
    result = simulate(scene, collisions=2000)   # or simulate("parabola-5.4hz", ...)
    heights = result.columns["q2"]   # numpy array, m
    df = result.to_pandas()          # DataFrame, units in df.attrs["units"] ([data] extra)
    again = open_run("runs/parabola-5.4hz")   # a run folder as the same Result
    view(result)                     # in a notebook: the run's interactive view, inline

This module is the public API only: it binds the names above from the wings that define
them (docs/design.md, "Layout"). The scene, simulation and calibration API is imported
eagerly; plotting, curves and run files on first use.
"""

from __future__ import annotations

import gc
import importlib
import importlib.util
import os
import sys
from importlib.machinery import ModuleSpec
from typing import Any

#: The subpackages pyproject.toml maps from folders beside billiard/ (package-dir): an
#: installed copy holds them inside billiard/, a source checkout beside it.
_MAPPED = {"billiard.derivation": "derivation", "billiard.generated": "generated"}


def _checkout_folders(package: str) -> dict[str, str]:
    """Where the mapped subpackages are when ``package`` (this package's folder) is the
    ``billiard/`` folder of a source checkout rather than an installed copy: the folders
    beside it, if that is this project's checkout (pyproject.toml and both folders, each
    with its ``__init__.py``); else an empty dict (an installed copy finds them itself)."""
    if os.path.isfile(os.path.join(package, "derivation", "__init__.py")):
        return {}
    root = os.path.dirname(package)
    folders = {name: os.path.join(root, folder) for name, folder in _MAPPED.items()}
    inits = [os.path.join(folder, "__init__.py") for folder in folders.values()]
    if os.path.isfile(os.path.join(root, "pyproject.toml")) and all(map(os.path.isfile, inits)):
        return folders
    return {}


class _CheckoutFinder:
    """Finds ``billiard.derivation`` and ``billiard.generated`` in a source checkout.

    Python started in a checkout's root imports the checkout's ``billiard/`` folder (the
    current directory comes first on ``sys.path``), even where the package is installed
    (``pip install .``); the installed copy holds the two subpackages, the checkout holds
    them beside ``billiard/``. It answers for these two names alone, so nothing else of
    the checkout's root becomes part of the package, and is asked first: the
    subpackages come from beside the ``billiard/`` folder imported, even where an
    editable install of another checkout maps them to that checkout's folders.
    """

    folders: dict[str, str] = {}

    @classmethod
    def find_spec(cls, fullname: str, path: Any = None, target: Any = None) -> ModuleSpec | None:
        folder = cls.folders.get(fullname)
        if folder is None:
            return None
        return importlib.util.spec_from_file_location(
            fullname, os.path.join(folder, "__init__.py"), submodule_search_locations=[folder]
        )


def _find_checkout_subpackages() -> None:
    """Put :class:`_CheckoutFinder` first in ``sys.meta_path`` when this package is
    imported from a source checkout (once: a reload replaces the finder a former import
    added)."""
    folders = _checkout_folders(os.path.dirname(os.path.abspath(__file__)))
    sys.meta_path[:] = [
        f
        for f in sys.meta_path
        if (getattr(f, "__module__", None), getattr(f, "__qualname__", None))
        != (__name__, "_CheckoutFinder")
    ]
    if folders:
        _CheckoutFinder.folders = folders
        sys.meta_path.insert(0, _CheckoutFinder)  # type: ignore[arg-type]


_find_checkout_subpackages()

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
    # type-conversion rules took 0.11-0.17 s instead of 0.01 s
    # (measured with python -X importtime; the same code, in another order)
    from billiard import jit  # noqa: F401
    from billiard.analysis.calibrate import calibrate
    from billiard.engine.simulation import Simulation
    from billiard.run.simulate import Result, simulate
    from billiard.scene.scene import (
        Scene,
        SceneError,
        builtin_scenes,
        load_scene,
        scene_from_dict,
        scene_to_toml,
        with_values,
    )
    from billiard.status import Status
finally:
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()
    if _collecting:
        gc.enable()

__version__ = "0.1.0"

_EXPORTS = {
    "load_curve": "billiard.geometry.curves",
    "read_collisions": "billiard.runfile.tables",
    "open_run": "billiard.run.load",
    "read_contacts": "billiard.runfile.tables",
    "read_trajectory": "billiard.runfile.tables",
    "camera_filter": "billiard.analysis.camera",
    "plot_run": "billiard.plot",
    "view": "billiard.plot.interactive",
    "run_ensemble": "billiard.sweep.ensemble",
    "run_hysteresis": "billiard.sweep.hysteresis",
    "run_uncertainty": "billiard.sweep.uncertainty",
    "find_orbit": "billiard.orbits.newton",
    "continue_orbit": "billiard.orbits.continuation",
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
    "continue_orbit",
    "find_orbit",
    "load_curve",
    "load_scene",
    "open_run",
    "plot_run",
    "read_collisions",
    "read_contacts",
    "read_trajectory",
    "run_ensemble",
    "run_hysteresis",
    "run_uncertainty",
    "scene_from_dict",
    "scene_to_toml",
    "simulate",
    "sweep",
    "view",
    "with_values",
]


def __getattr__(name: str) -> Any:
    if name == "sweep":  # the sweep package, which is also the call billiard.sweep(...)
        return importlib.import_module("billiard.sweep")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'billiard' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
