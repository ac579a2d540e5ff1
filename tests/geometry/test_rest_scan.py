"""The scan of ``Boundary.resting_position`` (``billiard.kernels.rest.offset_heights``,
compiled when the kernels are, else the twin) gives the bits of the surfaces asked one
abscissa at a time (``Boundary.offset_height``, the scan it replaced), and leaves the
warm starts where those calls leave them."""

from __future__ import annotations

import numpy as np
import pytest

from billiard import jit
from billiard.engine.simulation import Simulation
from billiard.geometry import boundary as boundary_module
from billiard.scene.scene import load_scene

SCENES = ["parabola-5.4hz", "wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz"]
MODES = [
    pytest.param(True, id="compiled", marks=pytest.mark.skipif(not jit.ENABLED, reason="no numba")),
    pytest.param(False, id="interpreted"),
]


@pytest.fixture(autouse=True)
def billiard_home(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))


@pytest.mark.parametrize("compiled", MODES)
@pytest.mark.parametrize("name", SCENES)
def test_scan_gives_the_bits_of_one_abscissa_at_a_time(name, compiled, monkeypatch):
    boundary = Simulation(load_scene(name)).boundary
    monkeypatch.setattr(boundary_module._jit, "ENABLED", compiled)
    xl, xr = boundary.x_range
    # a row that ends away from the bottom, so the warm starts end somewhere else
    xs = np.linspace(xl, 0.7 * xr, 1001)
    one_at_a_time = boundary.initial_warm()
    expected = [boundary.offset_height(float(x), one_at_a_time) for x in xs]
    warm = boundary.initial_warm()
    heights = boundary._offset_heights(xs, warm)
    assert [float(h).hex() for h in heights] == [h.hex() for h in expected]
    assert warm == one_at_a_time
    assert all(type(w) is float for pair in warm for w in pair)
    curved = [j for j, o in enumerate(boundary.offsets) if type(o).__name__ == "OffsetWall"]
    if curved:  # the warm starts moved along the row
        assert all(warm[j][0] != 0.0 for j in curved)
