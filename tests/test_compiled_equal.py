"""The compiled engine writes the interpreted engine's collisions.csv byte for byte.

:func:`billiard.compiled.simulate_compiled` runs the kernels of :mod:`billiard.kernels`
(numba, cached); :func:`billiard.simulate.simulate` is today's interpreted engine, the
reference. 20,000 impacts of the wedge without drag and the parabola with drag run by
default (with the first compile about 30 s); the other paper scenes, drag on and off,
are marked slow. The kernels run interpreted (NUMBA_DISABLE_JIT=1) give the same bytes
too: one source, two ways to run it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from billiard import jit
from billiard.scene import load_scene, with_values
from billiard.simulate import simulate

IMPACTS = 20_000

compiled = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


def _csv_pair(name: str, drag: str, impacts: int, tmp_path: Path) -> tuple[bytes, bytes]:
    from billiard.compiled import simulate_compiled

    scene = with_values(load_scene(name), {"air.drag": drag})
    simulate(scene, collisions=impacts, out_dir=tmp_path / "interpreted")
    run = simulate_compiled(scene, impacts, out_dir=tmp_path / "compiled")
    assert run.impacts == impacts, run.reason
    return (
        (tmp_path / "interpreted" / "collisions.csv").read_bytes(),
        (tmp_path / "compiled" / "collisions.csv").read_bytes(),
    )


def _first_difference(a: bytes, b: bytes) -> str:
    for n, (x, y) in enumerate(zip(a.splitlines(), b.splitlines(), strict=False)):
        if x != y:
            return f"line {n}:\n{x.decode()}\n{y.decode()}"
    return f"lengths {len(a)} and {len(b)}"


@compiled
@pytest.mark.parametrize(("name", "drag"), [("wedge-6.6hz", "none"), ("parabola-5.4hz", "fowles")])
def test_compiled_csv_equals_interpreted(name, drag, tmp_path):
    a, b = _csv_pair(name, drag, IMPACTS, tmp_path)
    assert a == b, _first_difference(a, b)


@compiled
@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "drag"),
    [
        ("wedge-6.6hz", "fowles"),
        ("parabola-5.4hz", "none"),
        ("hyperbola-5.8hz", "none"),
        ("hyperbola-5.8hz", "fowles"),
        ("hyperbola-4.5hz", "none"),
        ("hyperbola-4.5hz", "fowles"),
    ],
)
def test_compiled_csv_equals_interpreted_every_paper_scene(name, drag, tmp_path):
    a, b = _csv_pair(name, drag, IMPACTS, tmp_path)
    assert a == b, _first_difference(a, b)


_INTERPRETED = """
import sys
from billiard import jit
from billiard.compiled import simulate_compiled
from billiard.scene import load_scene, with_values
assert not jit.ENABLED
scene = with_values(load_scene(sys.argv[1]), {"air.drag": sys.argv[2]})
simulate_compiled(scene, int(sys.argv[3]), out_dir=sys.argv[4])
"""


@pytest.mark.parametrize(("name", "drag"), [("wedge-6.6hz", "none"), ("hyperbola-4.5hz", "fowles")])
def test_kernels_interpreted_equal_the_engine(name, drag, tmp_path):
    impacts = 300
    scene = with_values(load_scene(name), {"air.drag": drag})
    simulate(scene, collisions=impacts, out_dir=tmp_path / "engine")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run(
        [sys.executable, "-c", _INTERPRETED, name, drag, str(impacts), str(tmp_path / "kernels")],
        env=env,
        check=True,
    )
    a = (tmp_path / "engine" / "collisions.csv").read_bytes()
    b = (tmp_path / "kernels" / "collisions.csv").read_bytes()
    assert a == b, _first_difference(a, b)
