"""The compile workers (billiard.engine.compile_all) end with the process that started
them: SIGTERM during a run's first compile stops the run and its workers at once, and a
starting process killed outright (SIGKILL) leaves no worker compiling on."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from billiard import jit
from billiard.engine import compile_all

pytestmark = [
    pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}"),
    pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc"),
]


def _stat(pid: int) -> list[str] | None:
    """The fields of /proc/PID/stat after the command's name (state, ppid, ...)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text.rpartition(")")[2].split()


def children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            fields = _stat(int(entry.name))
            if fields and fields[1] == str(pid):
                found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    """Running (a zombie has ended: it waits only for its exit status to be read)."""
    fields = _stat(pid)
    return fields is not None and fields[0] != "Z"


def compiling(argv: list[str], tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    """``argv`` started on an empty numba cache, once its two workers compile."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env["BILLIARD_HOME"] = str(tmp_path / "home")
    env.pop("NUMBA_DISABLE_JIT", None)
    parent = subprocess.Popen(
        argv, env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert parent.stderr.readline().rstrip("\n") == compile_all.ALL_NOTICE
    waited = time.monotonic() + 30
    while len(workers := children(parent.pid)) < len(compile_all.WORKERS):
        assert time.monotonic() < waited, "no workers"
        time.sleep(0.05)
    time.sleep(1.0)  # importing, compiling
    return parent, workers


def ended(workers: list[int], seconds: float) -> bool:
    waited = time.monotonic() + seconds
    while any(map(alive, workers)):
        if time.monotonic() > waited:
            return False
        time.sleep(0.05)
    return True


def test_sigterm_during_a_runs_first_compile_ends_it_and_its_workers(tmp_path):
    """``billiard run`` on an empty cache, SIGTERM while its workers compile: it ends
    within seconds (the signal's default action, before the run is under way), and
    so do its workers (the end of their pipe)."""
    argv = [sys.executable, "-m", "billiard.cli", "run", "wedge-6.6hz", "--collisions", "100",
            "--no-plot", "--out", "run"]  # fmt: skip
    parent, workers = compiling(argv, tmp_path)
    parent.send_signal(signal.SIGTERM)
    assert parent.wait(timeout=5) == -signal.SIGTERM
    assert ended(workers, 5.0)


DEFERRED = """
from billiard.engine.compile_all import compile_all
from billiard.engine.interrupt import RunInterrupted, StopRequest, signals_deferred
request = StopRequest()
try:
    with signals_deferred(request):
        compile_all()
except RunInterrupted as exc:
    print(f"interrupted by {exc.signum}, stop request {request.signum}")
"""


def test_a_stop_request_breaks_off_the_compile_and_ends_the_workers(tmp_path):
    """Under a run's handler (SIGTERM: a stop at the next impact, which would come after
    the compile), SIGTERM breaks off the compile: the request is made, RunInterrupted
    is raised, and the workers have ended before the process does."""
    parent, workers = compiling([sys.executable, "-c", DEFERRED], tmp_path)
    parent.send_signal(signal.SIGTERM)
    assert parent.wait(timeout=5) == 0, parent.stderr.read()
    assert not any(map(alive, workers))
    term = int(signal.SIGTERM)
    assert parent.stdout.read() == f"interrupted by {term}, stop request {term}\n"


def test_the_workers_end_when_the_process_that_started_them_is_killed(tmp_path):
    script = "from billiard.engine.compile_all import compile_all; compile_all()"
    parent, workers = compiling([sys.executable, "-c", script], tmp_path)
    parent.kill()
    parent.wait()
    assert ended(workers, 5.0)
