"""The drive written once (:mod:`billiard.kernels.drive`): compiled, interpreted and as
:class:`billiard.geometry.drive.Drive` it gives, bit for bit, the formulas the kernels
wrote inline before (D = A sin(theta), A w cos(theta), -A w^2 sin(theta), the frames),
on both axes."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from billiard import jit
from billiard.geometry.drive import Drive
from billiard.kernels import interpreted as twin
from billiard.kernels import layout as L


def _modules() -> list:
    modules = [pytest.param(twin.drive, id="twin")]
    if jit.ENABLED:
        from billiard.kernels import drive

        modules.append(pytest.param(drive, id="compiled"))
    return modules


def _reference(a: float, w: float, horizontal: bool, theta: float, q1, q2, u1, u2, a1, a2):
    """The inline formulas of the kernels before (loop.boundary_frame, gap_acceleration,
    locate.relative_acceleration, contact_forces.boundary), operation for operation."""
    d = a * math.sin(theta)
    v = a * w * math.cos(theta)
    acc = -a * w * w * math.sin(theta)
    peak = a * w * w  # DRIVE_ACCEL, as locate read it
    acc_locate = -peak * math.sin(theta)
    if horizontal:
        frame = (q1 - d, q2, u1 - v, u2)
        relative = (a1 - acc_locate, a2)
        motion = (v, 0.0, acc, 0.0)
        lab = (q1 + d, q2)
    else:
        frame = (q1, q2 - d, u1, u2 - v)
        relative = (a1, a2 - acc_locate)
        motion = (0.0, v, 0.0, acc)
        lab = (q1, q2 + d)
    return d, v, acc, acc_locate, frame, relative, motion, lab


def _bits(values) -> bytes:
    return np.array(values, dtype=np.float64).tobytes()


@pytest.mark.parametrize("module", _modules())
def test_the_drive_functions_are_the_inline_formulas_bit_for_bit(module):
    rng = random.Random(11)
    for i in range(4000):
        horizontal = i % 2 == 0
        a = rng.choice([0.0, rng.uniform(1e-4, 0.05)]) * rng.choice([1.0, -1.0])
        w = rng.choice([0.0, 2.0 * math.pi * rng.uniform(0.5, 30.0)])
        drive = Drive(a, w, 0.0, horizontal)
        ctx = np.zeros(L.DR_END) if module is not twin.drive else [0.0] * L.DR_END
        drive.write(ctx)
        theta = rng.uniform(-10.0, 10.0)
        q1, q2, u1, u2, a1, a2 = (rng.uniform(-2.0, 2.0) for _ in range(6))
        d, v, acc, acc_locate, frame, relative, motion, lab = _reference(
            a, w, horizontal, theta, q1, q2, u1, u2, a1, a2
        )
        # the two ways the kernels wrote -A w^2 sin(theta) have the same bits
        assert _bits([acc]) == _bits([acc_locate])
        assert _bits([module.displacement(ctx, theta)]) == _bits([d])
        assert _bits([module.velocity(ctx, theta)]) == _bits([v])
        assert _bits([module.acceleration(ctx, theta)]) == _bits([acc])
        assert _bits(module.to_boundary_frame(ctx, theta, q1, q2, u1, u2)) == _bits(frame)
        assert _bits(module.accel_to_boundary_frame(ctx, theta, a1, a2)) == _bits(relative)
        assert _bits(module.boundary_motion(ctx, theta)) == _bits(motion)
        assert _bits(module.boundary_velocity(ctx, theta)) == _bits(motion[:2])
        assert _bits(module.to_lab_frame(ctx, theta, q1, q2)) == _bits(lab)
        assert module.static(ctx) == (a == 0.0 or w == 0.0)
        # and the Drive the interpreted models use
        assert _bits([drive.displacement(theta), drive.velocity(theta)]) == _bits([d, v])
        assert _bits([drive.acceleration(theta)]) == _bits([acc])
        assert _bits(drive.to_boundary_frame(theta, q1, q2, u1, u2)) == _bits(frame)
        assert _bits(drive.to_lab_frame(theta, q1, q2)) == _bits(lab)
        assert _bits(drive.boundary_velocity(theta)) == _bits(motion[:2])
        assert drive.static == (a == 0.0 or w == 0.0)


def test_the_drive_block_is_the_drive():
    drive = Drive(0.01, 2.0 * math.pi * 5.4, 0.3, True)
    ctx = [float("nan")] * L.SIZE
    drive.write(ctx)
    assert L.CTX.read(ctx, "drive.amplitude") == 0.01
    assert L.CTX.read(ctx, "drive.omega") == 2.0 * math.pi * 5.4
    assert L.CTX.read(ctx, "drive.horizontal") == 1.0
    assert L.CTX.read(ctx, "drive.peak_acceleration") == drive.peak_acceleration
    # the block and nothing else
    assert [i for i, x in enumerate(ctx) if x == x] == list(range(L.DR, L.DR_END))
    assert drive.period == pytest.approx(1.0 / 5.4, rel=1e-15)
    assert Drive(0.0, 3.0, 0.0, False).period == math.inf
