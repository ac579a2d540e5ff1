"""Stopping a streamed run cleanly: SIGINT (Ctrl-C) and SIGTERM become a stop request
that the run loop honours at the next impact boundary, where the files match the engine
state exactly."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

__all__ = ["RunInterrupted", "StopRequest", "signal_after", "signals_deferred"]


class RunInterrupted(KeyboardInterrupt):
    """A streamed run stopped by SIGINT or SIGTERM. Its files are complete up to
    ``rows`` impacts; ``checkpoint_rows`` (normally equal) is where a resume continues
    from.

    Attributes:
        signum: the signal (``signal.SIGINT`` or ``signal.SIGTERM``).
        rows: impacts kept in the CSV file.
        checkpoint_rows: impacts the checkpoint describes.
        out_dir: the run directory.
    """

    def __init__(
        self,
        signum: int,
        rows: int = 0,
        checkpoint_rows: int = 0,
        out_dir: Path | None = None,
    ):
        super().__init__(f"interrupted by signal {signum}")
        self.signum = signum
        self.rows = rows
        self.checkpoint_rows = checkpoint_rows
        self.out_dir = out_dir


class StopRequest:
    """Set by the signal handler of a streamed run; the loop looks at it once per impact."""

    __slots__ = ("signum",)

    def __init__(self) -> None:
        self.signum = 0


@contextlib.contextmanager
def signals_deferred(request: StopRequest) -> Iterator[None]:
    """Turn SIGINT and SIGTERM into a stop request for the duration of a run (main
    thread only; a signal that is ignored or has an application's own handler is left
    alone). A second signal raises KeyboardInterrupt at once."""
    installed: dict[int, Any] = {}

    def handler(signum: int, frame: Any) -> None:
        if request.signum:
            raise KeyboardInterrupt
        request.signum = signum

    if threading.current_thread() is threading.main_thread():
        for sig, default in (
            (signal.SIGINT, signal.default_int_handler),
            (signal.SIGTERM, signal.SIG_DFL),
        ):
            with contextlib.suppress(ValueError, OSError):
                if signal.getsignal(sig) is default:
                    installed[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, previous in installed.items():
            signal.signal(sig, previous)


def signal_after(impact: int, signum: int = signal.SIGINT) -> Callable[[int], None]:
    """An ``on_record`` hook that makes the process send itself ``signum`` right after
    impact ``impact``: interruptions (Ctrl-C, SIGTERM, SIGKILL) tested at an exact place."""
    import os

    def hook(n: int) -> None:
        if n == impact:
            os.kill(os.getpid(), signum)

    return hook
