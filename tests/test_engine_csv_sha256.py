"""collisions.csv of 20,000 impacts of every paper scene, drag on and off, has the
bytes the engine wrote before it ran on the kernels (``tests/data/collisions_sha256.json``):
the switch of engines is checked against the engine it replaced. Two combinations run by
default, the other six under ``-m slow``."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from billiard.scene import load_scene, with_values
from billiard.simulate import simulate

PINS = json.loads((Path(__file__).parent / "data" / "collisions_sha256.json").read_text())
DEFAULT = {("wedge-6.6hz", "none"), ("parabola-5.4hz", "fowles")}


def csv_sha256(name: str, drag: str, out: Path) -> str:
    """sha256 of collisions.csv of the pinned number of impacts of ``name``."""
    scene = with_values(load_scene(name), {"air.drag": drag})
    result = simulate(scene, collisions=PINS["impacts"], out_dir=out)
    assert len(result) == PINS["impacts"], result.stop_reason
    return hashlib.sha256((out / "collisions.csv").read_bytes()).hexdigest()


def _cases() -> list:
    cases = []
    for key in PINS["sha256"]:
        name, drag = key.split()
        marks = () if (name, drag) in DEFAULT else (pytest.mark.slow,)
        cases.append(pytest.param(name, drag, marks=marks, id=f"{name}-{drag}"))
    return cases


@pytest.mark.parametrize(("name", "drag"), _cases())
def test_collisions_csv_has_the_pinned_bytes(name, drag, tmp_path):
    assert csv_sha256(name, drag, tmp_path) == PINS["sha256"][f"{name} {drag}"]
