"""The kernels' source files loaded again under another package name: a twin of
:mod:`billiard.kernels`, whose decorators (:mod:`.decorators`) follow from the package
they are loaded in. :func:`load_package` makes the package (its ``__init__``, with
attributes set before any of its modules runs), :func:`load_module` one of its modules
by name: any module of ``billiard/kernels``, its sibling modules loaded with it (they
import each other relatively, so a twin is self-contained).

Twins: the interpreted one, ``billiard.kernels_py`` (:mod:`.interpreted`), and the
device twins of :mod:`billiard.engine.gpu`, one per curve, each carrying the curve's
device wall functions.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["KERNELS", "load_module", "load_package"]

#: the folder of the kernels' source files
KERNELS = Path(__file__).resolve().parent


def load_package(name: str, attributes: Mapping[str, Any] | None = None) -> ModuleType:
    """The package ``name`` over the kernels' folder (``billiard/kernels/__init__.py``,
    its modules found in the same folder), made once per process: later calls return
    it as it is. ``attributes`` are set on the package before any of its modules loads
    (a device twin's ``DEVICE``, read by :mod:`.decorators`)."""
    module = sys.modules.get(name)
    if module is not None:
        return module
    spec = importlib.util.spec_from_file_location(
        name, KERNELS / "__init__.py", submodule_search_locations=[str(KERNELS)]
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    for key, value in (attributes or {}).items():
        setattr(module, key, value)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def load_module(package: str, name: str) -> ModuleType:
    """The module ``name`` (e.g. ``"loop"``) of the twin ``package``, loaded by
    :func:`load_package` first."""
    load_package(package)
    return importlib.import_module(f"{package}.{name}")
