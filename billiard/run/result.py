"""The outcome of a run: its records (in memory or in the run's file, CSV or binary),
how it ended, and a one-line summary."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from billiard.runfile.npystream import NpyRecorder
from billiard.runfile.record import MemoryRecorder, read_collisions
from billiard.runfile.stream import CsvRecorder, Truncation
from billiard.status import Status

__all__ = ["Result", "RunFile"]


class RunFile:
    """A finished run's file of impacts (``collisions.csv`` or ``collisions.npy``),
    read-only, with the recorder interface of a Result."""

    def __init__(self, path: Path, rows: int):
        self.path = path
        self._rows = rows

    def __len__(self) -> int:
        return self._rows

    def close(self) -> None:
        pass

    def columns(self) -> dict[str, np.ndarray]:
        return read_collisions(self.path)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        if self.path.suffix == ".npy":
            from billiard.runfile.npyfile import COLLISIONS, export_csv

            export_csv(self.path, path, COLLISIONS)
        elif Path(path).resolve() != self.path.resolve():
            Path(path).write_bytes(self.path.read_bytes())


class Result:
    """The outcome of :func:`~billiard.run.simulate.simulate` or
    :func:`~billiard.run.persist.resume`.

    Attributes:
        scene: the scene as run (initial position resolved, count and method set).
        status: how the run ended (:class:`~billiard.status.Status`).
        stop_reason: None when the run did all it was asked for, else the one-line
            message of its stop.
        message: a one-line description of how the run ended (always set).
        wall_time: seconds the run took (this session only, for a resumed run).
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
    """

    def __init__(
        self,
        scene: Any,
        recorder: MemoryRecorder | CsvRecorder | NpyRecorder | RunFile,
        status: Status,
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
    ):
        self.scene = scene
        self.status = Status(status)
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
        self._columns: dict[str, np.ndarray] | None = None
        self.mode_times = mode_times
        self._contacts = contacts
        self._trajectory = trajectory
        self.final_mode = final_mode

    @property
    def contacts(self) -> dict[str, np.ndarray] | None:
        """The contact phases (``contact.model = "phases"``): column name -> array, the
        columns of contacts.csv; None for the impacts model."""
        return _side_columns(self._contacts, "contacts")

    @property
    def trajectory(self) -> dict[str, np.ndarray] | None:
        """The samples of a run with a sampling interval: column name -> array, the
        columns of trajectory.csv (t, q1, q2, v1, v2, omega, energy, mode); else None."""
        return _side_columns(self._trajectory, "trajectory")

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
    def columns(self) -> dict[str, np.ndarray]:
        """Column name -> numpy array (read back from the CSV file on first use)."""
        if self._columns is None:
            self._columns = self._recorder.columns()
        return self._columns

    def __len__(self) -> int:
        return len(self._recorder)

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the records as CSV (floats with repr, so they read back exactly)."""
        self._recorder.write_csv(path)

    def summary(self) -> str:
        n = len(self)
        c = self.counts
        done = n - (self.resumed_from or 0)
        rate = done / self.wall_time if self.wall_time > 0 else math.inf
        parts = [f"{c.get(name, 0)} {name}" for name in self.regimes]
        resting = c.get("resting", 0)
        if resting:
            # relaunches of a lying ball are impacts of the low-velocity rule (elastic)
            at = self.regimes.index("elastic") if "elastic" in self.regimes else -1
            parts[at] += f", of which {resting} relaunches of a resting ball"
        text = (
            f"{n} impacts ({', '.join(parts)}) up to t = {self.final_time:.6g} s "
            f"in {self.wall_time:.3g} s ({rate:,.0f} impacts/s)"
        )
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
        return text


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
