"""The notices of billiard.jit: a block that compiles billiard's functions (still
running after COMPILE_NOTICE_AFTER seconds) names what it compiles (a kernel family, a
curve's wall functions) and, when long, how long it took; a start from numba's cache
says nothing."""

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
    """No family announced yet in this process, short delays, no compile of every
    kernel at the first block (tests/engine/test_compile_all.py tests that)."""
    monkeypatch.setattr(jit, "_announced", set())
    monkeypatch.setattr(jit, "_compile_all_called", True)
    monkeypatch.setattr(jit, "COMPILE_NOTICE_AFTER", 0.05)


def busy(function, seconds, inner=()):
    """A block of ``seconds`` announced for ``function`` (as a first call that
    compiles), with the blocks ``inner`` (function, seconds) within it."""
    with jit.compiling(function):
        for other, length in inner:
            busy(other, length)
        time.sleep(seconds)


@compiled
def test_a_long_block_names_its_family_and_function_once(capsys, fresh_notices, monkeypatch):
    from billiard.kernels import locate, loop

    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", float("inf"))  # no end lines
    busy(loop.run_chunk, 0.3, inner=[(locate.locate, 0.1)])
    busy(loop.run_chunk, 0.3)  # again (other argument types): named once
    assert capsys.readouterr().err.splitlines() == [
        "billiard: compiling the impact loop with numba (billiard.kernels.loop.run_chunk); "
        "cached for later runs"
    ]


@compiled
def test_a_short_block_says_nothing(capsys, fresh_notices):
    from billiard.kernels import loop

    busy(loop.run_chunk, 0.0)  # a load from the cache
    assert capsys.readouterr().err == ""
    assert "the impact loop" not in jit._announced


@compiled
def test_a_long_compile_says_how_long_it_took(capsys, fresh_notices, monkeypatch):
    from billiard.kernels import contact, rest

    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", 0.2)
    busy(rest.offset_heights, 0.3)
    busy(contact.run_phase, 0.3, inner=[(rest.offset_heights, 0.1)])
    busy(contact.run_phase, 0.1)  # announced, and shorter than COMPILED_NOTICE_AFTER
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" with numba")[0] for line in lines[::2]] == [
        "billiard: compiling the resting-position scan",
        "billiard: compiling the contact phases (rolling, sliding)",
    ]
    assert [line.rsplit(" in ", 1)[0] for line in lines[1::2]] == [
        "billiard: compiled the resting-position scan",
        "billiard: compiled the contact phases (rolling, sliding)",
    ]
    for line in lines[1::2]:
        seconds = line.rsplit(" in ", 1)[1]
        assert seconds.endswith(" s") and float(seconds[:-2]) >= 0.2


@compiled
def test_blocks_in_other_threads_at_the_same_time_say_nothing(capsys, fresh_notices, monkeypatch):
    from billiard.kernels import float_text

    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", 0.0)
    threads = [threading.Thread(target=busy, args=(float_text.format_rows, 0.3)) for _ in range(3)]
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
    assert jit.compile_family(busy) is None  # not billiard's


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
