"""The surfaces over the state vector: the offset curve of a curved wall, of a straight
one, the lid and the escape level, with the warm starts in the surface's block of
``ctx``. The classes of :mod:`billiard.geometry.surfaces` are these functions, run interpreted.

A curved wall's functions come in ``walls = (f, df, d2f)``, each a tuple with one
function per wall of the curve, called through :func:`.wallcall.call_wall` as
``call_wall(walls, 1, w, x, p)`` (``walls[1][w](x, p)``); compiled, they are
first-class function values of type ``float64(float64, float64[::1])`` (see
:mod:`billiard.geometry.wall_functions`), so the kernels are compiled once for every
curve; on a GPU the call is the seam of :mod:`.wallcall`.
"""

from __future__ import annotations

import math

from .decorators import inline
from .layout import (
    CURVED,
    E_INVERSION,
    EN_ERR_VALUE,
    EN_STOP,
    LINE,
    S_A,
    S_B,
    S_C,
    S_D,
    S_KIND,
    S_SLOPE,
    S_SLOPE_AT,
    S_WALL,
    S_WS,
    S_WSLOPE,
    SURF,
    SURF_STRIDE,
    KernelError,
)
from .wallcall import call_wall

# Newton on the offset inversion stops once a step is below this (m); the error left after
# that step is of order curvature * step^2, far below a double's resolution.
FOOT_STEP_TOL = 1e-11


@inline
def offset_stretch(fp, f2, r):
    """dX/ds = 1 - r f''/(1 + f'^2)^(3/2) of the offset curve at a wall point with slope
    ``fp`` and second derivative ``f2`` (1/m), ball radius r (m): positive while the ball
    fits the curvature."""
    q = 1.0 + fp * fp
    return 1.0 - r * f2 / (q * math.sqrt(q))


@inline
def offset_curvature(fp, f2, r):
    """Curvature term F''(X) = f'' / (dX/ds) of the offset curve (1/m)."""
    return f2 / offset_stretch(fp, f2, r)


@inline
def foot(ctx, p, walls, base, x, s, fp):
    """Abscissa s of the wall point whose offset point has abscissa x (Newton from s;
    ``fp``: f'(s) when known, else nan)."""
    w = int(ctx[base + S_WALL])
    r = ctx[base + S_A]
    for _ in range(60):
        if math.isnan(fp):
            fp = call_wall(walls, 1, w, s, p)
        q = 1.0 + fp * fp
        wr = r / math.sqrt(q)
        ds = (s - fp * wr - x) / (1.0 - call_wall(walls, 2, w, s, p) * wr / q)
        s -= ds
        if abs(ds) < FOOT_STEP_TOL:
            return s
        fp = math.nan  # not known at the new s
    ctx[EN_ERR_VALUE] = x
    ctx[EN_STOP] = E_INVERSION
    raise KernelError(E_INVERSION)


@inline
def known_slope(ctx, base):
    """f'(s) at the warm start s of a curved surface's block when the slope memo holds
    it, else nan. f' is a pure function of s and of the block's wall (fixed while the
    block is in a ctx), so the memo is the value the call would return, bit for bit; not
    at s = 0, where +0 and -0 compare equal but may give slopes of opposite signs."""
    s = ctx[base + S_WS]
    if s == ctx[base + S_SLOPE_AT] and s != 0.0:
        return ctx[base + S_SLOPE]
    return math.nan


@inline
def remember_slope(ctx, base, s, fp):
    """The slope memo: fp = f'(s)."""
    ctx[base + S_SLOPE_AT] = s
    ctx[base + S_SLOPE] = fp


@inline
def offset_height(ctx, p, walls, j, x):
    """F(x): the height (m) of a centre touching wall surface j at abscissa x, the warm
    start s of its block moved to the foot (its slope left as it was). A contact phase
    watches the other walls by py - F(px), the quantity it always compared; gap_rate's
    py - f(s) - r/sqrt(1 + f'^2) rounds differently."""
    base = SURF + j * SURF_STRIDE
    if ctx[base + S_KIND] == CURVED:
        s = foot(ctx, p, walls, base, x, ctx[base + S_WS], math.nan)
        ctx[base + S_WS] = s
        w = int(ctx[base + S_WALL])
        fp = call_wall(walls, 1, w, s, p)
        return call_wall(walls, 0, w, s, p) + ctx[base + S_A] / math.sqrt(1.0 + fp * fp)
    return ctx[base + S_A] * x + ctx[base + S_B]


@inline
def gap_rate(ctx, p, walls, j, px, py, vx, vy):
    """(G, dG/dt) of surface j for a centre at p moving at v relative to the boundary."""
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == CURVED:
        s = foot(ctx, p, walls, base, px, ctx[base + S_WS], known_slope(ctx, base))
        w = int(ctx[base + S_WALL])
        fp = call_wall(walls, 1, w, s, p)
        ctx[base + S_WS] = s
        ctx[base + S_WSLOPE] = fp
        remember_slope(ctx, base, s, fp)
        f = call_wall(walls, 0, w, s, p)
        return py - f - ctx[base + S_A] / math.sqrt(1.0 + fp * fp), vy - fp * vx
    if kind == LINE:
        b = ctx[base + S_A]
        return py - b * px - ctx[base + S_B], vy - b * vx
    return ctx[base + S_A] - py, -vy


@inline
def gap_accel(ctx, p, walls, j, px, py, vx, vy, ax, ay):
    """d2G/dt2 of surface j for a relative acceleration a."""
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == CURVED:
        s = foot(ctx, p, walls, base, px, ctx[base + S_WS], known_slope(ctx, base))
        ctx[base + S_WS] = s
        w = int(ctx[base + S_WALL])
        fp = call_wall(walls, 1, w, s, p)
        remember_slope(ctx, base, s, fp)
        curvature = offset_curvature(fp, call_wall(walls, 2, w, s, p), ctx[base + S_A])
        return ay - fp * ax - curvature * vx * vx
    if kind == LINE:
        return ay - ctx[base + S_A] * ax
    return -ay


@inline
def gap_accel_bound(ctx, j, a):
    """Bound on |d2G/dt2| of surface j from a relative acceleration of size a (m/s^2),
    at the slope its last gap_rate saw: |a_y - F' a_x| <= a (1 + |F'|)."""
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == CURVED:
        return a * (1.0 + abs(ctx[base + S_WSLOPE]))
    if kind == LINE:
        return a * (1.0 + abs(ctx[base + S_A]))
    return a


@inline
def contact(ctx, p, walls, j, px):
    """(s, z) of the contact point of a centre at abscissa px on surface j's offset."""
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == CURVED:
        s = foot(ctx, p, walls, base, px, ctx[base + S_WS], known_slope(ctx, base))
        ctx[base + S_WS] = s
        fp = call_wall(walls, 1, int(ctx[base + S_WALL]), s, p)
        remember_slope(ctx, base, s, fp)
        return s, math.atan(fp)
    if kind == LINE:
        return px + ctx[base + S_C], ctx[base + S_D]
    return px, math.pi


@inline
def max_gap_deceleration(ctx, j, px, vx, tau, ax, ay_down, ay_up):
    """Bound on -d2G/dtau2 of surface j over a window of length tau."""
    base = SURF + j * SURF_STRIDE
    kind = ctx[base + S_KIND]
    if kind == CURVED:
        dx = abs(vx) * tau + 0.5 * ax * tau * tau
        vmax = abs(vx) + ax * tau
        return (
            ay_down
            + (abs(ctx[base + S_WSLOPE]) + 2.0 * ctx[base + S_C] * dx) * ax
            + ctx[base + S_B] * vmax * vmax
        )
    if kind == LINE:
        return ay_down + abs(ctx[base + S_A]) * ax
    return max(0.0, ay_up)
