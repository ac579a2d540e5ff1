"""What every command shares: the one-line user error and small helpers."""

from __future__ import annotations

import argparse
import contextlib
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


def check_output_folder(folder: str | os.PathLike[str], option: str) -> None:
    """Refuse, before any work, an output folder that cannot be created.

    The folders missing on the way are created and removed again (what can be created is
    only known by trying: permissions do not tell, e.g. ``/proc/nope`` as root).

    Raises:
        UserError: ``folder`` (or a file in its place) cannot be created or is not a
            folder; the message names the option, the folder and the reason.
    """
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
