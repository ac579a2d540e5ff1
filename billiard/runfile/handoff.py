"""Work handed to one thread of its own, in order: :class:`Handoff`, through which a
streamed run file (:class:`billiard.runfile.stream.CsvRecorder`) formats and writes its rows
while the engine computes the next ones (both release the GIL while they compute).

The queue is bounded: a producer that gets ahead waits, so memory stays bounded. An
error raised by the work is kept until the owner asks for it (:meth:`Handoff.raise_error`)
and the items handed over after it are dropped meanwhile: the owner raises it at its
next call, and its caller stops there, as if the work had been done in its own thread.
"""

from __future__ import annotations

import queue
import threading
import weakref
from typing import Any

__all__ = ["Handoff"]


def _work(ref: weakref.ref[Any], method: str, items: queue.Queue[Any], handoff: Handoff) -> None:
    """The thread: ``owner.<method>(item)`` for each item in turn, until None (or until
    the owner is gone: the thread holds it only while working on an item)."""
    while True:
        item = items.get()
        try:
            if item is None:
                return
            owner = ref()
            if owner is not None and handoff.error is None:
                try:
                    getattr(owner, method)(item)
                except BaseException as exc:
                    handoff.error = exc
            del owner
        finally:
            items.task_done()


class Handoff:
    """Items for ``getattr(owner, method)``, called in order on one thread, started by
    the first item; at most ``size`` items wait (:meth:`put` waits beyond them)."""

    def __init__(self, owner: Any, method: str, size: int, name: str):
        self._ref = weakref.ref(owner)
        self._method = method
        self._name = name
        self._items: queue.Queue[Any] = queue.Queue(size)
        self._thread: threading.Thread | None = None
        #: the error the work raised, not yet raised by :meth:`raise_error`
        self.error: BaseException | None = None

    def full(self) -> bool:
        """Are as many items waiting as the queue holds?"""
        return self._items.full()

    def put(self, item: Any) -> None:
        """Hand ``item`` over (not None); waits while the queue is full."""
        if self._thread is None:
            thread = threading.Thread(
                target=_work,
                args=(self._ref, self._method, self._items, self),
                name=self._name,
                daemon=True,
            )
            thread.start()
            self._thread = thread
            # an owner dropped without stop() ends its thread
            weakref.finalize(self._ref(), self._items.put, None).atexit = False
        self._items.put(item)

    def drain(self) -> None:
        """Wait until every item handed over has been worked on (or dropped)."""
        if self._thread is not None:
            self._items.join()

    def take_error(self) -> BaseException | None:
        """The work's error, now counted as raised (None if there was none); waits
        until the items handed over before it are dropped, so that none is worked on."""
        if self.error is None:
            return None
        self.drain()
        error, self.error = self.error, None
        return error

    def raise_error(self) -> None:
        """Raise the work's error, once (without waiting for the thread)."""
        error = self.take_error()
        if error is not None:
            raise error

    def stop(self) -> None:
        """Work on what was handed over, then end the thread."""
        if self._thread is not None:
            self._items.put(None)
            self._thread.join()
            self._thread = None
