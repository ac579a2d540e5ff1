"""`billiard run` compiled against `billiard run` interpreted (NUMBA_DISABLE_JIT=1): the
same collisions.csv bytes, on a curve derived at run time (20,000 impacts) and, marked
slow, over 10^6 impacts of the wedge and of the parabola with drag.

Both runs are fresh processes of the command users run, so the comparison covers the
whole path: scene, derivation of the user curve, kernels from numba's cache (compiled
once per signature, whatever the curve), chunks, and the CSV writer.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from billiard import jit

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

#: a quartic bowl, not one of the built-in curves: its wall functions are generated when
#: the scene is first run
USER_CURVE = "3e4*x**4 + 0.0063"


def _run(args: list[str], out: Path, interpreted: bool) -> str:
    """sha256 of the collisions.csv of ``billiard run ARGS`` (and its line count)."""
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    if interpreted:
        env["NUMBA_DISABLE_JIT"] = "1"
    done = subprocess.run(
        [sys.executable, "-m", "billiard.cli", "run", *args, "--no-plot", "--out", str(out)],
        env=env,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    digest = hashlib.sha256()
    lines = 0
    with open(out / "collisions.csv", "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
            lines += block.count(b"\n")
    return f"{digest.hexdigest()} ({lines} lines)"


def _both(args: list[str], tmp_path: Path) -> tuple[str, str]:
    return (
        _run(args, tmp_path / "interpreted", interpreted=True),
        _run(args, tmp_path / "compiled", interpreted=False),
    )


@compiled
def test_user_curve_compiled_equals_interpreted(tmp_path):
    args = [
        "parabola-5.4hz",
        "--set",
        f"boundary.curve={USER_CURVE}",
        "--set",
        "air.drag=fowles",
        "--collisions",
        "20000",
    ]
    interpreted, fast = _both(args, tmp_path)
    assert interpreted.endswith("(20001 lines)"), interpreted
    assert fast == interpreted


@compiled
@pytest.mark.slow
@pytest.mark.parametrize(("name", "drag"), [("wedge-6.6hz", "none"), ("parabola-5.4hz", "fowles")])
def test_million_impacts_compiled_equals_interpreted(name, drag, tmp_path):
    args = [name, "--set", f"air.drag={drag}", "--collisions", "1000000", "--store", "csv"]
    interpreted, fast = _both(args, tmp_path)
    assert interpreted.endswith("(1000001 lines)"), interpreted
    assert fast == interpreted
