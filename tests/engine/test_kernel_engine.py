"""One source, two ways to run it: the kernels interpreted (``NUMBA_DISABLE_JIT=1``, in
a fresh interpreter) write the same ``collisions.csv`` as the kernels compiled by numba
(on every platform: both call the same libm), and both have the bytes of the engine
before it ran on the kernels (``tests/data/collisions_sha256.json``, 20,000 impacts;
checked where the pins were made, :data:`csv_pins.PINNED_ON`): every paper scene, drag
on and off.
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
from tests.csv_pins import PINS, pinned_cases, require_pinned_platform

IMPACTS = PINS["impacts"]

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


#: The cases of the default suite: each scene once, and the drag kernels on the parabola;
#: the other four pairs run with the slow tests (the kernels they use are covered here).
DEFAULT_CASES = {"parabola-5.4hz-fowles", "wedge-6.6hz-none", "hyperbola-5.8hz-none"}


@pytest.fixture(
    scope="module",
    params=[
        pytest.param(
            case.values,
            id=case.id,
            marks=() if case.id in DEFAULT_CASES else (pytest.mark.slow,),
        )
        for case in pinned_cases()
    ],
)
def both_runs(request, tmp_path_factory) -> tuple[str, bytes, bytes]:
    """The pin's key and the collisions.csv bytes of one paper scene, interpreted and
    compiled (run once for the two tests below)."""
    if not jit.ENABLED:
        pytest.skip(f"numba unavailable: {jit.numba_problem()}")
    name, drag = request.param
    out = tmp_path_factory.mktemp(f"{name}-{drag}")
    scene = with_values(load_scene(name), {"air.drag": drag})
    result = simulate(scene, collisions=IMPACTS, out_dir=out / "compiled")
    assert len(result) == IMPACTS, result.stop_reason
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run(
        [sys.executable, "-c", _INTERPRETED, name, drag, str(IMPACTS), str(out / "kernels")],
        env=env,
        check=True,
    )
    a = (out / "kernels" / "collisions.csv").read_bytes()
    b = (out / "compiled" / "collisions.csv").read_bytes()
    return f"{name} {drag}", a, b


def test_interpreted_and_compiled_kernels_write_the_same_bytes(both_runs):
    _, a, b = both_runs
    assert a == b, _first_difference(a, b)


def test_interpreted_and_compiled_kernels_write_the_pinned_bytes(both_runs):
    require_pinned_platform()
    key, a, b = both_runs
    assert hashlib.sha256(a).hexdigest() == PINS["sha256"][key]
    assert hashlib.sha256(b).hexdigest() == PINS["sha256"][key]
