"""``billiard.lifeline.die_with_parent``: a process ends with its parent, killed by
SIGKILL, through the kernel (Linux) or the watching thread (elsewhere, forced here); and
at once when its parent has ended before it asked."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from tests.processes import HAS_PROC, alive, ended_within, reaped

pytestmark = pytest.mark.skipif(not HAS_PROC, reason="needs /proc")

#: the child: watches its parent (``poll``: by the thread), says it is ready, waits
CHILD = """
import os, sys, threading, time
from billiard import lifeline
if sys.argv[1] == "poll":
    lifeline._kernel_watches = lambda: False
lifeline.die_with_parent(os.getppid())
watching = any(t.name == "die-with-parent" for t in threading.enumerate())
assert watching == (sys.argv[1] == "poll"), "the other way watches"
open(sys.argv[2], "w").close()
time.sleep(120)
"""
#: the parent: starts the child, says its pid, waits to be killed
PARENT = """
import subprocess, sys, time
child = subprocess.Popen([sys.executable, "-c", sys.argv[1], *sys.argv[2:]])
print(child.pid, flush=True)
time.sleep(120)
"""


@pytest.mark.parametrize("how", ["kernel", "poll"])
def test_a_process_ends_with_its_killed_parent(how, tmp_path):
    if how == "kernel" and not sys.platform.startswith("linux"):
        pytest.skip("the kernel watches the parent on Linux only")
    ready = tmp_path / "ready"
    with reaped() as pids:
        parent = subprocess.Popen(
            [sys.executable, "-c", PARENT, CHILD, how, str(ready)],
            stdout=subprocess.PIPE,
            text=True,
        )
        pids += [parent.pid, int(parent.stdout.readline())]
        deadline = time.monotonic() + 60
        while not ready.exists():
            assert alive(pids[1]) and time.monotonic() < deadline, "the child did not start"
            time.sleep(0.01)
        assert alive(pids[1])
        killed = time.monotonic()
        parent.kill()
        parent.wait()
        # the kernel at once; the thread within a look (lifeline.POLL = 0.25 s)
        assert not ended_within(pids[1:], killed, 1.0), "the child outlived its parent"


def test_a_process_whose_parent_is_gone_ends_at_once():
    code = "from billiard import lifeline; lifeline.die_with_parent(-1); print('alive')"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode != 0 and "alive" not in done.stdout
