"""Stopping a streamed run (``billiard/engine/interrupt.py``): inside
``signals_deferred`` SIGINT and SIGTERM become a stop request, a second signal raises
KeyboardInterrupt at once, an application's own or ignored handler is left alone, and
the handlers in force before are back afterwards, however the run ends.

The signals are raised in this process: every test starts from Python's default
handlers (the fixture ``default_handlers``) and gets the previous ones back, and SIGTERM is only
raised where a test has checked that a Python handler catches it."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator

import pytest

from billiard.engine.interrupt import RunInterrupted, StopRequest, signal_after, signals_deferred

DEFAULTS = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}


@pytest.fixture(autouse=True)
def default_handlers() -> Iterator[None]:
    """Python's default handlers during the test, the previous ones after it."""
    previous = {sig: signal.getsignal(sig) for sig in DEFAULTS}
    for sig, handler in DEFAULTS.items():
        signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _raise(sig: int) -> None:
    """Raise ``sig`` in this process, unless its default action would end the test run."""
    assert signal.getsignal(sig) not in (signal.SIG_DFL, None), "no handler to catch it"
    signal.raise_signal(sig)


def _defaults_in_force() -> bool:
    return all(signal.getsignal(sig) is handler for sig, handler in DEFAULTS.items())


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_becomes_a_stop_request(sig):
    request = StopRequest()
    assert request.signum == 0
    with signals_deferred(request):
        _raise(sig)  # no KeyboardInterrupt: the run goes on to its next impact
        assert request.signum == sig
    assert _defaults_in_force()


def test_a_second_signal_interrupts_at_once():
    request = StopRequest()
    with pytest.raises(KeyboardInterrupt), signals_deferred(request):
        _raise(signal.SIGTERM)
        assert request.signum == signal.SIGTERM
        _raise(signal.SIGINT)
        pytest.fail("the second signal did not interrupt")
    assert request.signum == signal.SIGTERM  # the first signal is what the request says
    assert _defaults_in_force()


def test_the_previous_handlers_are_back_when_the_run_fails():
    request = StopRequest()
    with pytest.raises(RuntimeError, match="the run failed"), signals_deferred(request):
        assert not _defaults_in_force()
        raise RuntimeError("the run failed")
    assert _defaults_in_force()
    # and they act again: Ctrl-C after the run is an ordinary KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        signal.raise_signal(signal.SIGINT)
    assert request.signum == 0


def test_an_applications_handler_and_an_ignored_signal_are_left_alone():
    calls: list[int] = []

    def own(signum, frame) -> None:
        calls.append(signum)

    signal.signal(signal.SIGINT, own)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    request = StopRequest()
    with signals_deferred(request):
        assert signal.getsignal(signal.SIGINT) is own
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
        signal.raise_signal(signal.SIGINT)
        signal.raise_signal(signal.SIGTERM)  # ignored: safe to raise
    assert calls == [signal.SIGINT]
    assert request.signum == 0
    assert signal.getsignal(signal.SIGINT) is own
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN


def test_outside_the_main_thread_no_handler_is_touched():
    # Python lets only the main thread install handlers: a run in another thread
    # keeps the process's handlers (and does not fail)
    seen: dict[int, object] = {}
    failures: list[BaseException] = []

    def run() -> None:
        try:
            with signals_deferred(StopRequest()):
                seen.update({sig: signal.getsignal(sig) for sig in DEFAULTS})
        except BaseException as exc:  # reported below, in the test's thread
            failures.append(exc)

    thread = threading.Thread(target=run)
    thread.start()
    thread.join(10.0)
    assert not failures
    assert seen == DEFAULTS
    assert _defaults_in_force()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_after_sends_the_signal_right_after_its_impact(sig):
    request = StopRequest()
    hook = signal_after(3, sig) if sig != signal.SIGINT else signal_after(3)
    with signals_deferred(request):
        assert signal.getsignal(sig) not in (signal.SIG_DFL, None)  # caught, not fatal
        for n in (1, 2):
            hook(n)
            assert request.signum == 0, n
        hook(3)
        assert request.signum == sig
        request.signum = 0
        hook(4)  # only after impact 3
        assert request.signum == 0


def test_run_interrupted_is_a_keyboard_interrupt_with_the_runs_place(tmp_path):
    error = RunInterrupted(signal.SIGTERM, rows=120, checkpoint_rows=118, out_dir=tmp_path)
    assert isinstance(error, KeyboardInterrupt)  # what a caller's Ctrl-C handling catches
    assert str(error) == f"interrupted by signal {int(signal.SIGTERM)}"
    assert (error.signum, error.rows, error.checkpoint_rows, error.out_dir) == (
        signal.SIGTERM,
        120,
        118,
        tmp_path,
    )
    plain = RunInterrupted(signal.SIGINT)
    assert (plain.rows, plain.checkpoint_rows, plain.out_dir) == (0, 0, None)
