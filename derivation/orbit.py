"""Derivatives of the flight and of the impact maps, for the Jacobian of a periodic
orbit's return map (billiard.orbits).

The return map from one impact to the next is a flight, an event (the impact time) and
the impact law. Its exact Jacobian needs

* the flight's variational equations: the Jacobian of the accelerations (du1/dt, du2/dt)
  in the speeds (u1, u2, u3) (gravity, Fowles drag, Magnus force), which the runtime
  integrates along the flight; and, with no air forces, the Jacobian of the closed-form
  flight (q1, q2, u1, u2)(t) in its initial state, which needs no integration;
* the derivatives of the impact maps (post-impact u1, u2, u3) in the pre-impact speeds,
  the tangent angle z and the boundary's velocity (vb1, vb2): the saltation matrix of an
  impact is built from them (billiard/orbits/jacobian.py).

Everything is differentiated from the expressions of derivation/ball.py, so the
derivatives are those of the very maps the engine runs.
"""

from __future__ import annotations

import sympy as sm

from . import codegen
from .ball import BallDerivation, plain

__all__ = ["orbit_module"]


def _sym(name: str) -> sm.Symbol:
    return sm.Symbol(name)


def _rows(matrix: sm.Matrix) -> list[tuple]:
    return [tuple(matrix.row(i)) for i in range(matrix.rows)]


def orbit_module(d: BallDerivation) -> str:
    """The text of ``generated/orbit.py``."""
    S = _sym
    u1, u2, u3, q1, q2 = S("u1"), S("u2"), S("u3"), S("q1"), S("q2")
    m, r, k, g = S("m"), S("r"), S("k"), S("g")
    c_lin, c_quad, c_magnus = S("c_lin"), S("c_quad"), S("c_magnus")
    z, vb1, vb2, e, mu_k, sgn, t = (S(n) for n in ("z", "vb1", "vb2", "e", "mu_k", "sgn", "t"))

    def p(expr):
        expr = plain(expr)
        return expr.xreplace({a: S(a.name) for a in expr.free_symbols})

    rhs = p(d.rhs_magnus)[:2, :]
    flight_jac = sm.Matrix(rhs).jacobian([u1, u2, u3])
    exact = p(d.flight_exact)
    exact_jac = sm.Matrix(exact).jacobian([q1, q2, u1, u2])
    wrt = [u1, u2, u3, z, vb1, vb2]
    stick_jac = sm.Matrix(p(d.stick)[:3, :]).jacobian(wrt)
    slip_jac = sm.Matrix(p(d.slip)[:3, :]).jacobian(wrt)
    parts = [
        '"""Derivatives of the flight and of the impact maps (the Jacobian of a periodic '
        "orbit's\nreturn map, billiard/orbits/jacobian.py).\n\n"
        "Symbols and conventions: see docs/design.md and docs/derivation.md. SI units.\n"
        '"""\n\nimport math\n\n',
        codegen.function_source(
            "flight_jacobian",
            [u1, u2, u3, m, g, c_lin, c_quad, c_magnus],
            _rows(flight_jac),
            "d(du1/dt, du2/dt)/d(u1, u2, u3) in flight with gravity, Fowles drag and the "
            "Magnus force: two rows (1/s, m/(s rad)).",
        ),
        codegen.function_source(
            "flight_exact_jacobian",
            [t, q1, q2, u1, u2, g],
            _rows(exact_jac),
            "d(q1, q2, u1, u2)(t)/d(q1, q2, u1, u2)(0) of a drag-free flight of duration t: "
            "four rows.",
        ),
        codegen.function_source(
            "impact_stick_jacobian",
            [u1, u2, u3, z, vb1, vb2, m, r, k, e],
            _rows(stick_jac),
            "d(u1+, u2+, u3+)/d(u1, u2, u3, z, vb1, vb2) of the no-slip impact: three rows.",
        ),
        codegen.function_source(
            "impact_slip_jacobian",
            [u1, u2, u3, z, vb1, vb2, m, r, k, e, mu_k, sgn],
            _rows(slip_jac),
            "d(u1+, u2+, u3+)/d(u1, u2, u3, z, vb1, vb2) of the slipping impact (sgn the "
            "sign of wt before it, held fixed): three rows.",
        ),
    ]
    body = "\n\n".join(parts)
    header = codegen.generated_notice("derivation/orbit.py (derivatives of derivation/ball.py)") + [
        "Functions: flight_jacobian, flight_exact_jacobian, impact_stick_jacobian, "
        "impact_slip_jacobian",
    ]
    return codegen.module_text(header, body)
