"""The equations of a contact phase over the state vector: the boundary's motion, the
contact forces and the rates of (s, s_dot, u3) on one wall (the generated equations of
:mod:`billiard.generated.contact`), and the transition functions whose sign changes end
a phase. :mod:`billiard.kernels.contact` integrates them."""

from __future__ import annotations

from .contact_equations import centre_state, roll_rhs, slide_rhs, slip_velocity
from .decorators import inline
from .drive import boundary_motion
from .layout import (
    CURVED,
    LINE,
    NSURF,
    OMEGA,
    PH_CLIN,
    PH_CQUAD,
    PH_G,
    PH_HI,
    PH_K,
    PH_LO,
    PH_M,
    PH_MODE,
    PH_MUK,
    PH_MUS,
    PH_R,
    PH_SGN,
    PH_SURF,
    PH_THETA0,
    PH_WALL,
    ROLL,
    S_A,
    S_KIND,
    SURF,
    SURF_STRIDE,
)
from .surfaces import offset_height


@inline
def n_y(ctx):
    """Components of y: (s, s_dot) rolling, (s, s_dot, u3) sliding."""
    return 2 if ctx[PH_MODE] == ROLL else 3


@inline
def forces(ctx, p, walls, theta, s, sd):
    """(s_ddot, u3_dot, N, F) of the phase's mode at drive angle theta; u3_dot is that
    of the no-slip spin (0) while rolling."""
    w = int(ctx[PH_WALL])
    fp = walls[1][w](s, p)
    f2 = walls[2][w](s, p)
    f3 = walls[3][w](s, p)
    vb1, vb2, ab1, ab2 = boundary_motion(ctx, theta)
    if ctx[PH_MODE] == ROLL:
        sdd, n, f = roll_rhs(sd, fp, f2, f3, ab1, ab2, vb1, vb2, ctx[PH_M], ctx[PH_R],
                             ctx[PH_K], ctx[PH_G], ctx[PH_CLIN], ctx[PH_CQUAD])  # fmt: skip
        return sdd, 0.0, n, f
    return slide_rhs(sd, fp, f2, f3, ab1, ab2, vb1, vb2, ctx[PH_M], ctx[PH_R], ctx[PH_K],
                     ctx[PH_G], ctx[PH_CLIN], ctx[PH_CQUAD], ctx[PH_MUK], ctx[PH_SGN])  # fmt: skip


@inline
def rhs(ctx, p, walls, tau, y, out):
    """dy/dtau at tau of the state in ctx[y:y + 3] into ctx[out:out + 3]."""
    sdd, u3d, _, _ = forces(ctx, p, walls, ctx[PH_THETA0] + ctx[OMEGA] * tau, ctx[y], ctx[y + 1])
    ctx[out] = ctx[y + 1]
    ctx[out + 1] = sdd
    ctx[out + 2] = u3d if ctx[PH_MODE] != ROLL else 0.0


@inline
def at_rest(ctx, k):
    """Is every component of the derivative ctx[k:k + n_y] within 1e-15 of zero?"""
    for j in range(n_y(ctx)):
        if not abs(ctx[k + j]) <= 1e-15:
            return False
    return True


@inline
def conditions(ctx, p, walls, tau, y, out):
    """The functions positive while the phase lasts, at tau for the state ctx[y:y + 3],
    into ctx[out:]: N, s - lo, hi - s, the friction's (mu_s N - |F| rolling, the slip's
    sign sliding), then the gap of each other surface (which moves its warm start)."""
    theta = ctx[PH_THETA0] + ctx[OMEGA] * tau
    s, sd = ctx[y], ctx[y + 1]
    _, _, n, f = forces(ctx, p, walls, theta, s, sd)
    ctx[out] = n
    ctx[out + 1] = s - ctx[PH_LO]
    ctx[out + 2] = ctx[PH_HI] - s
    w = int(ctx[PH_WALL])
    r = ctx[PH_R]
    if ctx[PH_MODE] == ROLL:
        ctx[out + 3] = ctx[PH_MUS] * n - abs(f)
    elif ctx[PH_MUS] == 0.0:
        ctx[out + 3] = 1.0  # no friction: the slip's sign changes nothing
    else:
        slip = slip_velocity(sd, ctx[y + 2], walls[1][w](s, p), walls[2][w](s, p), r)
        ctx[out + 3] = ctx[PH_SGN] * slip
    nsurf = int(ctx[NSURF])
    if nsurf < 2:
        return
    f0 = walls[0][w](s, p)
    fp = walls[1][w](s, p)
    f2 = walls[2][w](s, p)
    px, py, _, _ = centre_state(s, sd, f0, fp, f2, 0.0, 0.0, 0.0, 0.0, r)
    i = out + 4
    own = int(ctx[PH_SURF])
    for j in range(nsurf):
        if j == own:
            continue
        kind = ctx[SURF + j * SURF_STRIDE + S_KIND]
        if kind == CURVED or kind == LINE:
            ctx[i] = py - offset_height(ctx, p, walls, j, px)
        else:
            ctx[i] = ctx[SURF + j * SURF_STRIDE + S_A] - py
        i += 1


@inline
def n_conditions(ctx):
    return 4 + max(int(ctx[NSURF]) - 1, 0)
