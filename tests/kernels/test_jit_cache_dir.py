"""numba's cache of the kernels: where it is (``NUMBA_CACHE_DIR``, else beside the
sources), and its invalidation when a source compiled into a kernel changes in
another file (numba checks only the kernel's own file: billiard.jit's stamp beside the
cache sees the rest, and removes the cache)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

ROOT = Path(__file__).resolve().parents[2]


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", "NUMBA_CACHE_DIR")}
    env.update(extra)
    return env


# --- the stamp, on a small kernel folder of its own ----------------------------------

KERNEL = """
import numba
from dep import VALUE

@numba.njit(cache=True)
def value():
    return VALUE
"""

SCRIPT = """
import sys
from pathlib import Path
from billiard.jit import refresh_kernel_cache
root = Path(sys.argv[1])
if sys.argv[2] == "refresh":
    print(refresh_kernel_cache(root / "kern", [root / "dep.py"]))
else:
    print("-")
sys.path[:0] = [str(root), str(root / "kern")]
import k
print(k.value())
"""


def _value(root: Path, refresh: bool, **env: str) -> tuple[str, float]:
    """(whether the stamp invalidated, the kernel's value) from a fresh process."""
    mode = "refresh" if refresh else "plain"
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(root), mode],
        env=_env(**env),
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    invalidated, value = done.stdout.split()
    return invalidated, float(value)


def _kernel_folder(tmp_path: Path) -> Path:
    (tmp_path / "kern").mkdir(parents=True)
    (tmp_path / "kern" / "k.py").write_text(KERNEL, encoding="utf-8")
    (tmp_path / "dep.py").write_text("VALUE = 1.0\n", encoding="utf-8")
    return tmp_path


@compiled
@pytest.mark.parametrize(
    "cache_dir",
    [False, pytest.param(True, marks=pytest.mark.slow)],  # the same stamp, another folder
    ids=["beside-sources", "NUMBA_CACHE_DIR"],
)
def test_an_edit_of_a_dependency_recompiles_the_kernels(tmp_path, cache_dir):
    root = _kernel_folder(tmp_path / "src")
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "cache")} if cache_dir else {}
    assert _value(root, refresh=True, **env) == ("True", 1.0)  # no stamp yet
    assert _value(root, refresh=True, **env) == ("False", 1.0)  # from the cache
    (root / "dep.py").write_text("VALUE = 2.0\n", encoding="utf-8")
    # numba alone reuses the machine code compiled with the old constant ...
    assert _value(root, refresh=False, **env) == ("-", 1.0)
    # ... the stamp sees the edit, and the kernel is compiled anew
    assert _value(root, refresh=True, **env) == ("True", 2.0)
    assert _value(root, refresh=True, **env) == ("False", 2.0)
    cached = list((tmp_path / "cache" if cache_dir else root / "kern").rglob("k.value-*.nbi"))
    assert cached, "numba cached nothing where it should"


@compiled
def test_an_unwritable_folder_leaves_the_stamp_to_the_users_cache(tmp_path, monkeypatch):
    """Where ``__pycache__`` cannot be written (an installation the user may not
    change), numba caches in the user's cache folder: the stamp goes there."""
    root = _kernel_folder(tmp_path / "src")
    assert _value(root, refresh=True) == ("True", 1.0)
    pycache = root / "kern" / "__pycache__"
    cached = sorted(pycache.glob("*.nb?"))
    before = (pycache / jit.STAMP_FILE).read_text(encoding="ascii")
    assert cached
    (root / "dep.py").write_text("VALUE = 2.0\n", encoding="utf-8")
    unlink = Path.unlink

    def refuse(path, *args, **kwargs):
        if path.parent == pycache:
            raise PermissionError("read-only")
        return unlink(path, *args, **kwargs)

    monkeypatch.setattr(Path, "unlink", refuse)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "user"))
    if sys.platform == "darwin":
        monkeypatch.setattr(Path, "home", lambda: tmp_path / "user")
    assert jit.refresh_kernel_cache(root / "kern", [root / "dep.py"]) is True
    assert sorted(pycache.glob("*.nb?")) == cached
    assert (pycache / jit.STAMP_FILE).read_text(encoding="ascii") == before
    (user_stamp,) = (tmp_path / "user").rglob(jit.STAMP_FILE)
    assert user_stamp.parent.name.startswith("kern_")
    assert user_stamp.read_text(encoding="ascii") != before


# --- the real kernels -----------------------------------------------------------------

RUN = """
from billiard.engine.simulation import Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
Simulation(load_scene("wedge-6.6hz")).run(20, MemoryRecorder())
"""


@pytest.mark.slow
@compiled
def test_kernels_cache_in_numba_cache_dir_and_load_from_there(tmp_path):
    env = _env(
        NUMBA_CACHE_DIR=str(tmp_path / "cache"),
        BILLIARD_HOME=str(tmp_path / "home"),
    )
    runs = []
    for _ in range(2):
        runs.append(
            subprocess.run([sys.executable, "-c", RUN], env=env, capture_output=True, text=True)
        )
        assert runs[-1].returncode == 0, runs[-1].stderr
    cached = [p.name for p in (tmp_path / "cache").rglob("*.nbi")]
    assert any(name.startswith("loop.run_chunk") for name in cached), cached
    # the first process compiled, and said what
    notices = runs[0].stderr.splitlines()
    assert notices and all(
        line.startswith(("billiard: compiling ", "billiard: compiled ")) for line in notices
    ), notices
    assert (
        jit.COMPILE_NOTICE.format(
            family="the impact loop", function="billiard.kernels.loop.run_chunk"
        )
        in notices
    )
    assert runs[1].stderr == ""  # the second loaded the cache


FORMAT = """
import numpy as np
from billiard.kernels import float_text
values = np.array([7.0, 1.5e-7, 123456.0])
sep = np.frombuffer(b",", dtype=np.uint8)
out = np.empty(100, dtype=np.uint8)
print(out[: float_text.format_floats(values, out, sep)].tobytes().decode("latin-1"))
"""


@pytest.mark.slow
@compiled
def test_an_edit_of_another_kernel_file_recompiles_a_copy_of_the_tree(tmp_path):
    """In a copy of the checkout, a constant of ``kernels/ryu.py`` that
    ``kernels/float_text.py`` compiles in is changed: the next run formats with it."""
    tree = tmp_path / "tree"
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc")
    for name in ("billiard", "generated", "derivation"):
        shutil.copytree(ROOT / name, tree / name, ignore=ignore)
    env = _env(PYTHONPATH=str(tree), BILLIARD_HOME=str(tmp_path / "home"))

    def formatted() -> str:
        done = subprocess.run(
            [sys.executable, "-c", FORMAT], env=env, cwd=tmp_path, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr
        return done.stdout.strip()

    assert formatted() == "7.0,1.5e-07,123456.0,"
    ryu = tree / "billiard" / "kernels" / "ryu.py"
    text = ryu.read_text(encoding="utf-8")
    zero = '_ZERO_CHAR = np.uint64(ord("0"))'
    assert zero in text
    ryu.write_text(text.replace(zero, '_ZERO_CHAR = np.uint64(ord("A"))'), encoding="utf-8")
    changed = formatted()
    assert changed != "7.0,1.5e-07,123456.0,"
    assert "H" in changed  # a digit 7 written as "A" + 7
