"""The one-line notices of billiard.jit: a compile of the kernels says so once; a start
from numba's cache says nothing."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


@compiled
def test_a_compile_of_the_kernels_is_announced_once(capsys, monkeypatch):
    from numba.core import event

    from billiard.kernels import loop

    monkeypatch.setattr(jit, "_compile_noticed", False)
    for dispatcher in (loop.run_chunk, loop.run_chunk):
        with event.trigger_event("numba:compile", data={"dispatcher": dispatcher}):
            pass
    assert capsys.readouterr().err.splitlines() == [jit.COMPILE_NOTICE]


@compiled
def test_other_compiles_are_not_announced(capsys, monkeypatch):
    import numba
    from numba.core import event

    monkeypatch.setattr(jit, "_compile_noticed", False)

    @numba.njit
    def twice(x):
        return 2 * x

    with event.trigger_event("numba:compile", data={"dispatcher": twice}):
        pass
    assert capsys.readouterr().err == ""


def two_compiled_runs(script: str, tmp_path) -> list[subprocess.CompletedProcess]:
    """``script`` run twice in fresh interpreters with numba enabled (the first fills
    the cache if it is empty); both must succeed."""
    env = {**os.environ, "BILLIARD_HOME": str(tmp_path)}
    env.pop("NUMBA_DISABLE_JIT", None)
    runs = [
        subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
        for _ in range(2)
    ]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr
    return runs


@compiled
def test_a_warm_start_prints_nothing(tmp_path):
    script = (
        "from billiard.engine import Simulation; from billiard.record import MemoryRecorder; "
        "from billiard.scene import load_scene; "
        "Simulation(load_scene('wedge-6.6hz')).run(5, MemoryRecorder())"
    )
    runs = two_compiled_runs(script, tmp_path)
    assert runs[1].stderr == ""  # the first run filled the cache if it was empty


@compiled
def test_a_warm_start_loads_no_registries_and_can_still_compile(tmp_path):
    """Loading the kernels from the cache skips numba's registries (its linear algebra
    among them); a function compiled afterwards in the same process still compiles and
    runs (the compiler loads them itself)."""
    script = (
        "import sys; from billiard.engine import Simulation; "
        "from billiard.record import MemoryRecorder; from billiard.scene import load_scene; "
        "Simulation(load_scene('wedge-6.6hz')).run(5, MemoryRecorder()); "
        "print('linalg' if 'numba.np.linalg' in sys.modules else 'light'); "
        "import numba, numpy; "
        "print(numba.njit(lambda a: numpy.sum(a))(numpy.full(3, 3.0)))"
    )
    runs = two_compiled_runs(script, tmp_path)
    assert runs[1].stdout.split() == ["light", "9.0"]


def test_missing_numba_is_announced_in_one_line():
    script = (
        "import sys; sys.modules['numba'] = None; from billiard import jit; "
        "assert not jit.ENABLED; jit.notice(); jit.notice()"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: numba unavailable"), lines
    assert "runs interpreted" in lines[0]
