"""What a run imports: ``billiard run --no-plot`` and an in-memory ``simulate`` load
neither the plotting nor the derivation stack (matplotlib, scipy, sympy), compiled or
interpreted, with the compiled kernels in the cache; numba's own import leaves scipy and
yaml out, yet still reads a ``.numba_config.yaml`` in the working directory.

Each case is a fresh process: the modules it ends with are what it imported.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

NEVER = ("matplotlib", "scipy", "sympy")

CLI = """
import json, sys
from billiard.cli import main
args = ["--collisions", "200", "--no-plot", "--out", sys.argv[1], "--overwrite"]
code = main(["run", "wedge-6.6hz", *args])
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""

IN_MEMORY = """
import json, sys
from billiard import load_scene
from billiard import simulate
result = simulate(load_scene("parabola-5.4hz"), collisions=200)
print(json.dumps({"rows": len(result), "modules": sorted(sys.modules)}))
"""


def _run(script: str, *args: str, interpreted: bool = False, cwd=None) -> dict:
    """The script's last line, as JSON, from a fresh process (run twice: a compile on a
    cold cache imports what numba's compiler needs, a run from the cache does not)."""
    _once(script, *args, interpreted=interpreted, cwd=cwd)
    return _once(script, *args, interpreted=interpreted, cwd=cwd)


def _once(script: str, *args: str, interpreted: bool = False, cwd=None) -> dict:
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    if interpreted:
        env["NUMBA_DISABLE_JIT"] = "1"
    done = subprocess.run(
        [sys.executable, "-c", script, *args],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def _top_level(modules: list[str]) -> set[str]:
    return {name.split(".")[0] for name in modules}


@pytest.mark.parametrize("interpreted", [False, True], ids=["compiled", "interpreted"])
def test_run_no_plot_imports_no_plotting_or_derivation(tmp_path, interpreted):
    out = _run(CLI, str(tmp_path / "run"), interpreted=interpreted)
    assert out["code"] == 0
    assert (tmp_path / "run" / "collisions.csv").read_bytes().count(b"\n") == 201
    assert _top_level(out["modules"]).isdisjoint(NEVER), sorted(
        _top_level(out["modules"]) & set(NEVER)
    )


@pytest.mark.parametrize("interpreted", [False, True], ids=["compiled", "interpreted"])
def test_simulate_in_memory_imports_no_plotting_or_derivation(interpreted):
    out = _run(IN_MEMORY, interpreted=interpreted)
    assert out["rows"] == 200
    found = _top_level(out["modules"])
    assert found.isdisjoint(NEVER), sorted(found & set(NEVER))
    assert "numpy.ma" not in out["modules"]
    if not interpreted and jit.ENABLED:
        assert "numba" in found


CONFIG = """
import json
import billiard
from numba.core import config
print(json.dumps({"quiet": config.DISABLE_PERFORMANCE_WARNINGS, "yaml": config._HAVE_YAML}))
"""


@compiled
@pytest.mark.skipif(importlib.util.find_spec("yaml") is None, reason="pyyaml not installed")
def test_numba_config_file_is_still_read(tmp_path):
    (tmp_path / ".numba_config.yaml").write_text(
        "disable_performance_warnings: 1\n", encoding="utf-8"
    )
    assert _run(CONFIG, cwd=tmp_path) == {"quiet": 1, "yaml": True}
    # without the file numba's default, and yaml still there for a later look
    (tmp_path / ".numba_config.yaml").unlink()
    out = _run(CONFIG, cwd=tmp_path)
    assert out == {"quiet": 0, "yaml": True}


COLLECTOR = """
import gc, json, sys
mine = [[i] for i in range(1000)]
frozen_before = {frozen}
if frozen_before:
    gc.freeze()
count = gc.get_freeze_count()
import billiard
modules = list(sys.modules)
print(json.dumps({{
    "enabled": gc.isenabled(),
    "frozen": gc.get_freeze_count(),
    "frozen_before": count,
    "numba_first": modules.index("numba") < modules.index("billiard.scene.scene"),
}}))
"""


@pytest.mark.parametrize("frozen", [False, True], ids=["plain", "user-froze"])
def test_import_leaves_the_collector_as_it_was(frozen):
    """``import billiard`` exempts nothing from collection (its objects go to the
    oldest generation, not the permanent one), leaves a program's own frozen objects
    frozen, and re-enables the collector."""
    out = _once(COLLECTOR.format(frozen=frozen))
    assert out["enabled"] is True
    # (frozen objects freed by their reference counts meanwhile leave the count)
    assert out["frozen"] <= out["frozen_before"]
    assert (out["frozen"] > 0) is frozen
    if jit.ENABLED:
        # numba imported before billiard's modules: its casting-rule set-up was ten
        # times slower after them (billiard/__init__.py)
        assert out["numba_first"]
