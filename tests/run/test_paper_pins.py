"""The paper scenes' records, pinned bit for bit.

``tests/data/paper_scene_pins.json`` holds the sha256 of ``collisions.csv`` for the first
2,000 impacts of each built-in paper scene. A restructuring must leave these bytes alone;
a change that is meant to move the numbers (a physics fix, a new printer) updates the pins
in its own commit, saying why: ``python tests/run/test_paper_pins.py --update``. The pins
hold on the platform they were made on (:data:`csv_pins.PINNED_ON`: the records' values
depend on libm's last bits) and are skipped elsewhere.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import pytest

from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene
from tests.csv_pins import require_pinned_platform

PINS = Path(__file__).resolve().parents[1] / "data" / "paper_scene_pins.json"


def csv_digest(name: str, impacts: int, directory: Path) -> str:
    simulate(load_scene(name), collisions=impacts, out_dir=directory)
    return hashlib.sha256((directory / "collisions.csv").read_bytes()).hexdigest()


@pytest.mark.parametrize("name", sorted(json.loads(PINS.read_text())))
def test_paper_scene_records_are_pinned(name, tmp_path):
    require_pinned_platform()
    pin = json.loads(PINS.read_text())[name]
    assert csv_digest(name, pin["impacts"], tmp_path) == pin["sha256"]


if __name__ == "__main__" and sys.argv[1:] == ["--update"]:
    import tempfile

    pins = json.loads(PINS.read_text())
    for name, pin in pins.items():
        with tempfile.TemporaryDirectory() as tmp:
            pin["sha256"] = csv_digest(name, pin["impacts"], Path(tmp))
    PINS.write_text(json.dumps(pins, indent=1) + "\n")
    print(f"updated {PINS}")
