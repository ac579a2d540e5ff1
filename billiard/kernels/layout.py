"""The state vector ``ctx`` of the kernels: one flat float64 array holding the scene's
constants, the flight's and the locator's working state, the engine state and one block
per surface. One array, so that a kernel call passes one reference (numba counts
references on every array argument of a call it does not inline).

Every quantity is declared once, in order, with its name, size, unit and meaning::

    IM_E = _ctx("IM_E", "restitution", 1, "", "Newton's coefficient of restitution")

gives ``IM_E`` the next free slot: the slots are consecutive, none is numbered by hand
(the constant's name is declared with it, and ``CTX.mismatches(globals())``, which the
tests run, lists any constant not bound to its declared slot). The constants stay plain
module-level integers (numba compiles them in as constants) and are what the kernels
read; :data:`CTX` is the declaration, by which a reader finds a quantity by name:
``CTX.slot("impact.restitution")`` (a :class:`Slot`: index, size, unit, meaning),
``CTX.read(ctx, "engine.t")`` and ``print(describe())``. A block of a surface (offsets
``S_*``, :data:`SURFACE`) is declared the same way.

Each model (flight, impact law, locator, contact phase, hold) keeps its coefficients in
its own block, and the interpreted models keep their own ``ctx`` in this layout; the
engine's is assembled from theirs (:mod:`billiard.engine.ctx`: each model's ``write``).
A block's first slot names the model's kind where there is a choice (``LOC_KIND``,
``FL_KIND``, ``IM_KIND``): the kernels branch on it, so every model with a kind runs
compiled (:mod:`billiard.models.kinds`). ``contact.restitution`` and
``contact.elastic_below`` have one slot each, the impact law's (``IM_E``, ``IM_EB``),
which the landing test of ``contact.model = "phases"`` reads too. No file stores a slot
number.

Also the codes the kernels use for surfaces, regimes, statuses and errors.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Slot:
    """One quantity: ``size`` consecutive floats of a layout from ``index``."""

    #: the module-level constant that holds ``index`` (e.g. ``"IM_E"``)
    constant: str
    #: ``block.quantity`` (e.g. ``"impact.restitution"``)
    name: str
    index: int
    size: int
    #: SI unit ("" for a number without unit, a code or a flag)
    unit: str
    meaning: str

    @property
    def stop(self) -> int:
        """The slot after the quantity's last."""
        return self.index + self.size


class Layout:
    """Quantities declared one after the other, in blocks; each takes the next free
    slots, so the layout has neither gaps nor overlaps."""

    def __init__(self, title: str):
        self.title = title
        self.slots: list[Slot] = []
        #: (name, start, stop) of each block, in order
        self.blocks: list[tuple[str, int, int]] = []
        self._block: str | None = None
        self._start = 0
        self._lookup: dict[str, Slot] = {}

    @property
    def size(self) -> int:
        """Slots declared so far: the length of a vector in this layout."""
        return self.slots[-1].stop if self.slots else 0

    def begin(self, block: str) -> int:
        """Open ``block`` (its quantities are named ``block.name``) at the next free
        slot, which is returned; an open block is closed first."""
        self.end()
        self._block, self._start = block, self.size
        return self._start

    def end(self) -> int:
        """Close the open block, if any; returns the slot after it."""
        if self._block is not None:
            self.blocks.append((self._block, self._start, self.size))
            self._block = None
        return self.size

    def add(self, constant: str, name: str, size: int, unit: str, meaning: str) -> int:
        """Declare a quantity of ``size`` slots at the next free slot, which is
        returned (the value of ``constant``)."""
        if size < 1:
            raise ValueError(f"{constant}: a quantity of {size} slots")
        full = name if self._block is None else f"{self._block}.{name}"
        for key in (constant, full):
            if key in self._lookup:
                raise ValueError(f"{key} declared twice in the {self.title} layout")
        slot = Slot(constant, full, self.size, size, unit, meaning)
        self.slots.append(slot)
        self._lookup[constant] = self._lookup[full] = slot
        return slot.index

    def slot(self, name: str) -> Slot:
        """The quantity called ``name`` (``"impact.restitution"``) or held by the
        constant ``name`` (``"IM_E"``).

        Raises:
            KeyError: no such quantity.
        """
        try:
            return self._lookup[name]
        except KeyError:
            raise KeyError(f"no quantity {name!r} in the {self.title} layout") from None

    def read(self, vector: Sequence[float], name: str) -> float | tuple[float, ...]:
        """The value of the quantity ``name`` in ``vector`` (a tuple when it has more
        than one slot)."""
        slot = self.slot(name)
        if slot.size == 1:
            return float(vector[slot.index])
        return tuple(float(x) for x in vector[slot.index : slot.stop])

    def describe(self) -> str:
        """The layout as a table: index, size, constant, name, unit, meaning."""
        lines = [f"{'index':>5} {'size':>4}  {'constant':<16} {'name':<32} {'unit':<8} meaning"]
        for s in self.slots:
            unit = s.unit or "-"
            lines.append(
                f"{s.index:>5} {s.size:>4}  {s.constant:<16} {s.name:<32} {unit:<8} {s.meaning}"
            )
        return "\n".join(lines)

    def spans(self) -> list[tuple[str, int, int, list[Slot]]]:
        """(name, start, stop, quantities) of each block and of each quantity declared
        outside one (named after itself), in order: the layout from start to end."""
        spans: list[tuple[str, int, int, list[Slot]]] = []
        blocks = iter(self.blocks)
        block = next(blocks, None)
        for s in self.slots:
            if block is not None and block[1] <= s.index < block[2]:
                if not spans or spans[-1][0] != block[0]:
                    spans.append((block[0], block[1], block[2], []))
                spans[-1][3].append(s)
                if s.stop == block[2]:
                    block = next(blocks, None)
            else:
                spans.append((s.name, s.index, s.stop, [s]))
        return spans

    def markdown(self) -> str:
        """:meth:`describe` as a Markdown table (one row per quantity)."""
        lines = ["| slots | constant | name | unit | meaning |", "| --- | --- | --- | --- | --- |"]
        for s in self.slots:
            cells = (_span(s.index, s.stop), f"`{s.constant}`", f"`{s.name}`", s.unit or "-")
            lines.append(f"| {' | '.join(cells)} | {s.meaning.replace('|', '&#124;')} |")
        return "\n".join(lines)

    def mismatches(self, namespace: Mapping[str, object]) -> list[str]:
        """The declared constants that ``namespace`` (a module's globals) does not
        bind to their index."""
        return [
            f"{s.constant} = {namespace.get(s.constant)!r}, declared {s.index}"
            for s in self.slots
            if type(namespace.get(s.constant)) is not int or namespace[s.constant] != s.index
        ]


#: the state vector ``ctx``
CTX = Layout("ctx")
#: one surface's block of ``ctx`` (offsets from the block's start)
SURFACE = Layout("surface")
_ctx = CTX.add
_surface = SURFACE.add

# --- drive (kernels: drive.py; written by billiard.geometry.drive.Drive.write) ------
DR = CTX.begin("drive")
AMP = _ctx("AMP", "amplitude", 1, "m", "drive amplitude")
OMEGA = _ctx("OMEGA", "omega", 1, "rad/s", "drive angular frequency")
HORIZ = _ctx("HORIZ", "horizontal", 1, "", "1.0: horizontal drive, 0.0: vertical")
DRIVE_ACCEL = _ctx("DRIVE_ACCEL", "peak_acceleration", 1, "m/s^2", "A w^2")

# --- locator ----------------------------------------------------------------------
DR_END = CTX.begin("locator")
LOC_KIND = _ctx("LOC_KIND", "kind", 1, "", "LOC_EVENT or LOC_RK4: which search the run takes")
G = _ctx("G", "gravity", 1, "m/s^2", "gravity (the flight's too)")
H_FIRST = _ctx("H_FIRST", "first_substep", 1, "s", "first substep of a flight")
H_LONGEST = _ctx("H_LONGEST", "longest_substep", 1, "s", "longest proven-clear substep")
TURN = _ctx("TURN", "turn", 1, "m", "rho / 2 of the offset curves")
H_BRACKET = _ctx("H_BRACKET", "longest_bracket", 1, "s", "longest root bracket of the substep")
SPLIT = _ctx("SPLIT", "split", 1, "", "1.0 when a substep had to be split")
THETA0 = _ctx("THETA0", "theta0", 1, "rad", "drive angle at the start of the flight")
NSURF = _ctx("NSURF", "surfaces", 1, "", "number of surfaces")

LOC_EVENT = 0.0  # the event locator (method "event"; kernels: locate.py, loop.run_chunk)
LOC_RK4 = 1.0  # the paper's fixed-step detection (method "rk4"; loop.run_chunk_fixed)

# --- flight -------------------------------------------------------------------------
FL = CTX.begin("flight")
FL_KIND = _ctx("FL_KIND", "kind", 1, "", "FLIGHT_EXACT, FLIGHT_ADAPTIVE or FLIGHT_RK4")
FL_M = _ctx("FL_M", "mass", 1, "kg", "mass")
FL_CLIN = _ctx("FL_CLIN", "c_lin", 1, "N s/m", "Fowles linear drag")
FL_CQUAD = _ctx("FL_CQUAD", "c_quad", 1, "N s^2/m^2", "Fowles quadratic drag")
FL_CMAG = _ctx("FL_CMAG", "c_magnus", 1, "kg", "Magnus coefficient")
FL_RTOL = _ctx("FL_RTOL", "rtol", 1, "", "Dormand-Prince tolerance")
FL_H = _ctx("FL_H", "step", 1, "s", "step proposal, carried from flight to flight")
FL_U3 = _ctx("FL_U3", "u3", 1, "rad/s", "spin of the current flight")
FL_TA = _ctx("FL_TA", "ta", 1, "s", "start of the current step")
FL_TB = _ctx("FL_TB", "tb", 1, "s", "end of the current step")
FL_YA = _ctx("FL_YA", "ya", 4, "m, m/s", "(q1, q2, u1, u2) at FL_TA")
FL_YB = _ctx("FL_YB", "yb", 4, "m, m/s", "(q1, q2, u1, u2) at FL_TB")
FL_KA = _ctx("FL_KA", "ka", 2, "m/s^2", "acceleration at FL_TA")
FL_KB = _ctx("FL_KB", "kb", 2, "m/s^2", "acceleration at FL_TB")
FL_END = CTX.end()

FLIGHT_EXACT = 0.0
FLIGHT_ADAPTIVE = 1.0
FLIGHT_RK4 = 2.0  # the paper's fixed-step RK4 (method "rk4"; kernels: fixed_step.py)

# --- impact law and ball ------------------------------------------------------------
# contact.restitution and contact.elastic_below: the impact law's, and the landing test's
# of contact.model = "phases" (loop.settles)
IM = CTX.begin("impact")
IM_KIND = _ctx("IM_KIND", "kind", 1, "", "the impact law: KANE_LEVINSON, WALTON, ...")
IM_M = _ctx("IM_M", "mass", 1, "kg", "mass")
IM_R = _ctx("IM_R", "radius", 1, "m", "radius")
IM_K = _ctx("IM_K", "inertia_factor", 1, "", "inertia factor I / (m r^2)")
IM_E = _ctx("IM_E", "restitution", 1, "", "Newton's coefficient of restitution")
IM_MUS = _ctx("IM_MUS", "mu_static", 1, "", "static friction")
IM_MUK = _ctx("IM_MUK", "mu_kinetic", 1, "", "kinetic friction")
IM_EB = _ctx("IM_EB", "elastic_below", 1, "m/s", "low-velocity threshold; the landing speed")
# the other laws' parameters (billiard.models.impact; 0.0 where a law has none)
IM_BETA0 = _ctx("IM_BETA0", "beta0", 1, "", "Walton: tangential restitution of a sticking impact")
IM_EREF = _ctx("IM_EREF", "e_ref", 1, "", "power law: restitution at v_ref")
IM_VREF = _ctx("IM_VREF", "v_ref", 1, "m/s", "power law: reference normal speed")
IM_EXP = _ctx("IM_EXP", "exponent", 1, "", "power law: exponent p of e ~ v^-p")
IM_VISC = _ctx("IM_VISC", "viscous", 1, "(s/m)^(1/5)", "viscoelastic: A alpha^(2/5)")
IM_ESCALE = _ctx("IM_ESCALE", "energy_scale", 1, "J", "energy-dependent: E0 (0: constant e)")
IM_ASLOPE = _ctx("IM_ASLOPE", "angle_slope", 1, "", "angle-dependent: de/d(tan incidence)")
IM_END = CTX.end()

# the kinds (kernels: impact.impact_law; models: billiard.models.impact, .kinds)
KANE_LEVINSON = 0.0  # Kane and Levinson's law with the low-velocity rule (impact.py)
WALTON = 1.0  # Walton's three-parameter law (e, mu, beta0)
POWER_LAW = 2.0  # Kane-Levinson with e(v) = min(1, e_ref (v / v_ref)^-p)
VISCOELASTIC = 3.0  # Kane-Levinson with the viscoelastic e(v) (Ramirez et al.'s series)
ENERGY_DEPENDENT = 4.0  # Kane-Levinson with e falling with the impact's normal energy
ANGLE_DEPENDENT = 5.0  # Kane-Levinson with e rising with the angle of incidence
POINT_PARTICLE = 6.0  # no friction, no change of spin: constant or energy-dependent e

# --- engine state -------------------------------------------------------------------
CTX.begin("engine")
EN_T = _ctx("EN_T", "t", 1, "s", "the ball: time")
EN_THETA = _ctx("EN_THETA", "theta", 1, "rad", "... drive angle")
EN_Q1 = _ctx("EN_Q1", "q1", 1, "m", "... position x")
EN_Q2 = _ctx("EN_Q2", "q2", 1, "m", "... position y")
EN_U1 = _ctx("EN_U1", "u1", 1, "m/s", "... velocity x")
EN_U2 = _ctx("EN_U2", "u2", 1, "m/s", "... velocity y")
EN_U3 = _ctx("EN_U3", "u3", 1, "rad/s", "... spin")
EN_Q3 = _ctx("EN_Q3", "q3", 1, "rad", "... rotation angle")
EN_CLOCK = _ctx("EN_CLOCK", "clock", 1, "s", "compensated clock: sum ...")
EN_CLOCK_ERR = _ctx("EN_CLOCK_ERR", "clock_error", 1, "s", "... and its running error")
EN_ZERO = _ctx("EN_ZERO", "zero_flights", 1, "", "consecutive zero flights")
EN_IMPACTS = _ctx("EN_IMPACTS", "impacts", 1, "", "impacts so far")
EN_UNTIL = _ctx("EN_UNTIL", "until", 1, "s", "simulated time at which the run ends (inf: none)")
EN_RCOUNT = _ctx("EN_RCOUNT", "recent_count", 1, "", "impacts in the collapse window")
EN_RHEAD = _ctx("EN_RHEAD", "recent_head", 1, "", "ring index of the oldest of them")
EN_TARGET = _ctx("EN_TARGET", "target", 1, "", "impact number to stop at")
EN_FAULT = _ctx("EN_FAULT", "fault", 1, "", "1.0: a collapse after the last impact")
# for the message of a stop: the value it names (tau_a of a failed step-size control, x
# of a failed offset inversion) and the time of the impact being made (nan while the
# next impact is searched for)
EN_ERR_VALUE = _ctx("EN_ERR_VALUE", "error_value", 1, "", "the value a stop names")
EN_EVENT_T = _ctx("EN_EVENT_T", "event_t", 1, "s", "time of the impact being made")
COUNTS = _ctx("COUNTS", "counts", 4, "", "impacts: stick, slip, elastic, resting")
# landing (contact.model = "phases"): after an impact on a wall whose rebound settles, the
# chunk ends (status LAND) so that the engine can put the ball in contact; the test
# reads IM_E and IM_EB
EN_LAND_ON = _ctx("EN_LAND_ON", "land_on", 1, "", "1.0: watch for landings; 0.0: impacts only")
EN_SETTLES = _ctx("EN_SETTLES", "settles", 1, "", "1.0: the last impact settles (status LAND)")
EN_LAST_J = _ctx("EN_LAST_J", "last_surface", 1, "", "the last impact: its surface, ...")
EN_LAST_S = _ctx("EN_LAST_S", "last_s", 1, "m", "... the contact point's parameter s ...")
EN_LAST_WN = _ctx("EN_LAST_WN", "last_wn", 1, "m/s", "... the normal speed before it ...")
EN_LAST_REGIME = _ctx("EN_LAST_REGIME", "last_regime", 1, "", "... and its regime")
CTX.end()

# --- surfaces -----------------------------------------------------------------------
# a surface's block, SURF_STRIDE slots: offsets from its start
SURFACE.begin("surface")
S_KIND = _surface("S_KIND", "kind", 1, "", "CURVED, LINE, LID or ESCAPE")
S_WALL = _surface("S_WALL", "wall", 1, "", "wall index (curved and straight walls)")
S_A = _surface("S_A", "a", 1, "", "curved: r (m); line: b; lid, escape: level (m)")
S_B = _surface("S_B", "b", 1, "", "curved: bend_bound (1/m); line: intercept (m)")
S_C = _surface("S_C", "c", 1, "", "curved: bend_abs (1/m); line: shift (m)")
S_D = _surface("S_D", "d", 1, "rad", "line: z")
S_E = _surface("S_E", "e", 1, "", "line: cos z")
# curved: the slope memo, f'(s) at s = S_SLOPE_AT as S_SLOPE (nan: none), so that an
# inversion starting where the last one ended does not call f' there again; a block copied
# from a surface (Surface.block) carries no memo
S_SLOPE_AT = _surface("S_SLOPE_AT", "slope_at", 1, "m", "the slope memo: s (nan: none)")
S_WS = _surface("S_WS", "warm_s", 1, "m", "warm start: s")
S_WSLOPE = _surface("S_WSLOPE", "warm_slope", 1, "", "warm start: slope")
S_GA = _surface("S_GA", "ga", 1, "m", "G at the substep's start")
S_DGA = _surface("S_DGA", "dga", 1, "m/s", "dG/dtau at the substep's start")
S_GB = _surface("S_GB", "gb", 1, "m", "G at its end")
S_DGB = _surface("S_DGB", "dgb", 1, "m/s", "dG/dtau at its end")
S_LEAVING = _surface("S_LEAVING", "leaving", 1, "", "1.0: the ball is separating from it")
S_SLOPE = _surface("S_SLOPE", "slope", 1, "", "the slope memo: f'(S_SLOPE_AT)")
SURF_STRIDE = SURFACE.end()
MAX_SURFACES = 16
SURF = _ctx("SURF", "surfaces", MAX_SURFACES * SURF_STRIDE, "", "one block per surface")

CURVED = 0.0
LINE = 1.0
LID = 2.0
ESCAPE = 3.0

# --- collapse window ----------------------------------------------------------------
#: slots of the ring: billiard.kernels.rules.COLLAPSE_COUNT + 1 (a test checks it)
RECENT_SLOTS = 201
RECENT = _ctx("RECENT", "recent", RECENT_SLOTS, "s", "ring of the latest impact times")

# --- the locator's pending substeps (the right halves still to scan) ---------------
STACK_ENTRY = 7  # ta, G(ta), dG(ta), tb, G(tb), dG(tb), splits
STACK_DEPTH = 24
STACK = _ctx("STACK", "stack", STACK_ENTRY * STACK_DEPTH, "", "pending substeps")

# --- a contact phase (rolling or sliding on one wall) -----------------------------
# The phase's constants, its Dormand-Prince state between calls (a phase is resumable:
# it returns at every sample time and goes on from there), the step's dense output, and
# the transition functions ("conditions") at the step's ends. Kernels: contact.py.
PH = CTX.begin("phase")
PH_M = _ctx("PH_M", "mass", 1, "kg", "mass")
PH_R = _ctx("PH_R", "radius", 1, "m", "radius")
PH_K = _ctx("PH_K", "inertia_factor", 1, "", "inertia factor")
PH_G = _ctx("PH_G", "gravity", 1, "m/s^2", "gravity")
PH_CLIN = _ctx("PH_CLIN", "c_lin", 1, "N s/m", "Fowles linear drag")
PH_CQUAD = _ctx("PH_CQUAD", "c_quad", 1, "N s^2/m^2", "Fowles quadratic drag")
PH_MUS = _ctx("PH_MUS", "mu_static", 1, "", "static friction")
PH_MUK = _ctx("PH_MUK", "mu_kinetic", 1, "", "kinetic friction")
PH_RTOL = _ctx("PH_RTOL", "rtol", 1, "", "the step's relative tolerance")
PH_WALL = _ctx("PH_WALL", "wall", 1, "", "index of the phase's wall in the wall functions")
PH_SURF = _ctx("PH_SURF", "surface", 1, "", "... among the surfaces (not watched)")
PH_LO = _ctx("PH_LO", "lo", 1, "m", "the wall's interval: start")
PH_HI = _ctx("PH_HI", "hi", 1, "m", "... end")
PH_MODE = _ctx("PH_MODE", "mode", 1, "", "ROLL or SLIDE")
PH_SGN = _ctx("PH_SGN", "slip_sign", 1, "", "sign of the slip while sliding")
PH_THETA0 = _ctx("PH_THETA0", "theta0", 1, "rad", "drive angle at the phase's start")
PH_LIMIT = _ctx("PH_LIMIT", "limit", 1, "s", "longest duration (inf: none)")
PH_STAGE = _ctx("PH_STAGE", "stage", 1, "", "STAGE_STEP, STAGE_EMIT or STAGE_SKIP")
PH_TAU = _ctx("PH_TAU", "tau", 1, "s", "time since the phase's start")
PH_H = _ctx("PH_H", "step", 1, "s", "step proposal")
PH_STEPS = _ctx("PH_STEPS", "steps", 1, "", "accepted steps")
PH_HMAX = _ctx("PH_HMAX", "longest_step", 1, "s", "longest step")
PH_RSPAN = _ctx("PH_RSPAN", "rest_span", 1, "s", "a drive period (0 on a static boundary)")
PH_RSINCE = _ctx("PH_RSINCE", "rest_since", 1, "s", "at rest since (inf: moving)")
PH_NEXT = _ctx("PH_NEXT", "next_sample", 1, "s", "next sample time (inf: none)")
PH_ERR = _ctx("PH_ERR", "error", 1, "", "scaled error of the last step")
PH_TA = _ctx("PH_TA", "ta", 1, "s", "the last step: its start, ...")
PH_HSTEP = _ctx("PH_HSTEP", "h", 1, "s", "... length ...")
PH_TB = _ctx("PH_TB", "tb", 1, "s", "... and end")
PH_END_T = _ctx("PH_END_T", "end_t", 1, "s", "the end found in the last step: time ...")
PH_END_I = _ctx("PH_END_I", "end_condition", 1, "", "... and condition (-1: none)")
PH_SAMPLE_T = _ctx("PH_SAMPLE_T", "sample_t", 1, "s", "a sample handed out: time")
# y = (s, s_dot, u3) (m, m/s, rad/s; u3 unused while rolling)
PH_Y = _ctx("PH_Y", "y", 3, "m, m/s, rad/s", "y at PH_TAU")
PH_YB = _ctx("PH_YB", "yb", 3, "m, m/s, rad/s", "y at the last step's end")
PH_YI = _ctx("PH_YI", "yi", 3, "m, m/s, rad/s", "a stage's argument")
PH_YD = _ctx("PH_YD", "yd", 3, "m, m/s, rad/s", "the dense output at a root candidate")
PH_END_Y = _ctx("PH_END_Y", "end_y", 3, "m, m/s, rad/s", "y at the end found")
PH_SAMPLE_Y = _ctx("PH_SAMPLE_Y", "sample_y", 3, "m, m/s, rad/s", "y of the sample handed out")
PH_KS = _ctx("PH_KS", "stages", 21, "", "the seven stages' derivatives, 3 per stage")
PH_NCOND = 20  # conditions: normal force, two wall ends, friction, one per other surface
PH_CPREV = _ctx("PH_CPREV", "conditions_start", PH_NCOND, "", "conditions at the step's start")
PH_CNEW = _ctx("PH_CNEW", "conditions_end", PH_NCOND, "", "... at its end")
PH_CTMP = _ctx("PH_CTMP", "conditions_candidate", PH_NCOND, "", "... at a root candidate")
# the phase pauses between two steps (PHASE_PAUSE), its state untouched, once it has
# taken PH_PAUSE steps or reached the time PH_PAUSE_T: the caller looks at its stop
# request and its progress, then goes on (or stops the phase where it is)
PH_PAUSE = _ctx("PH_PAUSE", "pause_steps", 1, "", "accepted steps at which to pause")
PH_PAUSE_T = _ctx("PH_PAUSE_T", "pause_t", 1, "s", "time since the start to pause at (inf: none)")
PH_END = CTX.end()

ROLL = 0.0
SLIDE = 1.0
STAGE_STEP = 0.0  # take the next step
STAGE_EMIT = 1.0  # hand out the samples up to the step's end, then end or go on
STAGE_SKIP = 2.0  # hand out the samples of skipped drive periods at rest

# --- a hold by two walls (the ball in a vertex: only its spin moves) --------------
# Its inputs, the hold's state between calls (resumable at sample times, as a phase),
# and what the last step found. The constants are the phase's (PH_M .. PH_MUK) and the
# drive's. Kernels: vertex.py.
VX = CTX.begin("hold")
VX_ZA = _ctx("VX_ZA", "za", 1, "rad", "tangent angle of the first wall at its contact point")
VX_ZB = _ctx("VX_ZB", "zb", 1, "rad", "... of the second")
VX_THETA0 = _ctx("VX_THETA0", "theta0", 1, "rad", "drive angle at the hold's start")
VX_LIMIT = _ctx("VX_LIMIT", "limit", 1, "s", "longest duration (inf: none)")
VX_STAGE = _ctx("VX_STAGE", "stage", 1, "", "STAGE_STEP, STAGE_EMIT or STAGE_SKIP")
VX_TAU = _ctx("VX_TAU", "tau", 1, "s", "time since the hold's start")
VX_W = _ctx("VX_W", "spin", 1, "rad/s", "spin u3 at VX_TAU; the spin at the start before begin")
VX_SIGMA = _ctx("VX_SIGMA", "spin_sign", 1, "", "its sign (0: no spin, no kinetic friction)")
VX_H = _ctx("VX_H", "step", 1, "s", "longest step: 1/64 drive period (inf: static)")
VX_RSPAN = _ctx("VX_RSPAN", "rest_span", 1, "s", "a drive period (0 on a static boundary)")
VX_RSINCE = _ctx("VX_RSINCE", "rest_since", 1, "s", "without spin since (inf: spinning)")
VX_NEXT = _ctx("VX_NEXT", "next_sample", 1, "s", "next sample time (inf: none)")
VX_STOPS = _ctx("VX_STOPS", "stops", 1, "s", "the last step: a static boundary stops the spin")
VX_END_T = _ctx("VX_END_T", "end_t", 1, "s", "... its end: a release, the limit, the step's end")
# 0, 1: the wall still pressing after a release; -1: neither; -2: no release
VX_KEEPS = _ctx("VX_KEEPS", "keeps", 1, "", "... the wall still pressing after a release")
VX_W_END = _ctx("VX_W_END", "end_spin", 1, "rad/s", "... the spin at VX_END_T")
VX_SAMPLE_T = _ctx("VX_SAMPLE_T", "sample_t", 1, "s", "a sample handed out: time ...")
VX_SAMPLE_W = _ctx("VX_SAMPLE_W", "sample_spin", 1, "rad/s", "... and spin")
VX_END = CTX.end()

# --- the paper's fixed-step detection (method "rk4") --------------------------------
# The step, the locator's memory between flights (the Newton starts of the walls'
# nearest points, the departures in a row), the walls' intervals, and the global nearest
# points the Python side computed for the search under way (kernels: fixed_step.py).
RK_MAX_ANSWERS = 64
RK = CTX.begin("rk4")
RK_H = _ctx("RK_H", "step", 1, "s", "the fixed step")
RK_R = _ctx("RK_R", "radius", 1, "m", "the offset radius (the ball's)")
RK_NWALLS = _ctx("RK_NWALLS", "walls", 1, "", "walls of the curve (the first surfaces)")
RK_LID = _ctx("RK_LID", "lid", 1, "", "the lid's index among the surfaces (-1: none)")
RK_ESCAPE = _ctx("RK_ESCAPE", "escape", 1, "", "the escape level's index (-1: none)")
RK_DEPARTURES = _ctx("RK_DEPARTURES", "departures", 1, "", "impacts in a row just after leaving")
RK_ANSWERS = _ctx("RK_ANSWERS", "answers", 1, "", "nearest points answered for this search")
RK_ASK = _ctx("RK_ASK", "ask", 3, "m, m, -", "the one asked for (E_FOOT): px, py, wall")
RK_FEET = _ctx("RK_FEET", "feet", MAX_SURFACES, "m", "Newton start of each wall's nearest point")
RK_FEET0 = _ctx("RK_FEET0", "feet_start", MAX_SURFACES, "m", "... as the search under way found")
RK_LO = _ctx("RK_LO", "lo", MAX_SURFACES, "m", "each wall's interval: start")
RK_HI = _ctx("RK_HI", "hi", MAX_SURFACES, "m", "... end")
RK_ANSWER = _ctx("RK_ANSWER", "answer", 4 * RK_MAX_ANSWERS, "", "answers: px, py (m), wall, s (m)")
RK_END = CTX.end()

# --- the stop -----------------------------------------------------------------------
# A stop of the impact path (loop, locate, flight, surfaces) writes its E_* code here
# before it raises KernelError: on a GPU, where numba-cuda does not report a device
# function's exception (the thread just ends), each trajectory's ctx row keeps its reason
# (billiard.engine.gpu). The CPU engine reads the exception; nothing reads this slot there.
CTX.begin("stop")
EN_STOP = _ctx("EN_STOP", "code", 1, "", "E_* code of the stop that ended the kernel (0: none)")
CTX.end()

# --- the trajectory state machine (contact.model = "phases", kernels: machine.py) -----
# The motion state and what the engine carries with it: the contact (as
# EngineState.contact: roll/slide: surface, s, s_dot, slip sign, start, settle; held:
# the two surfaces, the centre in the boundary's frame, start, settle), the time spent
# in finished phases, the last impact's time, the run's end so far; the container's
# range of x and each wall's interval (where a phase ends with wall-end), the contact
# span; and a phase under way between two calls.
CTX.begin("machine")
MC_MODE = _ctx("MC_MODE", "mode", 1, "", "M_FLIGHT, M_ROLL, M_SLIDE or M_HELD")
MC_CONTACT = _ctx("MC_CONTACT", "contact", 6, "", "the contact (see EngineState.contact)")
MC_PHASE_TIME = _ctx("MC_PHASE_TIME", "phase_time", 3, "s", "finished phases: roll, slide, held")
MC_LAST_IMPACT = _ctx("MC_LAST_IMPACT", "last_impact", 1, "s", "time of the last impact")
MC_FINAL = _ctx("MC_FINAL", "final_time", 1, "s", "the time the run has reached")
MC_SPAN = _ctx("MC_SPAN", "contact_span", 1, "s", "run.contact_span")
MC_X_LO = _ctx("MC_X_LO", "x_lo", 1, "m", "the container's range of x: start ...")
MC_X_HI = _ctx("MC_X_HI", "x_hi", 1, "m", "... and end")
MC_WALL_LO = _ctx("MC_WALL_LO", "wall_lo", MAX_SURFACES, "m", "each wall's interval: start")
MC_WALL_HI = _ctx("MC_WALL_HI", "wall_hi", MAX_SURFACES, "m", "... end")
MC_PHASE_ON = _ctx("MC_PHASE_ON", "phase_on", 1, "", "a phase under way: 0 none, 1 on, 2 paused")
MC_STOP_AT = _ctx("MC_STOP_AT", "stop_at", 1, "s", "the phase under way: its contact span's end")
MC_ROW = _ctx("MC_ROW", "row", 1, "", "impact rows written in this call")
MC_CROW = _ctx("MC_CROW", "contact_row", 1, "", "contact rows written in this call")
MC_FLYING = _ctx("MC_FLYING", "flying", 1, "", "1.0 while the flights run (a stop is theirs)")
MC_FLIGHT_FROM = _ctx("MC_FLIGHT_FROM", "flight_from", 1, "s", "the ball's time when they began")
# a flight's contact without impulse under contact phases (loop.impact): no row, no
# impact counted; the ball goes on from it (or lands)
EN_NO_ROW = _ctx("EN_NO_ROW", "no_row", 1, "", "1.0: the last contact gave no impulse (no row)")
MC_HOLD_ON = _ctx("MC_HOLD_ON", "hold_on", 1, "", "a hold under way between two calls: 1 on")
EN_ONE = _ctx("EN_ONE", "one_flight", 1, "", "1.0: run_chunk returns after each flight (FLOWN)")
CTX.end()

# --- trajectory samples (run --sample; kernels: samples.py, machine.py) --------------
# Samples at t0 + k dt from the run's start, written as rows of SCOL floats into the
# machine's sample buffer: from the flight's own closed form or integrator restarted at
# the flight's start (a second flight state, the sample ctx, ``sctx``), from a phase's
# dense output, from a hold's spin law. A flight's samples are written when it ends, up
# to its end; an emission that fills the buffer stays pending (SM_PENDING) and goes on
# at the next call.
CTX.begin("samples")
SM_DT = _ctx("SM_DT", "dt", 1, "s", "sample interval (0: no samples)")
SM_T0 = _ctx("SM_T0", "t0", 1, "s", "time of sample 0 (the run's start)")
SM_K = _ctx("SM_K", "count", 1, "", "samples reported so far (engine state)")
SM_GEN = _ctx("SM_GEN", "next_k", 1, "", "index of the phase's or hold's next sample")
SM_ROW = _ctx("SM_ROW", "row", 1, "", "sample rows written in this call")
SM_MARK = _ctx("SM_MARK", "mark", 1, "", "the count at the phase's or chatter's start")
SM_PENDING = _ctx("SM_PENDING", "pending", 1, "", "an emission under way: SRC_FLIGHT, SRC_CHATTER")
SM_DONE = _ctx("SM_DONE", "chatter_done", 1, "", "1.0: the chatter's samples are written")
SM_AFTER = _ctx("SM_AFTER", "after", 1, "", "the flight's status, returned once its samples are")
SM_FROM = _ctx("SM_FROM", "from", 1, "s", "the emission: from ...")
SM_TO = _ctx("SM_TO", "to", 1, "s", "... to")
SM_BALL = _ctx("SM_BALL", "ball", 7, "", "the flight's start: t, theta, q1, q2, u1, u2, u3")
SM_REACHED = _ctx("SM_REACHED", "reached", 1, "s", "the sample flight's integration reached")
# the rk4 flight's last step in the sample ctx (RK4Flight keeps them on the object)
SF_TA = _ctx("SF_TA", "rk4_ta", 1, "s", "sample ctx, rk4: the last step's start ...")
SF_TB = _ctx("SF_TB", "rk4_tb", 1, "s", "... and end")
SF_YA = _ctx("SF_YA", "rk4_ya", 4, "m, m/s", "... the state at its start ...")
SF_YB = _ctx("SF_YB", "rk4_yb", 4, "m, m/s", "... and at its end")
CTX.end()

SIZE = CTX.size


def describe() -> str:
    """The state vector's layout and a surface block's, as tables."""
    return f"{CTX.describe()}\n\n{SURFACE.describe()}"


def _span(start: int, stop: int) -> str:
    return str(start) if stop == start + 1 else f"{start}-{stop - 1}"


def markdown() -> str:
    """:func:`describe` in Markdown, the state vector's section of
    ``docs/compiled-engine.md`` (a test checks that the page holds it): the blocks, then
    every quantity of ``ctx`` and of a surface's block."""
    rows = []
    for name, start, stop, slots in CTX.spans():
        # a block lists its quantities; a quantity outside one says what it holds
        held = [s.name.removeprefix(f"{name}.") for s in slots]
        what = slots[0].meaning if held == [name] else ", ".join(held)
        rows.append(f"| {name} | {_span(start, stop)} | {what} |")
    return "\n".join(
        [
            f"`ctx` holds {SIZE:,} slots; a surface's block, {SURF_STRIDE} "
            f"(`SURF` holds {MAX_SURFACES} of them).",
            "",
            "| block | slots | quantities |",
            "| --- | --- | --- |",
            *rows,
            "",
            "<details><summary>Every quantity of <code>ctx</code></summary>",
            "",
            CTX.markdown(),
            "",
            "</details>",
            "",
            "A surface's block (offsets from the block's start, `S_*`):",
            "",
            SURFACE.markdown(),
        ]
    )


# --- rows ---------------------------------------------------------------------------
# one row per impact, the columns of collisions.csv in order; regime and wall as codes
NCOL = 18
STICK = 0.0
SLIP = 1.0
ELASTIC = 2.0
REGIMES = ("stick", "slip", "elastic")
LID_LABEL = -1.0  # wall column of an impact on the lid

# --- run_chunk statuses -------------------------------------------------------------
DONE = 0  # the target impact number was reached
FULL = 1  # the chunk's rows are full
TIME_LIMIT = 2  # the next impact comes after EN_UNTIL
COLLAPSE = 3  # an inelastic collapse after the last row
LAND = 4  # the last row's impact settles on a wall (EN_LAST_J, EN_LAST_S, EN_LAST_WN)
# ... and of the state machine (machine.run_machine)
PAUSED = 5  # a long phase paused between two steps (it goes on at the next call)
IN_CONTACT = 6  # no impact for run.contact_span (MC_FINAL: the time)
CONTACTS_FULL = 7  # the contact rows are full
SAMPLES_FULL = 8  # the sample rows are full (an emission may be pending)
FLOWN = 9  # run_chunk with EN_ONE: one flight done (an impact or a contact without impulse)

# --- trajectory samples -----------------------------------------------------------------
SCOL = 8  # t, q1, q2, u1, u2, u3, energy, mode (MC_MODE code)
SRC_FLIGHT = 1.0  # samples of a free flight from SM_BALL
SRC_CHATTER = 2.0  # samples of a ball landing at the end of a summed chatter series

# --- motion states (MC_MODE) --------------------------------------------------------
M_FLIGHT = 0.0
M_ROLL = 1.0
M_SLIDE = 2.0
M_HELD = 3.0
MOTION_NAMES = ("flight", "roll", "slide", "held")

# --- contact rows (machine.py): one per finished or cut phase -----------------------
# kind (0 finished, 1 cut), the impacts before it, t_start, t_end, surface, second
# surface (-1: none), mode, end, t_settle, the lab state at the start and at the end
# (q1, q2, u1, u2, u3 each)
CCOL = 19
END_NAMES = ("lift-off", "slip", "roll", "wall-end", "impact", "release", "cut")
END_LIFT_OFF = 0.0
END_SLIP = 1.0
END_ROLL = 2.0
END_WALL_END = 3.0
END_IMPACT = 4.0
END_RELEASE = 5.0
END_CUT = 6.0

# --- contact phase statuses (contact.advance) --------------------------------------
PHASE_END = 0  # a transition ends the phase: PH_END_T, PH_END_I, PH_END_Y
PHASE_LIMIT = 1  # the time limit came first: the state is PH_Y at PH_LIMIT
PHASE_SAMPLE = 2  # a sample at PH_SAMPLE_T: PH_SAMPLE_Y; set PH_NEXT and call again
PHASE_PAUSE = 3  # between two steps (PH_PAUSE, PH_PAUSE_T): the state is PH_Y at PH_TAU
# a hold (vertex.advance) returns the same three: PHASE_END a release (VX_END_T,
# VX_KEEPS, VX_W_END), PHASE_LIMIT the time limit (VX_W_END), PHASE_SAMPLE a sample
# (VX_SAMPLE_T, VX_SAMPLE_W; set VX_NEXT and call again)

# --- KernelError codes --------------------------------------------------------------
E_ESCAPED = 1
E_NO_IMPACT = 2
E_ROOT = 3
E_EXTREMUM = 4
E_STEP_CONTROL = 5
E_INVERSION = 6
E_NON_FINITE = 7
E_COLLAPSE = 8
E_PHASE_STEPS = 9  # a contact phase's step-size control failed
E_AT_REST = 10  # at rest relative to the boundary for good: from PH_RSINCE (a hold: VX_RSINCE)
E_DEPARTURES = 11  # rk4: DEPARTURE_LIMIT departures in a row (the step, s, in EN_ERR_VALUE)
E_FOOT = 12  # rk4: Newton failed from both starts: the global nearest point at RK_ASK
E_PHASE_NON_FINITE = 13  # a non-finite state at a phase's end (MC_FINAL: the time)
E_LEFT = 14  # a phase left the container's range of x (EN_ERR_VALUE: s; MC_FINAL: t)
E_KIND = 15  # a model kind (IM_KIND) the kernels do not have (EN_ERR_VALUE: the kind)


class KernelError(Exception):
    """A documented stop inside a kernel; ``args[0]`` is one of the ``E_*`` codes."""
