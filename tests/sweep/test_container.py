"""The container over a map of starting positions: the wall and lid in the lab frame at
the start time, as the engine places them when it checks a start."""

from __future__ import annotations

import math

import numpy as np
import pytest

from billiard import load_scene
from billiard.geometry.curves import load_curve
from billiard.sweep.container import lid_height, start_offset, wall_outline


def test_wall_at_drive_phase_zero_is_the_curve():
    scene = load_scene("parabola-5.4hz")
    x, y = wall_outline(scene, -0.05, 0.05, count=11)
    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    assert x.tolist() == pytest.approx(np.linspace(-0.05, 0.05, 11).tolist())
    assert y.tolist() == [curve.f(float(v)) for v in x]


def test_wall_is_shifted_by_the_drive_at_the_start_time():
    scene = load_scene("parabola-5.4hz", overrides=["drive.phase=0.5", "initial.t=0.01"])
    d = scene.drive.amplitude * math.sin(scene.drive.omega * 0.01 + 0.5)
    assert start_offset(scene) == (pytest.approx(d), 0.0)
    x, y = wall_outline(scene, -0.05, 0.05, count=11)
    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    # the lab grid asked for, the wall's height at the boundary's own x = lab x - D
    assert x.tolist() == pytest.approx(np.linspace(-0.05, 0.05, 11).tolist(), abs=1e-15)
    assert y.tolist() == pytest.approx([curve.f(float(v) - d) for v in x], abs=1e-15)


def test_wedge_vertex_is_drawn_sharp_and_a_vertical_drive_lifts_the_lid():
    scene = load_scene("wedge-6.6hz", overrides=["drive.direction=vertical", "drive.phase=1.0"])
    x, y = wall_outline(scene, -0.05, 0.05, count=10)  # the grid misses x = 0
    assert 0.0 in x.tolist() and y[x.tolist().index(0.0)] == y.min()  # the vertex
    d = scene.drive.amplitude * math.sin(1.0)
    assert lid_height(scene) == pytest.approx(scene.boundary.ceiling + d)
    curve = load_curve(scene.boundary.curve, dict(scene.boundary.parameters))
    assert y.tolist() == pytest.approx([curve.f(float(v)) + d for v in x])
