"""One source, two ways to run it: the kernels interpreted (``NUMBA_DISABLE_JIT=1``, in
a fresh interpreter) write the same ``collisions.csv`` as the kernels compiled by numba,
and both have the bytes of the engine before it ran on the kernels
(``tests/data/collisions_sha256.json``, 20,000 impacts): every paper scene, drag on
and off.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys

import pytest

from billiard import jit
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values
from tests.csv_pins import PINS, pinned_cases

IMPACTS = PINS["impacts"]

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")

_INTERPRETED = """
import sys
from billiard import jit
from billiard.scene.scene import load_scene, with_values
from billiard.run.simulate import simulate
assert not jit.ENABLED
scene = with_values(load_scene(sys.argv[1]), {"air.drag": sys.argv[2]})
result = simulate(scene, collisions=int(sys.argv[3]), out_dir=sys.argv[4])
assert len(result) == int(sys.argv[3]), result.stop_reason
"""


def _first_difference(a: bytes, b: bytes) -> str:
    for n, (x, y) in enumerate(zip(a.splitlines(), b.splitlines(), strict=False)):
        if x != y:
            return f"line {n}:\n{x.decode()}\n{y.decode()}"
    return f"lengths {len(a)} and {len(b)}"


@compiled
@pytest.mark.parametrize(("name", "drag"), pinned_cases())
def test_interpreted_and_compiled_kernels_write_the_pinned_bytes(name, drag, tmp_path):
    scene = with_values(load_scene(name), {"air.drag": drag})
    result = simulate(scene, collisions=IMPACTS, out_dir=tmp_path / "compiled")
    assert len(result) == IMPACTS, result.stop_reason
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run(
        [sys.executable, "-c", _INTERPRETED, name, drag, str(IMPACTS), str(tmp_path / "kernels")],
        env=env,
        check=True,
    )
    a = (tmp_path / "kernels" / "collisions.csv").read_bytes()
    b = (tmp_path / "compiled" / "collisions.csv").read_bytes()
    assert a == b, _first_difference(a, b)
    assert hashlib.sha256(a).hexdigest() == PINS["sha256"][f"{name} {drag}"]


@compiled
def test_simulate_compiled_is_the_engine(tmp_path):
    from billiard.run.compiled import simulate_compiled

    scene = load_scene("hyperbola-4.5hz")
    run = simulate_compiled(scene, 500, out_dir=tmp_path / "alias")
    assert run.impacts == 500 and run.compiled
    simulate(scene, collisions=500, out_dir=tmp_path / "engine")
    assert (tmp_path / "alias" / "collisions.csv").read_bytes() == (
        tmp_path / "engine" / "collisions.csv"
    ).read_bytes()
