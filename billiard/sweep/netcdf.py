"""The sweep's result file, ``DIR/sweep.nc``: netCDF-3, self-describing, one line to open::

    import xarray as xr;  ds = xr.open_dataset("runs/sweep-parabola-5.4hz/sweep.nc")
    # or, without xarray:  scipy.io.netcdf_file(path, mmap=False).variables

Every swept key is a dimension with a coordinate variable of the same name, dots made
underscores (``drive.frequency`` -> ``drive_frequency``; the attribute ``scene_key``
keeps the dotted key), with ``units`` and ``long_name``. Every measured quantity is a
variable over those dimensions (plus ``impact`` for the last K impacts), with ``units``
and ``long_name``; NaN means "not measured" (a failed point, or the exponent not
asked for). The global attributes hold the sweep file and the base scene as text.

The file is built from the points sorted by index and holds no timings, so its bytes do
not depend on the number of workers or the order in which they finished.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.io import netcdf_file

from billiard.sweep.attractor import CLASSES
from billiard.sweep.definition import Sweep, sweep_to_toml
from billiard.sweep.units import key_unit, variable_name

__all__ = ["RESULT_NAME", "write_result"]

RESULT_NAME = "sweep.nc"

# name -> (record field, dtype, units, long_name)
_SCALARS: tuple[tuple[str, str, str, str], ...] = (
    (
        "period",
        "i4",
        "1",
        "impacts per repetition of the post-impact state and drive phase "
        "(0: no period up to max_period)",
    ),
    ("drive_periods", "i4", "1", "drive periods per repetition of the state (0: no period)"),
    ("impacts", "i4", "1", "impacts measured (after the transient)"),
    ("total_impacts", "i4", "1", "impacts simulated, transient included"),
    ("rest_height", "f8", "m", "centre height of the ball at rest at the bottom"),
    ("height_mean", "f8", "m", "mean impact height q2 after the transient"),
    ("height_std", "f8", "m", "standard deviation of the impact height q2"),
    ("height_max", "f8", "m", "highest impact height q2 after the transient"),
    ("tof_mean", "f8", "s", "mean time of flight between impacts"),
    ("tof_std", "f8", "s", "standard deviation of the time of flight"),
    ("elastic_share", "f8", "1", "share of impacts under the low-velocity rule (e = 1)"),
    ("lid_share", "f8", "1", "share of impacts on the lid"),
    ("lyapunov", "f8", "1", "largest Lyapunov exponent per impact (NaN: not computed)"),
    ("lyapunov_per_second", "f8", "1/s", "largest Lyapunov exponent per second"),
)


class _Strings:
    """Fixed-width UTF-8 strings, one per point, widened as longer ones arrive (bytes
    the size of the result, not Python objects per point)."""

    def __init__(self, size: int):
        self.data = np.zeros(size, dtype="S1")

    def __setitem__(self, index: int, text: str) -> None:
        encoded = text.encode("utf-8")
        if len(encoded) > self.data.dtype.itemsize:
            self.data = self.data.astype(f"S{len(encoded)}")
        self.data[index] = encoded

    def chars(self, shape: tuple[int, ...]) -> tuple[np.ndarray, int]:
        width = max(1, self.data.dtype.itemsize)
        out = self.data.astype(f"S{width}").view("S1").reshape(*shape, width)
        return out, width


def _chars(strings: Sequence[str], shape: tuple[int, ...]) -> tuple[np.ndarray, int]:
    column = _Strings(len(strings))
    for i, text in enumerate(strings):
        column[i] = text
    return column.chars(shape)


#: Text variables: name -> long_name (the attractor's lists the classes).
_TEXT = (
    ("status", "ok, failed (the run stopped early: see reason) or invalid (skipped)"),
    ("reason", "why a point failed or was skipped (empty when ok)"),
    ("attractor", "attractor class: " + ", ".join(CLASSES)),
    (
        "run_status",
        "how the point's run ended (billiard.Status, lower case: complete, time_limit, "
        "at_rest, in_contact, or a stop)",
    ),
    ("final_mode", "the ball's motion when the run ended: flight, roll, slide or held"),
)


def write_result(
    path: Path, sweep: Sweep, records: Iterable[dict[str, Any]], scene_toml: str
) -> Path:
    """Write the result file from every point's record (any order: placed by index; read
    one at a time, so ``records`` may be a generator over points.jsonl)."""
    size, keep = sweep.size, sweep.keep
    seen = np.zeros(size, dtype=bool)
    text = {name: _Strings(size) for name, _ in _TEXT}
    scalars = {
        name: np.zeros(size, dtype=np.int32) if dtype == "i4" else np.full(size, np.nan)
        for name, dtype, _, _ in _SCALARS
    }
    tails = {name: np.full((size, keep), np.nan) for name in ("last_height", "last_tof")}
    for r in records:
        i = int(r["index"])
        seen[i] = True
        for name, _ in _TEXT:
            text[name][i] = str(r.get(name, ""))
        for name, dtype, _, _ in _SCALARS:
            if dtype == "i4":
                scalars[name][i] = int(r[name] or 0)
            else:
                scalars[name][i] = np.nan if r[name] is None else float(r[name])
        for name, data in tails.items():
            tail = r[name][-keep:]
            data[i, :] = np.nan
            if tail:
                data[i, keep - len(tail) :] = tail
    if not seen.all():
        raise ValueError(f"the result needs every point; {int(size - seen.sum())} missing")
    shape = sweep.shape
    dims = tuple(variable_name(axis.key) for axis in sweep.axes)
    tmp = path.with_name(path.name + ".tmp")
    f = netcdf_file(tmp, "w", version=2)
    try:
        f.title = "billiard sweep"
        f.source = "realworld-billiard, billiard sweep"
        f.conventions = "netCDF-3 (64-bit offset); SI units; NaN = not measured"
        f.attractor_classes = " ".join(CLASSES)
        f.sweep_definition = sweep_to_toml(sweep)
        f.base_scene = scene_toml
        f.points = size
        for axis, dim in zip(sweep.axes, dims, strict=True):
            f.createDimension(dim, len(axis.values))
            if axis.numeric:
                var = f.createVariable(dim, "f8", (dim,))
                var[:] = np.asarray(axis.values, dtype=float)
            else:
                chars, width = _chars([str(v) for v in axis.values], (len(axis.values),))
                f.createDimension(f"{dim}_strlen", width)
                var = f.createVariable(dim, "c", (dim, f"{dim}_strlen"))
                var[:] = chars
                var._Encoding = "utf-8"
            var.units = key_unit(axis.key)
            var.long_name = f"scene key {axis.key}"
            var.scene_key = axis.key
        f.createDimension("impact", keep)
        var = f.createVariable("impact", "i4", ("impact",))
        var[:] = np.arange(-keep, 0, dtype=np.int32)
        var.units = "1"
        var.long_name = "impact counted back from the last one (-1: the last)"

        var = f.createVariable("point", "i4", dims)
        var[:] = np.arange(size, dtype=np.int32).reshape(shape)
        var.units = "1"
        var.long_name = "point index (C order of the swept keys; as in points.jsonl)"
        for name, long_name in _TEXT:
            chars, width = text.pop(name).chars(shape)
            f.createDimension(f"{name}_strlen", width)
            var = f.createVariable(name, "c", (*dims, f"{name}_strlen"))
            var[:] = chars
            var._Encoding = "utf-8"
            var.long_name = long_name
        for name, dtype, units, long_name in _SCALARS:
            var = f.createVariable(name, dtype, dims)
            var[:] = scalars.pop(name).reshape(shape)
            var.units = units
            var.long_name = long_name
        for name, units, long_name in (
            ("last_height", "m", "last impact heights q2 (NaN-padded at the front)"),
            ("last_tof", "s", "last times of flight (NaN-padded at the front)"),
        ):
            var = f.createVariable(name, "f8", (*dims, "impact"))
            var[:] = tails.pop(name).reshape(*shape, keep)
            var.units = units
            var.long_name = long_name
    finally:
        f.close()
    os.replace(tmp, path)
    return path


def read_result(path: Path) -> dict[str, Any]:
    """The result file as a dict of numpy arrays (strings decoded) and its attributes."""
    with netcdf_file(path, "r", mmap=False) as f:
        out: dict[str, Any] = {}
        for name, var in f.variables.items():
            data = np.array(var.data)
            if data.dtype.kind == "S" and data.dtype.itemsize == 1 and data.ndim >= 1:
                rows = data.reshape(-1, data.shape[-1])
                text = [b"".join(row).rstrip(b"\0").decode() for row in rows]
                data = np.array(text, dtype=object).reshape(data.shape[:-1])
            out[name] = data
        out["_attributes"] = {
            k: (v.decode() if isinstance(v, bytes) else v) for k, v in f._attributes.items()
        }
    return out
