"""What a run imports: ``billiard run --no-plot`` and an in-memory ``simulate`` load
neither the plotting nor the derivation stack (matplotlib, sympy), compiled or
interpreted, with the compiled kernels in the cache; interpreted, not scipy either
(compiled, numba imports it itself: its version check, and its linear algebra's BLAS
when its implementations are set up for the first kernel loaded).

Each case is a fresh process: the modules it ends with are what it imported.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from billiard import jit

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


def _never(interpreted: bool) -> tuple[str, ...]:
    """The packages a run must not import (scipy: numba's own, when compiled)."""
    return NEVER if interpreted or not jit.ENABLED else ("matplotlib", "sympy")


@pytest.mark.parametrize("interpreted", [False, True], ids=["compiled", "interpreted"])
def test_run_no_plot_imports_no_plotting_or_derivation(tmp_path, interpreted):
    out = _run(CLI, str(tmp_path / "run"), interpreted=interpreted)
    assert out["code"] == 0
    assert (tmp_path / "run" / "collisions.csv").read_bytes().count(b"\n") == 201
    never = _never(interpreted)
    assert _top_level(out["modules"]).isdisjoint(never), sorted(
        _top_level(out["modules"]) & set(never)
    )


@pytest.mark.parametrize("interpreted", [False, True], ids=["compiled", "interpreted"])
def test_simulate_in_memory_imports_no_plotting_or_derivation(interpreted):
    out = _run(IN_MEMORY, interpreted=interpreted)
    assert out["rows"] == 200
    found = _top_level(out["modules"])
    never = _never(interpreted)
    assert found.isdisjoint(never), sorted(found & set(never))
    if interpreted or not jit.ENABLED:
        assert "numba" not in found and "numpy.ma" not in out["modules"]
    else:
        assert "numba" in found


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
