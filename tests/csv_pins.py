"""The pinned sha256 of collisions.csv of 20,000 impacts of every paper scene, drag on
and off (``tests/data/collisions_sha256.json``, written by the engine before it ran on
the kernels), and the test cases over them: two combinations by default, the other six
under ``-m slow``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

PINS = json.loads((Path(__file__).parent / "data" / "collisions_sha256.json").read_text())
DEFAULT = {("wedge-6.6hz", "none"), ("parabola-5.4hz", "fowles")}


def pinned_cases() -> list:
    """One pytest parameter (scene name, drag) per pinned file."""
    cases = []
    for key in PINS["sha256"]:
        name, drag = key.split()
        marks = () if (name, drag) in DEFAULT else (pytest.mark.slow,)
        cases.append(pytest.param(name, drag, marks=marks, id=f"{name}-{drag}"))
    return cases
