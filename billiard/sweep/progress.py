"""Progress of a sweep on stderr: a bar with rate and ETA on a terminal, otherwise one
line every few seconds (for logs and batch jobs)."""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

from billiard.engine.progress import duration_text

__all__ = ["SweepProgress"]


class SweepProgress:
    """Counts finished points and reports them.

    Args:
        total: points in the sweep.
        done: points already finished before this session (resume).
        stream: where to write (default stderr); a terminal gets a bar redrawn in place.
        interval: seconds between lines when the stream is not a terminal.
    """

    def __init__(
        self, total: int, done: int = 0, stream: TextIO | None = None, interval: float = 5.0
    ):
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.total = total
        self.done = done
        self.started_with = done
        self.impacts = 0
        self.interval = interval
        self.started = time.perf_counter()
        self.last = self.started if not self.tty else 0.0
        self.active = False

    def point(self, record: dict[str, Any]) -> None:
        self.chunk(1, int(record.get("total_impacts") or 0))

    def chunk(self, points: int, impacts: int) -> None:
        """A finished chunk of ``points`` points that simulated ``impacts`` impacts."""
        self.done += points
        self.impacts += impacts
        self.tick(force=self.tty)

    def text(self) -> str:
        elapsed = max(time.perf_counter() - self.started, 1e-9)
        new = self.done - self.started_with
        rate = new / elapsed
        left = self.total - self.done
        eta = left / rate if rate > 0 else float("inf")
        return (
            f"{self.done}/{self.total} points, {rate:.3g} points/s, "
            f"{self.impacts / elapsed:,.0f} impacts/s, "
            f"elapsed {duration_text(elapsed)}, ETA {duration_text(eta) if left else '0 s'}"
        )

    def tick(self, force: bool = False) -> None:
        now = time.perf_counter()
        if not force and now - self.last < (0.5 if self.tty else self.interval):
            return
        self.last = now
        if self.tty:
            width = 30
            filled = int(width * self.done / self.total) if self.total else width
            self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.text()} ")
            self.active = True
        else:
            self.stream.write(f"billiard sweep: {self.text()}\n")
        self.stream.flush()

    def close(self) -> None:
        if self.tty and self.active:
            self.stream.write("\n")
            self.stream.flush()
            self.active = False
