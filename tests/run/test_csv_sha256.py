"""collisions.csv of 20,000 impacts of every paper scene, drag on and off, has the
bytes the engine wrote before it ran on the kernels (``tests/data/collisions_sha256.json``):
the switch of engines is checked against the engine it replaced. The pins hold on the
platform they were made on (:data:`csv_pins.PINNED_ON`) and are skipped elsewhere."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values
from tests.csv_pins import PINS, pinned_cases, require_pinned_platform


def csv_sha256(name: str, drag: str, out: Path) -> str:
    """sha256 of collisions.csv of the pinned number of impacts of ``name``."""
    scene = with_values(load_scene(name), {"air.drag": drag})
    result = simulate(scene, collisions=PINS["impacts"], out_dir=out)
    assert len(result) == PINS["impacts"], result.stop_reason
    return hashlib.sha256((out / "collisions.csv").read_bytes()).hexdigest()


@pytest.mark.parametrize(("name", "drag"), pinned_cases())
def test_collisions_csv_has_the_pinned_bytes(name, drag, tmp_path):
    require_pinned_platform()
    assert csv_sha256(name, drag, tmp_path) == PINS["sha256"][f"{name} {drag}"]
