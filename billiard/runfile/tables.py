"""The tables of a run, CSV or binary (the file's name tells which), read by one
function each: :func:`read_collisions` (``collisions.csv`` / ``collisions.npy``, one row
per impact), :func:`read_contacts` (``contacts.csv`` / ``contacts.npy``, one row per
contact phase of a run with ``contact.model = "phases"``) and :func:`read_trajectory`
(``trajectory.csv`` / ``trajectory.npy``, the samples of ``billiard run --sample DT``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from billiard.runfile.npyfile import COLLISIONS, CONTACTS, TRAJECTORY, Table, read_table
from billiard.runfile.record import NPY_MAGIC, RunDataError, read_collisions_csv
from billiard.runfile.sidecsv import read_side_csv
from billiard.scene.userfile import FileRefused, check_regular

__all__ = ["read_collisions", "read_contacts", "read_trajectory"]


def read_collisions(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a run's impacts, ``collisions.csv`` or ``collisions.npy``, into numpy arrays,
    one per column; the file's name tells which format it is read as (``.npy`` binary,
    ``.csv`` text; a file of the other format is refused, not read as it), and for
    another name its contents (a ``.npy`` file starts with NumPy's magic bytes).

    CSV: as :func:`billiard.runfile.record.read_collisions_csv` (bulk parsing, bit-exact
    values, an unterminated last row skipped). Binary (:mod:`billiard.runfile.npyfile`):
    the rows its header counts; the numeric columns are read-only views of the file
    mapped into memory (nothing is read before it is used), ``regime`` is decoded from
    its codes.

    Returns:
        A dict column name -> 1-D array with one entry per impact, in file order, with
        the same dtypes as ``Result.columns`` whatever the format: ``n`` and ``wall``
        int64 (``wall`` -1 for the lid), ``regime`` strings, every other column float64 in
        SI units (s, m, m/s, rad/s, J, N s).

    Raises:
        RunDataError: the file is missing or unreadable, or not a run's impact table (see
            :func:`~billiard.runfile.record.read_collisions_csv`); or its binary header is
            not that of a run file or promises more rows than it holds.
    """
    try:
        binary = _is_binary(path)
    except (FileRefused, OSError):
        binary = False  # the CSV reader says what is wrong with the file, in its words
    return read_table(path, COLLISIONS) if binary else read_collisions_csv(path)


def _is_binary(path: str | os.PathLike[str]) -> bool:
    """Is ``path`` to be read as a binary table? Its name says so (``.npy``) or not
    (``.csv``): a file whose contents are of the other format is refused by the reader of
    its name's, never read as the other (CSV text in ``collisions.npy`` is not a binary
    run file). Only a file named otherwise is told by its first bytes.

    Raises:
        FileRefused, OSError: the file cannot be opened to look (another name only).
    """
    suffix = Path(path).suffix.lower()
    if suffix in (".npy", ".csv"):
        return suffix == ".npy"
    check_regular(path)  # /dev/zero or a pipe would be read without end
    with open(path, "rb") as handle:
        return handle.read(len(NPY_MAGIC)) == NPY_MAGIC


def read_contacts(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The contact phases of a run: ``contacts.csv`` or ``contacts.npy`` (the file's
    name tells which, as for :func:`read_collisions`).

    Returns:
        Column name -> 1-D array, one entry per phase, in the columns' order
        (:data:`~billiard.runfile.record.CONTACT_COLUMNS`): ``wall`` and ``wall_other``
        int64 (the wall's index, -1 the lid; ``wall_other`` the second wall of a phase
        held by two, else -2), ``mode`` and ``end`` strings, every other column float64
        (s, m, m/s, rad/s), whatever the format and whichever version wrote the file
        (``a+b`` text of earlier files reads as a and b). The numeric columns of a
        binary file are read-only views of the mapped file.

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
        if _is_binary(path):
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
