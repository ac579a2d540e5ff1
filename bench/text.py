"""The prose of performance-tables.md, the appendix of full tables: how each section is
measured, and the notes that explain its tables; the numbers and tables come from
bench/report.py. The prose of performance.md is in bench/page.py."""

INTRO = """# Performance: the full tables

The tables behind [performance.md](performance.md), which has the charts and what they
mean; each section here says how its tables are measured. Written by `{command}` ({mode}
mode, {date}, {elapsed:.0f} s of measurements) from the raw results in
[`figures/performance/results.json`](figures/performance/results.json).

Machine: {machine}. The machine is shared and noisy: a time is the median of several
runs, speed comparisons are ratios of times measured in the same run, and single times
can be off by tens of per cent. Work is CPU time of the run loop alone
(`time.process_time`, building the simulation excluded) in sections 1 and 2, wall time
in sections 3 and 4. The methods compared are described in
[performance.md](performance.md#what-is-measured-and-on-what).
"""

TARGETS = """The compiled-engine targets (CPU per impact, whole runs, 10^6 impacts, start-up,
compile) are measured in section 4, each interpreted figure in the same bench run; the
machine is shared, so a ratio near 30x can fall on either side of it from one run to
the next (the interpreted medians move by a third between runs).

The method speed-up targets compare the CPU time at which each method reaches an
impact-time error of 1e-9 s after the first checkpoint (section 1, "Cost at equal
accuracy"), like for like: rk4 runs on the compiled kernels as the default method does,
so that ratio is of two compiled methods; the solve_ivp peer is scipy's integrator,
interpreted, so it is compared with the default method's kernels interpreted too. Where
only the default method reaches that accuracy (the other one fails or stalls above it in
every setting of its ladder) there is no ratio; the verdict counts the cases where both
reach it.
"""

WORKPRECISION = """## 1. Work against precision

For each paper scene, all methods start from one state on the attractor: the full model
is run from rest for a transient, and the ball is taken a third of the way through the
next flight of at least 0.05 s (`bench/common.py: start_scene`). Each method and setting
then simulates the same number of impacts, drag on (`air.drag = "fowles"`) and off
(`"none"`). Errors are the differences of the n-th impact time and impact point from the
reference's n-th impact:

* drag off: the default method, whose flights are exact parabolas and whose impact
  times are roots located to a few ulps: exact to rounding;
* drag on: the default method at `run.rtol = 1e-13`. It is cross-checked against
  DOP853 careful at rtol 1e-13 (row "reference check"); DOP853 is not the reference
  because its event detection only sees sign changes at step ends (section 2).

A chaotic scene amplifies any error: the row "start moved by 1e-15 m" (grey lines in
the figures) is the error that rounding-sized changes of the start grow into, the floor
below which no method can be compared at that impact. On a stable periodic orbit
(parabola, hyperbola at 4.5 Hz) errors do not grow, and the error after n impacts is
the per-impact error. Errors of exactly 0 are drawn at 1e-16; a run that stopped early
(no impact found: the ball went through a wall) has an infinite error and no point in
the figure (see the note in the table).
"""

FAILURES = """## 2. Where methods fail

One flight at a time, from many real states: the post-impact states of the first
impacts of each scene run from rest (the ball lying at the bottom, chattering, lifting
off, then on the attractor), and, for the wedge, states of balls dropped 0.5-5 mm into
its vertex and of their first 15 impacts ("wedge vertex drops"). From each state every
method flies to its next impact, which is compared with the truth (`bench/failures.py`):

* drag off, the truth is the default method, and it is itself checked against an
  independent geometry: the Euclidean clearance `Boundary.clearance` (nearest point
  from the curve's polynomial roots) of the exact parabolic arc, sampled at 24 points
  inside the flight, must stay positive, and must be zero (to 1e-9 m) at the impact;
* drag on, the truth is the default method at rtol 1e-13, for the default method's
  tolerance ladder.

A *missed* impact: the method's next impact comes more than 1e-6 s after the truth's
(the ball went through the wall, or the run stopped); *spurious*: more than 1e-6 s
before it. *Penetration*: how far the ball centre is inside the wall, by the Euclidean
clearance, at the impact the method reports, or, for a missed impact, at the deepest
sampled point of the true arc past the wall. *Energy error*: relative error of the
mechanical energy just after a correctly found impact.
"""

FAILURES_AFTER = """What the failures are:

* **DOP853 (typical)** misses impacts that follow an impact closely. A flight starts where
  the previous impact was found, at G = 0 to rounding (the engine reports the first
  representable time with G <= 0). When the next impact is near (a hop after a slow or
  chattering impact, the ball lying on a wall), `solve_ivp`'s first step already ends
  past it: G has the same sign at both ends of the step, no event fires, and the ball
  flies through the wall (penetrations of centimetres) until the run ends with "no
  impact within 10 s". The tolerance does not cure it: the drag-free or nearly
  drag-free flight is a low-degree polynomial, so DOP853 takes large steps at any
  tolerance. This is also why it fails in section 1 on every scene where the ball
  chatters.
* **DOP853 careful** (`first_step = 1e-6 s`, `max_step = T/20`) removes those misses.
  What is left are grazing excursions: seen from the moving boundary, the ball's path
  can dip into a wall and come back out within one step (T/20 = 7.6 ms at 6.6 Hz), and
  a sign test at the ends of the step cannot see it (wedge, 0.5 % of the flights).
* **rk4**: the spurious impacts are the impact just resolved, found again. When the next
  hop is shorter than a step, the first step ends inside the wall, and the Baraff
  search from the start of the step, where |gap| <= 1e-12 m already holds, returns a
  flight of length ~1e-15 s, and the impact law is applied a second time to a ball
  that is already leaving. They disappear below a step of about 1e-4 s. rk4 misses no
  impact in these sets: its signed distance catches a ball that ends a step inside a
  wall; only an excursion that enters and leaves a wall within one step could escape it.
* **The default method** has no missed and no spurious impact in any set, drag on or
  off; by the independent Euclidean clearance its impact points lie on the wall to
  ~1e-16 m, and nowhere along the sampled arcs does the ball enter a wall. With drag
  on its tolerance only changes the energy after an impact, by up to ~1e-7 relative
  at rtol 1e-6 and ~3e-9 at the default 1e-10.
* **Energy** after a correctly found impact agrees with the truth to 1e-14 (median) for
  every method; rk4's worst cases are ~1e-8, from the 1e-12 m gap tolerance of its
  impact search.

The low-velocity rule (`contact.elastic_below`):

* With 0, a ball lying at the bottom cannot take off: every impact has zero relative
  normal speed, restitution returns zero, and every run from rest ends at once in
  inelastic collapse (1,000 impacts with zero time of flight). Started in flight, the
  parabola and the hyperbola at 4.5 Hz never need the rule (their orbits have no slow
  impacts), while the wedge and the hyperbola at 5.8 Hz fall to rest and collapse
  within a few seconds of simulated time (section 3).
* Small thresholds (1e-4 m/s) keep the runs alive but the ball chatters at the bottom in
  hops of 2 v/g ~ 20 us: up to ~1e5 impacts per simulated second, and 5,000 impacts
  cover only a fraction of a second. From about 3e-3 m/s on, the impact rate of the
  periodic scenes no longer depends on the threshold; in the chaotic scenes it keeps
  falling as the threshold grows, because a larger share of impacts is made elastic
  (wedge: 80 % at 1e-3, 61 % at the default 1e-2, 24 % at 0.1): the rule is part of the
  model there, not a numerical safeguard, and its value shapes the statistics.
* The wedge's vertex: balls dropped into the vertex make series of short hops (median
  flight under 1 ms) between the two walls. The default method handles them (no
  failure), rk4 adds its spurious re-impacts there as elsewhere (15 % of the flights at
  a 1 ms step, none from 1e-4 s down), the typical DOP853 misses about three quarters
  of them, and the careful DOP853 one in 1,344 (a grazing excursion of ~2 um).
"""

LADDER = """## 3. The model ladder

Each physical term is switched off in turn in the built-in scene, run as a user runs it
(from rest, default method); what changes is what the paper reports: the period-one
orbit's height (parabola; the orbit is detected as in `billiard calibrate`) and
return-map statistics over the impacts after the first 10 %: mean and standard deviation
of the impact height q2, the fraction of return-map points above the diagonal
(q2 of the next impact higher), the mean time of flight. The +- values are standard
errors from 10 batch means. "near-point ball" keeps the real ball's drag
coefficients and mass; its q2 is the centre height, about r = 1.55 mm lower at the same
contact point. The verdict "no change" means: a locked orbit within 0.5 mm, or every
statistic within twice the combined standard error or within 1 %.
"""

THROUGHPUT = """## 4. Throughput, start-up and memory

The compiled engine (numba) against the interpreted one (the same kernels run by
CPython), on the built-in scenes from rest, default method; then whole runs with their
start-up, a run of 10^6 impacts, start-up and compile time, and peak memory.
"""

PROFILE = """## 5. Where the default method spends its time

`cProfile` of one run of each built-in scene (full model, from rest), after a short run
in the same process has loaded the compiled kernels. The impact loop is one call into
compiled code (`billiard.kernels.loop.run_chunk`, a few calls per run as the chunks
grow): what the profiler sees apart from it is the Python around the kernels, building
the simulation and handing out the rows. Shares are of the profiled total.
"""

CONTACT = """## 6. Contact phases against the hops they replace

`contact.model = "impacts"` (the paper's model) has no contact: a ball lying on a wall is
relaunched at `contact.elastic_below` (0.01 m/s) by every impact and hops, about 500
times per simulated second on a flat bottom. `contact.model = "phases"` replaces the
hops by rolling and sliding phases, integrated as one smooth motion
(`billiard/models/contact.py`). This section measures what a simulated second costs under each
model (`bench/contact.py`): every case is built twice, differing only in
`contact.model`, started from the same state and run for the same simulated time
(`run.duration`); the two models are run alternately and the CPU time of the run loop
(`time.process_time`, building the simulation and deriving a curve excluded) is the
median of the repeats. The ratio is the impact model's CPU per simulated second over
the phase model's, from the same run of the benchmark; the ratio of each repeat's pair of
runs (one right after the other) shows how far the load moved it.

The cases: the four paper scenes as built in (drag as each scene says, the ball from rest
at the bottom, as `billiard run` starts it), and closed-form cases of the validation tests
(`tests/validation/test_contact.py`) with the paper's ball, restitution and friction: a
ball at rest at the bottom of the static parabola and in the static wedge's vertex,
small rolling oscillations in the static parabola, a drop onto a static flat floor
(`boundary.curve = "0.001"`), a slide down a straight wall too steep to roll on
(slope 3 > 7/2 mu_s), stopped before it reaches the vertex, and a ball resting on a
table shaken vertically with Gamma = A w^2 / g = 0.9.

"Chatter dominates" where most of the impact model's impacts relaunch a resting ball
(`Result.counts["resting"]`, the "resting relaunches" column). "Contact phases" counts
the finished phases plus the one still open at the end. Times spent flying, rolling,
sliding and held by two walls (the wedge's vertex) are the engine's
(`Result.mode_times`); the impact model only flies. A ball at rest relative to a shaken
boundary for a whole drive period skips the periods that repeat it, so resting costs
one integrated period whatever the duration. A run under "phases" that ends early
because the ball rests on the boundary for good (`Status.AT_REST`, only without a time
limit) has simulated its whole duration: its CPU per simulated second uses the
requested duration and the rest of it counts as time in contact (the "ended" column
says "at rest"). A run that
stops for another reason (an inelastic collapse, the impact cap) is measured over the
time it reached and not compared.

The targets: the ratio >= 1x on each paper scene (phases never dearer than the hops they
replace) and >= 10x on each closed-form case (where rest, chatter or one long phase
dominates); a case not compared misses its target. One contact phase, all in: the CPU of
the phases run less what its impacts cost at the impact model's CPU per impact in the
same case, over its contact phases, on the cases with at least 100 phases (the paper's
chaotic scenes; a closed-form case makes one phase, which measures its integration, not
the cost of a phase); target <= 15 us. The first-use compile: `billiard run SCENE
--collisions 100 --no-plot` in fresh processes with an empty numba cache
(`NUMBA_CACHE_DIR` in a new folder): the wedge, then the parabola (air drag, one wall),
then the wedge under phases, then the wedge again; the compile is the first run's wall
time less the last's, the waits are the runs that printed a compile notice; target
<= 20 s in one wait.
"""

CONTACT_AFTER = """Why the ratios are what they are. Both models make their impacts on the
compiled loop (`run_chunk`). Under "phases" the whole trajectory runs on the compiled
state machine (`billiard/kernels/machine.py`; `docs/compiled-engine.md`, "Contact phases
and holds: the state machine"): the loop hands an impact that settles to the machine's
landing, and each rolling or sliding phase and each hold is integrated in the same call,
its end and the transition after it included; Python sees the run only when a buffer is
full, every 1,000 steps of a long phase, and at the end. A phase costs its integration
steps and a few microseconds around them (the phase cost above: the wedge's phases about
10 us each, the longer ones of hyperbola-5.8hz about 22 us), where the engine's Python
bookkeeping cost about 140 us a phase before.

* **A ball at rest** (bowl at rest, the floor after the drop, the vertex, the shaken
  table at rest between its chatter): the impact model relaunches it hundreds of times
  per simulated second, each hop a located flight. Under "phases" the ball lies in one
  phase or hold; on a static boundary the phase's step grows fivefold per step when the
  error estimate is zero, and on a shaken one whole drive periods at rest are skipped,
  so a run costs a handful of steps and some 0.15 ms of set-up: the ratio grows with the
  simulated time and is not a constant.
* **Rolling oscillations in the bowl, the slide down the steep wall**: the phase is
  integrated with Dormand-Prince 5(4) at the scene's `run.rtol` (1e-10, the flights'
  tolerance), about 500 steps per simulated second in the bowl, each with six
  right-hand-side calls and the end conditions: a few times cheaper than the compiled
  hops it replaces, not ten times; the phase's cost is its step count. The slide lasts
  1.3 s and is one phase of a few steps: its run is mostly the 0.15 ms of a run's
  set-up in Python (engine state into the state vector and back), against 0.46 ms of
  hops.
* **The paper scenes**: the ball is in contact a few per cent of the time or less. Where
  it hardly lands (parabola-5.4hz, hyperbola-4.5hz: a handful of phases in 600 s) the two
  models make the same flights on the same loop, and "phases" pays only its landing test
  after every impact (the rebound's speed against the landing speed, the chatter's
  tail): within 3 % of 1x, inside the noise of these times. In the wedge and
  hyperbola-5.8hz a phase replaces the dozen or more hops of 1-4 us each it would take
  the impact model, so "phases" is now the cheaper of the two. In the chaotic scenes the
  two models follow different trajectories after the first contact, so their ratio
  compares two samples of the same attractor and moves by tens of per cent from one
  measurement to the next.

The target of 10x therefore holds where a contact phase replaces hops of a ball that
lies still or is held on a wall, and not where the phase itself must be integrated
finely (rolling oscillations) or is so short that a run's set-up dominates (the slide);
a looser error tolerance for contact phases than for flights would cut the step counts,
and is not measured here. The first-use compile grew from 20 s to 40 s with the machine
(docs/design.md, "One compile"): the target of 20 s is missed.
"""
