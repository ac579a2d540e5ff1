"""Kane's method for the planar rotating ball, and Kane and Levinson's impact equations.

Read top to bottom, this module follows the derivation in the order a student meets it
(and in the order ``docs/derivation.md`` prints it):

1. frames: the lab frame N, the ball's body frame B, the contact frame c;
2. generalized coordinates q1, q2 (centre) and q3 (rotation angle about n3);
3. generalized speeds u1, u2 (centre velocity in N) and u3 (spin); the paper's u4,
   the centre's velocity along c1, is an output of these;
4. partial velocities of the centre and of the ball's material contact point;
5. equations of motion in flight (gravity, Fowles drag, optional Magnus force):
   Kane's mass matrix and forcing vector, kept separate, never inverted symbolically;
6. impact equations (generalized impulse = jump in generalized momentum) for a
   moving boundary, under the hypotheses of sticking and of slipping, and with Walton's
   tangential restitution of the contact point in place of sticking.

Every expression is built from ``sympy.physics.mechanics`` objects; nothing here is a
hand-written formula for a sphere.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sm
import sympy.physics.mechanics as me

# --- symbols -------------------------------------------------------------------------

t = me.dynamicsymbols._t
m, r, k, g = sm.symbols("m r k g", positive=True)
c_lin, c_quad, c_magnus = sm.symbols("c_lin c_quad c_magnus", real=True)
z = sm.symbols("z", real=True)  # tangent angle of the boundary at the contact point
vb1, vb2 = sm.symbols("vb1 vb2", real=True)  # boundary velocity at the impact
e, mu_k = sm.symbols("e mu_k", nonnegative=True)
sgn = sm.symbols("sgn", real=True)  # sign of the slip velocity before the impact
# Walton's tangential restitution of the contact point in a sticking impact: wt+ = -beta0 wt-
beta0 = sm.symbols("beta0", real=True)
Rt, Rn = sm.symbols("Rt Rn", real=True)  # impulse components along c1 and c2

q1, q2, q3 = me.dynamicsymbols("q1 q2 q3")
u1, u2, u3 = me.dynamicsymbols("u1 u2 u3")


@dataclass
class Step:
    """One step of the derivation, as printed in docs/derivation.md."""

    title: str
    text: str
    equations: list[tuple[str, sm.Basic]] = field(default_factory=list)


@dataclass
class BallDerivation:
    """Everything the code generator and the report need about the ball."""

    steps: list[Step]
    q: list[sm.Function]
    u: list[sm.Function]
    mass_matrix: sm.Matrix
    forcing_drag: sm.Matrix
    rhs_drag: sm.Matrix
    rhs_magnus: sm.Matrix
    flight_exact: sm.Matrix  # (q1, q2, u1, u2) after a drag-free flight of duration t
    contact_velocity: sm.Matrix  # (wt, wn)
    frame_velocity: sm.Matrix  # (u4, un)
    stick: sm.Matrix  # (u1+, u2+, u3+, Rt, Rn)
    slip: sm.Matrix
    walton: sm.Matrix  # (u1+, u2+, u3+, Rt, Rn) with wt+ = -beta0 wt-
    energy: sm.Basic
    post: list[sm.Symbol]  # symbols of the post-impact speeds


def derive_ball() -> BallDerivation:
    steps: list[Step] = []

    # 1. Frames -------------------------------------------------------------------
    N = me.ReferenceFrame("N")  # n1 horizontal, n2 up, n3 out of the plane
    B = N.orientnew("B", "Axis", [q3, N.z])  # fixed in the ball
    c = N.orientnew("c", "Axis", [z, N.z])  # contact frame: c1 tangent, c2 inward normal
    steps.append(
        Step(
            "Frames",
            "The lab frame N has n1 horizontal, n2 vertically up and n3 = n1 x n2 out of the "
            "plane. The ball's frame B is rotated from N by the angle q3 about n3. The contact "
            "frame c is rotated from N by the boundary's tangent angle z at the contact point, "
            "so c1 lies along the tangent and c2 is the normal pointing into the container.",
            [
                (r"\hat{c}_1", c.x.to_matrix(N).T),
                (r"\hat{c}_2", c.y.to_matrix(N).T),
            ],
        )
    )

    # 2-3. Coordinates and generalized speeds ---------------------------------------
    origin = me.Point("O")
    origin.set_vel(N, 0)
    C = origin.locatenew("C", q1 * N.x + q2 * N.y)
    kd = [q1.diff(t) - u1, q2.diff(t) - u2, q3.diff(t) - u3]
    C.set_vel(N, u1 * N.x + u2 * N.y)
    B.set_ang_vel(N, u3 * N.z)
    steps.append(
        Step(
            "Generalized coordinates and speeds",
            "The configuration is the centre's position (q1, q2) in N and the rotation angle "
            "q3. The generalized speeds are the centre's velocity components in N and the "
            "spin, so the kinematic differential equations are trivial. The paper's u4, the "
            "centre's velocity along c1, and the normal velocity un are outputs of these.",
            [
                (r"\mathbf{r}^{C}", C.pos_from(origin).to_matrix(N).T),
                (r"\mathbf{v}^{C}", C.vel(N).to_matrix(N).T),
                (r"\boldsymbol{\omega}^{B}", B.ang_vel_in(N).to_matrix(N).T),
                (r"\dot q - u", sm.Matrix(kd).T),
                (r"(u_4,\ u_n)", sm.Matrix([C.vel(N).dot(c.x), C.vel(N).dot(c.y)]).T),
            ],
        )
    )

    # 4. Partial velocities --------------------------------------------------------
    # P is the ball's material point at the contact; it lies a radius from C against c2.
    P = C.locatenew("P", -r * c.y)
    P.v2pt_theory(C, N, B)
    u = [u1, u2, u3]
    partial_C = me.partial_velocity([C.vel(N)], u, N)[0]
    partial_P = me.partial_velocity([P.vel(N)], u, N)[0]
    steps.append(
        Step(
            "Partial velocities",
            "The partial velocity of a point with respect to u_r is the coefficient of u_r in "
            "the point's velocity. The contact point P = C - r c2 moves with the ball, so its "
            "partial velocity with respect to the spin is r c1.",
            [
                (rf"\mathbf{{v}}^{{C}}_{{{i + 1}}}", v.to_matrix(N).T)
                for i, v in enumerate(partial_C)
            ]
            + [
                (
                    rf"\mathbf{{v}}^{{P}}_{{{i + 1}}}\ \text{{(in }}\hat c\text{{)}}",
                    v.to_matrix(c).T.applyfunc(sm.simplify),
                )
                for i, v in enumerate(partial_P)
            ],
        )
    )

    # 5. Equations of motion in flight ------------------------------------------------
    inertia = me.inertia(B, k * m * r**2, k * m * r**2, k * m * r**2)
    ball = me.RigidBody("ball", C, B, m, (inertia, C))
    ball.potential_energy = m * g * q2
    speed = sm.sqrt(u1**2 + u2**2)
    gravity = (C, -m * g * N.y)
    drag = (C, -(c_lin + c_quad * speed) * C.vel(N))
    magnus = (C, c_magnus * B.ang_vel_in(N).cross(C.vel(N)))

    def kane(loads):
        km = me.KanesMethod(N, q_ind=[q1, q2, q3], u_ind=u, kd_eqs=kd)
        km.kanes_equations([ball], loads)
        return km

    km_drag = kane([gravity, drag])
    km_magnus = kane([gravity, drag, magnus])
    km_free = kane([gravity])
    M = km_drag.mass_matrix
    F_drag = km_drag.forcing
    # The right-hand side M^-1 F is solved symbolically by LU (no inverse is formed): for
    # this ball M is diagonal, so the solve reduces to divisions, but nothing relies on that.
    rhs_drag = M.LUsolve(F_drag)
    rhs_magnus = km_magnus.mass_matrix.LUsolve(km_magnus.forcing)
    steps.append(
        Step(
            "Equations of motion in flight",
            "Kane's equations Fr + Fr* = 0 with gravity, Fowles drag -(c_lin + c_quad |v|) v "
            "acting at the centre, and an optional Magnus force c_magnus (omega x v), give "
            "M(q) du/dt = F(q, u). The right-hand side du/dt = M^-1 F is solved symbolically "
            "by LU, without forming an inverse (M is diagonal here), and generated as "
            "flight_rhs_drag and flight_rhs_magnus. No load has a moment about C, so the "
            "spin is constant in flight.",
            [
                (r"M", M),
                (r"F_{\mathrm{drag}}", F_drag),
                (r"F_{\mathrm{drag+Magnus}}", km_magnus.forcing),
            ],
        )
    )

    # Drag-free flight: the forcing is constant, so the motion integrates in closed form.
    tau = sm.Symbol("t", nonnegative=True)
    accel = km_free.mass_matrix.LUsolve(km_free.forcing)
    u0 = sm.Matrix(u)
    u_of_t = u0 + accel * tau
    q_of_t = sm.Matrix([q1, q2, q3]) + sm.Matrix([sm.integrate(ui, (tau, 0, tau)) for ui in u_of_t])
    flight_exact = sm.Matrix([q_of_t[0], q_of_t[1], u_of_t[0], u_of_t[1]])
    steps.append(
        Step(
            "Drag-free flight in closed form",
            "Without drag the forcing vector is constant; integrating M du/dt = F twice gives "
            "the exact flight used by the default method when a scene turns drag off.",
            [(r"(q_1, q_2, u_1, u_2)(t)", flight_exact.T)],
        )
    )

    # 6. Impact equations -----------------------------------------------------------
    # Relative velocity of the material contact point with respect to the boundary.
    w = P.vel(N) - (vb1 * N.x + vb2 * N.y)
    wt, wn = w.dot(c.x), w.dot(c.y)
    contact_velocity = sm.Matrix([wt, wn]).applyfunc(sm.expand)
    frame_velocity = sm.Matrix([C.vel(N).dot(c.x), C.vel(N).dot(c.y)])
    impulse = Rt * c.x + Rn * c.y
    generalized_impulse = sm.Matrix([v.dot(impulse) for v in partial_P])

    post = list(sm.symbols("u1p u2p u3p", real=True))
    pre = {u1: sm.Symbol("u1"), u2: sm.Symbol("u2"), u3: sm.Symbol("u3")}
    to_post = dict(zip(u, post, strict=True))
    momentum_jump = M * (sm.Matrix(post) - sm.Matrix(u))
    impulse_momentum = list(momentum_jump - generalized_impulse)
    restitution = wn.subs(to_post) + e * wn
    no_slip = wt.subs(to_post)
    coulomb = Rt + mu_k * sgn * Rn
    tangential = wt.subs(to_post) + beta0 * wt
    unknowns = post + [Rt, Rn]

    def solve(conditions):
        A, b = sm.linear_eq_to_matrix(impulse_momentum + conditions, unknowns)
        sol = A.LUsolve(b)
        return sol.applyfunc(lambda ex: sm.simplify(sm.expand_trig(ex)))

    stick = solve([restitution, no_slip])
    slip = solve([restitution, coulomb])
    walton = solve([restitution, tangential])
    steps.append(
        Step(
            "Impact: generalized impulse equals the jump in generalized momentum",
            "During the impact the boundary exerts the impulse R = Rt c1 + Rn c2 at P. Kane "
            "and Levinson's impulse-momentum equations equate, for each generalized speed, the "
            "jump in generalized momentum (mass matrix times the jump in u) to the generalized "
            "impulse (partial velocity of P dotted with R). The boundary moves with velocity "
            "V_B, so restitution and friction act on the velocity of P relative to it, "
            "w = v^P - V_B, with components wt along c1 and wn along c2 (wn < 0 approaching).",
            [
                (r"(w_t,\ w_n)", contact_velocity.T),
                (r"M\,(u^+ - u^-) - \tilde I", sm.Matrix(impulse_momentum).T),
            ],
        )
    )
    steps.append(
        Step(
            "Impact, first hypothesis: no slip",
            "Newton's restitution acts on the relative normal velocity, wn+ = -e wn-, and the "
            "contact point stops slipping, wt+ = 0. The five linear equations give the "
            "post-impact speeds and both impulse components. The solution is valid if and "
            "only if |Rt| <= mu_s Rn.",
            [(r"(u_1^+, u_2^+, u_3^+, R_t, R_n)_{\mathrm{stick}}", stick.T)],
        )
    )
    steps.append(
        Step(
            "Impact, second hypothesis: slip",
            "If the no-slip impulse needs more friction than mu_s Rn, the ball slips throughout "
            "the impact and kinetic friction opposes the initial slip: Rt = -mu_k sgn(wt-) Rn, "
            "with the same restitution condition.",
            [(r"(u_1^+, u_2^+, u_3^+, R_t, R_n)_{\mathrm{slip}}", slip.T)],
        )
    )

    steps.append(
        Step(
            "Impact, third hypothesis: tangential restitution of the contact point",
            "Walton's law of granular physics (O. R. Walton, in Particulate Two-Phase Flow, "
            "1993; S. F. Foerster, M. Y. Louge, H. Chang and K. Allia, Phys. Fluids 6, 1108, "
            "1994) replaces the no-slip condition of a sticking impact by a tangential "
            "restitution of the contact point, wt+ = -beta0 wt-, with the same normal "
            "restitution: beta0 = 0 is the no-slip impact above, beta0 = -1 leaves wt "
            "unchanged (a smooth sphere), beta0 > 0 reverses it as real spheres do. A "
            "sliding impact is the slip hypothesis above, taken when this impulse needs "
            "more than mu Rn.",
            [(r"(u_1^+, u_2^+, u_3^+, R_t, R_n)_{\mathrm{Walton}}", walton.T)],
        )
    )

    energy = ball.kinetic_energy(N) + ball.potential_energy
    return BallDerivation(
        steps=steps,
        q=[q1, q2, q3],
        u=u,
        mass_matrix=M,
        forcing_drag=F_drag,
        rhs_drag=rhs_drag,
        rhs_magnus=rhs_magnus,
        flight_exact=flight_exact,
        contact_velocity=contact_velocity,
        frame_velocity=frame_velocity,
        stick=stick.xreplace(pre),
        slip=slip.xreplace(pre),
        walton=walton.xreplace(pre),
        energy=energy,
        post=post,
    )


def plain(expr):
    """Replace the time-dependent symbols q(t), u(t) by plain symbols for printing."""
    mapping = {f: sm.Symbol(f.func.__name__) for f in (q1, q2, q3, u1, u2, u3)}
    return me.msubs(expr, mapping)
