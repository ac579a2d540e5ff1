"""Where the compiled kernels are cached when the package's own folder cannot be written
(an installation the user may not write to): in the user's cache directory, and the
next process starts from there without compiling.

The read-only folder is simulated (the tests may run as root, for whom no folder is
read-only): numba's in-tree cache locator is made to fail its writability check, as it
does on a read-only folder. Slow: the first run compiles the kernels (about 15 s).
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from billiard import jit

SCRIPT = """
from numba.core import caching
def read_only(self):
    raise PermissionError("read-only package folder")
caching.InTreeCacheLocator.ensure_cache_path = read_only
from billiard.engine.simulation import Simulation
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
Simulation(load_scene("wedge-6.6hz")).run(20, MemoryRecorder())
"""


@pytest.mark.slow
@pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")
def test_kernels_cache_in_the_user_cache_dir_when_the_package_is_read_only(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", "NUMBA_CACHE_DIR")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    env["BILLIARD_HOME"] = str(tmp_path / "home")
    runs = []
    for _ in range(2):
        runs.append(
            subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True)
        )
        assert runs[-1].returncode == 0, runs[-1].stderr
    cached = [p.name for p in (tmp_path / "cache" / "numba").rglob("*.nbi")]
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
    assert runs[1].stderr == ""  # the second loaded the user-wide cache
