"""Kane's method for the ball in sustained contact with one wall of the moving boundary.

Read top to bottom, this module follows the derivation in the order a student meets it
(and in the order ``docs/derivation.md`` prints it, after the impact sections):

1. the wall's local geometry at the contact abscissa s, in terms of f'(s), f''(s) and
   f'''(s) only, so that one set of equations serves every curve;
2. the holonomic constraint: the centre C lies on the wall's offset curve, C = W(s) + r c2;
   the coordinates are s (in the boundary's frame) and the rotation angle q3, the speeds
   u_s = ds/dt and the spin u3; the velocity of C and the slip of the contact point;
3. auxiliary generalized speeds that bring the contact forces into evidence: u_n, a
   translation of the ball along the normal c2 (for N), and in the rolling mode u_t, a
   translation along the tangent c1 (for the friction F);
4. rolling: the no-slip condition as a nonholonomic constraint (u3 dependent), Kane's
   equation for u_s, the auxiliary equations for F and N, and their solution;
5. sliding: two degrees of freedom, Coulomb friction F = -mu_k N sgn, Kane's equations for
   u_s and u3 with the auxiliary equation for N;
6. outputs for the runtime's transitions: the centre's lab state from (s, ds/dt), ds/dt from
   a lab velocity, the energy in the boundary's frame.

The boundary translates with a prescribed displacement (d1, d2) in N; its velocity
(vb1, vb2) and acceleration (ab1, ab2) enter as inputs, so one set of equations serves a
horizontal and a vertical drive. Gravity and Fowles drag (on the centre's lab velocity,
still air) act as in flight. The normal force N and the friction F are never written by
hand: they come out of Kane's auxiliary equations.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sm
import sympy.physics.mechanics as me

from .ball import Step

t = me.dynamicsymbols._t

# --- symbols -------------------------------------------------------------------------

m, r, k, g = sm.symbols("m r k g", positive=True)
c_lin, c_quad = sm.symbols("c_lin c_quad", real=True)
mu_k, sgn = sm.symbols("mu_k sgn", real=True)
N_force, F_force = sm.symbols("N F", real=True)  # contact force on the ball: F c1 + N c2
ab1, ab2, vb1, vb2 = sm.symbols("ab1 ab2 vb1 vb2", real=True)  # boundary acceleration, velocity
d1, d2 = sm.symbols("d1 d2", real=True)  # boundary displacement in N
u1, u2 = sm.symbols("u1 u2", real=True)  # a lab velocity of the centre
#: The drag factor c_lin + c_quad |v|, a placeholder while the equations are solved.
c_drag = sm.Symbol("c_drag", real=True)

# The wall's local geometry at the contact abscissa: plain symbols in the final equations.
fp, f2, f3, f0 = sm.symbols("fp f2 f3 f0", real=True)  # f'(s), f''(s), f'''(s), f(s)
z, L, L_s, z_s, z_ss = sm.symbols("z L L_s z_s z_ss", real=True)

s, q3 = me.dynamicsymbols("s q3")
us, u3 = me.dynamicsymbols("u_s u3")
ut, un = me.dynamicsymbols("u_t u_n")  # auxiliary speeds: along c1 and along c2
dd1, dd2 = me.dynamicsymbols("d1 d2")  # the boundary's prescribed displacement


def _geometry_function(name: str, derivative=None):
    """An undefined function of s whose derivative is the next one in the chain; the
    chain ends where the contact equations stop needing derivatives."""

    def fdiff(self, argindex=1):
        if derivative is None:
            raise NotImplementedError(f"d{name}/ds is not part of the contact geometry")
        return derivative(self.args[0])

    return type(name, (sm.Function,), {"fdiff": fdiff})


# z(s) the tangent angle, z_s = dz/ds, z_ss; L(s) = |dW/ds|, L_s = dL/ds.
_Zss = _geometry_function("z_ss")
_Zs = _geometry_function("z_s", _Zss)
_Z = _geometry_function("z", _Zs)
_Ls = _geometry_function("L_s")
_L = _geometry_function("L", _Ls)
_F0 = _geometry_function("f_0")  # the wall's height f(s): only its value is used


@dataclass
class ContactDerivation:
    """Everything the code generator and the report need about sustained contact.

    Expressions are in the plain symbols s_dot (= u_s), u3, the geometry (z, L, L_s, z_s,
    z_ss, f0, s) and the parameters; :attr:`geometry` maps the geometry to f', f'', f'''.
    """

    steps: list[Step]
    geometry: dict[sm.Symbol, sm.Basic]  # z, L, L_s, z_s, z_ss in terms of fp, f2, f3
    roll: sm.Matrix  # (s_ddot, spin_dot, F, N)
    slide: sm.Matrix  # (s_ddot, spin_dot, N, F)
    roll_spin: sm.Basic  # u3 from the no-slip condition
    slip: sm.Basic  # slip velocity of the contact point relative to the wall, along c1
    centre: sm.Matrix  # (q1, q2, u1, u2) in N
    s_dot: sm.Basic  # ds/dt from a lab velocity (u1, u2) of the centre
    energy: sm.Basic  # in the boundary's frame
    drag_factor: sm.Basic  # c_lin + c_quad |v|, the value of the placeholder c_drag


# Names of the speeds and their rates in the generated code.
S_DOT, SPIN, S_DDOT, SPIN_DOT = sm.symbols("s_dot u3 s_ddot spin_dot", real=True)
#: How the report prints the plain symbols.
DISPLAY = {
    S_DOT: sm.Symbol("u_s"),
    S_DDOT: sm.Symbol(r"\dot{u}_{s}"),
    SPIN_DOT: sm.Symbol(r"\dot{u}_{3}"),
    fp: sm.Symbol("f'"),
    f2: sm.Symbol("f''"),
    f3: sm.Symbol("f'''"),
}


def _plain(expr):
    """Dynamic symbols and geometry functions -> plain symbols (for code and printing);
    the auxiliary speeds are zero."""
    if not isinstance(expr, sm.MatrixBase):
        expr = sm.sympify(expr)
    rates = {us.diff(t): S_DDOT, u3.diff(t): SPIN_DOT, s.diff(t): S_DOT, q3.diff(t): SPIN}
    geo = {_Zss(s): z_ss, _Zs(s): z_s, _Z(s): z, _Ls(s): L_s, _L(s): L, _F0(s): f0}
    return me.msubs(expr, rates, geo, {us: S_DOT, u3: SPIN, ut: 0, un: 0})


def printable(expr):
    """An expression of the derivation as the report prints it."""
    return _plain(expr).xreplace(DISPLAY)


def derive_contact() -> ContactDerivation:
    steps: list[Step] = []
    fpx = sm.Function("f")(sm.Symbol("s", real=True))
    sx = fpx.args[0]
    show = {
        sm.Derivative(fpx, (sx, 3)): sm.Symbol("f'''"),
        sm.Derivative(fpx, (sx, 2)): sm.Symbol("f''"),
        sm.Derivative(fpx, sx): sm.Symbol("f'"),
    }
    as_code = {sm.Symbol("f'''"): f3, sm.Symbol("f''"): f2, sm.Symbol("f'"): fp}

    # 1. The wall's local geometry ---------------------------------------------------
    # In the boundary's frame the wall is W(s) = (s, f(s)). Its tangent angle and the
    # length of dW/ds, with the derivatives that the velocity and acceleration of the
    # centre need, follow from f by differentiation.
    slope = fpx.diff(sx)
    z_of_s = sm.atan(slope)
    L_of_s = sm.sqrt(1 + slope**2)
    geometry_shown = {
        z: z_of_s,
        L: L_of_s,
        z_s: sm.simplify(z_of_s.diff(sx)),
        L_s: sm.simplify(L_of_s.diff(sx)),
        z_ss: sm.simplify(z_of_s.diff(sx, 2)),
    }
    geometry_shown = {key: val.xreplace(show) for key, val in geometry_shown.items()}
    geometry = {key: val.xreplace(as_code) for key, val in geometry_shown.items()}
    # The tangent dW/ds = (1, f') is L c1: check it in the contact frame's components.
    tangent_c = sm.Matrix(
        [
            sm.cos(z) * 1 + sm.sin(z) * slope,  # dW/ds . c1
            -sm.sin(z) * 1 + sm.cos(z) * slope,  # dW/ds . c2
        ]
    ).subs(z, z_of_s)
    tangent_c = tangent_c.applyfunc(sm.simplify)
    if tangent_c[1] != 0 or sm.simplify(tangent_c[0] - L_of_s) != 0:
        raise AssertionError(f"dW/ds is not L c1: {tangent_c}")
    steps.append(
        Step(
            "Sustained contact: the wall's local geometry",
            "From here on the ball stays in contact with one wall y = f(x) of the boundary. "
            "The contact point's abscissa s in the boundary's frame locates the wall point "
            "W(s) = (s, f(s)). Its tangent dW/ds = (1, f') has length L and direction c1 at "
            "the tangent angle z; the normal c2 points into the container. The centre's "
            "velocity needs dz/ds and its acceleration d2z/ds2 and dL/ds, so the equations "
            "below depend on the curve only through f', f'' and f''' at s: one set of "
            "generated functions serves every curve, each curve module supplying f'''. The "
            "tangent's components along c1 and c2 confirm dW/ds = L c1.",
            [
                (r"z", geometry_shown[z]),
                (r"L", geometry_shown[L]),
                (r"z_s = \frac{dz}{ds}", geometry_shown[z_s]),
                (r"L_s = \frac{dL}{ds}", geometry_shown[L_s]),
                (r"z_{ss} = \frac{d^2 z}{ds^2}", geometry_shown[z_ss]),
                (
                    r"\frac{dW}{ds}\cdot\left(\hat c_1,\ \hat c_2\right)",
                    tangent_c.T.xreplace(show),
                ),
            ],
        )
    )

    # 2. The holonomic constraint, coordinates and speeds ------------------------------
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [q3, N.z])  # fixed in the ball
    B.set_ang_vel(N, u3 * N.z)
    c = N.orientnew("c", "Axis", [_Z(s), N.z])  # the contact frame moves with s
    c.set_ang_vel(N, _Zs(s) * us * N.z)  # d z(s)/dt = z_s ds/dt
    origin = me.Point("O")
    origin.set_vel(N, 0)
    Ob = origin.locatenew("O_B", dd1 * N.x + dd2 * N.y)  # the boundary frame's origin
    Ob.set_vel(N, Ob.pos_from(origin).dt(N))
    W = Ob.locatenew("W", s * N.x + _F0(s) * N.y)  # the wall point at s
    W.set_vel(N, Ob.vel(N) + _L(s) * us * c.x)  # dW/dt = V_B + (dW/ds) ds/dt
    C = W.locatenew("C", r * c.y)  # the centre, on the offset curve: C = W + r c2
    C.v2pt_theory(W, N, c)  # C is fixed in the contact frame, a radius from W
    v_C = C.vel(N)
    P = C.locatenew("P", -r * c.y)  # the ball's material point at the contact
    P.v2pt_theory(C, N, B)
    slip = sm.expand((P.vel(N) - Ob.vel(N)).dot(c.x))
    normal = sm.expand((P.vel(N) - Ob.vel(N)).dot(c.y))
    if normal != 0:
        raise AssertionError(f"the contact point moves off the wall: {normal}")
    kd = [s.diff(t) - us, q3.diff(t) - u3]
    # The boundary's prescribed motion: its velocity and acceleration are inputs.
    drive = {dd1.diff(t, 2): ab1, dd2.diff(t, 2): ab2, dd1.diff(t): vb1, dd2.diff(t): vb2}
    steps.append(
        Step(
            "Sustained contact: the constraint, coordinates and speeds",
            "The centre C lies on the wall's offset curve, C = W(s) + r c2 (a holonomic "
            "constraint: one coordinate along the wall fixes it). The coordinates are s and "
            "the ball's rotation angle q3; the speeds are u_s = ds/dt and the spin u3. The "
            "boundary frame's origin moves with the drive, so C's velocity is the boundary's "
            "velocity V_B = (vb1, vb2) plus the velocity along the offset curve, whose "
            "length per unit s is L - r z_s (the factor 1 - r kappa of a parallel curve). The "
            "ball's material point P = C - r c2 has no velocity along c2 relative to the "
            "wall; along c1 its relative velocity is the slip w_t.",
            [
                (r"\mathbf{v}^{C}\ \text{(in N)}", me.msubs(v_C.to_matrix(N).T, drive)),
                (
                    r"\mathbf{v}^{C} - \mathbf{V}_B\ \text{(in }\hat c\text{)}",
                    _plain((v_C - Ob.vel(N)).to_matrix(c).T),
                ),
                (r"\boldsymbol{\omega}^{B}", _plain(B.ang_vel_in(N).to_matrix(N).T)),
                (r"w_t = (\mathbf{v}^{P} - \mathbf{V}_B)\cdot\hat c_1", _plain(slip)),
            ],
        )
    )

    # 3. Auxiliary speeds: the contact forces into evidence ------------------------------
    inertia = me.inertia(B, k * m * r**2, k * m * r**2, k * m * r**2)
    ball = me.RigidBody("ball", C, B, m, (inertia, C))
    velocity = v_C.to_matrix(N)
    drag_factor = c_lin + c_quad * sm.sqrt(velocity[0] ** 2 + velocity[1] ** 2)
    gravity = (C, -m * g * N.y)
    # Fowles drag on the centre's lab velocity; its factor c_lin + c_quad |v| stays a
    # symbol while the equations are solved (it multiplies v, linear in the unknowns).
    drag = (C, -c_drag * v_C)

    def with_aux(aux):
        """Give C (and so P) the auxiliary velocity sum(u_aux * direction)."""
        C.set_vel(N, v_C + sum((a * d for a, d in aux), sm.S.Zero * N.x))
        P.v2pt_theory(C, N, B)

    def kane(u_ind, aux, loads, **constraints):
        with_aux(aux)
        km = me.KanesMethod(
            N,
            q_ind=[s, q3],
            u_ind=u_ind,
            kd_eqs=kd,
            u_auxiliary=[a for a, _ in aux],
            **constraints,
        )
        fr, frstar = km.kanes_equations([ball], loads)
        eqs = [me.msubs(e, drive) for e in fr + frstar]
        return km, eqs

    contact_force = (P, F_force * c.x + N_force * c.y)
    with_aux([(ut, c.x), (un, c.y)])
    partial_P = me.partial_velocity([P.vel(N)], [us, u3, ut, un], N)[0]
    steps.append(
        Step(
            "Sustained contact: auxiliary speeds for the contact forces",
            "The wall pushes on the ball at P with N c2 and rubs with F c1. Neither does work "
            "in a motion the constraints allow, so neither appears in Kane's equations for "
            "u_s and u3 (in the rolling mode F does no work either, since P does not slip). "
            "Kane and Levinson bring such forces into evidence with auxiliary generalized "
            "speeds: motions that violate a constraint, here a translation of the whole ball "
            "by u_n along c2 and by u_t along c1. The partial velocities of P with respect to "
            "them are c2 and c1, so the generalized active forces for u_n and u_t contain N "
            "and F. Their Kane equations, written with the auxiliary speeds and their rates "
            "set to zero afterwards, are the extra equations that determine N and F. The "
            "partial velocities of P, in c, with respect to (u_s, u3, u_t, u_n):",
            [
                (
                    rf"\mathbf{{v}}^{{P}}_{{{name}}}\ \text{{(in }}\hat c\text{{)}}",
                    _plain(vec.to_matrix(c).T.applyfunc(sm.simplify)),
                )
                for name, vec in zip(("u_s", "u_3", "u_t", "u_n"), partial_P, strict=True)
            ],
        )
    )

    def finish(solution):
        """Each unknown as one fraction, its numerator grouped by the drag factor, the
        friction coefficient and the powers of u_s (cheap rational algebra; no
        trigonometric simplification)."""
        out = []
        for expr in solution:
            num, den = sm.fraction(sm.cancel(sm.together(_plain(expr))))
            num = sm.collect(
                sm.expand(num),
                [c_drag, mu_k],
                func=lambda part: sm.collect(part, S_DOT, func=sm.factor),
            )
            out.append(sm.factor_terms(num) / sm.factor(den))
        return sm.Matrix(out)

    # 4. Rolling --------------------------------------------------------------------
    no_slip = slip  # w_t = 0: a velocity constraint with u3 dependent on u_s
    km_roll, roll_eqs = kane(
        [us],
        [(ut, c.x), (un, c.y)],
        [gravity, drag, contact_force],
        u_dependent=[u3],
        velocity_constraints=[no_slip],
    )
    # The acceleration constraint, d/dt of the no-slip condition.
    roll_acc = me.msubs(no_slip.diff(t), {s.diff(t): us})
    udots = [us.diff(t), u3.diff(t)]
    A, b = sm.linear_eq_to_matrix(
        [_plain(e) for e in [*roll_eqs, roll_acc]],
        [_plain(x) for x in [*udots, F_force, N_force]],
    )
    roll = finish(A.LUsolve(b))
    roll_spin = sm.solve(_plain(no_slip), SPIN)[0]
    steps.append(
        Step(
            "Rolling: the no-slip constraint and Kane's equations",
            "While the ball rolls the slip w_t vanishes: a nonholonomic velocity constraint "
            "that makes u3 a dependent speed, u3 = -(L - r z_s) u_s / r, leaving one degree "
            "of freedom. Kane's equation for u_s (its inertia and active forces combined over "
            "the independent and the dependent speed), the two auxiliary equations for u_t "
            "and u_n, and the time derivative of the constraint form four linear equations in "
            "du_s/dt, du3/dt, F and N. Drag acts at C with the factor "
            "c_drag = c_lin + c_quad |v|, v the centre's lab velocity (still air); the "
            "boundary's acceleration (ab1, ab2) enters through C's acceleration.",
            [
                (r"u_3", roll_spin),
                (r"F_r + F_r^* \ (u_s)", roll_eqs[0]),
                (r"F_r + F_r^* \ (u_t)", roll_eqs[1]),
                (r"F_r + F_r^* \ (u_n)", roll_eqs[2]),
                (r"\frac{d w_t}{dt}", roll_acc),
                (r"\dot u_s", roll[0]),
                (r"F", roll[2]),
                (r"N", roll[3]),
            ],
        )
    )

    # 5. Sliding --------------------------------------------------------------------
    coulomb = (P, -mu_k * sgn * N_force * c.x + N_force * c.y)
    _, slide_eqs = kane([us, u3], [(un, c.y)], [gravity, drag, coulomb])
    A, b = sm.linear_eq_to_matrix(
        [_plain(e) for e in slide_eqs],
        [_plain(x) for x in [*udots, N_force]],
    )
    sol = finish(A.LUsolve(b))
    slide = sm.Matrix([sol[0], sol[1], sol[2], -mu_k * sgn * sol[2]])
    steps.append(
        Step(
            "Sliding: Coulomb friction and Kane's equations",
            "While the contact point slips, u_s and u3 are independent and kinetic friction "
            "opposes the slip: F = -mu_k N sgn, sgn the sign of w_t. N is still a constraint "
            "force, found from the auxiliary speed u_n; F is now a known multiple of it. "
            "Kane's equations for u_s and u3 and the auxiliary equation for u_n are linear "
            "in du_s/dt, du3/dt and N.",
            [
                (r"F_r + F_r^* \ (u_s)", slide_eqs[0]),
                (r"F_r + F_r^* \ (u_3)", slide_eqs[1]),
                (r"F_r + F_r^* \ (u_n)", slide_eqs[2]),
                (r"\dot u_s", slide[0]),
                (r"\dot u_3", slide[1]),
                (r"N", slide[2]),
            ],
        )
    )

    # 6. Outputs for the transitions --------------------------------------------------
    with_aux([])
    position = C.pos_from(origin).to_matrix(N)  # D + (s, f(s)) + r c2
    centre = sm.Matrix(
        [
            _plain(position[0]).subs({dd1: d1}),
            _plain(position[1]).subs({dd2: d2}),
            _plain(me.msubs(velocity[0], drive)),
            _plain(me.msubs(velocity[1], drive)),
        ]
    ).xreplace({s: sm.Symbol("s", real=True)})
    u_lab = sm.Matrix([u1, u2, 0])
    relative = (u_lab - sm.Matrix([vb1, vb2, 0])).dot(c.x.to_matrix(N))
    s_dot = sm.solve(sm.Eq(_plain((v_C - Ob.vel(N)).dot(c.x)), _plain(relative)), S_DOT)[0]
    energy_expr = (
        sm.Rational(1, 2) * m * (v_C - Ob.vel(N)).dot(v_C - Ob.vel(N))
        + sm.Rational(1, 2) * k * m * r**2 * u3**2
        + m * g * centre[1].subs(d2, 0)
    )
    energy = sm.factor_terms(_plain(energy_expr))
    drag_factor = _plain(me.msubs(drag_factor, drive))
    steps.append(
        Step(
            "Sustained contact: the state for the transitions",
            "The runtime switches between flight, rolling and sliding. Lift-off comes when N "
            "would fall below zero; rolling turns to sliding when |F| would exceed mu_s N; "
            "sliding turns to rolling when the slip w_t reaches zero. For these it needs the "
            "centre's lab state from (s, ds/dt) (the boundary displaced by (d1, d2) and "
            "moving with (vb1, vb2)), ds/dt from a lab velocity (u1, u2) of the centre on "
            "entering contact, and, for checks, the energy in the boundary's frame (the "
            "boundary's own motion excluded; conserved when the boundary is still, drag is "
            "off and the ball rolls or slides without friction).",
            [
                (r"(q_1, q_2, u_1, u_2)", centre.T),
                (r"u_s", s_dot),
                (r"E_B", energy),
            ],
        )
    )
    return ContactDerivation(
        steps=steps,
        geometry=geometry,
        roll=roll,
        slide=slide,
        roll_spin=roll_spin,
        slip=_plain(slip),
        centre=centre,
        s_dot=s_dot,
        energy=energy,
        drag_factor=drag_factor,
    )
