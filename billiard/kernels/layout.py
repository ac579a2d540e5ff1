"""The state vector ``ctx`` of the kernels: one flat float64 array holding the scene's
constants, the flight's and the locator's working state, the engine state and one block
per surface. One array, so that a kernel call passes one reference (numba counts
references on every array argument of a call it does not inline).

Also the codes the kernels use for surfaces, regimes, statuses and errors.
"""

from __future__ import annotations

# --- drive and locator ------------------------------------------------------------
AMP = 0  # drive amplitude (m)
OMEGA = 1  # drive angular frequency (rad/s)
HORIZ = 2  # 1.0: horizontal drive, 0.0: vertical
DRIVE_ACCEL = 3  # A w^2 (m/s^2)
G = 4  # gravity (m/s^2)
H_FIRST = 5  # first substep of a flight (s)
H_LONGEST = 6  # longest proven-clear substep (s)
TURN = 7  # rho / 2 of the offset curves (m)
H_BRACKET = 8  # longest root bracket of the current substep (s)
SPLIT = 9  # 1.0 when a substep had to be split
THETA0 = 10  # drive angle at the start of the flight (rad)
NSURF = 11  # number of surfaces

# --- flight -------------------------------------------------------------------------
FL_KIND = 16  # FLIGHT_EXACT or FLIGHT_ADAPTIVE
FL_M = 17  # mass (kg)
FL_CLIN = 18  # Fowles linear drag (N s/m)
FL_CQUAD = 19  # Fowles quadratic drag (N s^2/m^2)
FL_CMAG = 20  # Magnus coefficient (kg)
FL_RTOL = 21  # Dormand-Prince tolerance
FL_H = 22  # step proposal, carried from flight to flight (s)
FL_U3 = 23  # spin of the current flight (rad/s)
FL_TA = 24  # start of the current step (s)
FL_TB = 25  # end of the current step (s)
FL_YA = 26  # (q1, q2, u1, u2) at FL_TA: 26..29
FL_YB = 30  # (q1, q2, u1, u2) at FL_TB: 30..33
FL_KA = 34  # acceleration at FL_TA: 34, 35
FL_KB = 36  # acceleration at FL_TB: 36, 37

FLIGHT_EXACT = 0.0
FLIGHT_ADAPTIVE = 1.0
FLIGHT_RK4 = 2.0  # the paper's fixed-step RK4 (method "rk4"; kernels: fixed_step.py)

# --- impact law and ball ------------------------------------------------------------
IM_M = 40  # mass (kg)
IM_R = 41  # radius (m)
IM_K = 42  # inertia factor
IM_E = 43  # restitution
IM_MUS = 44  # static friction
IM_MUK = 45  # kinetic friction
IM_EB = 46  # low-velocity threshold (m/s)

# --- engine state -------------------------------------------------------------------
EN_T = 50  # ball: t, theta, q1, q2, u1, u2, u3, q3 at 50..57
EN_THETA = 51
EN_Q1 = 52
EN_Q2 = 53
EN_U1 = 54
EN_U2 = 55
EN_U3 = 56
EN_Q3 = 57
EN_CLOCK = 58  # compensated clock: sum ...
EN_CLOCK_ERR = 59  # ... and its running error
EN_ZERO = 60  # consecutive zero flights
EN_IMPACTS = 61  # impacts so far
EN_UNTIL = 62  # simulated time at which the run ends (inf: none)
EN_RCOUNT = 63  # impacts in the collapse window (ring at RECENT)
EN_RHEAD = 64  # ring index of the oldest of them
EN_TARGET = 65  # impact number to stop at
EN_FAULT = 66  # 1.0: a collapse was detected after the last impact
# for the message of a stop: the value it names (tau_a of a failed step-size control, x
# of a failed offset inversion) and the time of the impact being made (nan while the
# next impact is searched for)
EN_ERR_VALUE = 67
EN_EVENT_T = 68
COUNTS = 70  # stick, slip, elastic, resting: 70..73
# landing (contact.model = "phases"): after an impact on a wall whose rebound settles, the
# chunk ends (status LAND) so that the engine can put the ball in contact
EN_LAND_ON = 74  # 1.0: watch for landings; 0.0: impacts only
EN_LAND_E = 75  # the contact model's restitution
EN_LAND_BELOW = 76  # the landing speed, contact.elastic_below (m/s)
EN_SETTLES = 77  # 1.0: the last impact settles (the chunk ended with LAND)
EN_LAST_J = 78  # the last impact: its surface, ...
EN_LAST_S = 79  # ... the contact point's parameter s (m) ...
EN_LAST_WN = 80  # ... the relative normal speed before it (m/s) ...
EN_LAST_REGIME = 81  # ... and its regime (STICK, SLIP, ELASTIC)

# --- surfaces -----------------------------------------------------------------------
SURF = 100
SURF_STRIDE = 16
MAX_SURFACES = 16
# offsets in a surface's block
S_KIND = 0
S_WALL = 1  # wall index (curved and straight walls)
S_A = 2  # curved: r;          line: b;         lid, escape: level
S_B = 3  # curved: bend_bound; line: intercept
S_C = 4  # curved: bend_abs;   line: shift
S_D = 5  # line: z
S_E = 6  # line: cos z
# curved: the slope memo, f'(s) at s = S_SLOPE_AT as S_SLOPE (nan: none), so that an
# inversion starting where the last one ended does not call f' there again; a block copied
# from a surface (Surface.block) carries no memo
S_SLOPE_AT = 7
S_WS = 8  # warm start: s
S_WSLOPE = 9  # warm start: slope
S_GA = 10  # G, dG/dtau at the substep's start
S_DGA = 11
S_GB = 12  # G, dG/dtau at its end
S_DGB = 13
S_LEAVING = 14  # 1.0: the ball is separating from it
S_SLOPE = 15

CURVED = 0.0
LINE = 1.0
LID = 2.0
ESCAPE = 3.0

# --- collapse window ----------------------------------------------------------------
RECENT = 400  # ring of the latest impact times (COLLAPSE_COUNT + 1 slots)

# --- the locator's pending substeps (the right halves still to scan) ---------------
STACK = 640
STACK_ENTRY = 7  # ta, G(ta), dG(ta), tb, G(tb), dG(tb), splits
STACK_DEPTH = 24

# --- a contact phase (rolling or sliding on one wall) -----------------------------
# The phase's constants, its Dormand-Prince state between calls (a phase is resumable:
# it returns at every sample time and goes on from there), the step's dense output, and
# the transition functions ("conditions") at the step's ends. Kernels: contact.py.
PH = STACK + STACK_ENTRY * STACK_DEPTH
PH_M = PH  # mass (kg)
PH_R = PH + 1  # radius (m)
PH_K = PH + 2  # inertia factor
PH_G = PH + 3  # gravity (m/s^2)
PH_CLIN = PH + 4  # Fowles linear drag (N s/m)
PH_CQUAD = PH + 5  # Fowles quadratic drag (N s^2/m^2)
PH_MUS = PH + 6  # static friction
PH_MUK = PH + 7  # kinetic friction
PH_RTOL = PH + 8  # the step's relative tolerance
PH_WALL = PH + 9  # index of the phase's wall in the wall functions
PH_SURF = PH + 10  # index of the phase's wall among the surfaces (not watched)
PH_LO = PH + 11  # the wall's interval (m)
PH_HI = PH + 12
PH_MODE = PH + 13  # ROLL or SLIDE
PH_SGN = PH + 14  # sign of the slip while sliding
PH_THETA0 = PH + 15  # drive angle at the phase's start (rad)
PH_LIMIT = PH + 16  # longest duration (s; inf: none)
PH_STAGE = PH + 17  # where the phase goes on: STAGE_STEP, STAGE_EMIT, STAGE_SKIP
PH_TAU = PH + 18  # time since the phase's start (s)
PH_H = PH + 19  # step proposal (s)
PH_STEPS = PH + 20  # accepted steps
PH_HMAX = PH + 21  # longest step (s)
PH_RSPAN = PH + 22  # rest span: a drive period (0 on a static boundary)
PH_RSINCE = PH + 23  # at rest relative to the boundary since (s; inf: moving)
PH_NEXT = PH + 24  # next sample time (s; inf: none)
PH_ERR = PH + 25  # scaled error of the last step
PH_TA = PH + 26  # the last step: its start (s), length (s), end (s)
PH_HSTEP = PH + 27
PH_TB = PH + 28
PH_END_T = PH + 29  # the end found in the last step: time (s), condition (-1: none)
PH_END_I = PH + 30
PH_SAMPLE_T = PH + 31  # a sample handed out: time (s)
PH_Y = PH + 32  # y = (s, s_dot, u3) at PH_TAU: 32..34 (u3 unused while rolling)
PH_YB = PH + 35  # y at the last step's end: 35..37
PH_YI = PH + 38  # a stage's argument: 38..40
PH_YD = PH + 41  # the dense output at a root candidate: 41..43
PH_END_Y = PH + 44  # y at the end found: 44..46
PH_SAMPLE_Y = PH + 47  # y of the sample handed out: 47..49
PH_KS = PH + 50  # the seven stages' derivatives, 3 per stage: 50..70
PH_NCOND = 20  # conditions: normal force, two wall ends, friction, one per other surface
PH_CPREV = PH + 71  # conditions at the step's start
PH_CNEW = PH_CPREV + PH_NCOND  # ... at its end
PH_CTMP = PH_CNEW + PH_NCOND  # ... at a root candidate
# the phase pauses between two steps (PHASE_PAUSE), its state untouched, once it has
# taken PH_PAUSE steps or reached the time PH_PAUSE_T: the caller looks at its stop
# request and its progress, then goes on (or stops the phase where it is)
PH_PAUSE = PH_CTMP + PH_NCOND  # accepted steps at which to pause
PH_PAUSE_T = PH_PAUSE + 1  # time since the phase's start (s) at which to pause (inf: none)
PH_END = PH_PAUSE_T + 1

ROLL = 0.0
SLIDE = 1.0
STAGE_STEP = 0.0  # take the next step
STAGE_EMIT = 1.0  # hand out the samples up to the step's end, then end or go on
STAGE_SKIP = 2.0  # hand out the samples of skipped drive periods at rest

# --- a hold by two walls (the ball in a vertex: only its spin moves) --------------
# Its inputs, the hold's state between calls (resumable at sample times, as a phase),
# and what the last step found. The constants are the phase's (PH_M .. PH_MUK) and the
# drive's. Kernels: vertex.py.
VX = PH_END
VX_ZA = VX  # tangent angles (rad) of the two walls at their contact points
VX_ZB = VX + 1
VX_THETA0 = VX + 2  # drive angle at the hold's start (rad)
VX_LIMIT = VX + 3  # longest duration (s; inf: none)
VX_STAGE = VX + 4  # where the hold goes on: STAGE_STEP, STAGE_EMIT, STAGE_SKIP
VX_TAU = VX + 5  # time since the hold's start (s)
VX_W = VX + 6  # spin u3 at VX_TAU (rad/s); the spin at the start before begin()
VX_SIGMA = VX + 7  # its sign (0: no spin, no kinetic friction)
VX_H = VX + 8  # longest step: 1/64 drive period (inf on a static boundary)
VX_RSPAN = VX + 9  # rest span: a drive period (0 on a static boundary)
VX_RSINCE = VX + 10  # without spin since (s; inf: spinning)
VX_NEXT = VX + 11  # next sample time (s; inf: none)
VX_STOPS = VX + 12  # the last step: when a static boundary stops the spin (s; inf: no)
VX_END_T = VX + 13  # ... its end (s): a release, the time limit or the step's end
VX_KEEPS = VX + 14  # ... the wall still pressing after a release (0, 1; -1 neither;
#                        -2: no release)
VX_W_END = VX + 15  # ... the spin at VX_END_T (rad/s)
VX_SAMPLE_T = VX + 16  # a sample handed out: time (s) and spin (rad/s)
VX_SAMPLE_W = VX + 17
VX_END = VX + 18

# --- the paper's fixed-step detection (method "rk4") --------------------------------
# The step, the locator's memory between flights (the Newton starts of the walls'
# nearest points, the departures in a row), the walls' intervals, and the global nearest
# points the Python side computed for the search under way (kernels: fixed_step.py).
RK = VX_END
RK_H = RK  # the fixed step (s)
RK_R = RK + 1  # the ball's radius (m)
RK_NWALLS = RK + 2  # walls of the curve (the first surfaces)
RK_LID = RK + 3  # the lid's index among the surfaces (-1: none)
RK_ESCAPE = RK + 4  # the escape level's index (-1: none)
RK_DEPARTURES = RK + 5  # impacts in a row found where the ball had just left the wall
RK_ANSWERS = RK + 6  # global nearest points answered for the search under way
RK_ASK = RK + 7  # the one asked for (E_FOOT): px, py (m), wall: 7..9
RK_FEET = RK + 10  # Newton start of each wall's nearest point (m): MAX_SURFACES slots
RK_FEET0 = RK_FEET + 16  # ... as the search under way found them
RK_LO = RK_FEET0 + 16  # each wall's interval (m)
RK_HI = RK_LO + 16
RK_ANSWER = RK_HI + 16  # answers: px, py, wall, s; RK_MAX_ANSWERS of them
RK_MAX_ANSWERS = 64
RK_END = RK_ANSWER + 4 * RK_MAX_ANSWERS

SIZE = RK_END

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


class KernelError(Exception):
    """A documented stop inside a kernel; ``args[0]`` is one of the ``E_*`` codes."""
