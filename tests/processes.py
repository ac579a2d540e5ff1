"""Processes a test started, looked at through /proc (Linux): which are a process's
children, which are still running, and waiting for them to end; :func:`reaped` kills
those a test leaves running."""

from __future__ import annotations

import contextlib
import os
import signal
import time
from collections.abc import Iterator
from pathlib import Path

HAS_PROC = Path("/proc/self/stat").exists()


def _stat(pid: int) -> list[str]:
    """The fields of /proc/PID/stat after the command's name (state, parent, ...)."""
    return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid``."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parent = int(_stat(int(entry.name))[1])
            except (OSError, IndexError, ValueError):  # ended meanwhile
                continue
            if parent == pid:
                found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    """Is ``pid`` still running (a zombie has ended: only its exit status is left)?"""
    try:
        return _stat(pid)[0] != "Z"
    except (OSError, IndexError):
        return False


def ended_within(pids: list[int], since: float, seconds: float) -> list[int]:
    """Wait until the processes ``pids`` have ended, at most ``seconds`` after the
    ``time.monotonic()`` ``since``; returns those still running then."""
    while any(alive(pid) for pid in pids) and time.monotonic() < since + seconds:
        time.sleep(0.01)
    return [pid for pid in pids if alive(pid)]


@contextlib.contextmanager
def reaped() -> Iterator[list[int]]:
    """A list for the processes a test starts or finds; any still running at the end of
    the ``with`` block are killed."""
    pids: list[int] = []
    try:
        yield pids
    finally:
        for pid in pids:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
