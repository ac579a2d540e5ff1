"""A run's tables where users hold data: numpy columns with units (:class:`Table`),
pandas DataFrames and xarray Datasets.

A run has up to three tables, named as :data:`~billiard.runfile.column_units.TABLES`:

``impacts``
    one row per impact (``Result.columns``, ``collisions.csv``).
``contacts``
    one row per rolling, sliding or held phase (``Result.contacts``, ``contacts.csv``;
    ``contact.model = "phases"`` only).
``samples``
    the state every ``sample`` seconds of simulated time (``Result.trajectory``,
    ``trajectory.csv``; a run with a sampling interval only).

pandas and xarray are optional (the ``data`` extra): they are imported when a
conversion is asked for, and their absence raises :class:`MissingExtraError` with the
command that installs them. Each DataFrame and Dataset carries the unit and description
of every column (:mod:`billiard.runfile.column_units`).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from billiard.runfile.column_units import TABLES, column_info

__all__ = [
    "DATA_HINT",
    "MissingExtraError",
    "Table",
    "TableError",
    "require_extra",
    "to_pandas",
    "to_xarray",
]

#: The command that installs pandas and xarray for this package.
DATA_HINT = 'pip install "realworld-billiard[data]"'

#: The dimension of each table in an xarray Dataset.
DIMENSIONS = {"impacts": "impact", "contacts": "contact", "samples": "sample"}


class MissingExtraError(ImportError):
    """An optional dependency (pandas, xarray) is not installed; the message is one line
    naming the extra that installs it."""


class TableError(ValueError):
    """A table that does not exist: an unknown name, or one the run has none of (contact
    phases of the impacts model, samples without a sampling interval). One line."""


def require_extra(module: str, what: str) -> Any:
    """The module ``module`` imported, or :class:`MissingExtraError` naming ``what`` needs
    it and the extra that installs it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtraError(f"{what} needs {module}: {DATA_HINT}") from None


def check_table(name: Any) -> str:
    """``name`` if it names a table, else :class:`TableError`."""
    if name not in TABLES:
        raise TableError(f"unknown table {name!r}: the tables are {', '.join(TABLES)}")
    return name


class Table(dict[str, np.ndarray]):
    """One of a run's tables: column name -> 1-D numpy array, all of one length, in the
    file's column order. A dict (``table["q2"]``), with the columns also as attributes
    (``table.q2``) and their units in :attr:`units`.

    Attributes:
        name: ``"impacts"``, ``"contacts"`` or ``"samples"``.
    """

    def __init__(self, name: str, columns: Mapping[str, np.ndarray]):
        super().__init__(columns)
        self.name = check_table(name)

    def __getattr__(self, column: str) -> np.ndarray:
        # only for names that are not attributes; never for dunders (pickle and copy
        # ask for __setstate__ and the like before the instance has its name)
        if column.startswith("__") or column not in self:
            name = self.__dict__.get("name", "")
            raise AttributeError(f"the {name} table has no column {column!r}")
        return self[column]

    @property
    def rows(self) -> int:
        """Number of rows (impacts, phases or samples)."""
        return len(next(iter(self.values()))) if self else 0

    @property
    def units(self) -> dict[str, str]:
        """Column name -> SI unit (``""``: none, e.g. a count or a label)."""
        return {column: column_info(self.name, column)[0] for column in self}

    @property
    def descriptions(self) -> dict[str, str]:
        """Column name -> a short description."""
        return {column: column_info(self.name, column)[1] for column in self}

    def to_records(self) -> np.ndarray:
        """The rows as a numpy structured array (one record per row, one field per
        column, each with its column's dtype)."""
        dtype = [(column, values.dtype) for column, values in self.items()]
        records = np.empty(self.rows, dtype=dtype)
        for column, values in self.items():
            records[column] = values
        return records

    def __repr__(self) -> str:
        return f"<Table {self.name!r}: {self.rows} rows, columns {', '.join(self) or 'none'}>"


def _version() -> str:
    import importlib.metadata  # here: reading metadata is for a Dataset, not every start

    try:
        return importlib.metadata.version("realworld-billiard")
    except importlib.metadata.PackageNotFoundError:
        return "(version unknown: not installed)"


def to_pandas(table: Table, attrs: Mapping[str, Any] | None = None) -> Any:
    """A pandas DataFrame of ``table``: one column per column (same dtype, same values),
    one row per row, a default integer index.

    ``df.attrs`` holds ``table`` (the table's name), ``units`` (column -> SI unit),
    ``descriptions`` (column -> description) and the entries of ``attrs``.

    Raises:
        MissingExtraError: pandas is not installed.
    """
    pd = require_extra("pandas", "to_pandas()")
    frame = pd.DataFrame({column: values for column, values in table.items()})
    frame.attrs.update(
        {"table": table.name, "units": table.units, "descriptions": table.descriptions}
    )
    frame.attrs.update(attrs or {})
    return frame


def to_xarray(table: Table, attrs: Mapping[str, Any] | None = None) -> Any:
    """An xarray Dataset of ``table``: one variable per column along the table's
    dimension (``impact``, ``contact`` or ``sample``), each with the attributes
    ``units`` and ``long_name`` (a column without a unit has no ``units``). The
    ``impact`` dimension's coordinate is the impact number ``n``.

    The Dataset's attributes are ``table``, ``source`` (package and version) and the
    entries of ``attrs``.

    Raises:
        MissingExtraError: xarray is not installed.
    """
    xr = require_extra("xarray", "to_xarray()")
    dim = DIMENSIONS[table.name]
    variables = {}
    for column, values in table.items():
        unit, description = column_info(table.name, column)
        var_attrs = {"long_name": description or column}
        if unit:
            var_attrs["units"] = unit
        variables[column] = xr.Variable((dim,), values, attrs=var_attrs)
    coords = {}
    if table.name == "impacts" and "n" in table:
        coords[dim] = xr.Variable((dim,), table["n"], attrs={"long_name": "impact number"})
    dataset = xr.Dataset(variables, coords=coords)
    dataset.attrs.update({"table": table.name, "source": f"realworld-billiard {_version()}"})
    dataset.attrs.update(attrs or {})
    return dataset
