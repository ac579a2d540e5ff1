"""A run folder opened as the :class:`~billiard.run.result.Result` of its run:
:func:`open_run`.

A folder written by ``billiard run`` (or ``simulate(..., out_dir=DIR)``) holds the
resolved scene (``scene.toml``), the impacts (``collisions.npy`` or ``collisions.csv``),
the checkpoint (``checkpoint.json``: how the run ended, its impact counts and final
state) and, for some runs, the side tables ``contacts.csv`` and ``trajectory.csv``.
:func:`open_run` reads the scene and the checkpoint, which are small, checks the tables
against the checkpoint's checksums (:mod:`billiard.run.verify`), and leaves them on disk
until they are asked for (``result.columns``, ``result.to_pandas()``...).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from billiard.run.persist import CSV_NAME, SCENE_NAME
from billiard.run.result import Result, RunFile
from billiard.run.verify import DamagedRunError, table_file, verify_run
from billiard.runfile.folder import COLLISIONS_NPY, data_file, side_file
from billiard.runfile.record import RunDataError
from billiard.scene.scene import scene_from_toml
from billiard.scene.userfile import MAX_SCENE_BYTES, FileRefused, read_limited
from billiard.status import Status

__all__ = [
    "NPY_NAME",
    "DamagedRunError",
    "NotARunError",
    "impact_file",
    "open_run",
]

#: The binary impact table; read in preference to ``collisions.csv`` when both are there.
NPY_NAME = COLLISIONS_NPY


class NotARunError(RunDataError):
    """A folder that holds no run (no impact table or no scene), or a path that is not a
    folder. The message is one line; the command line exits with status 2."""


def impact_file(run_dir: Path) -> Path | None:
    """The impact table of the run folder ``run_dir``: ``collisions.npy`` when present,
    else ``collisions.csv``; None when it has neither."""
    path = data_file(run_dir)
    return path if path.is_file() else None


def open_run(run_dir: str | os.PathLike[str]) -> Result:
    """The run in the folder ``run_dir``, as the :class:`~billiard.run.result.Result`
    that ``simulate(scene, out_dir=run_dir)`` returned: the same scene, status, stop
    reason, impact counts, final time (s), motion state and tables, value for value.

    Every data file is checked against the checkpoint first (:mod:`billiard.run.verify`:
    its format, and the CRC-32 of the bytes the checkpoint recorded; for a run that
    ended, that nothing follows them): one read of each file, about 0.1 s for 10^6
    impacts stored binary, 0.3 s as CSV. The tables are read on first use
    (``result.columns``, ``result.contacts``, ``result.trajectory``,
    ``result.to_pandas()``...). ``result.wall_time`` is NaN (a folder does not keep it).

    A run that has not ended (interrupted, still being written, or killed) opens too,
    with the rows on disk: its ``status`` is None and ``unfinished`` says why
    (``billiard run --resume DIR`` continues it); rows after its last checkpoint are not
    verified. So does a folder without a readable checkpoint (``unfinished =
    "unknown"``, no impact counts), with an :class:`~billiard.run.verify.UnverifiedRunWarning`
    saying that its files are not verified, and a run whose checkpoint predates the
    checksums (version 2), with the same warning.

    Raises:
        NotARunError: ``run_dir`` is not a folder, or holds no ``collisions.npy`` or
            ``collisions.csv``, or no ``scene.toml``.
        DamagedRunError: a data file is missing, of another format than its name says,
            or differs from what the checkpoint recorded (a
            :class:`~billiard.runfile.record.RunDataError`; one line naming the file).
        SceneError: ``scene.toml`` is not a valid scene.
    """
    out = Path(run_dir)
    if not out.is_dir():
        what = "does not exist" if not out.exists() else "is not a folder"
        raise NotARunError(f"{out} {what}: open_run() takes a run folder")
    table = impact_file(out)
    if table is None:
        raise NotARunError(
            f"{out} holds no run: no {NPY_NAME} or {CSV_NAME} "
            f"(`billiard run SCENE --out {out}` writes one)"
        )
    scene = _scene(out / SCENE_NAME)
    verified = verify_run(out)
    if verified is None:
        # the side tables are in the impact table's format (contacts.npy beside
        # collisions.npy)
        sides = {name: side_file(out, name) for name in ("contacts", "trajectory")}
        return Result(
            scene, RunFile(table, None), None, None, math.nan, {}, math.nan,
            unfinished="unknown", **sides,
        )  # fmt: skip
    checkpoint, files = verified
    # the side tables the run wrote and the folder still has
    sides = {}
    for name in ("contacts", "trajectory"):
        path = out / table_file(name, files.store)
        sides[name] = path if name in files.side_sizes and path.is_file() else None
    return _from_checkpoint(scene, out / table_file("collisions", files.store), checkpoint, sides)


def _scene(path: Path) -> Any:
    try:
        text = read_limited(path, MAX_SCENE_BYTES).decode("utf-8")
    except FileNotFoundError:
        raise NotARunError(f"{path} is missing: the folder holds no complete run") from None
    except FileRefused as exc:
        raise NotARunError(f"{path} {exc.reason}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise NotARunError(f"{path} cannot be read: {exc}") from None
    return scene_from_toml(text, source=f"'{path}'")


def _get(data: Any, *keys: str) -> Any:
    """``data[k1][k2]...``, or None where an entry is missing or not a mapping."""
    for key in keys:
        if not isinstance(data, Mapping):
            return None
        data = data.get(key)
    return data


def _from_checkpoint(
    scene: Any, table: Path, checkpoint: Mapping[str, Any], sides: Mapping[str, Path | None]
) -> Result:
    """The Result of a run from its checkpoint (its last one, for a run that ended)."""
    engine = checkpoint.get("engine")
    counts = _get(engine, "counts")
    counts = {str(k): int(v) for k, v in counts.items()} if isinstance(counts, Mapping) else {}
    regimes = tuple(name for name in counts if name != "resting")
    ended = checkpoint.get("status") in ("complete", "stopped")
    # the rows a checkpoint counts are the file's rows for a run that ended; rows written
    # after the last checkpoint of one that did not (a kill) are read from the file
    rows = _get(engine, "impacts") if ended else None
    if rows is None and ended and table.name == CSV_NAME:
        rows = _get(checkpoint, "csv", "rows")
    outcome = checkpoint.get("outcome")
    final_time = _get(outcome, "final_time")
    if final_time is None:  # a checkpoint of an earlier version: the last state's time
        final_time = _get(engine, "ball", "t")
    mode_times = _get(outcome, "mode_times")
    return Result(
        scene,
        RunFile(table, rows if isinstance(rows, int) else None),
        Status(checkpoint.get("stop_status", Status.COMPLETE)) if ended else None,
        checkpoint.get("stop_reason") if ended else None,
        math.nan,
        counts,
        float(final_time) if isinstance(final_time, (int, float)) else math.nan,
        **({"regimes": regimes} if regimes else {}),
        mode_times=dict(mode_times) if isinstance(mode_times, Mapping) else None,
        final_mode=_get(outcome, "final_mode") or _get(engine, "mode"),
        unfinished=None if ended else str(checkpoint.get("status", "unknown")),
        contacts=sides["contacts"],
        trajectory=sides["trajectory"],
    )
