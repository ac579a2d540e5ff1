"""Worker processes that end with the process that started them.

A sweep's worker processes (and any helper process) hold a few hundred MB each; a
parent ended by SIGKILL (or a crash) runs no clean-up, and its workers would go on
computing for nobody, reparented to init. :func:`die_with_parent`, called first thing
in the worker, ends the worker when its parent ends.

On Linux the kernel does it (``prctl(PR_SET_PDEATHSIG, SIGKILL)``): at once, even while
the worker runs compiled code that holds the GIL. Elsewhere a daemon thread looks at the
parent's id every :data:`POLL` seconds. A base module: every wing may use it.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time

__all__ = ["POLL", "die_with_parent"]

#: Seconds between two looks at the parent where the kernel cannot watch it.
POLL = 0.25
#: prctl's option that sends the process a signal when its parent ends (linux/prctl.h).
_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """End this process (SIGKILL, or ``os._exit``) when the process ``parent`` ends (its
    parent's pid, as the parent saw it: ``os.getpid()`` there); at once if it ended
    already.

    On Linux the signal comes when the parent's *thread* that started this process
    ends: start workers from a thread that outlives them (as a process pool does, from
    the thread that submits to it).
    """
    if not _kernel_watches():
        threading.Thread(target=_watch, args=(parent,), name="die-with-parent", daemon=True).start()
    # the parent may have ended before the watch began: this process is someone else's
    if os.getppid() != parent:
        _end()


def _kernel_watches() -> bool:
    """Ask Linux to send this process SIGKILL when its parent ends; False elsewhere (or
    when the call fails)."""
    if not sys.platform.startswith("linux"):
        return False
    with contextlib.suppress(OSError, AttributeError, TypeError):
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    return False


def _watch(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(POLL)
    _end()


def _end() -> None:
    """End this process now, without clean-up (as SIGKILL would): its work is for a
    parent that is gone."""
    os._exit(1)
