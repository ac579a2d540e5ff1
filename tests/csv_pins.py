"""The pinned sha256 of collisions.csv of 20,000 impacts of every paper scene, drag on
and off (``tests/data/collisions_sha256.json``, written by the engine before it ran on
the kernels), and the test cases over them: all eight run by default."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

PINS = json.loads((Path(__file__).parent / "data" / "collisions_sha256.json").read_text())


def pinned_cases() -> list:
    """One pytest parameter (scene name, drag) per pinned file."""
    return [pytest.param(*key.split(), id=key.replace(" ", "-")) for key in PINS["sha256"]]
