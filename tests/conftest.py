"""Settings every test assumes."""

from __future__ import annotations

import signal


def pytest_configure(config) -> None:
    """Python's own Ctrl-C handler, as in a run started from a terminal. A shell without
    job control starts a background command (``pytest &``) with SIGINT ignored, and a
    run leaves an ignored SIGINT alone (billiard.engine.interrupt), so the tests that
    interrupt a run with SIGINT would see no stop."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
