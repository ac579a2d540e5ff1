"""Soak test: many events across the paper's scenes and random valid scenes with either
contact model, every event audited.

    python -m bench.soak --events 1000000      # the full soak (--impacts is the same)
    python -m bench.soak --quick               # 20,000 events (seconds)

Run from the root of a source checkout (it is a test harness, not part of the installed
package).

An event is an impact or, in a scene with ``contact.model = "phases"``, a finished contact
phase (rolling or sliding on a wall, one row of contacts.csv); the requested total counts
both. Every run is streamed to a temporary directory exactly as ``billiard run`` streams
it (CSV files, scene file, checkpoints) by an :class:`AuditedSimulation`: the impact law
wrapped by :class:`ImpactAudit` and, with phases, every finished phase given to a
:class:`PhaseAudit` in the order the engine makes the events; afterwards every row of
collisions.csv is checked against the geometry with :func:`audit_rows`, and every row of
contacts.csv with :func:`audit_contact_rows`. Counted, and required to be zero:

penetrations
    impacts at which the ball overlaps the wall or the lid by more than ``GAP_LIMIT``
    (1e-9 m): the clearance from :meth:`billiard.geometry.boundary.Boundary.clearance`, the
    Euclidean distance from the ball's centre to the curve (global nearest point) minus r.
detached impacts
    impacts recorded with the ball more than ``GAP_LIMIT`` away from every surface.
non-finite values
    in any row of collisions.csv (``non_finite_rows``) or contacts.csv
    (``contact_non_finite_rows``).
energy created
    impacts after which the kinetic energy relative to the boundary (translation
    relative to the boundary's velocity at the impact, plus spin) exceeds the energy
    before by more than rounding (1e-12 of the energies involved). The low-velocity
    rule's lift of a ball lying on the surface adds energy by design: under the impacts
    model it is allowed exactly the designed amount, m (v_e^2 - w_n^2) / 2
    (v_e = ``elastic_below``, w_n the normal velocity it replaces), and counted
    separately; under contact phases no impact has an allowance (a lying ball lands or
    reflects, the lift is never made).
zero-impulse rows
    phases scenes: rows of collisions.csv with neither a normal nor a tangential
    impulse (a contact without impulse is no impact under contact phases).
small-impulse rows
    phases scenes: rows of collisions.csv whose impulse is below ``SMALL_IMPULSE``
    (1e-20 N s) in both components, zero included: the tail of a series of impacts at
    one instant followed impact by impact (a corner resolves it at once).
event energy rises
    phases scenes on a static boundary: events (an impact, a phase's or hold's start, a
    landing after a summed chatter series) whose state just before has more mechanical
    energy, m |v|^2 / 2 + I omega^2 / 2 + m g q2, than the state after the event before
    it, by more than ``ENERGY_ROUNDING`` of the energies involved, with no allowance:
    nothing on a still boundary adds energy (a flight conserves it, drag takes some).
contact penetrations, contact detached
    contact phases at whose start or end the centre is off the wall's offset curve:
    clearance below -``GAP_LIMIT`` (in a wall or the lid) or above it (off the wall).
    Only a phase's two ends are checked, not the path between them.
transition energy created, transition jumps, unlinked phases
    transitions into a contact phase (landing at an impact, roll -> slide, slide ->
    roll, the start in contact) that raise the kinetic energy relative to the boundary
    beyond rounding, or move the centre by more than ``GAP_LIMIT``; phases that start
    at no event. Exact on any drive: see :class:`PhaseAudit`.
phase energy created
    on a static boundary, contact phases whose mechanical energy at the end exceeds
    that at the start by more than the integrator's tolerance (``rtol`` per step of the
    energies involved, see :class:`PhaseAudit`). On a shaken boundary the drive does
    work on the ball during a phase, and the balance in the boundary's (accelerating)
    frame is a path integral that the phase's ends do not fix: not audited there.
resume mismatches
    for every fifth random scene the run is also interrupted (a real SIGTERM the process
    sends itself after a random impact of those the run made, ``BILLIARD_STOP_AFTER``),
    resumed from its checkpoint, and compared byte for byte with the audited
    uninterrupted run: collisions.csv, and contacts.csv for a phases scene.

Early stops (escape from an open container, inelastic collapse, numerical faults) end
a run with a documented reason; they are tallied by kind, and random scenes are added
until the requested number of events has been simulated. The scene generator
:func:`scene_from_draw` is shared with the property-based tests; half its scenes use
each contact model, and a phases scene runs for at most ``PHASES_DURATION`` (30 s) of
simulated time (a ball rolling to and fro in a drag-free bowl never ends its phase).
"""

from __future__ import annotations

import argparse
import contextlib
import filecmp
import json
import math
import multiprocessing
import os
import random
import signal
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from billiard.engine.interrupt import signal_after
from billiard.engine.state import BallState
from billiard.errors import GeometryError
from billiard.geometry.boundary import Boundary, Drive
from billiard.geometry.curves import load_curve
from billiard.kernels.layout import REGIMES
from billiard.models.impact import Contact, ImpactResult
from billiard.run.simulate import (
    CSV_NAME,
    RunInterrupted,
    Simulation,
    resume,
    run_streamed,
    simulate,
)
from billiard.runfile.sidecsv import CONTACTS_NAME, read_side_csv
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import PAPER_SCENES, Scene, fowles_coefficients, load_scene, with_values
from billiard.scene.spec import LAW_PARAMETERS
from billiard.status import Status

__all__ = [
    "CURVES",
    "GAP_LIMIT",
    "MODELS",
    "PAPER_SCENES",
    "PHASES_DURATION",
    "AuditedSimulation",
    "ImpactAudit",
    "PhaseAudit",
    "audit_contact_rows",
    "audit_impulses",
    "audit_rows",
    "random_draw",
    "scene_from_draw",
    "stop_kind",
]

#: Curves of the random scenes: the paper's three and two expressions (a flat-bottomed
#: quartic bowl and a sharply rounded V, whose radius of curvature at the bottom, 5 mm,
#: is close to the ball's).
CURVES = ("parabola", "wedge", "hyperbola", "30*x**4 + 0.0063", "sqrt(0.0001 + 2*x**2) + 0.005")
#: |clearance| (m) beyond which an impact counts as a penetration or as detached.
GAP_LIMIT = 1e-9
#: Relative rounding allowance of the energy audit.
ENERGY_ROUNDING = 1e-12
#: Impulse (N s) below which a row of collisions.csv of a phases scene counts as a
#: small-impulse row (both components).
SMALL_IMPULSE = 1e-20
#: Contact models of the random scenes (``contact.model``).
MODELS = ("impacts", "phases")
#: the impact laws (``contact.law``), each drawn as often
LAWS = tuple(LAW_PARAMETERS)
#: Simulated time (s) a random ``phases`` scene runs at most (``run.duration``).
PHASES_DURATION = 30.0
_LARGEST_RADIUS = 4e-3  # m; random balls are at most this large
_STOP_KINDS = {
    Status.COMPLETE: "complete",
    Status.TIME_LIMIT: "complete",
    Status.AT_REST: "complete",
    Status.ESCAPED: "escape",
    Status.COLLAPSE: "collapse",
    Status.NON_FINITE: "non-finite",
    Status.NUMERICAL_FAULT: "numerical",
    Status.SOLVER_FAILED: "root",
}


# ----------------------------------------------------------------------------------
# random valid scenes


def random_draw(rng: random.Random) -> dict[str, Any]:
    """One random set of the primitive choices :func:`scene_from_draw` turns into a scene
    (the property-based tests draw the same keys with hypothesis)."""
    uniform = rng.uniform
    mu_s = uniform(0.0, 1.2)
    return {
        "curve": rng.choice(CURVES),
        "lid": rng.random() < 0.7,
        "top": uniform(0.0, 1.0),
        "amplitude": 0.0 if rng.random() < 0.15 else uniform(0.0, 0.03),
        "frequency": uniform(1.0, 12.0),
        "direction": rng.choice(("horizontal", "vertical")),
        "phase": uniform(0.0, 2.0 * math.pi),
        "restitution": uniform(0.0, 1.0),
        "mu_static": mu_s,
        "mu_kinetic_fraction": uniform(0.0, 1.0),
        "elastic_below": rng.choice((0.0, 1e-3, 1e-2, 3e-2)),
        "radius_fraction": uniform(0.05, 0.97),
        "log_mass": uniform(-5.0, -2.0),
        "inertia_factor": uniform(0.1, 1.0),
        "drag": rng.choice(("fowles", "none")),
        "magnus": 0.0 if rng.random() < 0.7 else uniform(0.0, 1e-8),
        "start": rng.choice(("rest", "inside", "inside")),
        "x_fraction": uniform(0.0, 1.0),
        "y_fraction": 0.0 if rng.random() < 0.1 else uniform(0.0, 0.95),
        "v1": uniform(-2.0, 2.0),
        "v2": uniform(-2.0, 2.0),
        "omega": uniform(-300.0, 300.0),
        "t0": uniform(0.0, 50.0),
        "model": rng.choice(MODELS),
        # the impact law and every law's parameters (those of the law drawn are used)
        "law": rng.choice(LAWS),
        "beta0": uniform(-1.0, 1.0),
        "e_ref": uniform(0.0, 1.0),
        "v_ref": uniform(0.01, 2.0),
        "exponent": uniform(0.0, 0.5),
        "viscous": uniform(0.0, 2.0),
        "energy_scale": 10.0 ** uniform(-8.0, -3.0),
        "angle_slope": uniform(0.0, 1.0),
    }


_RADIUS_LIMITS: dict[tuple[str, float], float] = {}


def radius_limit(curve: str, top: float) -> float:
    """Smallest radius of curvature (m) of ``curve`` below height ``top``: the largest
    ball that still touches it at single points (inf for straight walls)."""
    key = (curve, top)
    if key not in _RADIUS_LIMITS:
        walls = load_curve(curve).walls
        probe = Boundary(walls, 1e-6, Drive(0.0, 0.0, 0.0, True), ceiling=top)
        xl, xr = probe.x_range
        rho = math.inf
        for wall in walls:
            lo, hi = max(wall.lo, xl), min(wall.hi, xr)
            for x in np.linspace(lo, hi, 4001) if hi > lo else ():
                f2 = float(wall.d2f(float(x), wall.p))
                if f2 > 0.0:
                    fp = float(wall.df(float(x), wall.p))
                    rho = min(rho, (1.0 + fp * fp) ** 1.5 / f2)
        _RADIUS_LIMITS[key] = rho
    return _RADIUS_LIMITS[key]


def scene_from_draw(draw: Mapping[str, Any]) -> Scene:
    """A valid scene from the primitive choices of :func:`random_draw`.

    Every parameter is within its documented range: mu_k <= mu_s, a ball radius below
    the curve's smallest radius of curvature, a lid (or escape level) above the bottom,
    and an initial position inside the container (on or above the wall, below the lid),
    or at rest on the bottom. ``contact.model`` is the draw's ``model``, always set
    explicitly; a ``phases`` scene also gets ``run.duration = PHASES_DURATION``.
    ``contact.law`` is the draw's ``law`` (Kane and Levinson's where it has none), with
    the law's parameters from the draw.
    """
    curve = draw["curve"]
    bottom = load_curve(curve).f(0.0)
    top = bottom + 0.04 + 0.2 * draw["top"]
    limit = min(radius_limit(curve, top), _LARGEST_RADIUS)
    radius = draw["radius_fraction"] * limit
    c_lin, c_quad = fowles_coefficients(radius)
    amplitude = draw["amplitude"]
    values: dict[str, Any] = {
        "boundary.curve": curve,
        "boundary.ceiling": top if draw["lid"] else None,
        "boundary.escape_height": top,
        "drive.amplitude": amplitude,
        "drive.frequency": draw["frequency"] if amplitude > 0.0 else 0.0,
        "drive.direction": draw["direction"],
        "drive.phase": draw["phase"],
        "contact.restitution": draw["restitution"],
        "contact.mu_static": draw["mu_static"],
        "contact.mu_kinetic": draw["mu_static"] * draw["mu_kinetic_fraction"],
        "contact.elastic_below": draw["elastic_below"],
        "contact.model": draw["model"],
        "ball.radius": radius,
        "ball.mass": 10.0 ** draw["log_mass"],
        "ball.inertia_factor": draw["inertia_factor"],
        "air.drag": draw["drag"],
        "air.c_lin": c_lin,
        "air.c_quad": c_quad,
        "air.magnus": draw["magnus"],
        "initial.q1": None,
        "initial.q2": None,
        "initial.v1": 0.0,
        "initial.v2": 0.0,
        "initial.omega": 0.0,
        "initial.t": draw["t0"],
        # a ball rolling to and fro in a drag-free bowl never ends its phase: a phases
        # scene runs for a bounded simulated time
        "run.duration": PHASES_DURATION if draw["model"] == "phases" else None,
    }
    law = draw.get("law", "kane-levinson")
    values["contact.law"] = law
    for key in sum(LAW_PARAMETERS[law], ()):
        values[f"contact.{key}"] = draw[key]
    scene = with_values(load_scene("parabola-5.4hz"), values)
    scene = with_values(scene, {"name": "random", "description": "random valid scene"})
    if draw["start"] != "inside":
        return scene
    walls = load_curve(curve).walls
    boundary = Boundary.from_scene(scene, walls)
    xl, xr = boundary.x_range
    px = xl + draw["x_fraction"] * (xr - xl)
    low = boundary.offset_height(px)
    high = (top - radius) if draw["lid"] else top
    if not low < high:
        return scene  # the rim: no room inside at this abscissa
    py = low + draw["y_fraction"] * (high - low)
    theta = boundary.drive.angle(draw["t0"])
    q1, q2 = boundary.drive.to_lab_frame(theta, px, py)
    return with_values(
        scene,
        {
            "initial.q1": q1,
            "initial.q2": q2,
            "initial.v1": draw["v1"],
            "initial.v2": draw["v2"],
            "initial.omega": draw["omega"],
        },
    )


# ----------------------------------------------------------------------------------
# audits


@dataclass
class ImpactAudit:
    """An impact law wrapped to check every impact for energy created in the boundary's
    frame (see the module docstring); use as ``sim.impact = ImpactAudit(sim.impact)``.

    Attributes:
        impacts: impacts seen.
        created: impacts that created energy beyond rounding (lifts beyond their
            designed allowance included).
        lifts: lifts of a lying ball by the low-velocity rule.
        separating: impacts applied although the contact point was not approaching the
            boundary (relative normal velocity w_n >= 0 before; lifts excepted): Newton's
            law then turns a separating velocity into an approaching one with a pulling
            (negative) normal impulse, the known source of created energy.
        worst: largest (energy after - before - allowance) / scale seen, scale being
            the energies involved; rounding keeps it near 1e-16.
        examples: the first few violations, for a report.
    """

    law: Any
    impacts: int = 0
    created: int = 0
    lifts: int = 0
    separating: int = 0
    worst: float = -math.inf
    examples: list[str] = field(default_factory=list)
    #: when a list, gets (energy before, energy after, allowance) of every impact
    history: list[tuple[float, float, float]] | None = None
    #: called as ``on_impact(state before, result)`` after every impact (how
    #: :class:`PhaseAudit` learns the state each landing starts from)
    on_impact: Callable[[Any, ImpactResult], None] | None = None
    #: whether a lift gets its designed allowance: the impacts model's rule; under
    #: contact phases a lying ball lands or reflects, and no impact may add energy
    lift_allowed: bool = True

    @property
    def regimes(self) -> tuple[str, ...]:
        return self.law.regimes

    def apply(self, state: Any, contact: Any) -> ImpactResult:
        """The wrapped law's outcome, checked."""
        res = self.law.apply(state, contact)
        self.check(state, contact, res)
        return res

    def check(self, state: Any, contact: Any, res: ImpactResult) -> None:
        """Check one impact: the ball's ``state`` before it (t, q1, q2, u1, u2, u3), the
        ``contact`` (its vb1, vb2) and the law's outcome ``res``."""
        law = self.law
        m, inertia = law.m, law.k * law.m * law.r * law.r
        vb1, vb2 = contact.vb1, contact.vb2
        w1, w2 = state.u1 - vb1, state.u2 - vb2
        x1, x2 = res.u1 - vb1, res.u2 - vb2
        before = 0.5 * m * (w1 * w1 + w2 * w2) + 0.5 * inertia * state.u3 * state.u3
        after = 0.5 * m * (x1 * x1 + x2 * x2) + 0.5 * inertia * res.u3 * res.u3
        allowance = 0.0
        if res.resting:
            self.lifts += 1
            if self.lift_allowed:
                allowance = 0.5 * m * max(0.0, law.elastic_below**2 - res.wn * res.wn)
        elif res.wn >= 0.0:
            self.separating += 1
        # rounding scale: every energy that went into the comparison
        scale = (
            before
            + allowance
            + 0.5 * m * (state.u1**2 + state.u2**2 + vb1 * vb1 + vb2 * vb2)
            + 0.5 * inertia * res.u3 * res.u3
        )
        excess = (after - before - allowance) / scale if scale > 0.0 else 0.0
        self.impacts += 1
        self.worst = max(self.worst, excess)
        if self.history is not None:
            self.history.append((before, after, allowance))
        if excess > ENERGY_ROUNDING:
            self.created += 1
            if len(self.examples) < 5:
                self.examples.append(
                    f"impact {self.impacts} (t = {state.t!r} s, {res.regime}"
                    f"{', lift' if res.resting else ''}, w_n = {res.wn:.3g} m/s, "
                    f"Rn = {res.Rn:.3g} N s): relative-frame energy {before!r} -> {after!r} J "
                    f"(+{(after - before) / before:.2g}), allowance {allowance!r} J"
                )
        if self.on_impact is not None:
            self.on_impact(state, res)


class _Clearances:
    """Tally of the ball's clearance at recorded states: penetrations and detached states
    (beyond ``GAP_LIMIT``), the extremes, and the first few examples."""

    def __init__(self, boundary: Boundary, drive: Any):
        self.boundary, self.drive = boundary, drive
        self.penetrations = self.detached = 0
        self.lowest, self.highest = math.inf, -math.inf
        self.examples: list[str] = []

    def check(self, t: float, q1: float, q2: float, where: Callable[[], str]) -> None:
        px, py, _, _ = self.drive.to_boundary_frame(self.drive.angle(t), q1, q2, 0.0, 0.0)
        gap = self.boundary.clearance(px, py)
        self.lowest, self.highest = min(self.lowest, gap), max(self.highest, gap)
        if gap < -GAP_LIMIT or gap > GAP_LIMIT:
            if gap < 0.0:
                self.penetrations += 1
            else:
                self.detached += 1
            if len(self.examples) < 5:
                self.examples.append(f"{where()}: clearance {gap:.3g} m")


def _finite_rows(columns: Mapping[str, np.ndarray], rows: int) -> np.ndarray:
    finite = np.ones(rows, dtype=bool)
    for values in columns.values():
        if values.dtype.kind == "f":
            finite &= np.isfinite(values)
    return finite


def audit_rows(boundary: Boundary, drive: Any, columns: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Check a run's rows against the geometry: penetrations and detached impacts
    (clearance beyond ``GAP_LIMIT``), non-finite values; with the extreme clearances."""
    finite = _finite_rows(columns, len(columns["n"]))
    tally = _Clearances(boundary, drive)
    for i, (t, q1, q2) in enumerate(
        zip(columns["t"].tolist(), columns["q1"].tolist(), columns["q2"].tolist(), strict=True)
    ):
        if finite[i]:
            tally.check(t, q1, q2, lambda i=i, t=t: f"impact {i + 1} (t = {t!r} s)")
    return {
        "rows": len(finite),
        "penetrations": tally.penetrations,
        "detached": tally.detached,
        "non_finite_rows": int((~finite).sum()),
        "lowest_clearance": tally.lowest,
        "highest_clearance": tally.highest,
        "examples": tally.examples,
    }


def audit_impulses(columns: Mapping[str, np.ndarray]) -> dict[str, int]:
    """Rows of a phases scene's collisions.csv without impulse (Rn = Rt = 0) and with an
    impulse below ``SMALL_IMPULSE`` in both components (zero included)."""
    rn, rt = np.abs(columns["Rn"]), np.abs(columns["Rt"])
    return {
        "zero_impulse_rows": int(((rn == 0.0) & (rt == 0.0)).sum()),
        "small_impulse_rows": int((np.maximum(rn, rt) < SMALL_IMPULSE).sum()),
    }


#: Absolute error allowed per step of a contact phase on s (m) and s_dot (m/s), as in
#: :mod:`billiard.models.contact` (its ``_ATOL``): the absolute part of the phase-energy
#: tolerance.
PHASE_ATOL = 1e-12


@dataclass
class PhaseAudit:
    """Energy audit of the contact phases of a ``contact.model = "phases"`` run and of
    the transitions into them, in the boundary's frame. Build it with
    :meth:`PhaseAudit.of`; it gets every impact's outcome (``ImpactAudit.on_impact``)
    and every finished phase (:meth:`contact`, a
    :class:`billiard.runfile.record.ContactRecord`) in the order the engine makes them, so each
    phase is linked to the event it starts from.

    Transitions (any drive; exact). A phase starts at a landing (an impact, also one at a
    second wall, after which the rebound's normal speed is dropped), at a roll -> slide
    or slide -> roll transition (the end of the previous phase), or at the run's start.
    All happen at one instant t, so the boundary frame's potential energies (gravity,
    and the fictitious potential m D''(t) of the drive's acceleration) change only with
    the position: the audit requires the position to be continuous (a jump beyond
    ``GAP_LIMIT`` is a ``transition_jump``) and the kinetic energy relative to the
    boundary, 0.5 m |v - V_B(t)|^2 + 0.5 I omega^2, not to grow beyond rounding
    (``ENERGY_ROUNDING`` of the energies involved): ``transition_energy_created``. One
    designed change is allowed exactly: a phase that starts rolling takes the rolling
    spin, which differs from the spin it starts from by the slip it snaps to zero;
    ``ContactModel.mode_for`` snaps only a slip |w| <= 1e-12 m/s + 1e-9 of the contact
    speeds (|s_dot| sqrt(1 + f'^2) + r |omega|), recomputed here: within that
    (``snaps``, the largest energy change in ``worst_snap``) the spin energy's change
    is allowed, beyond it it is not. The
    other transitions are audited elsewhere: the impact at a second wall (the wedge's
    vertex) by :class:`ImpactAudit`, like every impact; lift-off and the wall's end
    keep the phase's recorded end state, no speed added.

    Phases (static boundary only). On a boundary at rest (amplitude or frequency 0) the
    normal force does no work, rolling friction none, sliding friction and drag only
    take energy: the mechanical energy E = 0.5 m |v|^2 + 0.5 I omega^2 + m g q2 at a
    phase's end must not exceed that at its start by more than the integrator's
    tolerance: per step, ``rtol`` (``run.rtol``) of the energies involved,
    KE_start + KE_end + m g (|q2_start| + |q2_end|), plus the absolute tolerance
    ``PHASE_ATOL`` times m (g + |v_start| + |v_end|); times the phase's accepted steps
    (``ContactModel.steps`` counts them). Measured, the growth per step stays below 1e-3 of it
    (rolling without drag, rtol = 1e-10). On a shaken boundary the drive does work
    through the normal force and friction, and in the boundary's frame the fictitious
    force -m D''(t) is not conservative (D'' depends on time): the energy balance over
    a phase is a path integral that the phase's two ends do not determine, so it is not
    audited there; its transitions are.

    Attributes:
        phases: phases seen; ``ends`` counts them by "mode/end reason".
        transitions: transitions into a phase checked.
        chatter_landings: landings at the end of a summed chatter series checked (the
            ball's step to the series' end: no move relative to the boundary beyond
            ``GAP_LIMIT``, no kinetic-energy gain; counted in the two counters above).
        transition_energy_created, transition_jumps: see above.
        snaps: rolling starts whose spin snap was allowed; ``worst_snap`` the largest
            energy it added, relative to the energies involved.
        unlinked: phases whose start matched no previous event (time differs).
        static_phases: phases whose energy was checked (static boundary).
        phase_energy_created: phases that gained energy beyond the tolerance.
        worst_transition: largest relative kinetic-energy growth at a transition.
        worst_phase: largest energy growth over a phase, as a fraction of its tolerance.
        examples: the first few violations, for a report.
    """

    m: float
    inertia: float
    g: float
    rtol: float
    drive: Any
    static: bool
    #: the engine's boundary and contact model (to recompute the snap's tolerance)
    boundary: Any = None
    model: Any = None
    phases: int = 0
    ends: Counter = field(default_factory=Counter)
    transitions: int = 0
    chatter_landings: int = 0
    transition_energy_created: int = 0
    transition_jumps: int = 0
    snaps: int = 0
    worst_snap: float = -math.inf
    unlinked: int = 0
    static_phases: int = 0
    phase_energy_created: int = 0
    worst_transition: float = -math.inf
    worst_phase: float = -math.inf
    #: static boundary: events checked for a rise of the mechanical energy, those that
    #: rose beyond rounding, and the largest rise relative to the energies involved
    event_checks: int = 0
    event_energy_rises: int = 0
    worst_event: float = -math.inf
    examples: list[str] = field(default_factory=list)
    #: the state after the last event: (what, t, q1, q2, v1, v2, omega)
    last: tuple[Any, ...] | None = None

    @classmethod
    def of(cls, sim: Simulation) -> PhaseAudit:
        """The audit of ``sim``'s scene, starting from its initial state."""
        sc = sim.scene
        m, r = sc.ball.mass, sc.ball.radius
        audit = cls(
            m,
            sc.ball.inertia_factor * m * r * r,
            sc.run.gravity,
            sc.run.rtol,
            sim.drive,
            sim.drive.amplitude == 0.0 or sim.drive.omega == 0.0,
            sim.boundary,
            sim.contact_model,
        )
        b = sim.initial
        audit.last = ("start", b.t, b.q1, b.q2, b.u1, b.u2, b.u3)
        return audit

    def mechanical(self, q2: float, v1: float, v2: float, omega: float) -> tuple[float, float]:
        """(E, scale): the mechanical energy (J) of a state and the energies in it,
        kinetic plus m g |q2|, to which rounding is relative."""
        kinetic = 0.5 * self.m * (v1 * v1 + v2 * v2) + 0.5 * self.inertia * omega * omega
        return kinetic + self.m * self.g * q2, kinetic + self.m * self.g * abs(q2)

    def arrive(self, what: str, t: float, q2: float, v1: float, v2: float, omega: float) -> None:
        """On a static boundary: the state just before an event (``what`` at t) has no
        more mechanical energy than the state after the event before it, with no
        allowance beyond rounding (``event_energy_rises``)."""
        if not self.static or self.last is None:
            return
        self.event_checks += 1
        before, scale_b = self.mechanical(*self.last[3:])
        after, scale_a = self.mechanical(q2, v1, v2, omega)
        scale = scale_a + scale_b
        excess = (after - before) / scale if scale > 0.0 else 0.0
        self.worst_event = max(self.worst_event, excess)
        if excess > ENERGY_ROUNDING:
            self.event_energy_rises += 1
            self._note(
                f"{what} at t = {t!r} s after the {self.last[0]} at t = {self.last[1]!r} s: "
                f"mechanical energy {before!r} -> {after!r} J (+{excess:.2g} of {scale:.3g} J)"
            )

    def impact(self, state: Any, res: ImpactResult) -> None:
        """After an impact at ``state`` with outcome ``res``."""
        self.arrive("impact", state.t, state.q2, state.u1, state.u2, state.u3)
        self.last = ("impact", state.t, state.q1, state.q2, res.u1, res.u2, res.u3)

    def chatter(self, before: Any, after: Any) -> None:
        """A landing at the end of a summed chatter series: from the state after the
        impact (``before``, a BallState) to the contact's start (``after``), later by
        the series' duration. The ball stays where it was relative to the boundary (a
        move beyond ``GAP_LIMIT`` in the boundary's frame is a ``transition_jump``) and
        its kinetic energy relative to the boundary must not grow (it keeps the
        tangential part): ``transition_energy_created`` beyond rounding."""
        m, inertia, drive = self.m, self.inertia, self.drive
        # counted apart from ``transitions`` (one per finished phase, linked to the event
        # before it: this landing is the event before the phase it starts)
        self.chatter_landings += 1
        where = f"landing after a chatter series (t = {before.t!r} -> {after.t!r} s)"
        ends = []
        for b in (before, after):
            theta = drive.angle(b.t)
            px, py, _, _ = drive.to_boundary_frame(theta, b.q1, b.q2, 0.0, 0.0)
            vb1, vb2 = drive.boundary_velocity(theta)
            ke = 0.5 * m * ((b.u1 - vb1) ** 2 + (b.u2 - vb2) ** 2) + 0.5 * inertia * b.u3**2
            speeds = 0.5 * m * (b.u1**2 + b.u2**2 + vb1 * vb1 + vb2 * vb2)
            ends.append((px, py, ke, speeds))
        (x0, y0, ke0, s0), (x1, y1, ke1, s1) = ends
        self.arrive("landing after a chatter series", before.t, before.q2, before.u1,
                    before.u2, before.u3)  # fmt: skip
        scale = ke0 + s0 + s1 + 0.5 * inertia * (before.u3**2 + after.u3**2)
        excess = (ke1 - ke0) / scale if scale > 0.0 else 0.0
        self.worst_transition = max(self.worst_transition, excess)
        if excess > ENERGY_ROUNDING:
            self.transition_energy_created += 1
            self._note(f"{where}: kinetic energy relative to the boundary {ke0!r} -> {ke1!r} J")
        jump = math.hypot(x1 - x0, y1 - y0)
        if jump > GAP_LIMIT:
            self.transition_jumps += 1
            self._note(f"{where}: the centre moves {jump:.3g} m relative to the boundary")
        self.last = ("chatter", after.t, after.q1, after.q2, after.u1, after.u2, after.u3)

    def _note(self, text: str) -> None:
        if len(self.examples) < 5:
            self.examples.append(text)

    def contact(self, rec: Any, steps: int = 1) -> None:
        """Audit a finished phase ``rec`` (a ContactRecord) of at most ``steps``
        integration steps."""
        self.phases += 1
        self.ends[f"{rec.mode}/{rec.end}"] += 1
        m, inertia = self.m, self.inertia
        self.arrive(f"{rec.mode} phase", rec.t_start, rec.q2_start, rec.v1_start,
                    rec.v2_start, rec.omega_start)  # fmt: skip
        last = self.last
        self.last = ("phase", rec.t_end, rec.q1_end, rec.q2_end, rec.v1_end, rec.v2_end,
                     rec.omega_end)  # fmt: skip
        where = f"phase {self.phases} ({rec.mode}, end {rec.end}, t = {rec.t_start!r} s)"
        if last is None or last[1] != rec.t_start:
            self.unlinked += 1
            self._note(f"{where}: starts at no event (last event at t = {last and last[1]!r})")
        else:
            what, t, q1, q2, u1, u2, u3 = last
            self.transitions += 1
            vb1, vb2 = self.drive.boundary_velocity(self.drive.angle(t))
            v1, v2, w = rec.v1_start, rec.v2_start, rec.omega_start
            before = 0.5 * m * ((u1 - vb1) ** 2 + (u2 - vb2) ** 2) + 0.5 * inertia * u3 * u3
            after = 0.5 * m * ((v1 - vb1) ** 2 + (v2 - vb2) ** 2) + 0.5 * inertia * w * w
            scale = (
                before
                + 0.5 * m * (u1 * u1 + u2 * u2 + v1 * v1 + v2 * v2 + 2.0 * (vb1 * vb1 + vb2 * vb2))
                + 0.5 * inertia * (u3 * u3 + w * w)
            )
            if rec.mode == "roll" and w != u3 and self._snapped(rec, t, u3):
                snap = 0.5 * inertia * (w * w - u3 * u3)
                before += max(0.0, snap)
                self.snaps += 1
                self.worst_snap = max(self.worst_snap, snap / scale)
            excess = (after - before) / scale if scale > 0.0 else 0.0
            self.worst_transition = max(self.worst_transition, excess)
            if excess > ENERGY_ROUNDING:
                self.transition_energy_created += 1
                self._note(
                    f"{where}: from the {what}, kinetic energy relative to the boundary "
                    f"{before!r} -> {after!r} J (+{excess:.2g} of {scale:.3g} J)"
                )
            jump = math.hypot(rec.q1_start - q1, rec.q2_start - q2)
            if jump > GAP_LIMIT:
                self.transition_jumps += 1
                self._note(f"{where}: from the {what}, the centre jumps {jump:.3g} m")
        if not self.static:
            return
        self.static_phases += 1
        g = self.g
        ke0 = 0.5 * m * (rec.v1_start**2 + rec.v2_start**2) + 0.5 * inertia * rec.omega_start**2
        ke1 = 0.5 * m * (rec.v1_end**2 + rec.v2_end**2) + 0.5 * inertia * rec.omega_end**2
        growth = (ke1 + m * g * rec.q2_end) - (ke0 + m * g * rec.q2_start)
        speeds = math.hypot(rec.v1_start, rec.v2_start) + math.hypot(rec.v1_end, rec.v2_end)
        tolerance = max(1, steps) * (
            self.rtol * (ke0 + ke1 + m * g * (abs(rec.q2_start) + abs(rec.q2_end)))
            + PHASE_ATOL * m * (g + speeds)
        )
        ratio = growth / tolerance
        self.worst_phase = max(self.worst_phase, ratio)
        if not growth <= tolerance:
            self.phase_energy_created += 1
            self._note(
                f"{where}: mechanical energy {ke0 + m * g * rec.q2_start!r} -> "
                f"{ke1 + m * g * rec.q2_end!r} J over {steps} steps at most "
                f"(+{growth:.3g} J, {ratio:.3g} times the tolerance)"
            )

    def _snapped(self, rec: Any, t: float, spin: float) -> bool:
        """Is the spin change from ``spin`` to the rolling phase's start spin the snap of
        a slip within ``ContactModel.mode_for``'s tolerance?"""
        if self.boundary is None or self.model is None:
            return False
        surface = self.boundary.offsets[int(rec.wall)]
        theta = self.drive.angle(t)
        px, _, _, _ = self.drive.to_boundary_frame(theta, rec.q1_start, rec.q2_start, 0.0, 0.0)
        s = surface.contact(px, list(surface.initial_warm()))[0]
        wall = surface.wall
        sd = self.model.s_dot(wall, theta, s, rec.v1_start, rec.v2_start)
        fp = wall.df(s, wall.p)
        slip = self.model.slip(wall, s, sd, spin)
        speeds = abs(sd) * math.sqrt(1.0 + fp * fp) + self.model.r * abs(spin)
        return abs(slip) <= 1e-12 + 1e-9 * speeds

    def report(self) -> dict[str, Any]:
        """The tallies, for a job's report."""
        return {
            "contact_phases": self.phases,
            "phase_ends": dict(self.ends),
            "transitions": self.transitions,
            "chatter_landings": self.chatter_landings,
            "transition_energy_created": self.transition_energy_created,
            "transition_jumps": self.transition_jumps,
            "unlinked_phases": self.unlinked,
            "snaps": self.snaps,
            "worst_snap": self.worst_snap,
            "static_phases": self.static_phases,
            "phase_energy_created": self.phase_energy_created,
            "worst_transition_excess": self.worst_transition,
            "worst_phase_energy_ratio": self.worst_phase,
            "event_checks": self.event_checks,
            "event_energy_rises": self.event_energy_rises,
            "worst_event_excess": self.worst_event,
            "phase_examples": list(self.examples),
        }


class AuditedSimulation(Simulation):
    """The engine with every event audited: every impact checked by :class:`ImpactAudit`
    (``impact_audit``) and, with ``contact.model = "phases"``, every finished contact
    phase also given to a :class:`PhaseAudit` (``phase_audit``) before it goes wherever
    ``on_contact`` sends it (a streamed run sets that to contacts.csv). On a static
    boundary each phase's accepted steps (``PH_STEPS`` at its end) scale the energy
    tolerance.

    The engine runs interpreted (``driver.interpreted``: the same source as compiled, to
    the bit), and while it runs the audit taps its functions in the interpreted twin:
    the impact law (with the state and time of the impact, from the function that makes
    it), the landing at the end of a summed chatter series, and the end of a phase. The
    phase audit takes these events in the order the engine made them, each finished
    phase with the events before it.
    """

    def __init__(self, scene: Any, method: str | None = None, history: list | None = None):
        self._forward: Callable[[Any], None] | None = None
        self.phase_audit: PhaseAudit | None = None
        super().__init__(scene, method)
        self.driver.interpreted = True
        self.impact_audit = ImpactAudit(self.impact, history=history)
        #: the events made since the last finished phase was audited, in order
        self._events: list[tuple[Any, ...]] = []
        #: the impact being made: (t or None: EN_EVENT_T, q1, q2)
        self._at: tuple[Any, ...] = (None, 0.0, 0.0)
        if self.phases:
            self.impact_audit.lift_allowed = False
            self.phase_audit = PhaseAudit.of(self)

    # ------------------------------------------------------------------ the taps

    @contextlib.contextmanager
    def _tapped(self) -> Iterator[None]:
        """The interpreted engine's functions wrapped while a run or step runs."""
        from billiard.kernels.interpreted import engine_modules

        machine, loop, _ = engine_modules()
        law_loop, law_machine = loop.impact_law, machine.impact_law
        impact, from_contact = loop.impact, machine.impact_from_contact
        end_chatter, end_phase = machine.end_chatter, machine.end_phase
        layout = machine.M_HELD, machine.PH_STEPS, machine.EN_EVENT_T

        def flight_impact(ctx, p, walls, out, row, tau, j, q1, q2, *rest):
            self._at = (None, q1, q2)
            return impact(ctx, p, walls, out, row, tau, j, q1, q2, *rest)

        def contact_impact(ctx, p, walls, out, other, index, t, *rest):
            self._at = (t, ctx[machine.EN_Q1], ctx[machine.EN_Q2])
            return from_contact(ctx, p, walls, out, other, index, t, *rest)

        def audited(law):
            def tapped(ctx, u1, u2, u3, z, vb1, vb2, pressing):
                out = law(ctx, u1, u2, u3, z, vb1, vb2, pressing)
                t, q1, q2 = self._at
                t = ctx[layout[2]] if t is None else t
                state = BallState(t, 0.0, q1, q2, u1, u2, u3, 0.0)
                res = ImpactResult(*out[:5], REGIMES[int(out[5])], out[7], out[8], out[6])
                self.impact_audit.check(state, Contact(z, vb1, vb2, pressing), res)
                self._events.append(("impact", state, res))
                return out

            return tapped

        def chatter(ctx, p, walls, until):
            before = self.ball
            moved = end_chatter(ctx, p, walls, until)
            if moved:
                self._events.append(("chatter", before, self.ball))
            return moved

        def phase_ended(ctx, mode, *rest):
            steps = 0 if mode == layout[0] else int(ctx[layout[1]])
            self._events.append(("phase", steps))
            return end_phase(ctx, mode, *rest)

        taps = (
            (loop, "impact_law", audited(law_loop)),
            (machine, "impact_law", audited(law_machine)),
            (loop, "impact", flight_impact),
            (machine, "impact_from_contact", contact_impact),
            (machine, "end_chatter", chatter),
            (machine, "end_phase", phase_ended),
        )
        kept = [(module, name, getattr(module, name)) for module, name, _ in taps]
        try:
            for module, name, tap in taps:
                setattr(module, name, tap)
            yield
        finally:
            for module, name, original in kept:
                setattr(module, name, original)

    def step(self, until: float = math.inf) -> Any:
        with self._tapped():
            return super().step(until)

    def run(self, *args: Any, **kwargs: Any) -> str | None:
        with self._tapped():
            return super().run(*args, **kwargs)

    # ------------------------------------------------------------------ the phases

    @property  # type: ignore[override]
    def on_contact(self) -> Callable[[Any], None] | None:
        return self._forward if self.phase_audit is None else self._tap

    @on_contact.setter
    def on_contact(self, forward: Callable[[Any], None] | None) -> None:
        self._forward = forward

    def _tap(self, record: Any) -> None:
        """A finished phase: the events before it go to the phase audit first."""
        audit, steps = self.phase_audit, 0
        while self._events:
            event = self._events.pop(0)
            if event[0] == "impact":
                audit.impact(event[1], event[2])
            elif event[0] == "chatter":
                audit.chatter(event[1], event[2])
            else:
                steps = event[1]
                break
        audit.contact(record, steps)
        if self._forward is not None:
            self._forward(record)


def audit_contact_rows(
    boundary: Boundary, drive: Any, columns: Mapping[str, np.ndarray]
) -> dict[str, Any]:
    """Check contacts.csv rows against the geometry: at each phase's start and end the
    centre is on the wall's offset curve, |clearance| <= ``GAP_LIMIT`` (else a
    penetration, of a wall or the lid, or detached: off the wall); non-finite values."""
    rows = len(columns["t_start"])
    finite = _finite_rows(columns, rows)
    tally = _Clearances(boundary, drive)
    for i in range(rows):
        if not finite[i]:
            continue
        for end in ("start", "end"):
            t = float(columns[f"t_{end}"][i])
            q1, q2 = float(columns[f"q1_{end}"][i]), float(columns[f"q2_{end}"][i])
            tally.check(
                t,
                q1,
                q2,
                lambda i=i, end=end, t=t: (
                    f"contact phase {i + 1} {end} ({columns['mode'][i]}, end "
                    f"{columns['end'][i]}, t = {t!r} s)"
                ),
            )
    # the phase in progress when the run ended is written too, as cut: no finished phase
    cut = int(sum(1 for end in columns["end"] if str(end) == "cut"))
    return {
        "contact_rows": rows - cut,
        "contact_cut_rows": cut,
        "contact_penetrations": tally.penetrations,
        "contact_detached": tally.detached,
        "contact_non_finite_rows": int((~finite).sum()),
        "contact_lowest_clearance": tally.lowest,
        "contact_highest_clearance": tally.highest,
        "contact_examples": tally.examples,
    }


def stop_kind(status: Status) -> str:
    """Category of a run's status: complete, escape, collapse, non-finite, numerical, or
    root (a root or step-size solve that failed)."""
    return _STOP_KINDS[Status(status)]


# ----------------------------------------------------------------------------------
# jobs


@dataclass(frozen=True)
class Job:
    """One audited run: a paper scene by name, or a random scene by its draw."""

    label: str
    impacts: int
    method: str = "event"
    scene_name: str | None = None
    draw: dict[str, Any] | None = None
    resume_at: int | None = None


def run_job(job: Job) -> dict[str, Any]:
    """Run one job (in a worker process) and return its report. Its ``events`` are its
    impacts plus, with ``contact.model = "phases"``, its finished contact phases."""
    started = time.process_time()
    report: dict[str, Any] = {
        "label": job.label,
        "method": job.method,
        "impacts": 0,
        "events": 0,
        "draw": job.draw,
    }
    try:
        scene = load_scene(job.scene_name) if job.scene_name else scene_from_draw(job.draw or {})
        sim = AuditedSimulation(scene, job.method)
    except GeometryError as exc:
        report.update(stop="geometry", reason=str(exc), cpu=time.process_time() - started)
        return report
    audit = sim.impact_audit
    report["model"] = scene.contact.model
    report["law"] = scene.contact.law
    with tempfile.TemporaryDirectory(prefix="billiard-soak-") as tmp:
        result = run_streamed(sim, Path(tmp) / "a", collisions=job.impacts)
        columns = read_collisions(Path(tmp) / "a" / "collisions.csv")
        report.update(audit_rows(sim.boundary, sim.drive, columns))
        if scene.contact.model == "phases":
            # under contact phases a row is an impact: a contact without impulse is none
            report.update(audit_impulses(columns))
        report.update(
            impacts=len(result),
            events=len(result),
            stop=stop_kind(result.status),
            reason=result.stop_reason,
            energy_created=audit.created,
            lifts=audit.lifts,
            separating=audit.separating,
            elastic_below=scene.contact.elastic_below,
            worst_energy_excess=audit.worst,
            energy_examples=audit.examples,
        )
        contacts = Path(tmp) / "a" / CONTACTS_NAME
        if sim.phase_audit is not None:
            report.update(sim.phase_audit.report())
            report.update(audit_contact_rows(sim.boundary, sim.drive, read_side_csv(contacts)))
            report["events"] = len(result) + report["contact_rows"]
            report["static"] = int(sim.phase_audit.static)
        if job.resume_at is not None and len(result) >= 2:
            # interrupt within the impacts the run made (a phases scene may make far
            # fewer than it asked for before its time limit), before its last one: a
            # signal after the last impact finds the files complete and acts as the
            # process's own signal would (persist.run_streamed), and SIGTERM's default
            # ends the worker, whose job the pool would then wait for forever
            at = 1 + (job.resume_at - 1) % (len(result) - 1)
            report["resume_checked"] = 1
            try:
                simulate(
                    scene,
                    collisions=job.impacts,
                    method=job.method,
                    out_dir=Path(tmp) / "b",
                    on_record=signal_after(at, signal.SIGTERM),
                )
                interrupted = False
            except RunInterrupted:
                interrupted = True
            if interrupted:
                resume(Path(tmp) / "b")
            names = [CSV_NAME] + ([CONTACTS_NAME] if contacts.exists() else [])
            same = all(
                filecmp.cmp(Path(tmp) / "a" / name, Path(tmp) / "b" / name, shallow=False)
                for name in names
            )
            report["resume_mismatches"] = 0 if same else 1
            report["resume_interrupted"] = int(interrupted)
            report["resume_phases"] = int(contacts.exists())
    report["cpu"] = time.process_time() - started
    return report


def plan(total: int, seed: int) -> tuple[list[Job], random.Random]:
    """The paper-scene jobs for ``total`` events (40 %, 10 % per scene, each one long
    run from rest; their events are impacts) and the random generator of the rest."""
    rng = random.Random(seed)
    paper = int(0.10 * total)
    jobs = [Job(name, paper, scene_name=name) for name in PAPER_SCENES]
    return jobs, rng


def random_jobs(rng: random.Random, events: int, quick: bool, start: int) -> list[Job]:
    """Random-scene jobs worth about ``events`` events (each asks for ``size`` impacts;
    a phases scene also makes contact phases, and stops at ``PHASES_DURATION`` of
    simulated time); every fifth is also interrupted and resumed; one scene in sixteen
    uses rk4 (with a quarter of the impacts)."""
    size = 1000 if quick else 4000
    jobs: list[Job] = []
    count = max(1, math.ceil(events / size))
    for i in range(start, start + count):
        draw = random_draw(rng)
        method = "rk4" if rng.random() < 1 / 16 else "event"
        n = size // 4 if method == "rk4" else size  # rk4 is some 30 times slower
        resume_at = rng.randrange(1, n) if i % 5 == 0 else None
        jobs.append(Job(f"random-{i}", n, method, draw=draw, resume_at=resume_at))
    return jobs


def soak(
    total: int, *, seed: int = 2024, workers: int = 2, quick: bool = False, echo: Any = print
) -> dict[str, Any]:
    """Run the soak and return the aggregated report (see the module docstring)."""
    started = time.perf_counter()
    for curve in CURVES:  # derive the expressions once, before the workers need them
        load_curve(curve)
    jobs, rng = plan(total, seed)
    paper_events = sum(job.impacts for job in jobs)
    reports: list[dict[str, Any]] = []
    context = multiprocessing.get_context("fork" if sys.platform != "win32" else "spawn")
    with context.Pool(workers, maxtasksperchild=20) as pool:
        pending = jobs + random_jobs(rng, total - paper_events, quick, 0)
        made = len(pending) - len(jobs)
        while pending:
            for report in pool.imap_unordered(run_job, pending):
                reports.append(report)
                echo(_job_line(report))
            done = sum(r["events"] for r in reports)
            # runs that stopped early leave events to make up with more random scenes
            pending = random_jobs(rng, total - done, quick, made) if done < total else []
            made += len(pending)
    summary = _aggregate(reports)
    summary.update(
        requested=total,
        seed=seed,
        workers=workers,
        wall_time=time.perf_counter() - started,
    )
    return summary


def _job_line(report: dict[str, Any]) -> str:
    extra = f" ({report['reason']})" if report.get("stop") not in (None, "complete") else ""
    phases = ""
    if report.get("model") == "phases":
        phases = (
            f" +{report.get('contact_phases', 0)} phases: pen "
            f"{report.get('contact_penetrations', 0)} det {report.get('contact_detached', 0)} "
            f"nonfin {report.get('contact_non_finite_rows', 0)} "
            f"zero-impulse {report.get('zero_impulse_rows', 0)} transition "
            f"{report.get('transition_energy_created', 0)}/{report.get('transition_jumps', 0)}"
            f" phase-energy {report.get('phase_energy_created', 0)}"
        )
    return (
        f"{report['label']:>14} {report['method']:>5} {report.get('model', '-'):>7} "
        f"e_below {report.get('elastic_below')} {report['impacts']:>7} impacts "
        f"{report.get('cpu', 0.0):6.1f} s  pen {report.get('penetrations', 0)} "
        f"det {report.get('detached', 0)} nonfin {report.get('non_finite_rows', 0)} "
        f"energy {report.get('energy_created', 0)}{phases} "
        f"resume {report.get('resume_mismatches', '-')}  {report.get('stop')}{extra}"
    )


def _aggregate(reports: list[dict[str, Any]]) -> dict[str, Any]:
    def total(key: str, runs: list[dict[str, Any]] = reports) -> int:
        return int(sum(r.get(key, 0) for r in runs))

    def extreme(key: str, pick: Any, empty: float) -> float:
        return pick((r.get(key, empty) for r in reports), default=empty)

    paper = [r for r in reports if r["label"] in PAPER_SCENES]
    random_runs = [r for r in reports if r["label"] not in PAPER_SCENES]
    phase_runs = [r for r in random_runs if r.get("model") == "phases"]
    stops = Counter(r.get("stop", "?") for r in random_runs)
    phase_stops = Counter(r.get("stop", "?") for r in phase_runs)
    ends: Counter = Counter()
    for r in phase_runs:
        ends.update(r.get("phase_ends", {}))
    laws = {
        law: {
            key: total(key, [r for r in reports if r.get("law") == law])
            for key in ("impacts", "energy_created", "separating")
        }
        for law in LAWS
    }
    return {
        "laws": laws,
        "events": total("events"),
        "impacts": total("impacts"),
        "contact_phases": total("contact_phases"),
        "phase_ends": dict(sorted(ends.items())),
        "paper_impacts": sum(r["impacts"] for r in paper),
        "random_impacts": sum(r["impacts"] for r in random_runs),
        "phases_scene_events": total("events", phase_runs),
        "phases_scene_impacts": total("impacts", phase_runs),
        "rk4_impacts": sum(r["impacts"] for r in reports if r["method"] == "rk4"),
        "runs": len(reports),
        "random_scenes": len(random_runs),
        "phases_scenes": len(phase_runs),
        "static_phases_scenes": total("static", phase_runs),
        "penetrations": total("penetrations"),
        "detached": total("detached"),
        "non_finite_rows": total("non_finite_rows"),
        "energy_created": total("energy_created"),
        "contact_penetrations": total("contact_penetrations"),
        "contact_detached": total("contact_detached"),
        "contact_non_finite_rows": total("contact_non_finite_rows"),
        "zero_impulse_rows": total("zero_impulse_rows"),
        "small_impulse_rows": total("small_impulse_rows"),
        "event_energy_rises": total("event_energy_rises"),
        "event_checks": total("event_checks"),
        "worst_event_excess": extreme("worst_event_excess", max, -math.inf),
        "transition_energy_created": total("transition_energy_created"),
        "transition_jumps": total("transition_jumps"),
        "unlinked_phases": total("unlinked_phases"),
        "phase_energy_created": total("phase_energy_created"),
        "transitions": total("transitions"),
        "chatter_landings": total("chatter_landings"),
        "snaps": total("snaps"),
        "worst_snap": extreme("worst_snap", max, -math.inf),
        "static_phases": total("static_phases"),
        "lifts": total("lifts"),
        "separating": total("separating"),
        "separating_rule_on": int(
            sum(r.get("separating", 0) for r in reports if r.get("elastic_below", 0.0) > 0.0)
        ),
        "energy_created_rule_off": int(
            sum(r.get("energy_created", 0) for r in reports if r.get("elastic_below") == 0.0)
        ),
        "energy_created_rk4": int(
            sum(r.get("energy_created", 0) for r in reports if r["method"] == "rk4")
        ),
        "resume_checks": total("resume_checked"),
        "resume_interrupted": total("resume_interrupted"),
        "resume_phases": total("resume_phases"),
        "resume_phases_interrupted": int(
            sum(r.get("resume_interrupted", 0) for r in reports if r.get("resume_phases"))
        ),
        "resume_mismatches": total("resume_mismatches"),
        "lowest_clearance": extreme("lowest_clearance", min, math.inf),
        "highest_clearance": extreme("highest_clearance", max, -math.inf),
        "contact_lowest_clearance": extreme("contact_lowest_clearance", min, math.inf),
        "contact_highest_clearance": extreme("contact_highest_clearance", max, -math.inf),
        "worst_energy_excess": extreme("worst_energy_excess", max, -math.inf),
        "worst_transition_excess": extreme("worst_transition_excess", max, -math.inf),
        "worst_phase_energy_ratio": extreme("worst_phase_energy_ratio", max, -math.inf),
        "stops": dict(sorted(stops.items())),
        "phases_stops": dict(sorted(phase_stops.items())),
        "paper": {r["label"]: {"impacts": r["impacts"], "stop": r.get("stop")} for r in paper},
        "cpu": sum(r.get("cpu", 0.0) for r in reports),
        "violations": [
            f"{r['label']}: {e}"
            for r in reports
            for e in r.get("examples", [])
            + r.get("energy_examples", [])
            + r.get("contact_examples", [])
            + r.get("phase_examples", [])
        ][:20],
        "violating_draws": [
            {"label": r["label"], "method": r["method"], "draw": r["draw"]}
            for r in reports
            if r.get("draw") is not None and any(r.get(key) for key in MUST_BE_ZERO)
        ][:10],
        "stop_reasons": sorted(
            {
                f"{r['stop']}: {r['reason']}"
                for r in random_runs
                if r.get("stop") not in ("complete", "escape")
            }
        )[:20],
    }


MUST_BE_ZERO = (
    "penetrations",
    "detached",
    "non_finite_rows",
    "energy_created",
    "contact_penetrations",
    "contact_detached",
    "contact_non_finite_rows",
    "zero_impulse_rows",
    "small_impulse_rows",
    "event_energy_rises",
    "transition_energy_created",
    "transition_jumps",
    "unlinked_phases",
    "phase_energy_created",
    "resume_mismatches",
)


def format_summary(s: dict[str, Any]) -> str:
    """The aggregated report as text."""
    lines = [
        f"soak: {s['events']:,} events ({s['impacts']:,} impacts, {s['contact_phases']:,} "
        f"contact phases) in {s['runs']} runs ({s['paper_impacts']:,} impacts on the paper "
        f"scenes, {s['random_impacts']:,} on {s['random_scenes']} random scenes, "
        f"{s['rk4_impacts']:,} of them with rk4; {s['phases_scenes']} random scenes with "
        f'contact.model = "phases", {s["static_phases_scenes"]} of them static: '
        f"{s['phases_scene_events']:,} events, {s['phases_scene_impacts']:,} impacts), "
        f"seed {s['seed']}, {s['workers']} workers, {s['wall_time']:.0f} s wall, "
        f"{s['cpu']:.0f} s CPU",
        "  contact phases by mode/end: "
        + ", ".join(f"{key} {n:,}" for key, n in s["phase_ends"].items()),
    ]
    for key in MUST_BE_ZERO:
        lines.append(f"  {key:<26} {s[key]}")
    lines += [
        f"  clearance at impacts: {s['lowest_clearance']:.3g} .. {s['highest_clearance']:.3g} m",
        f"  clearance at contact phases' ends: {s['contact_lowest_clearance']:.3g} .. "
        f"{s['contact_highest_clearance']:.3g} m",
        f"  worst energy excess at impacts (relative): {s['worst_energy_excess']:.3g}",
        f"  transitions into a phase audited: {s['transitions']:,} (and "
        f"{s.get('chatter_landings', 0):,} landings after a summed chatter series), worst relative "
        f"kinetic-energy excess {s['worst_transition_excess']:.3g} ({s['snaps']:,} rolling "
        f"starts with the spin snapped within mode_for's tolerance, largest energy change "
        f"{s['worst_snap']:.3g})",
        f"  phases on a static boundary audited: {s['static_phases']:,}, worst energy "
        f"growth {s['worst_phase_energy_ratio']:.3g} of the tolerance",
        f"  events on a static boundary audited for a rise of the mechanical energy: "
        f"{s['event_checks']:,}, worst relative rise {s['worst_event_excess']:.3g}",
        f"  lifts of a lying ball (designed energy input, audited): {s['lifts']:,}",
        f"  impacts at a separating contact (w_n >= 0, no lift): {s['separating']:,} "
        f"({s['separating_rule_on']:,} with elastic_below > 0)",
        f"  energy created with elastic_below = 0: {s['energy_created_rule_off']}, "
        f"with rk4: {s['energy_created_rk4']}",
        f"  resume checks: {s['resume_checks']} ({s['resume_interrupted']} interrupted "
        f"mid-run; {s['resume_phases']} phases scenes, {s['resume_phases_interrupted']} "
        f"interrupted)",
        f"  random-scene outcomes: {s['stops']} (phases scenes: {s['phases_stops']})",
        "  impacts (energy created, at a separating contact) by impact law: "
        + ", ".join(
            f"{law} {n['impacts']:,} ({n['energy_created']}, {n['separating']})"
            for law, n in s["laws"].items()
        ),
    ]
    lines += [f"  violation: {v}" for v in s["violations"]]
    lines += [f"  violating draw: {json.dumps(d)}" for d in s["violating_draws"]]
    lines += [f"  stop: {r}" for r in s["stop_reasons"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.soak",
        description="Soak test: impacts and contact phases on the paper scenes and random "
        "valid scenes, each audited for penetration, non-finite values, energy creation "
        "and resume equality.",
    )
    parser.add_argument(
        "--impacts",
        "--events",
        dest="events",
        type=int,
        default=1_000_000,
        help="total events: impacts, plus contact phases in phases scenes (default 10^6)",
    )
    parser.add_argument("--quick", action="store_true", help="20,000 events, small jobs")
    parser.add_argument("--seed", type=int, default=2024, help="random seed (default 2024)")
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (default: all cores)",
    )
    parser.add_argument("--json", metavar="PATH", help="also write the report as JSON")
    parser.add_argument("--verbose", action="store_true", help="one line per run")
    args = parser.parse_args(argv)
    total = 20_000 if args.quick else args.events
    echo = (lambda line: print(line, flush=True)) if args.verbose else (lambda line: None)
    summary = soak(total, seed=args.seed, workers=args.workers, quick=args.quick, echo=echo)
    print(format_summary(summary))
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1) + "\n")
    return 1 if any(summary[key] for key in MUST_BE_ZERO) else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
