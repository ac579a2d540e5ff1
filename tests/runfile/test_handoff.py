"""Work handed to a thread of its own (``billiard/runfile/handoff.py``): items are worked
on in order on one thread; the queue is bounded; an error is kept until the owner raises
it, once, and the items handed over after it are dropped meanwhile; an owner dropped
without ``stop()`` ends its thread."""

from __future__ import annotations

import gc
import itertools
import threading
import time

import pytest

from billiard.runfile.handoff import Handoff

_names = itertools.count()


class Owner:
    """Records what it was handed and on which thread; fails on the items in ``fail``;
    sets ``entered`` and waits for ``gate`` in each item."""

    def __init__(self, size: int = 4, fail: tuple[int, ...] = ()):
        self.done: list[int] = []
        self.threads: set[int] = set()
        self.fail = fail
        self.gate = threading.Event()
        self.gate.set()
        self.entered = threading.Event()
        self.name = f"handoff-test-{next(_names)}"
        self.handoff = Handoff(self, "take", size, self.name)

    def take(self, item: int) -> None:
        self.entered.set()
        self.gate.wait(10.0)
        self.threads.add(threading.get_ident())
        if item in self.fail:
            raise ValueError(f"item {item} refused")
        self.done.append(item)


def _thread(name: str) -> threading.Thread | None:
    return next((t for t in threading.enumerate() if t.name == name), None)


def test_items_are_worked_on_in_order_on_one_other_thread():
    owner = Owner(size=3)
    assert _thread(owner.name) is None  # started by the first item
    for item in range(500):
        owner.handoff.put(item)
    owner.handoff.drain()
    assert owner.done == list(range(500))
    assert len(owner.threads) == 1 and threading.get_ident() not in owner.threads
    assert _thread(owner.name) is not None
    owner.handoff.stop()
    assert _thread(owner.name) is None
    owner.handoff.raise_error()  # no error: nothing raised


def test_stop_works_on_what_was_handed_over_first():
    owner = Owner()
    owner.gate.clear()
    for item in range(4):
        owner.handoff.put(item)
    assert owner.done == []
    owner.gate.set()
    owner.handoff.stop()
    assert owner.done == [0, 1, 2, 3]


def test_the_queue_is_bounded():
    owner = Owner(size=2)
    owner.gate.clear()
    owner.handoff.put(0)
    assert owner.entered.wait(10.0)  # the thread has taken item 0 and waits in it
    owner.handoff.put(1)
    owner.handoff.put(2)
    assert owner.handoff.full()  # items 1 and 2 wait: a queue of two is full
    blocked = threading.Thread(target=owner.handoff.put, args=(3,))
    blocked.start()
    blocked.join(0.2)
    assert blocked.is_alive()  # a producer that gets ahead waits
    owner.gate.set()
    blocked.join(10.0)
    assert not blocked.is_alive()
    owner.handoff.stop()
    assert owner.done == [0, 1, 2, 3]
    assert not owner.handoff.full()


def test_an_error_is_raised_once_and_later_items_are_dropped():
    owner = Owner(fail=(3,))
    for item in range(10):
        owner.handoff.put(item)
    owner.handoff.drain()
    # items 4 to 9 were handed over after the error and dropped, not worked on
    assert owner.done == [0, 1, 2]
    with pytest.raises(ValueError, match="item 3 refused"):
        owner.handoff.raise_error()
    owner.handoff.raise_error()  # once: it now counts as raised
    assert owner.handoff.error is None
    # the error raised, what is handed over afterwards is worked on again
    owner.handoff.put(10)
    owner.handoff.stop()
    assert owner.done == [0, 1, 2, 10]


def test_take_error_waits_for_the_items_before_it_to_be_dropped():
    owner = Owner(size=8, fail=(0,))
    owner.gate.clear()
    for item in range(5):
        owner.handoff.put(item)
    owner.gate.set()
    deadline = time.monotonic() + 10.0
    while owner.handoff.error is None and time.monotonic() < deadline:
        time.sleep(0.001)  # the thread fails on item 0
    error = owner.handoff.take_error()
    assert isinstance(error, ValueError) and str(error) == "item 0 refused"
    assert owner.handoff.take_error() is None
    # items 1 to 4 were dropped before take_error returned: none of them is worked on
    # once the error no longer stands, only what is handed over afterwards
    owner.handoff.put(5)
    owner.handoff.stop()
    assert owner.done == [5]


def test_a_base_exception_is_kept_too():
    # KeyboardInterrupt in the work surfaces in the owner's thread, as if raised there
    class Interrupting(Owner):
        def take(self, item: int) -> None:
            raise KeyboardInterrupt

    owner = Interrupting()
    owner.handoff.put(1)
    owner.handoff.drain()
    with pytest.raises(KeyboardInterrupt):
        owner.handoff.raise_error()
    owner.handoff.stop()


def test_an_owner_dropped_without_stop_ends_its_thread():
    owner = Owner()
    name = owner.name
    owner.handoff.put(1)
    owner.handoff.drain()
    thread = _thread(name)
    assert thread is not None and thread.is_alive()
    del owner
    gc.collect()
    thread.join(10.0)
    assert not thread.is_alive()
