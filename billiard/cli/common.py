"""What every command shares: the one-line user error and small helpers."""

from __future__ import annotations

import argparse
import contextlib
import errno
import os
import sys
from pathlib import Path


class UserError(Exception):
    """An error to report in one line, without a traceback."""


def _note(line: str) -> None:
    print(f"billiard: note: {line}", file=sys.stderr)


def add_set_argument(parser: argparse.ArgumentParser, help: str) -> None:
    """The repeatable ``--set KEY=VALUE`` scene override every scene command takes."""
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help=help)


#: Longest name of one file or folder (bytes) where the file system does not say:
#: 255 on ext4, XFS, Btrfs, APFS and NTFS.
NAME_MAX = 255
#: Characters of an over-long name shown in a message (the rest is elided).
_SHOWN = 40


def _name_max(path: Path) -> int:
    """The file system's limit on one name, asked of the nearest folder that exists."""
    probe = path.absolute()
    while True:
        with contextlib.suppress(OSError, ValueError):
            if probe.is_dir():
                return os.pathconf(probe, "PC_NAME_MAX")
        if probe == probe.parent:
            return NAME_MAX
        probe = probe.parent


def name_too_long(path: str | os.PathLike[str], option: str | None = None) -> str | None:
    """Why ``path`` cannot be a file's or folder's path, in one line, when one of its
    names is longer than the file system allows (the error ``File name too long``);
    else None. ``option`` (e.g. ``--out``) is named in the message."""
    path = Path(path)
    limit = _name_max(path)
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > limit:
            shown = part if len(part) <= _SHOWN else f"{part[:_SHOWN]}..."
            where = f"{option} " if option else ""
            return (
                f"{where}{shown}: a name of {size} bytes in the path; this file system allows "
                f"at most {limit} per file or folder name (file name too long)"
            )
    return None


def long_name_error(exc: OSError) -> UserError | None:
    """The one-line error for an ``OSError`` of a path with an over-long name
    (``ENAMETOOLONG``: a file or folder name, or the whole path, beyond the file
    system's limit), else None."""
    if exc.errno != errno.ENAMETOOLONG:
        return None
    filename = exc.filename if exc.filename is not None else ""
    why = name_too_long(os.fsdecode(filename)) if filename else None
    if why is not None:
        return UserError(why)
    shown = str(filename) if len(str(filename)) <= _SHOWN else f"{str(filename)[:_SHOWN]}..."
    return UserError(
        f"{shown}: the path is longer than this file system allows (file name too long)"
    )


def check_output_folder(folder: str | os.PathLike[str], option: str) -> None:
    """Refuse, before any work, an output folder that cannot be created.

    The folders missing on the way are created and removed again (what can be created is
    only known by trying: permissions do not tell, e.g. ``/proc/nope`` as root).

    Raises:
        UserError: ``folder`` (or a file in its place) cannot be created or is not a
            folder; the message names the option, the folder and the reason.
    """
    why = name_too_long(folder, option)
    if why is not None:
        raise UserError(why)
    path = Path(folder)
    missing: list[Path] = []
    probe = path
    while not probe.exists() and probe != probe.parent:
        missing.append(probe)
        probe = probe.parent
    if path.exists() and not path.is_dir():
        raise UserError(f"{option} {path}: it is not a folder")
    if not probe.is_dir():  # a file where a folder on the way should be
        raise UserError(f"{option} {path}: {probe} is not a folder")
    try:
        for part in reversed(missing):
            part.mkdir()
    except OSError as exc:
        reason = exc.strerror or str(exc)
        where = "" if exc.filename in (None, str(path)) else f" ({exc.filename})"
        raise UserError(f"{option} {path}: cannot create the folder: {reason}{where}") from None
    finally:
        # leave no trace: the folders are made when the command writes into them
        for part in missing:
            with contextlib.suppress(OSError):
                part.rmdir()
