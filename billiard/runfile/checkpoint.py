"""Atomic files and checkpoints: what lets a streamed run continue after an interruption.

A checkpoint is a JSON file written atomically (temporary file, sync, rename) with a
format, a version and a checksum; floats are written with :func:`repr`, so an engine
state survives the round trip bit for bit.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from billiard.scene.userfile import FileRefused, open_regular, read_limited

__all__ = [
    "open_checked",
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "CheckpointError",
    "read_checkpoint",
    "write_checkpoint",
    "write_text_atomic",
]

#: Largest checkpoint file read (bytes): one holds an engine state, a few kilobytes.
MAX_CHECKPOINT_BYTES = 1 << 20
#: ``format`` and ``version`` fields of a checkpoint file.
CHECKPOINT_FORMAT = "billiard-checkpoint"
CHECKPOINT_VERSION = 3
#: Versions read: 3 adds the CRC-32 of each file's rows before the checkpoint and the
#: sha256 of scene.toml's bytes; a version 2 checkpoint (without them) is resumed
#: without those two checks.
READABLE_VERSIONS = (2, 3)


class CheckpointError(ValueError):
    """A run directory cannot be resumed: the checkpoint is missing, corrupt or does not
    match the CSV file or the scene. The message is one line."""


def open_checked(path: Path) -> int:
    """A descriptor of the run file ``path`` for reading, to check it against a
    checkpoint (the caller closes it).

    Raises:
        CheckpointError: the file is missing, not a regular file, or cannot be opened.
    """
    try:
        return open_regular(path)
    except FileNotFoundError:
        raise CheckpointError(f"{path} is missing") from None
    except FileRefused as exc:
        raise CheckpointError(f"{path} {exc.reason}") from None
    except OSError as exc:
        raise CheckpointError(f"{path} cannot be read: {exc.strerror or exc}") from None


def _fsync_directory(directory: Path) -> None:
    """Make a rename in ``directory`` durable (best effort: not every platform or file
    system lets a directory be opened)."""
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Replace ``path`` by ``text`` atomically: a reader (or a crash) sees the old file
    or the new one, never a mixture (temporary file in the same directory, synced, then
    ``os.replace``)."""
    path = Path(path)
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(temp, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temp.unlink()
        raise
    _fsync_directory(path.parent)


def _checksum(body: Mapping[str, Any]) -> str:
    canonical = json.dumps(body, sort_keys=True, allow_nan=False, separators=(",", ":"))
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def write_checkpoint(path: str | os.PathLike[str], body: Mapping[str, Any]) -> None:
    """Write a checkpoint atomically: ``body`` plus format, version and a checksum.

    Floats are written by :mod:`json` with :func:`repr`, which reads back to the same
    double, so an engine state survives the round trip bit for bit. Non-finite floats
    are refused (``ValueError``): they have no JSON spelling.
    """
    data = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, **body}
    data["sha256"] = _checksum(data)
    text = json.dumps(data, indent=1, allow_nan=False) + "\n"
    write_text_atomic(path, text)


def read_checkpoint(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and verify a checkpoint written by :func:`write_checkpoint`.

    Raises:
        CheckpointError: the file is missing, unreadable, not JSON, of another format
            or version, or fails its checksum.
    """
    path = Path(path)
    try:
        text = read_limited(path, MAX_CHECKPOINT_BYTES).decode("utf-8")
    except FileNotFoundError:
        raise CheckpointError(f"{path} is missing") from None
    except FileRefused as exc:
        raise CheckpointError(f"{path} {exc.reason}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CheckpointError(f"{path} cannot be read: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CheckpointError(f"{path} is corrupt (not valid JSON: {exc})") from None
    if not isinstance(data, dict) or data.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not a billiard checkpoint")
    version = data.get("version")
    if isinstance(version, bool) or version not in READABLE_VERSIONS:
        readable = " and ".join(map(str, READABLE_VERSIONS))
        raise CheckpointError(
            f"{path} has checkpoint version {version!r}; this version of "
            f"billiard reads versions {readable}"
        )
    stored = data.pop("sha256", None)
    try:
        expected = _checksum(data)
    except ValueError:
        expected = None
    if stored != expected:
        raise CheckpointError(f"{path} is corrupt (its checksum does not match its content)")
    return data
