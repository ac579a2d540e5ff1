"""The outcome of a run: its records (in memory or in the run's file, CSV or binary),
how it ended, a one-line summary, and its tables as DataFrames and Datasets
(:mod:`billiard.run.frames`)."""

from __future__ import annotations

import math
import os
import shlex
from pathlib import Path
from typing import Any

import numpy as np

from billiard.run.frames import Table, TableError, check_table, to_pandas, to_xarray
from billiard.runfile.npystream import NpyRecorder
from billiard.runfile.record import MemoryRecorder
from billiard.runfile.stream import CsvRecorder, Truncation
from billiard.runfile.tables import read_collisions
from billiard.scene.display import html_table, scene_rows
from billiard.scene.scene import scene_to_toml
from billiard.status import Status

__all__ = ["Result", "RunFile"]


class RunFile:
    """A finished run's impact table on disk (``collisions.csv`` or ``collisions.npy``, or
    any file :func:`~billiard.runfile.tables.read_collisions` reads), read-only, with the
    recorder interface of a Result. Nothing is read before the columns are asked for.

    Args:
        path: the file.
        rows: its number of impacts when known (a checkpoint says it), else None: then
            ``len()`` reads the file.
    """

    def __init__(self, path: Path, rows: int | None):
        self.path = path
        self._rows = rows
        self._columns: dict[str, np.ndarray] | None = None

    def __len__(self) -> int:
        if self._rows is None:
            self._rows = len(self.columns()["n"])
        return self._rows

    def close(self) -> None:
        pass

    def columns(self) -> dict[str, np.ndarray]:
        if self._columns is None:
            self._columns = read_collisions(self.path)
        return self._columns

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if self.path.suffix == ".npy":
            from billiard.runfile.npyfile import COLLISIONS, export_csv

            export_csv(self.path, path, COLLISIONS)
        elif Path(path).resolve() != self.path.resolve():
            Path(path).write_bytes(self.path.read_bytes())


class Result:
    """The outcome of :func:`~billiard.run.simulate.simulate` or
    :func:`~billiard.run.persist.resume`.

    Its tables (impacts, contact phases, trajectory samples) are :attr:`columns`,
    :attr:`contacts` and :attr:`trajectory`, each a :class:`~billiard.run.frames.Table`
    of numpy arrays, and :meth:`to_pandas` and :meth:`to_xarray` give them as a DataFrame
    or a Dataset with their units. :func:`~billiard.run.load.open_run` gives the same
    object for a run folder.

    Attributes:
        scene: the scene as run (initial position resolved, count and method set).
        status: how the run ended (:class:`~billiard.status.Status`); None for a run
            opened from a folder that is not known to have ended (:attr:`unfinished`).
        stop_reason: None when the run did all it was asked for, else the one-line
            message of its stop.
        message: a one-line description of how the run ended (always set).
        wall_time: seconds the run took (this session only, for a resumed run; NaN for
            a run opened from its folder).
        counts: impacts per regime of the impact law, and how many of them relaunched
            a ball lying on the surface (``resting``).
        regimes: the impact law's regimes, in the order the summary lists them.
        path: the streamed file of impacts (collisions.csv or collisions.npy), or None
            for an in-memory run.
        final_time: simulated time the run reached (s): the last impact, or
            ``run.duration`` when that ended it.
        resumed_from: for a resumed run, the impacts already on disk when it started
            (None for a fresh run).
        truncation: for a resumed run, what was cut off the CSV file's end.
        already_finished: the resume found the run complete (or stopped) and did nothing.
        final_mode: the ball's motion state when the run ended: ``flight``, ``roll``,
            ``slide`` or ``held`` (None when not known, e.g. a finished run found again).
        unfinished: for a run opened from its folder that has not ended, why:
            ``"interrupted"`` (``billiard run --resume DIR`` continues it), ``"running"``
            (still being written, or killed) or ``"unknown"`` (no readable
            checkpoint.json); else None.
    """

    def __init__(
        self,
        scene: Any,
        recorder: MemoryRecorder | CsvRecorder | NpyRecorder | RunFile,
        status: Status | None,
        stop_reason: str | None,
        wall_time: float,
        counts: dict[str, int],
        final_time: float,
        *,
        regimes: tuple[str, ...] = ("stick", "slip", "elastic"),
        resumed_from: int | None = None,
        truncation: Truncation | None = None,
        already_finished: bool = False,
        mode_times: dict[str, float] | None = None,
        contacts: Any = None,
        trajectory: Any = None,
        final_mode: str | None = None,
        unfinished: str | None = None,
    ):
        self.scene = scene
        self.status: Status | None = None if status is None else Status(status)
        self.unfinished = unfinished
        self.final_time = final_time
        self._recorder = recorder
        self.stop_reason = stop_reason
        self.wall_time = wall_time
        self.counts = dict(counts)
        self.regimes = tuple(regimes)
        self.path: Path | None = getattr(recorder, "path", None)
        self.resumed_from = resumed_from
        self.truncation = truncation
        self.already_finished = already_finished
        self._columns: Table | None = None
        self._sides: dict[str, Table | None] = {}
        self.mode_times = mode_times
        self._contacts = contacts
        self._trajectory = trajectory
        self.final_mode = final_mode

    @property
    def contacts(self) -> Table | None:
        """The contact phases (``contact.model = "phases"``): the ``contacts`` table,
        column name -> array, the columns of contacts.csv (read from the file on first
        use; ``wall`` and ``wall_other`` int64, see
        :func:`~billiard.runfile.tables.read_contacts`); None for the impacts model."""
        return self._side("contacts", self._contacts)

    @property
    def trajectory(self) -> Table | None:
        """The samples of a run with a sampling interval: the ``samples`` table, column
        name -> array, the columns of trajectory.csv (t, q1, q2, v1, v2, omega, energy,
        mode; read from the file on first use); else None."""
        return self._side("samples", self._trajectory)

    def _side(self, name: str, source: Any) -> Table | None:
        if name not in self._sides:
            columns = _side_columns(source, name)
            self._sides[name] = None if columns is None else Table(name, columns)
        return self._sides[name]

    @property
    def side_files(self) -> tuple[Path, ...]:
        """The files a streamed run wrote beside its impacts' file: contacts.csv (or
        .npy) under ``contact.model = "phases"``, trajectory.csv (or .npy) with a
        sampling interval."""
        return tuple(p for p in (self._contacts, self._trajectory) if isinstance(p, Path))

    @property
    def message(self) -> str:
        if self.stop_reason:
            return self.stop_reason
        if self.status is None:
            return _unfinished_message(self.unfinished, self.path)
        if self.status is Status.TIME_LIMIT:
            return f"reached the simulated time t = {self.final_time:.6g} s"
        if self.status is Status.AT_REST:
            return (
                "the ball rests on the boundary, moving with it, "
                f"from t = {self.final_time:.6g} s: nothing more happens"
            )
        if self.status is Status.IN_CONTACT:
            return _in_contact_message(self.scene, self.final_mode)
        return "all impacts simulated"

    @property
    def columns(self) -> Table:
        """The ``impacts`` table: column name -> numpy array, the columns of
        collisions.csv (read back from the run's file on first use)."""
        if self._columns is None:
            self._columns = Table("impacts", self._recorder.columns())
        return self._columns

    def table(self, name: str = "impacts") -> Table:
        """The table ``name``: ``"impacts"`` (:attr:`columns`), ``"contacts"``
        (:attr:`contacts`) or ``"samples"`` (:attr:`trajectory`).

        Raises:
            TableError: an unknown name, or a table this run has none of.
        """
        check_table(name)
        if name == "impacts":
            return self.columns
        table = self.contacts if name == "contacts" else self.trajectory
        if table is None:
            why = (
                'contact phases need contact.model = "phases"'
                if name == "contacts"
                else "samples need a sampling interval (simulate(..., sample=DT), --sample DT)"
            )
            raise TableError(f"the run of {self.scene.name!r} has no {name} table: {why}")
        return table

    def _attrs(self) -> dict[str, Any]:
        """What a DataFrame or Dataset of this run says about it (plain strings and
        numbers, so that a Dataset writes to netCDF)."""
        return {
            "scene": self.scene.name,
            "status": self.status_word,
            "final_time_s": float(self.final_time),
            "scene_toml": scene_to_toml(self.scene),
        }

    def to_pandas(self, table: str = "impacts") -> Any:
        """The table ``table`` (``"impacts"``, ``"contacts"`` or ``"samples"``) as a
        pandas DataFrame: the same columns, dtypes and values, SI units.

        ``df.attrs["units"]`` maps each column to its unit, ``df.attrs["descriptions"]``
        to a description; ``df.attrs`` also holds the table's name, the scene's name and
        TOML text, the run's status and final time (s). See
        :func:`billiard.run.frames.to_pandas`.

        Raises:
            TableError: an unknown table, or one this run has none of.
            MissingExtraError: (an ImportError) pandas is not installed.
        """
        return to_pandas(self.table(table), self._attrs())

    def to_xarray(self, table: str = "impacts") -> Any:
        """The table ``table`` as an xarray Dataset: one variable per column along the
        dimension ``impact``, ``contact`` or ``sample``, each with ``units`` and
        ``long_name``; the impacts' coordinate is the impact number. The Dataset's
        attributes name the scene (and hold its TOML text), the run's status, its final
        time (s) and the package version. See :func:`billiard.run.frames.to_xarray`.

        Raises:
            TableError: an unknown table, or one this run has none of.
            MissingExtraError: (an ImportError) xarray is not installed.
        """
        return to_xarray(self.table(table), self._attrs())

    @property
    def status_word(self) -> str:
        """How the run ended, in one word: the status's name in lower case
        (``complete``, ``time_limit``, ``escaped``, ...), or for a run that has not
        ended, :attr:`unfinished`."""
        if self.status is None:
            return self.unfinished or "unknown"
        return self.status.name.lower()

    def __repr__(self) -> str:
        return (
            f"<Result {self.scene.name!r}: {self.status_word}, {len(self)} impacts, "
            f"t = {self.final_time:.6g} s>"
        )

    def _repr_html_(self) -> str:
        """The scene's settings and the run's outcome as a small HTML table."""
        rows = [("status", self.status_word), ("impacts", f"{len(self)}")]
        rows += [("final time", f"{self.final_time:.6g} s")]
        if self.counts:
            rows.append(("regimes", ", ".join(f"{v} {k}" for k, v in self.counts.items())))
        if self.mode_times is not None:
            times = ", ".join(f"{v:.6g} s {k}" for k, v in self.mode_times.items())
            rows.append(("time per motion state", times))
        if self.stop_reason:
            rows.append(("stopped", self.stop_reason))
        if self.path is not None:
            rows.append(("file", str(self.path)))
        return html_table(scene_rows(self.scene) + rows, f"Result of {self.scene.name!r}")

    def __len__(self) -> int:
        return len(self._recorder)

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the records as CSV (floats with repr, so they read back exactly)."""
        self._recorder.write_csv(path)

    def summary(self) -> str:
        n = len(self)
        c = self.counts
        done = n - (self.resumed_from or 0)
        parts = [f"{c.get(name, 0)} {name}" for name in self.regimes]
        resting = c.get("resting", 0)
        if resting:
            # relaunches of a lying ball are impacts of the low-velocity rule (elastic)
            at = self.regimes.index("elastic") if "elastic" in self.regimes else -1
            parts[at] += f", of which {resting} relaunches of a resting ball"
        text = f"{n} impacts ({', '.join(parts)}) up to t = {self.final_time:.6g} s"
        if math.isfinite(self.wall_time):  # not for a run opened from its folder
            rate = done / self.wall_time if self.wall_time > 0 else math.inf
            text += f" in {self.wall_time:.3g} s ({rate:,.0f} impacts/s)"
        if n and resting >= 0.9 * n:
            text += (
                "; the ball lies on the wall nearly all the time, hopping at "
                "contact.elastic_below "
                "(the low-velocity rule standing in for rolling): a stronger drive "
                "(drive.amplitude, m) or a start above the wall (initial.q2, m) makes it fly"
            )
        if self.mode_times is not None:
            m = self.mode_times
            text += (
                f"; {m['flight']:.6g} s flying, {m['roll']:.6g} s rolling, "
                f"{m['slide']:.6g} s sliding"
            )
            if m.get("held"):
                text += f", {m['held']:.6g} s held by two walls"
        if self.resumed_from is not None:
            text += f"; resumed after impact {self.resumed_from}"
        if self.status is Status.TIME_LIMIT:
            text += "; reached run.duration"
        if self.status is Status.AT_REST:
            text += "; at rest on the boundary (moving with it): nothing more happens"
        if self.status is Status.IN_CONTACT:
            text += "; " + _in_contact_message(self.scene, self.final_mode)
            if n == 0:
                text += (
                    "; a stronger drive (drive.amplitude, m) or a start above the wall "
                    "(initial.q2, m) makes it fly"
                )
        if self.stop_reason:
            text += f"; stopped: {self.stop_reason}"
        elif self.status is None:
            text += f"; {self.message}"
        return text


def _unfinished_message(word: str | None, path: Path | None) -> str:
    """What is known of a run opened from its folder that has not ended."""
    again = f"`billiard run --resume {shlex.quote(str(path.parent))}`" if path else "a resume"
    if word == "interrupted":
        return f"interrupted before its end; {again} continues it"
    if word == "running":
        return f"not ended: still being written, or killed ({again} continues a killed run)"
    return "how the run ended is not known (its folder has no readable checkpoint.json)"


_MODE_WORDS = {"roll": "rolling", "slide": "sliding", "held": "held by two walls"}


def _in_contact_message(scene: Any, mode: str | None) -> str:
    """Why a run ended with status IN_CONTACT, and how to follow the ball further."""
    span = getattr(getattr(scene, "run", None), "contact_span", None)
    how = _MODE_WORDS.get(mode or "", "in contact")
    return (
        f"no impact for run.contact_span = {span:g} s of simulated time, the ball "
        f"{how} on the boundary: ended; --duration SECONDS (run.duration) follows it further"
    )


def _side_columns(source: Any, name: str) -> dict[str, np.ndarray] | None:
    if source is None:
        return None
    if isinstance(source, (str, os.PathLike)):
        from billiard.runfile.tables import read_contacts, read_trajectory

        return (read_contacts if name == "contacts" else read_trajectory)(source)
    return source.columns()
