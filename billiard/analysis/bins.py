"""Points counted per bin of a regular 2-D grid: the numbers behind a density image
(:mod:`billiard.plot.density`, the sweep's bifurcation diagram). Plain numpy, no drawing.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bin_counts"]


def bin_counts(
    x: np.ndarray,
    y: np.ndarray,
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    bins: tuple[int, int] = (200, 200),
    *,
    log: bool = False,
    weight: float | None = None,
) -> np.ndarray:
    """Number of points ``(x, y)`` in each bin of a regular grid, as :func:`numpy.histogram2d`
    counts them (a point on the upper edge of the range is in the last bin) but transposed:
    ``counts[j, i]`` is bin i along x and bin j along y, the layout of an image.

    Points that are not finite or lie outside the ranges are not counted. With ``log``,
    the bins are equally wide in log10 of x and y (both ranges positive) and points with
    x or y <= 0 are not counted. With ``weight``, each point counts that much (e.g. the
    time step of points sampled uniformly in time: the result is the time per bin).

    Returns:
        An array of shape ``(bins[1], bins[0])``: integers, or floats with ``weight``.
    """
    nx, ny = (int(b) for b in bins)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    (x0, x1), (y0, y1) = (float(v) for v in x_range), (float(v) for v in y_range)
    if log:
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = np.log10(x), np.log10(y)
        x0, x1, y0, y1 = np.log10([x0, x1, y0, y1])
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"empty bin ranges {x_range}, {y_range}")
    keep = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)  # NaN compares False
    ix = ((x[keep] - x0) * (nx / (x1 - x0))).astype(np.intp)
    iy = ((y[keep] - y0) * (ny / (y1 - y0))).astype(np.intp)
    np.minimum(ix, nx - 1, out=ix)  # the upper edge belongs to the last bin
    np.minimum(iy, ny - 1, out=iy)
    counts = np.bincount(iy * nx + ix, minlength=nx * ny).reshape(ny, nx)
    return counts if weight is None else counts * float(weight)
