"""The notices of billiard.jit: a compile of billiard's functions names what it
compiles (a kernel family, a curve's wall functions) and, when long, how long it took; a
start from numba's cache says nothing."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


@pytest.fixture
def fresh_notices(monkeypatch):
    """No family announced yet in this process, no compile in progress."""
    monkeypatch.setattr(jit, "_announced", set())
    monkeypatch.setattr(jit, "_compiling", [])


def compile_signal(function, inner=()):
    """numba's "numba:compile" signals of a compile of ``function`` that compiles the
    functions ``inner`` within it (as a kernel compiles the kernels it calls)."""
    from numba.core import event

    with event.trigger_event("numba:compile", data={"dispatcher": function}):
        for other in inner:
            compile_signal(other)


@compiled
def test_a_compile_names_its_family_and_function_once(capsys, fresh_notices, monkeypatch):
    from billiard.kernels import locate, loop

    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", float("inf"))  # no end lines
    compile_signal(loop.run_chunk, inner=[locate.locate, loop.step])
    compile_signal(loop.run_chunk)  # again (other argument types): named once
    assert capsys.readouterr().err.splitlines() == [
        "billiard: compiling the impact loop with numba (billiard.kernels.loop.run_chunk); "
        "cached for later runs"
    ]


@compiled
def test_a_long_compile_says_how_long_it_took(capsys, fresh_notices, monkeypatch):
    from billiard.kernels import contact, rest

    monkeypatch.setattr(jit, "COMPILED_NOTICE_AFTER", 0.0)  # every compile is "long"
    compile_signal(rest.offset_heights)
    compile_signal(contact.run_phase, inner=[rest.offset_heights])
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
        assert seconds.endswith(" s") and float(seconds[:-2]) >= 0.0


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
    assert jit.compile_family(compile_signal) is None  # not billiard's


@compiled
def test_other_compiles_are_not_announced(capsys, fresh_notices):
    import numba

    @numba.njit
    def twice(x):
        return 2 * x

    compile_signal(twice)
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


@compiled
def test_a_warm_start_loads_no_registries_and_can_still_compile(tmp_path):
    """Loading the kernels from the cache skips numba's registries (its linear algebra
    among them); a function compiled afterwards in the same process still compiles and
    runs (the compiler loads them itself)."""
    script = (
        "import sys; from billiard.engine.simulation import Simulation; "
        "from billiard.runfile.record import MemoryRecorder; "
        "from billiard.scene.scene import load_scene; "
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
