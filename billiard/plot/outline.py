"""The moving boundary as drawn: its outline y = f(x) and the drive's displacement D(t).

The outline uses only :meth:`billiard.geometry.curves.CurveModel.f` (the curve's height, m) and
its ``breakpoints`` (the x of its kinks, added to every grid so that a wedge's vertex is
drawn sharp).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from billiard.geometry.curves import load_curve
from billiard.plot.common import RunDataError
from billiard.scene.scene import Scene

__all__ = ["boundary_function", "boundary_outline", "drive_offset"]


def drive_offset(scene: Scene, t: np.ndarray | float) -> np.ndarray:
    """The boundary's displacement D(t) = A sin(omega t + phase) (m) at times t (s).

    It is along n1 for ``drive.direction = "horizontal"`` and along n2 for
    ``"vertical"``.
    """
    drive = scene.drive
    return drive.amplitude * np.sin(drive.omega * np.asarray(t, dtype=float) + drive.phase)


def _curve(scene: Scene):
    boundary = scene.boundary
    try:
        return load_curve(boundary.curve, dict(boundary.parameters))
    except (ValueError, ArithmeticError) as exc:
        raise RunDataError(
            f"boundary curve {boundary.curve!r} cannot be drawn: {' '.join(str(exc).split())}"
        ) from None


def boundary_function(scene: Scene) -> Callable[[np.ndarray], np.ndarray]:
    """f(x) (m) of the scene's boundary in its own frame, vectorized over x (m).

    Points where f is undefined give NaN.

    Raises:
        RunDataError: the curve cannot be loaded (unknown name, bad parameters).
    """
    scalar = _curve(scene).f

    def f(x: np.ndarray) -> np.ndarray:
        out = np.empty(np.shape(x))
        for i, xi in enumerate(np.ravel(x)):
            try:
                out.flat[i] = scalar(float(xi))
            except (ValueError, ArithmeticError):
                out.flat[i] = np.nan
        return out

    return f


def boundary_outline(
    scene: Scene, lo: float, hi: float, count: int = 801
) -> tuple[np.ndarray, np.ndarray]:
    """``(x, f(x))`` (m) on ``count`` points from ``lo`` to ``hi`` (m), plus the curve's
    breakpoints inside that range."""
    return _curve(scene).samples(lo, hi, count)
