"""A continued branch as CF netCDF (``DIR/branch.nc``), written as the sweeps write
theirs (:mod:`billiard.sweep.netcdf`: scipy's netCDF 3 writer, no extra dependency).

Dimensions ``point`` (along the branch) and ``multiplier``; the varied key as a variable
named with underscores (``drive_amplitude``); the orbit's state just after its first
impact (``t_phase``, ``s``, ``q1``, ``q2``, ``v1``, ``v2``, ``omega``); the Floquet
multipliers as ``multipliers_real`` and ``multipliers_imag``; ``stable`` 0/1; and
``bifurcation``, an int8 code with ``flag_values`` and ``flag_meanings``; ``period``
(impacts, or lift-offs through contact phases), ``drive_periods`` and ``branch`` (0 the
continued branch, k the k-th switched onto at a period doubling) as int32.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from billiard.orbits.bifurcation import BIFURCATIONS

__all__ = ["attributes", "write_branch"]

#: (units, long_name) of the state's variables
_STATE = {
    "t_phase": ("s", "time of the first impact modulo the drive period"),
    "s": ("m", "contact abscissa of the first impact in the boundary's frame"),
    "q1": ("m", "centre's horizontal position just after the first impact"),
    "q2": ("m", "centre's height just after the first impact"),
    "v1": ("m/s", "centre's horizontal velocity just after the first impact"),
    "v2": ("m/s", "centre's vertical velocity just after the first impact"),
    "omega": ("rad/s", "spin just after the first impact"),
}


def attributes(key: str, units: str = "", long_name: str = "") -> dict[str, dict[str, Any]]:
    """CF attributes of every variable of a branch in scene key ``key`` (its ``units``
    and ``long_name`` as the caller knows them: the sweeps' table of keys lies above
    this wing)."""
    name = key.replace(".", "_")
    out: dict[str, dict[str, Any]] = {
        name: {"long_name": long_name or f"scene key {key}", "scene_key": key}
    }
    if units:
        out[name]["units"] = units
    for var, (u, long_name) in _STATE.items():
        out[var] = {"units": u, "long_name": long_name}
    out["multipliers_real"] = {"long_name": "real part of the Floquet multipliers", "units": "1"}
    out["multipliers_imag"] = {
        "long_name": "imaginary part of the Floquet multipliers",
        "units": "1",
    }
    out["stable"] = {
        "long_name": "linearly stable (every multiplier inside the unit circle)",
        "flag_values": np.array([0, 1], dtype=np.int8),
        "flag_meanings": "unstable stable",
    }
    out["period"] = {
        "long_name": "impacts per period of the orbit (lift-offs through contact phases)",
        "units": "1",
    }
    out["drive_periods"] = {"long_name": "drive periods per period of the orbit", "units": "1"}
    out["branch"] = {
        "long_name": "branch of the point: 0 the one continued, k >= 1 the k-th period-2N "
        "branch switched onto at a period doubling",
        "units": "1",
    }
    out["bifurcation"] = {
        "long_name": "bifurcation located at this point",
        "flag_values": np.arange(len(BIFURCATIONS), dtype=np.int8),
        "flag_meanings": " ".join(BIFURCATIONS),
    }
    return out


def write_branch(
    path: str | os.PathLike[str],
    arrays: dict[str, np.ndarray],
    key: str,
    title: str,
    units: str = "",
    long_name: str = "",
) -> Path:
    """Write a branch's arrays (:meth:`billiard.orbits.continuation.Branch.arrays`) to
    ``path`` as CF netCDF 3, through a temporary file renamed into place."""
    from scipy.io import netcdf_file

    path = Path(path)
    attrs = attributes(key, units, long_name)
    points = len(arrays["bifurcation"])
    width = arrays["multipliers_real"].shape[1] if arrays["multipliers_real"].ndim == 2 else 0
    tmp = path.with_name(path.name + ".tmp")
    f = netcdf_file(tmp, "w", version=2)
    try:
        f.Conventions = "CF-1.8"
        f.title = title
        f.comment = "SI units; one point per row of the branch, in the order continued"
        f.createDimension("point", points)
        f.createDimension("multiplier", width)
        for name, values in arrays.items():
            dims = ("point", "multiplier") if values.ndim == 2 else ("point",)
            kind = {np.dtype(np.int8): "b", np.dtype(np.int32): "i"}.get(values.dtype, "f8")
            var = f.createVariable(name, kind, dims)
            var[:] = values
            for attr, value in attrs.get(name, {}).items():
                setattr(var, attr, value)
    finally:
        f.close()
    os.replace(tmp, path)
    return path
