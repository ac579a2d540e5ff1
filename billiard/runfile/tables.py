"""The side tables of a run, CSV or binary, read by one function each:
:func:`read_contacts` (``contacts.csv`` / ``contacts.npy``, one row per contact phase of a
run with ``contact.model = "phases"``) and :func:`read_trajectory` (``trajectory.csv`` /
``trajectory.npy``, the samples of ``billiard run --sample DT``). The impacts are
:func:`billiard.runfile.record.read_collisions`.
"""

from __future__ import annotations

import os

import numpy as np

from billiard.runfile.npyfile import CONTACTS, TRAJECTORY, Table, read_table
from billiard.runfile.record import NPY_MAGIC, RunDataError
from billiard.runfile.sidecsv import read_side_csv
from billiard.scene.userfile import FileRefused, check_regular

__all__ = ["read_contacts", "read_trajectory"]


def read_contacts(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The contact phases of a run: ``contacts.csv`` or ``contacts.npy`` (the file's
    contents tell which).

    Returns:
        Column name -> 1-D array, one entry per phase, in the columns' order
        (:data:`~billiard.runfile.record.CONTACT_COLUMNS`): ``wall``, ``mode`` and ``end``
        strings (``wall`` is ``a+b`` for a phase held by two walls), every other column
        float64 (s, m, m/s, rad/s). The numeric columns of a binary file are read-only
        views of the mapped file.

    Raises:
        RunDataError: the file is missing, unreadable or not a contacts table.
    """
    return _read(path, CONTACTS)


def read_trajectory(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The samples of a run (``billiard run --sample DT``): ``trajectory.csv`` or
    ``trajectory.npy``.

    Returns:
        Column name -> 1-D array, one entry per sample: ``t``, ``q1``, ``q2``, ``v1``,
        ``v2``, ``omega``, ``energy`` float64 (s, m, m/s, rad/s, J) and ``mode`` strings
        (``flight``, ``roll``, ``slide``, ``held``).

    Raises:
        RunDataError: the file is missing, unreadable or not a trajectory table.
    """
    return _read(path, TRAJECTORY)


def _read(path: str | os.PathLike[str], table: Table) -> dict[str, np.ndarray]:
    try:
        check_regular(path)
        with open(path, "rb") as handle:
            binary = handle.read(len(NPY_MAGIC)) == NPY_MAGIC
        if binary:
            return read_table(path, table)
        columns = read_side_csv(path)
    except FileRefused as exc:
        raise RunDataError(f"{path}: {exc.reason}") from None
    except FileNotFoundError:
        raise RunDataError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, ValueError, IndexError) as exc:
        if isinstance(exc, RunDataError):
            raise
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise RunDataError(f"{path}: cannot read: {reason}") from None
    missing = [name for name in table.columns if name not in columns]
    if missing:
        raise RunDataError(f"{path}: missing column(s) {', '.join(missing)}")
    return columns
