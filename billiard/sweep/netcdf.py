"""The sweep's result file, ``DIR/sweep.nc``: netCDF-3 following the CF conventions
(CF-1.8), self-describing, one line to open::

    import xarray as xr;  ds = xr.open_dataset("runs/sweep-parabola-5.4hz/sweep.nc")
    ds.height_mean.sel(drive_frequency=5.4)       # the value asked for selects its point
    # or, without xarray:  scipy.io.netcdf_file(path, mmap=False).variables

Every swept key is a dimension with a coordinate variable of the same name, dots made
underscores (``drive.frequency`` -> ``drive_frequency``; the attribute ``scene_key``
keeps the dotted key), with ``units`` and ``long_name``. Its values are the values the
points ran with, the grid's decimals (``0.02:0.03:11`` holds 0.027, the float of the
text "0.027"), so ``sel`` with the value asked for finds the point.

Every measured quantity is a variable over those dimensions (plus ``impact`` for the last
K impacts), with ``units`` and ``long_name``. What was not measured is missing, declared
by ``_FillValue`` (readers such as xarray mask it): NaN for real numbers (a failed point,
the exponent not asked for), :data:`INT_FILL` for ``period`` and ``drive_periods`` where
no period was found. ``attractor`` is a coded integer, its classes named by the CF
attributes ``flag_values`` and ``flag_meanings`` (the codes of
:data:`billiard.sweep.attractor.CLASSES`, in that order). Text variables (``status``,
``reason``, ``run_status``, ``final_mode``) and the class codes are not quantities and
carry no ``units``.

The global attributes: ``Conventions``, ``title``, ``source`` (the package and its
version), ``history`` (the command that makes the file again), ``comment``, and the sweep
file and the base scene as text (``sweep_definition``, ``base_scene``). The file is built
from the points sorted by index and holds no wall-clock time (the start and end times are
in ``sweep.log`` beside it), so its bytes depend only on the sweep and the package
version: not on the number of workers, the order in which they finished, interruptions
or the folder.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.io import netcdf_file

from billiard.sweep.attractor import CLASSES
from billiard.sweep.columns import CODES, share
from billiard.sweep.definition import Sweep, sweep_to_toml
from billiard.sweep.units import key_long_name, key_unit, variable_name

__all__ = [
    "CONVENTIONS",
    "INT_FILL",
    "RESULT_NAME",
    "open_result",
    "read_result",
    "write_result",
]

RESULT_NAME = "sweep.nc"
DISTRIBUTION = "realworld-billiard"
CONVENTIONS = "CF-1.8"
#: ``_FillValue`` of the integer variables (netCDF's own default fill for a 32-bit int).
INT_FILL = -2147483647
#: Integer variables whose 0 in a point's record means "none": stored as INT_FILL.
_NONE_IS_ZERO = ("period", "drive_periods")
#: The global attributes, in the order written (read back by name: public API only).
GLOBAL_ATTRIBUTES = (
    "Conventions",
    "title",
    "source",
    "history",
    "comment",
    "sweep_definition",
    "base_scene",
    "points",
)

# name -> (record field, dtype, units, long_name)
_SCALARS: tuple[tuple[str, str, str, str], ...] = (
    (
        "period",
        "i4",
        "1",
        "impacts per repetition of the post-impact state and drive phase "
        "(missing: no period up to max_period)",
    ),
    (
        "drive_periods",
        "i4",
        "1",
        "drive periods per repetition of the state (missing: no period)",
    ),
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


#: Text variables: name -> long_name.
_TEXT = (
    ("status", "ok, failed (the run stopped early: see reason) or invalid (skipped)"),
    ("reason", "why a point failed or was skipped (empty when ok)"),
    (
        "run_status",
        "how the point's run ended (billiard.Status, lower case: complete, time_limit, "
        "at_rest, in_contact, or a stop)",
    ),
    ("final_mode", "the ball's motion when the run ended: flight, roll, slide or held"),
)


def history_line() -> str:
    """The ``history`` attribute: the command that makes the file again from its folder,
    and the package that made it (no time: the file's bytes depend only on the sweep)."""
    return (
        f"billiard sweep sweep.toml (the sweep folder's definition; {_source()}); "
        "wall-clock times are in sweep.log"
    )


def _source() -> str:
    """The distribution and its version (that of the package imported, in a checkout run
    without installing: its parent package is loaded before this module)."""
    import importlib.metadata

    try:
        version = importlib.metadata.version(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        version = getattr(sys.modules.get("billiard"), "__version__", "unknown")
    return f"{DISTRIBUTION} {version}"


def _title(sweep: Sweep) -> str:
    keys = ", ".join(axis.key for axis in sweep.axes)
    return f"billiard sweep of {sweep.scene.name} over {keys}"


def _widths(blocks: Callable[[], Iterable[np.ndarray]], size: int) -> dict[str, int]:
    """Check that the rows hold every point, and the width of each coded text variable:
    its longest text present (at least 1)."""
    seen = np.zeros(size, dtype=bool)
    present: dict[str, set[int]] = {name: set() for name, _ in _TEXT if name in CODES}
    for rows in blocks():
        seen[rows["index"]] = True
        for name, codes in present.items():
            codes.update(np.unique(rows[name]).tolist())
    if not seen.all():
        raise ValueError(f"the result needs every point; {int(size - seen.sum())} missing")
    return {
        name: max([1, *(len(CODES[name][c].encode("utf-8")) for c in codes)])
        for name, codes in present.items()
    }


def write_result(
    path: Path,
    sweep: Sweep,
    blocks: Callable[[], Iterable[np.ndarray]],
    reasons: Callable[[], Iterable[tuple[int, str]]],
    scene_toml: str,
) -> Path:
    """Write the result file from the stored rows of every point and the reasons of the
    points not ok.

    Args:
        blocks: gives the ``points.npy`` rows of every point, a block at a time, in any
            order (each placed by its index); called twice.
        reasons: gives (index, reason) pairs; called twice (a later pair of a point
            replaces an earlier one).

    Memory: the result's own arrays (scipy holds them until the file is closed), filled
    in place; the rows are read a block at a time.
    """
    size, keep = sweep.size, sweep.keep
    widths = _widths(blocks, size)
    widths["reason"] = max([1, *(len(r.encode("utf-8")) for _, r in reasons())])
    shape = sweep.shape
    dims = tuple(variable_name(axis.key) for axis in sweep.axes)
    tmp = path.with_name(path.name + ".tmp")
    f = netcdf_file(tmp, "w", version=2)
    try:
        # numbers as numpy scalars: scipy writes a Python float as a 32-bit float
        f.Conventions = CONVENTIONS
        f.title = _title(sweep)
        f.source = f"{_source()}, billiard sweep"
        f.history = history_line()
        f.comment = (
            "SI units; NaN or _FillValue: not measured; netCDF-3 (64-bit offset); "
            "sweep_definition and base_scene hold the sweep file and its base scene"
        )
        f.sweep_definition = sweep_to_toml(sweep)
        f.base_scene = scene_toml
        f.points = np.int32(size)
        for axis, dim in zip(sweep.axes, dims, strict=True):
            f.createDimension(dim, len(axis.values))
            if axis.numeric:
                var = f.createVariable(dim, "f8", (dim,))
                var[:] = np.asarray(axis.values, dtype=float)  # the values the points ran
            else:
                chars, width = _chars([str(v) for v in axis.values], (len(axis.values),))
                f.createDimension(f"{dim}_strlen", width)
                var = f.createVariable(dim, "c", (dim, f"{dim}_strlen"))
                var[:] = chars
                var._Encoding = "utf-8"
            var.units = key_unit(axis.key)
            var.long_name = key_long_name(axis.key)
            var.scene_key = axis.key
        f.createDimension("impact", keep)
        var = f.createVariable("impact", "i4", ("impact",))
        var[:] = np.arange(-keep, 0, dtype=np.int32)
        var.units = "1"
        var.long_name = "impact counted back from the last one (-1: the last)"

        var = f.createVariable("point", "i4", dims)
        var[:] = np.arange(size, dtype=np.int32).reshape(shape)
        var.units = "1"
        var.long_name = "point index (C order of the swept keys; as in points.npy)"
        # every variable below is filled in place (its array, as scipy holds it) from
        # the rows, in one pass once all are made
        fill: dict[str, Callable[[np.ndarray, np.ndarray], None]] = {}
        var = f.createVariable("attractor", "b", dims)
        fill["attractor"] = _filler(var.data.reshape(size), "attractor")
        var.long_name = "attractor class (code; flag_meanings names each flag_values)"
        var.flag_values = np.arange(len(CLASSES), dtype=np.int8)
        var.flag_meanings = " ".join(CLASSES)
        for name, long_name in _TEXT:
            width = widths[name]
            f.createDimension(f"{name}_strlen", width)
            var = f.createVariable(name, "c", (*dims, f"{name}_strlen"))
            text = var.data.reshape(size * width).view(f"S{width}")
            if name == "reason":
                text[...] = b""
                for index, reason in reasons():
                    text[index] = reason.encode("utf-8")
            else:
                table = np.array([n.encode("utf-8") for n in CODES[name]], dtype=f"S{width}")
                fill[name] = _coded_filler(text, name, table)
            var._Encoding = "utf-8"
            var.long_name = long_name
        for name, dtype, units, long_name in _SCALARS:
            var = f.createVariable(name, dtype, dims)
            fill[name] = _filler(var.data.reshape(size), name)
            var.units = units
            var.long_name = long_name
            if name in _NONE_IS_ZERO:
                var._FillValue = np.int32(INT_FILL)
            elif dtype == "f8":
                var._FillValue = np.float64(np.nan)
        for name, units, long_name in (
            ("last_height", "m", "last impact heights q2 (NaN-padded at the front)"),
            ("last_tof", "s", "last times of flight (NaN-padded at the front)"),
        ):
            var = f.createVariable(name, "f8", (*dims, "impact"))
            fill[name] = _filler(var.data.reshape(size, keep), name)
            var.units = units
            var.long_name = long_name
            var._FillValue = np.float64(np.nan)
        for rows in blocks():
            index = np.asarray(rows["index"], dtype=np.int64)
            for put in fill.values():
                put(index, rows)
    finally:
        f.close()
    os.replace(tmp, path)
    return path


def _filler(out: np.ndarray, name: str) -> Callable[[np.ndarray, np.ndarray], None]:
    """Places a block's values of the variable ``name`` (from its rows) at their
    points."""
    if name in ("elastic_share", "lid_share"):
        count = name.replace("share", "impacts")

        def put_share(index: np.ndarray, rows: np.ndarray) -> None:
            out[index] = share(rows[count], rows["impacts"])

        return put_share
    if name in _NONE_IS_ZERO:

        def put_or_fill(index: np.ndarray, rows: np.ndarray) -> None:
            values = np.asarray(rows[name], dtype=np.int32)
            out[index] = np.where(values == 0, np.int32(INT_FILL), values)

        return put_or_fill

    def put(index: np.ndarray, rows: np.ndarray) -> None:
        out[index] = rows[name]

    return put


def _coded_filler(
    out: np.ndarray, name: str, table: np.ndarray
) -> Callable[[np.ndarray, np.ndarray], None]:
    def put(index: np.ndarray, rows: np.ndarray) -> None:
        out[index] = table[rows[name]]

    return put


def _text(value: Any) -> Any:
    return value.decode("utf-8") if isinstance(value, bytes) else value


def _decode(var: Any) -> np.ndarray:
    """One variable's data, decoded as xarray decodes it (see :func:`read_result`)."""
    data = np.array(var.data)
    if data.dtype.kind == "S" and data.dtype.itemsize == 1 and data.ndim >= 1:
        rows = data.reshape(-1, data.shape[-1])
        text = [b"".join(row).rstrip(b"\0").decode() for row in rows]
        data = np.array(text, dtype=object).reshape(data.shape[:-1])
    meanings = getattr(var, "flag_meanings", None)
    fill = getattr(var, "_FillValue", None)
    if meanings is not None:
        codes = np.ravel(var.flag_values).tolist()
        names = dict(zip(codes, _text(meanings).split(), strict=True))
        flat = [names[int(code)] for code in data.ravel()]
        data = np.array(flat, dtype=object).reshape(data.shape)
    elif fill is not None and data.dtype.kind in "iu":
        data = np.where(data == fill, np.nan, data.astype(float))
    return data


def open_result(path: str | os.PathLike[str]) -> Any:
    """The result file as an ``xarray.Dataset`` for notebooks: opened lazily as
    ``xarray.open_dataset`` opens it, except ``attractor``, which holds the class names
    (strings, read through ``flag_meanings``; the codes stay in ``attractor_code``), so
    that a plot or a ``groupby`` shows "period-1", not 1.0.

    Raises:
        ModuleNotFoundError: xarray is not installed.
    """
    import xarray

    ds = xarray.open_dataset(path)
    if "attractor" not in ds or "flag_meanings" not in ds["attractor"].attrs:
        return ds  # a file written before the attractor was coded holds the names
    coded = ds["attractor"]
    names = np.array(str(coded.attrs["flag_meanings"]).split(), dtype=object)
    codes = np.ravel(coded.attrs["flag_values"]).astype(int)
    lookup = np.empty(int(codes.max()) + 1, dtype=object)
    lookup[codes] = names
    decoded = xarray.DataArray(
        lookup[coded.values.astype(int)],
        dims=coded.dims,
        coords=coded.coords,
        attrs={"long_name": "attractor class"},
    )
    return ds.rename_vars({"attractor": "attractor_code"}).assign(attractor=decoded)


def read_result(path: Path, names: Iterable[str] | None = None) -> dict[str, Any]:
    """The result file as a dict of numpy arrays, decoded as xarray decodes them, and its
    global attributes (under ``"_attributes"``).

    Text variables become arrays of ``str``; ``attractor`` its class names (through
    ``flag_meanings``); an integer variable with a ``_FillValue`` becomes float, NaN where
    filled (``period`` where no period was found). Files written before the attractor
    was coded (text) read the same. ``names``: only these variables (a large sweep's
    plots need a few of them).
    """
    wanted = None if names is None else set(names)
    # mapped when only some variables are read: the others are never loaded
    f = netcdf_file(path, "r", mmap=wanted is not None)
    try:
        out: dict[str, Any] = {
            name: _decode(var)
            for name, var in f.variables.items()
            if wanted is None or name in wanted
        }
        out["_attributes"] = {
            name: _text(getattr(f, name)) for name in GLOBAL_ATTRIBUTES if hasattr(f, name)
        }
    finally:
        f.variables.clear()  # no array left on the mapping: it closes cleanly
        f.close()
    return out
