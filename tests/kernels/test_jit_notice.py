"""The notices of billiard.jit: a block in which numba compiles billiard's functions
(numba is asked: a miss of its cache) names what it compiles (a kernel family, a curve's
wall functions) and, when long, how long the compile took; a start from numba's cache
says nothing, however long the block takes."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


@pytest.fixture
def fresh_notices(monkeypatch):
    """No family announced yet in this process, no compile of every kernel at the
    first block (tests/engine/test_compile_all.py tests that)."""
    monkeypatch.setattr(jit, "_announced", set())
    monkeypatch.setattr(jit, "_compile_all_called", True)


def kernel(module: str, name: str = "kernel"):
    """A new numba function, not cached, that billiard.jit takes for one of
    ``module``'s: its first call for a kind of argument compiles."""
    import numba

    def fn(x):
        return 2.0 * x + 1.0

    fn.__module__, fn.__qualname__ = module, name
    return numba.njit(fn)


def ended_in(line: str) -> float:
    """The seconds of a COMPILED_NOTICE line."""
    seconds = line.rsplit(" in ", 1)[1]
    assert seconds.endswith(" s"), line
    return float(seconds[:-2])


@compiled
def test_numba_is_asked_whether_it_compiles():
    k = kernel("billiard.kernels.loop")
    ask = jit.compiles(k)
    assert ask() is False
    assert k(1.0) == 3.0  # compiles: a miss, then the machine code in place
    assert ask() is None
    again = jit.compiles(k)
    assert k(2.0) == 5.0  # the same kind of argument: nothing compiled
    assert again() is False
    assert k(2) == 5.0  # an int: another compile
    assert again() is None
    assert jit.compiles(k.py_func)() is False  # not a dispatcher: never


@compiled
def test_a_compile_names_its_family_and_function_once(capsys, fresh_notices, monkeypatch):
    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", float("inf"))  # no end lines
    k = kernel("billiard.kernels.loop", "run_chunk")
    with jit.compiling(k):
        k(1.0)
    with jit.compiling(k):
        k(1)  # again (another type of argument): named once
    assert capsys.readouterr().err.splitlines() == [
        "billiard: compiling the impact loop with numba (billiard.kernels.loop.run_chunk); "
        "cached for later runs"
    ]


@compiled
def test_a_slow_block_that_compiles_nothing_says_nothing(capsys, fresh_notices):
    """A block that loads or reuses machine code says nothing, even where it lasts
    long (a loaded machine, or a first call that runs long)."""
    k = kernel("billiard.kernels.loop")
    k(1.0)  # compiled before the block
    with jit.compiling(k):
        assert k(2.0) == 5.0
        time.sleep(0.6)
    assert capsys.readouterr().err == ""
    assert "the impact loop" not in jit._announced


@compiled
def test_a_compile_says_how_long_the_compile_took(capsys, fresh_notices, monkeypatch):
    """The end line gives the compile's seconds, not the block's: a block that
    compiles, then runs 1.5 s, reports well under its length."""
    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", 0.0)
    k = kernel("billiard.kernels.contact", "run_phase")
    began = time.perf_counter()
    with jit.compiling(k):
        k(1.0)
        time.sleep(1.5)
    block = time.perf_counter() - began
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == (
        "billiard: compiling the contact phases (rolling, sliding) with numba "
        "(billiard.kernels.contact.run_phase); cached for later runs"
    )
    assert lines[1].startswith("billiard: compiled the contact phases (rolling, sliding) in ")
    assert len(lines) == 2
    assert 0.0 < ended_in(lines[1]) < block - 1.0


@compiled
def test_a_short_compile_ends_without_a_line(capsys, fresh_notices, monkeypatch):
    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", float("inf"))
    k = kernel("billiard.kernels.rest", "offset_heights")
    with jit.compiling(k):
        k(1.0)
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("billiard: compiling the resting-position scan with numba")


@compiled
def test_blocks_in_other_threads_at_the_same_time_say_nothing(capsys, fresh_notices, monkeypatch):
    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", 0.0)
    k = kernel("billiard.kernels.float_text", "format_rows")
    start = threading.Barrier(3)

    def block():
        start.wait()
        with jit.compiling(k):
            k(1.0)
            time.sleep(0.2)  # the blocks overlap

    threads = [threading.Thread(target=block) for _ in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" with numba")[0].split(" in ")[0] for line in lines] == [
        "billiard: compiling the CSV number formatting",
        "billiard: compiled the CSV number formatting",
    ]


def test_the_families_name_the_kernels_and_a_curves_wall_functions():
    from billiard.generated.curves import wedge

    from billiard.geometry.curves import curve_module
    from billiard.kernels import fixed_step, float_text, loop, vertex

    assert jit.compile_family(wedge.f_0) == "the wall functions of curve 'wedge'"
    expression = curve_module("3*x**2 + 0.005")  # derived into BILLIARD_HOME if new
    family = jit.compile_family(expression.f_0)
    assert family == f"the wall functions of the curve f(x) = {expression.EXPRESSION}"
    for function, family in (
        (fixed_step.locate, "the rk4 method's fixed steps"),
        (loop.run_chunk_fixed, "the impact loop of the rk4 method"),
        (float_text.format_rows, "the CSV number formatting"),
        (vertex.begin, "the hold in a vertex"),
    ):
        assert jit.compile_family(getattr(function, "py_func", function)) == family
    assert jit.compile_family(ended_in) is None  # not billiard's


@compiled
def test_other_compiles_are_not_announced(capsys, fresh_notices):
    import numba

    @numba.njit
    def twice(x):
        return 2 * x

    with jit.compiling(twice):
        assert twice(3) == 6
        time.sleep(0.2)
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
        "from billiard.engine.simulation import Simulation; "
        "from billiard.runfile.record import MemoryRecorder; "
        "from billiard.scene.scene import load_scene; "
        "Simulation(load_scene('wedge-6.6hz')).run(5, MemoryRecorder())"
    )
    runs = two_compiled_runs(script, tmp_path)
    assert runs[1].stderr == ""  # the first run filled the cache if it was empty


COLD_THEN_WARM = """
import sys, time
from billiard import jit
from billiard.generated.curves import parabola
from billiard.geometry.wall_functions import WallFunction
from billiard.kernels.decorators import _ulp_compiled
jit.on_first_compile(None)  # this kernel alone, not every kernel together
jit.COMPILED_NOTICE_AFTER = 0.0
with jit.compiling(_ulp_compiled):
    assert _ulp_compiled(1.0) == 2.0**-52
    time.sleep(float(sys.argv[1]))  # a loaded machine: the block lasts this long
WallFunction(parabola.f_0)  # a curve's wall function (numba.cfunc)
"""


@compiled
def test_a_compile_is_announced_and_a_slow_load_from_the_cache_is_not(tmp_path):
    """In an empty cache (NUMBA_CACHE_DIR) a kernel and a wall function compile, with
    their lines; in the next process they load from the cache, within a block that
    lasts a second as on a loaded machine, and nothing is printed."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env["BILLIARD_HOME"] = str(tmp_path / "home")
    env.pop("NUMBA_DISABLE_JIT", None)
    runs = []
    for slow in ("0", "1.0"):
        done = subprocess.run(
            [sys.executable, "-c", COLD_THEN_WARM, slow], env=env, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr
        runs.append(done.stderr.splitlines())
    cold, warm = runs
    assert cold[0] == jit.COMPILE_NOTICE.format(
        family="the engine's kernels (billiard.kernels.decorators)",
        function="billiard.kernels.decorators._ulp_compiled",
    )
    assert cold[1].startswith("billiard: compiled the engine's kernels (billiard.kernels.")
    assert 0.0 < ended_in(cold[1]) < 60.0
    assert cold[2] == jit.COMPILE_NOTICE.format(
        family="the wall functions of curve 'parabola'",
        function="billiard.generated.curves.parabola.f_0",
    )
    assert len(cold) in (3, 4), cold  # and the wall function's seconds
    assert warm == []


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
