"""Every kernel compiled together (billiard.engine.compile_all, billiard.jit's mark and
first-compile hook, the wall tables' one type): the mark follows the stamp, the hook runs
once before the first compile, and after one cold compile a process running another
scene compiles nothing."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from billiard import jit
from billiard.engine import compile_all

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    """numba's cache in a folder of its own, stamped for the kernels' sources."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    jit.refresh_kernel_cache()
    (folder,) = jit._cache_folders(jit._KERNELS)
    return folder


@compiled
def test_the_mark_says_all_compiled_until_the_sources_change(cache_dir):
    assert not jit.all_compiled()
    jit.mark_all_compiled()
    assert jit.all_compiled()
    mark = (cache_dir / jit.ALL_COMPILED_FILE).read_text(encoding="ascii")
    assert mark.startswith(jit.kernel_source_hash().hex()) and jit.numba.__version__ in mark
    # another source hash: the cache and the mark go, and nothing is all compiled
    (cache_dir / jit.STAMP_FILE).write_text("0" * 64 + "\n", encoding="ascii")
    assert not jit.all_compiled()
    assert jit.refresh_kernel_cache()
    assert not (cache_dir / jit.ALL_COMPILED_FILE).exists()
    assert not jit.all_compiled()


@compiled
def test_a_marked_cache_or_a_worker_starts_no_compile(cache_dir, monkeypatch, capsys):
    jit.mark_all_compiled()
    assert compile_all.compile_all() is False
    (cache_dir / jit.ALL_COMPILED_FILE).unlink()
    monkeypatch.setenv("BILLIARD_COMPILE_WORKER", "1")
    assert compile_all.compile_all() is False
    monkeypatch.delenv("BILLIARD_COMPILE_WORKER")
    (cache_dir / jit.STAMP_FILE).unlink()  # no stamp: numba cannot cache here
    assert not jit.cache_stamped()
    assert compile_all.compile_all() is False
    assert capsys.readouterr().err == ""


@compiled
def test_the_hook_runs_once_before_the_first_block(monkeypatch, capsys):
    from billiard.kernels import loop, rest

    calls = []
    monkeypatch.setattr(jit, "_compile_all", lambda: calls.append(jit._running))
    monkeypatch.setattr(jit, "_compile_all_called", False)
    monkeypatch.setattr(jit, "_announced", set())
    with jit.compiling(loop.run_chunk):
        with jit.compiling(rest.offset_heights):
            pass
    with jit.compiling(rest.offset_heights):
        pass
    assert calls == [0]  # once, outside any block
    assert capsys.readouterr().err == ""


@compiled
def test_a_block_in_another_thread_waits_for_the_hook(monkeypatch):
    import threading

    from billiard.kernels import rest

    events = []

    def hook():
        events.append("hook starts")
        time.sleep(0.3)
        events.append("hook ends")

    def block(name):
        with jit.compiling(rest.offset_heights):
            events.append(name)

    monkeypatch.setattr(jit, "_compile_all", hook)
    monkeypatch.setattr(jit, "_compile_all_called", False)
    first = threading.Thread(target=block, args=("first block",))
    first.start()
    time.sleep(0.1)  # within the hook
    block("second block")
    first.join()
    assert events[:2] == ["hook starts", "hook ends"]
    assert sorted(events[2:]) == ["first block", "second block"]


@compiled
def test_the_engine_registers_the_hook():
    assert jit._compile_all is compile_all.compile_all


@compiled
def test_curves_of_one_and_two_walls_give_the_kernels_one_type():
    from billiard.generated.curves import parabola, wedge

    from billiard.geometry.wall_functions import WALL_SLOTS, WallFunction, WallTable

    def table(module, walls):
        names = [[f"{n}_{i}" for i in range(walls)] for n in ("f", "df", "d2f")]
        return WallTable(tuple(WallFunction(getattr(module, n)) for n in row) for row in names)

    one, two = table(parabola, 1), table(wedge, 2)
    assert [len(row) for row in one] == [WALL_SLOTS] * 3
    assert all(row[1] is row[0] for row in one)  # the one wall, repeated
    assert one.numba_type == two.numba_type
    three = WallTable([(one[0][0],) * 3])
    assert len(three[0]) == 3 and three.numba_type != one.numba_type


PARENT = """
from billiard.engine import compile_all
compile_all.WORKERS = ((), ())  # two workers that import the package and run nothing
assert compile_all.compile_all()
"""
MARK = """
import os as _os
open(_os.path.join(_os.environ["MARKS"], "{name}-%d" % _os.getpid()), "w").close()
"""


@compiled
def test_the_workers_import_the_package_of_the_process_that_starts_them(tmp_path):
    """The starting process imports a copy of the project (``copy``, as an installed
    copy) from a folder holding another ``billiard/`` (``checkout``, as a source
    checkout beside an installed copy): both workers import the first, as it did."""
    root = Path(__file__).resolve().parents[2]
    copy, checkout, marks = tmp_path / "copy", tmp_path / "checkout", tmp_path / "marks"
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc")
    for name in ("billiard", "generated", "derivation"):
        shutil.copytree(root / name, copy / name, ignore=ignore)
    shutil.copy(root / "pyproject.toml", copy)
    with open(copy / "billiard" / "__init__.py", "a", encoding="utf-8") as init:
        init.write(MARK.format(name="copy"))
    (checkout / "billiard").mkdir(parents=True)
    (checkout / "billiard" / "__init__.py").write_text(MARK.format(name="checkout"))
    marks.mkdir()
    env = {**os.environ, "PYTHONPATH": str(copy), "MARKS": str(marks)}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "cache")
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run(
        [sys.executable, "-P", "-c", PARENT], cwd=checkout, env=env, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    names = sorted(path.name.split("-")[0] for path in marks.iterdir())
    assert names == ["copy", "copy", "copy"]  # the starting process and its two workers


@compiled
def test_a_worker_that_imported_another_copy_exits(tmp_path, capsys):
    with pytest.raises(SystemExit) as exited:
        compile_all.run_jobs([], str(tmp_path))
    assert exited.value.code == compile_all.WRONG_COPY
    assert capsys.readouterr().err.startswith("billiard: compile worker imported ")


SCRIPT = (
    "import sys; from billiard.engine.simulation import Simulation; "
    "from billiard.runfile.record import MemoryRecorder; "
    "from billiard.scene.scene import load_scene, with_values; "
    "scene = load_scene(sys.argv[1]); "
    "scene = with_values(scene, {'contact.model': sys.argv[2]}); "
    "Simulation(scene).run(100, MemoryRecorder())"
)


@pytest.mark.slow
@compiled
def test_one_cold_compile_then_no_other_process_compiles(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env["BILLIARD_HOME"] = str(tmp_path / "home")
    env.pop("NUMBA_DISABLE_JIT", None)
    runs = []
    for scene, model in (
        ("wedge-6.6hz", "impacts"),
        ("parabola-5.4hz", "impacts"),
        ("wedge-6.6hz", "phases"),
        ("hyperbola-5.8hz", "phases"),
    ):
        began = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", SCRIPT, scene, model],
            env=env,
            cwd=tmp_path,
            capture_output=True,
            text=True,
        )
        assert done.returncode == 0, done.stderr
        runs.append((done.stderr.splitlines(), time.perf_counter() - began))
    first, seconds = runs[0]
    assert first[0] == compile_all.ALL_NOTICE
    assert first[1].startswith("billiard: compiled the engine's kernels in ")
    assert len(first) == 2, first
    assert [lines for lines, _ in runs[1:]] == [[], [], []]  # every other run: cached
    assert all(later < seconds for _, later in runs[1:])
