"""Lagrange's equations and the impulse balance: a second derivation to audit Kane's.

``ball.py`` and ``contact.py`` derive the equations of motion with Kane's method
(generalized speeds, partial velocities, auxiliary speeds for the contact forces). This
module derives the same equations a second, independent way, so that a sign or a frame
error in one shows as a difference (``tests/derivation/test_lagrange.py`` compares them):

1. flight: Lagrange's equations in the centre's position (x, y) and the rotation angle
   theta, gravity from the potential m g y, Fowles drag and the Magnus force as
   generalized forces (``LagrangesMethod``'s forcelist);
2. sustained contact on a wall y = f(s) of a boundary translated by a prescribed
   displacement D(t) = (d1, d2): coordinates s (contact abscissa in the boundary's frame),
   n (the centre's distance off the offset curve, held at zero by a holonomic constraint)
   and theta. The contact forces are never modelled: the normal force N is the Lagrange
   multiplier of n = 0; in rolling, the friction F is the multiplier of the no-slip
   constraint; in sliding, Coulomb friction -mu_k sgn N acts at the contact point as a
   generalized force, N still the multiplier. Vectors are written in lab components from
   f and its derivatives, without the contact frame's angle z;
3. impacts: the linear impulse balance m (v+ - v-) = R and the angular impulse balance
   about the centre I (w+ - w-) = ((P - C) x R)_z, written directly, with the impact laws.

Symbols for the parameters are those of ``ball.py`` and ``contact.py`` (same names and
assumptions), so the results are comparable term by term; nothing else is shared.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy as sm
import sympy.physics.mechanics as me

from . import ball as kb
from . import contact as kc

t = me.dynamicsymbols._t
m, r, k, g = kb.m, kb.r, kb.k, kb.g

#: Plain symbols of the flight state (as ``ball.plain`` prints Kane's speeds).
U1, U2, U3 = sm.symbols("u1 u2 u3")
#: The contact abscissa as a plain symbol.
S = sm.Symbol("s", real=True)


# --- flight -----------------------------------------------------------------------------


def flight_rhs(magnus: bool = True) -> sm.Matrix:
    """(x'', y'', theta'') from Lagrange's equations of the ball in flight, in the plain
    speeds u1 = x', u2 = y', u3 = theta'."""
    x, y, th = me.dynamicsymbols("x y theta")
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    C = origin.locatenew("C", x * N.x + y * N.y)
    C.set_vel(N, C.pos_from(origin).dt(N))
    B = N.orientnew("B", "Axis", [th, N.z])
    inertia = k * m * r**2
    body = me.RigidBody("ball", C, B, m, (me.inertia(B, inertia, inertia, inertia), C))
    body.potential_energy = m * g * y  # gravity: n2 is up
    lagrangian = me.Lagrangian(N, body)
    v = C.vel(N)
    speed = sm.sqrt(x.diff(t) ** 2 + y.diff(t) ** 2)
    loads = [(C, -(kb.c_lin + kb.c_quad * speed) * v)]
    if magnus:
        loads.append((C, kb.c_magnus * B.ang_vel_in(N).cross(v)))
    lm = me.LagrangesMethod(lagrangian, [x, y, th], forcelist=loads, frame=N)
    lm.form_lagranges_equations()
    acc = lm.mass_matrix.LUsolve(lm.forcing)
    plain = {x.diff(t): U1, y.diff(t): U2, th.diff(t): U3}
    return me.msubs(acc, plain)


# --- sustained contact --------------------------------------------------------------------


def _chain(names: list[str]) -> list[type[sm.Function]]:
    """Undefined functions f0(s), f1(s), ... with d f_i/ds = f_(i+1): a generic wall and
    its derivatives. The last has no derivative: the equations must not need it."""
    funcs: list[type[sm.Function]] = []
    for name in reversed(names):
        nxt = funcs[0] if funcs else None

        def fdiff(self, argindex=1, _nxt=nxt, _name=name):
            if _nxt is None:
                raise NotImplementedError(f"the contact equations need d{_name}/ds")
            return _nxt(self.args[0])

        funcs.insert(0, type(name, (sm.Function,), {"fdiff": fdiff}))
    return funcs


#: A generic wall y = f(s): f, f', f'', f''' as functions of s.
_F = _chain(["wall_f", "wall_fp", "wall_f2", "wall_f3"])


def generic_wall(q: sm.Basic) -> sm.Basic:
    """The generic wall height at the coordinate q (its derivatives follow by the chain)."""
    return _F[0](q)


@dataclass
class ContactEquations:
    """Lagrange's equations of sustained contact in the plain symbols of ``contact.py``
    (s_dot, u3, s_ddot, spin_dot, ab, vb, c_drag, F, N) and S for the abscissa; a generic
    wall's height and derivatives appear as f0, fp, f2, f3.

    For each mode: Lagrange's equations (with the acceleration constraint while rolling),
    linear in the rates, the contact forces and the multipliers, and the multipliers in
    terms of the contact forces (from the rows that equate the generalized force of
    F t + N n at the contact point with the constraint forces). The rows of that
    identification not used to solve for the multipliers are kept in ``identities``:
    they must vanish.
    """

    roll_equations: list[sm.Basic]  # in s_ddot, spin_dot, F, N and the multipliers
    roll_multipliers: dict[sm.Basic, sm.Basic]  # lam_i in terms of F, N
    slide_equations: list[sm.Basic]  # in s_ddot, spin_dot, N and the multiplier
    slide_multipliers: dict[sm.Basic, sm.Basic]
    identities: list[sm.Basic]
    roll_spin: sm.Basic  # theta' while rolling
    drag_factor: sm.Basic  # c_lin + c_quad |v_C|

    def residuals(self, mode: str, values: sm.Matrix) -> list[sm.Basic]:
        """The equations of ``mode`` at (s_ddot, spin_dot, F, N) (rolling) or
        (s_ddot, spin_dot, N) (sliding): all zero if and only if the values solve them."""
        if mode == "roll":
            eqs, lam, unknowns = self.roll_equations, self.roll_multipliers, _ROLL
        else:
            eqs, lam, unknowns = self.slide_equations, self.slide_multipliers, _SLIDE
        known = dict(zip(unknowns, values, strict=True))
        return [e.xreplace(lam).xreplace(known) for e in eqs]

    def roll(self) -> sm.Matrix:
        """(s_ddot, spin_dot, F, N) while rolling."""
        return _solve([e.xreplace(self.roll_multipliers) for e in self.roll_equations], _ROLL)

    def slide(self) -> sm.Matrix:
        """(s_ddot, spin_dot, N, F) while sliding, F = -mu_k sgn N."""
        eqs = [e.xreplace(self.slide_multipliers) for e in self.slide_equations]
        sol = _solve(eqs, _SLIDE)
        return sm.Matrix([*sol, -kc.mu_k * kc.sgn * sol[2]])


_ROLL = [kc.S_DDOT, kc.SPIN_DOT, kc.F_force, kc.N_force]
_SLIDE = [kc.S_DDOT, kc.SPIN_DOT, kc.N_force]


def contact_equations(wall: Callable[[sm.Basic], sm.Basic] = generic_wall) -> ContactEquations:
    """Rolling and sliding on the wall y = wall(s) by Lagrange's equations with multipliers."""
    s, n, th = me.dynamicsymbols("s n theta")
    d1, d2 = me.dynamicsymbols("d1 d2")  # the boundary's prescribed displacement
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    f = wall(s)
    fp = f.diff(s)
    length = sm.sqrt(1 + fp**2)
    tangent = (N.x + fp * N.y) / length
    normal = (-fp * N.x + N.y) / length  # into the container
    Ob = origin.locatenew("Ob", d1 * N.x + d2 * N.y)
    Ob.set_vel(N, Ob.pos_from(origin).dt(N))
    # The centre, n off the wall's offset curve (n = 0 is the contact constraint).
    C = Ob.locatenew("C", s * N.x + f * N.y + (r + n) * normal)
    C.set_vel(N, C.pos_from(origin).dt(N))
    B = N.orientnew("B", "Axis", [th, N.z])
    # The ball's material point at the contact, a radius from C against the normal.
    P = C.locatenew("P", -r * normal)
    P.set_vel(N, C.vel(N) + B.ang_vel_in(N).cross(-r * normal))
    inertia = k * m * r**2
    body = me.RigidBody("ball", C, B, m, (me.inertia(B, inertia, inertia, inertia), C))
    body.potential_energy = m * g * C.pos_from(origin).dot(N.y)
    lagrangian = me.Lagrangian(N, body)
    slip = (P.vel(N) - Ob.vel(N)).dot(tangent)  # relative to the wall, along the tangent
    drag = (C, -kc.c_drag * C.vel(N))  # the factor stays a symbol, as in contact.py
    q = [s, n, th]
    qd = [a.diff(t) for a in q]
    on_wall = {n.diff(t, 2): 0, n.diff(t): 0, n: 0}
    drive = {
        d1.diff(t, 2): kc.ab1,
        d2.diff(t, 2): kc.ab2,
        d1.diff(t): kc.vb1,
        d2.diff(t): kc.vb2,
    }
    plain = {
        s.diff(t, 2): kc.S_DDOT,
        th.diff(t, 2): kc.SPIN_DOT,
        s.diff(t): kc.S_DOT,
        th.diff(t): kc.SPIN,
    }
    generic = {_F[3](s): kc.f3, _F[2](s): kc.f2, _F[1](s): kc.fp, _F[0](s): kc.f0}

    def to_plain(expr):
        return me.msubs(expr, on_wall, drive, plain, generic, {s: S})

    def identify(lm, F, Nn):
        """Rows (s, n, theta) that equate the generalized force of F t + N n at P with
        the constraint forces -(d coneqs/dq')^T lam (LagrangesMethod's sign convention:
        its equations carry + (d coneqs/dq')^T lam)."""
        partial = me.partial_velocity([P.vel(N)], qd, N)[0]
        applied = sm.Matrix([v.dot(F * tangent + Nn * normal) for v in partial])
        rows = applied - lm.lam_coeffs.T * lm.lam_vec
        return [to_plain(row) for row in rows], [to_plain(a) for a in lm.lam_vec]

    F_force, N_force = kc.F_force, kc.N_force

    # Rolling: n = 0 (holonomic) and no slip (nonholonomic), one multiplier each.
    lm = me.LagrangesMethod(
        lagrangian, q, forcelist=[drag], frame=N, hol_coneqs=[n], nonhol_coneqs=[slip]
    )
    roll_eqs = [to_plain(e) for e in [*lm.form_lagranges_equations(), slip.diff(t)]]
    rows, lam = identify(lm, F_force, N_force)
    # The n-row and the theta-row give the multipliers; the s-row must then hold.
    roll_lam = dict(zip(lam, _solve(rows[1:], lam), strict=True))
    identities = [rows[0].xreplace(roll_lam)]
    spin = sm.solve(to_plain(slip), kc.SPIN)[0]

    # Sliding: n = 0 only; Coulomb friction -mu_k sgn N at P, N from the multiplier.
    friction = (P, -kc.mu_k * kc.sgn * N_force * tangent)
    lm = me.LagrangesMethod(lagrangian, q, forcelist=[drag, friction], frame=N, hol_coneqs=[n])
    slide_eqs = [to_plain(e) for e in lm.form_lagranges_equations()]
    rows, lam = identify(lm, 0, N_force)
    slide_lam = dict(zip(lam, _solve(rows[1:2], lam), strict=True))  # the n-row
    identities += [rows[0], rows[2]]  # N n does no work along s or theta

    v = to_plain(C.vel(N).to_matrix(N))
    return ContactEquations(
        roll_equations=roll_eqs,
        roll_multipliers=roll_lam,
        slide_equations=slide_eqs,
        slide_multipliers=slide_lam,
        identities=identities,
        roll_spin=spin,
        drag_factor=kb.c_lin + kb.c_quad * sm.sqrt(v[0] ** 2 + v[1] ** 2),
    )


def _solve(equations: list[sm.Basic], unknowns: list[sm.Basic]) -> sm.Matrix:
    """The solution of n linear equations in n unknowns (LU, no inverse formed)."""
    A, b = sm.linear_eq_to_matrix(equations, unknowns)
    return A.LUsolve(b)


# --- impacts ----------------------------------------------------------------------------


@dataclass
class ImpulseBalance:
    """The impact solved from the impulse balance, in ball.py's symbols: (u1+, u2+, u3+,
    Rt, Rn) with u1, u2, u3 the plain pre-impact speeds."""

    stick: sm.Matrix
    slip: sm.Matrix
    #: Angular momentum about the contact point, before and after (as functions of the
    #: speeds): the impulse has no moment about it, so it is conserved.
    contact_momentum: Callable[[sm.Basic, sm.Basic, sm.Basic], sm.Basic]


def impulse_balance() -> ImpulseBalance:
    """The impact from Newton's and Euler's impulse balance and the impact laws, solved
    (LU) for the post-impact speeds and the impulse."""
    z = kb.z
    c1 = sm.Matrix([sm.cos(z), sm.sin(z), 0])  # tangent
    c2 = sm.Matrix([-sm.sin(z), sm.cos(z), 0])  # normal into the container
    ez = sm.Matrix([0, 0, 1])
    u1, u2, u3 = U1, U2, U3
    post = _post()
    u1p, u2p, u3p = post
    Rt, Rn = kb.Rt, kb.Rn
    R = Rt * c1 + Rn * c2
    inertia = k * m * r**2
    arm = -r * c2  # P - C
    v_before, v_after = sm.Matrix([u1, u2, 0]), sm.Matrix([u1p, u2p, 0])
    linear = m * (v_after - v_before) - R
    angular = inertia * (u3p - u3) - arm.cross(R).dot(ez)
    vb = sm.Matrix([kb.vb1, kb.vb2, 0])

    def contact_velocity(v, w):
        return v + (w * ez).cross(arm) - vb  # P's velocity relative to the boundary

    w_before = contact_velocity(v_before, u3)
    w_after = contact_velocity(v_after, u3p)
    restitution = w_after.dot(c2) + kb.e * w_before.dot(c2)
    balance = [linear[0], linear[1], angular, restitution]
    unknowns = [*post, Rt, Rn]

    def solve(law):
        A, b = sm.linear_eq_to_matrix([*balance, law], unknowns)
        return A.LUsolve(b)

    def contact_momentum(v1, v2, w):
        # H_P = I w + ((C - P) x m v)_z: the ball's angular momentum about the contact point.
        return inertia * w + (-arm).cross(m * sm.Matrix([v1, v2, 0])).dot(ez)

    return ImpulseBalance(
        stick=solve(w_after.dot(c1)),
        slip=solve(Rt + kb.mu_k * kb.sgn * Rn),
        contact_momentum=contact_momentum,
    )


def _post() -> list[sm.Symbol]:
    """ball.py's names for the post-impact speeds."""
    return list(sm.symbols("u1p u2p u3p", real=True))


# --- an exact zero test ------------------------------------------------------------------


def _half_powers(expr: sm.Basic) -> list[sm.Pow]:
    return [p for p in expr.atoms(sm.Pow) if p.exp.is_Rational and p.exp.q == 2]


def _root_symbol(radicand: sm.Basic, roots: list) -> tuple[sm.Dummy, sm.Basic]:
    """(y, c) with sqrt(radicand) = sqrt(c) y: a known root's symbol when the radicands
    differ by a positive rational factor c, else a new symbol (added to ``roots``)."""
    for y, known in roots:
        ratio = sm.cancel(radicand / known)
        if ratio.is_Rational and ratio > 0:
            return y, ratio
    y = sm.Dummy("y", positive=True)
    roots.append((y, radicand))
    return y, sm.S.One


def vanishes(expr: sm.Basic) -> bool:
    """Whether ``expr``, rational in its symbols and in square roots of such expressions,
    is identically zero. Exact: each square root sqrt(b) becomes a new symbol y with
    y**2 = b (innermost first; roots whose radicands differ by a positive rational factor
    share one symbol), the numerator is reduced modulo these relations, and what is left
    must expand to zero. True proves zero; a perfect square under a root can give a
    false False, never a false True."""
    expr = sm.sympify(expr)
    roots: list[tuple[sm.Dummy, sm.Basic]] = []  # (y, radicand as one fraction)
    while halves := _half_powers(expr):
        base = next(p.base for p in halves if not _half_powers(p.base))
        y, ratio = _root_symbol(sm.cancel(sm.together(base)), roots)
        expr = expr.replace(
            lambda p, b=base: p.is_Pow and p.base == b and p.exp.is_Rational and p.exp.q == 2,
            lambda p, y=y, c=ratio: c**p.exp * y ** (2 * p.exp),
        )
    parts = [sm.numer(sm.together(expr))]
    for y, radicand in reversed(roots):  # the outermost root first
        top, bottom = sm.fraction(radicand)
        relation = sm.Poly(y**2 * bottom - top, y)
        reduced = []
        for part in parts:
            rest = sm.prem(sm.Poly(sm.expand(part), y), relation)
            # a + b y with y irrational over the rest: both must vanish
            reduced += [rest.coeff_monomial(1), rest.coeff_monomial(y)]
        parts = reduced
    return all(sm.expand(part) == 0 for part in parts)
