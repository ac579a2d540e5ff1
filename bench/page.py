"""performance.md: what is measured and on what, the key figures and charts, and what they
mean, each section short. Every number comes from the saved results; the full tables,
with how each is measured, are the appendix (performance-tables.md, bench/report.py)."""

from __future__ import annotations

import math

from bench import baseline as baseline_mod
from bench import contact as contact_mod
from bench import report, runio
from bench.markdown import table
from bench.report import figure, num

#: The appendix with the full tables, beside performance.md.
TABLES = "performance-tables.md"
#: Its sections (GitHub's anchors of the headings report.render_tables writes).
ANCHORS = {
    "targets": "#targets",
    "workprecision": "#1-work-against-precision",
    "failures": "#2-where-methods-fail",
    "ladder": "#3-the-model-ladder",
    "throughput": "#4-throughput-start-up-and-memory",
    "baseline": "#before-and-after",
    "profile": "#5-where-the-default-method-spends-its-time",
    "contact": "#6-contact-phases-against-the-hops-they-replace",
    "io": "#7-run-files-writing-reading-plotting",
}
DRAG = {"fowles": "on", "none": "off"}


def _tables(key: str, text: str = "full tables") -> str:
    return f"[{text}]({TABLES}{ANCHORS[key]})"


def _span(values: list[float], fmt: str, unit: str = "") -> str:
    """'a to b unit' over ``values`` (one value: 'a unit')."""
    lo, hi = min(values), max(values)
    text = format(lo, fmt) if lo == hi else f"{lo:{fmt}} to {hi:{fmt}}"
    return text + unit


def _met(ok: bool) -> str:
    return "met" if ok else "missed"


# ---------------------------------------------------------------------------- head


def intro(results: dict, command: str) -> str:
    s = results["sections"]
    m = results["machine"]
    elapsed = sum(v.get("elapsed", 0.0) for v in s.values())
    quick = (
        "\n**Quick mode**: every measurement is smaller (fewer impacts, settings and states) "
        "than in the documented run; the conclusions below are those of the full run.\n"
        if results["mode"] == "quick"
        else ""
    )
    return f"""# Performance

How fast the simulation runs and how accurate it is, against the methods a user could
use instead, on the four paper scenes. Every number, table and chart here is written by
`billiard bench` from its saved results; the full tables, with how each one is measured,
are in [{TABLES}]({TABLES}), the raw results in
[`figures/performance/results.json`](figures/performance/results.json).
{quick}
```bash
{command:<50} # these pages: {results["mode"]} mode, {results["date"]}, {elapsed:.0f} s
billiard bench --quick                             # the same, smaller, in runs/bench-quick/
billiard bench --only ladder                       # measure one section again, keep the rest
billiard bench --only throughput --baseline main   # this tree against commit main, side by side
billiard bench --render                            # rewrite pages and charts from the results
```

## What is measured, and on what

* **Scenes**: the paper's four (`parabola-5.4hz`, `wedge-6.6hz`, `hyperbola-5.8hz`,
  `hyperbola-4.5hz`), with air drag on (`air.drag = "fowles"`) and off, run from rest
  as `billiard run` starts them, or (section 1) from a state on their attractor.
* **Methods**: **event**, the default: exact parabolic flights without drag, an
  error-controlled Dormand-Prince 5(4) flight with drag, impacts located on the
  offset-curve gap with proven no-contact intervals. **rk4**, the paper's scheme:
  fixed-step Runge-Kutta with a Euclidean distance check after each step. **DOP853**,
  what a typical user writes: `scipy.integrate.solve_ivp(method="DOP853")` with one
  event function per wall and the same impact law; **DOP853 careful** adds a first step
  of 1e-6 s and a largest step of a twentieth of the drive period.
* **Engines**: the default method's kernels compiled with numba, and the same kernels
  run by CPython (`NUMBA_DISABLE_JIT=1`), so that a method run by scipy is compared
  with the default method interpreted too.
* **Times**: CPU time of the run loop (`time.process_time`, building the simulation
  excluded) for work, wall time of fresh processes for start-up and whole runs; each is
  the median of several runs, and every ratio is of two times from the same bench run.
* **Machine**: Python {m["python"]} on {m["platform"]}, {m["cpus"]} CPUs, shared with
  other work (load average {m["load"][0]:.1f} at the end), so a single time can be off by
  tens of per cent; code: {m.get("code", "unknown")}.
"""


def key_figures(results: dict) -> str:
    """The headline numbers, one row per question, each with its target's verdict."""
    s = results["sections"]
    rows: list[list[str]] = []
    if "workprecision" in s:
        rows += _speed_rows(s["workprecision"])
    if "failures" in s:
        rows += _failure_rows(s["failures"])
    if "throughput" in s and "compiled_startup" in s["throughput"]:
        rows += _throughput_rows(s["throughput"])
    if "contact" in s:
        rows += report.contact_targets(s["contact"])
    if "io" in s:
        rows += runio.target_rows(s["io"])
    verdicts = [row[2] for row in report.target_rows(results)]
    met = sum(v == "met" for v in verdicts)
    judged = sum(v != "-" for v in verdicts)
    return (
        "## Key figures\n\n"
        + table(["question", "measured", "target"], rows)
        + f"\n\nOf the {judged} targets the bench checks, {met} are met "
        f"({_tables('targets', 'the targets table')}).\n"
    )


def _speed_rows(wp: dict) -> list[list[str]]:
    rows = []
    like = [report.like_for_like(r) for r in report.speed_ratios(wp)]
    for method in ("rk4", "DOP853 careful", "DOP853"):
        mine = [r for r in like if r["method"] == method]
        both = [r["ratio"] for r in mine if "x" in report.speed_verdict(r)]
        only = sum(report.speed_verdict(r).startswith("only the default") for r in mine)
        how = report.compared_how(mine[0]) if mine else ""
        measured = f"{_span(both, '.1f', 'x')} less CPU" if both else "no comparable case"
        if only:
            measured += f"; in {only} of {len(mine)} cases only the default reaches 1e-9 s"
        short = [x for x in both if x < report.SPEED_TARGET]
        rows.append(
            [
                f"default method against {method} at equal accuracy (1e-9 s), {how}",
                measured,
                f">= {report.SPEED_TARGET:.0f}x: "
                + (f"met in {len(both) - len(short)} of {len(both)}" if both else "-"),
            ]
        )
    return rows


def _failure_summary(f: dict) -> list[dict]:
    """Per method and drag setting, pooled over the sets of states: for each setting,
    coarse to fine, the flights, the missed and spurious impacts and the deepest
    penetration."""
    groups: dict[tuple[str, str], dict[str, dict]] = {}
    for r in f["rows"]:
        by_setting = groups.setdefault((r["method"], r["drag"]), {})
        g = by_setting.setdefault(
            r["setting"],
            {"setting": r["setting"], "flights": 0, "failed": 0, "penetration": 0.0},
        )
        g["flights"] += r["flights"]
        g["failed"] += r["missed"] + r["spurious"]
        if math.isfinite(r["penetration"]):
            g["penetration"] = max(g["penetration"], r["penetration"])
    return [
        {"method": method, "drag": drag, "settings": list(settings.values())}
        for (method, drag), settings in groups.items()
    ]


def _settings(settings: list[dict]) -> str:
    """'step 0.003 s, 0.001 s' / 'rtol 1e-05, 1e-07': the kind of setting named once."""
    names = [x["setting"] for x in settings]
    kind = names[0].split(" ", 1)[0]
    if kind in ("step", "rtol") and all(n.startswith(kind + " ") for n in names):
        return kind + " " + ", ".join(n.split(" ", 1)[1] for n in names)
    return ", ".join(names)


def _failure_rows(f: dict) -> list[list[str]]:
    summary = _failure_summary(f)
    default = [g for g in summary if g["method"] == "event"]
    failed = sum(s["failed"] for g in default for s in g["settings"])
    flights = sum(s["flights"] for g in default for s in g["settings"])
    others = []
    for g in summary:
        if g["method"] == "event" or g["drag"] != "none":
            continue
        ends = (g["settings"][0], g["settings"][-1])
        others.append(
            f"{g['method']} "
            + " and ".join(
                f"{1000 * e['failed'] / e['flights']:.3g} at {e['setting']}" for e in ends
            )
        )
    return [
        [
            "impacts missed or found twice per 1,000 flights, from many real states",
            f"default method: {failed} in {flights:,} flights; " + "; ".join(others),
            "-",
        ]
    ]


def _throughput_rows(t: dict) -> list[list[str]]:
    fast = [r["compiled"]["cpu_per_impact"] * 1e6 for r in t["rates"]]
    slow = [r["interpreted"]["cpu_per_impact"] * 1e6 for r in t["rates"]]
    ratio = [r["ratio"] for r in t["rates"]]
    target = report_throughput_targets()
    rows = [
        [
            "CPU per impact, compiled (interpreted)",
            f"{_span(fast, '.2f')} us ({_span(slow, '.0f')} us): {_span(ratio, '.0f', 'x')} less",
            f">= {target['ratio']:.0f}x: met in {sum(x >= target['ratio'] for x in ratio)} of "
            f"{len(ratio)}",
        ]
    ]
    runs = [r["median"] for r in t["runs"] if r["how"] == "billiard run"]
    if runs:
        rows.append(
            [
                f"`billiard run` of {t['runs'][0]['impacts']:,} impacts, start-up included",
                f"{_span(runs, '.2f', ' s')} wall",
                f"<= {target['wall_25000']} s: met in "
                f"{sum(x <= target['wall_25000'] for x in runs)} of {len(runs)}",
            ]
        )
    for m in t["million"]:
        bound = f"<= {target['wall_million']:.0f} s: {_met(m['wall'] <= target['wall_million'])}"
        if not m["how"].startswith("in memory"):  # kept in memory, the rows are not bounded
            ok = m["peak_mb"] <= target["peak_million_mb"]
            bound += f"; <= {target['peak_million_mb']:.0f} MB: {_met(ok)}"
        rows.append(
            [
                f"{m['impacts']:,} wedge impacts, {m['how']}",
                f"{m['wall']:.2f} s, peak memory {m['peak_mb']:.0f} MB",
                bound,
            ]
        )
    s = t["compiled_startup"]
    rows.append(
        [
            "start-up to the first impact, kernels cached (empty cache: compiling)",
            f"{s['warm_median']:.2f} s ({s['cold']:.0f} s)",
            f"<= {target['warm_start']} s: {_met(s['warm_median'] <= target['warm_start'])}; "
            f"compiling <= {target['cold_compile']:.0f} s: "
            f"{_met(s['cold'] <= target['cold_compile'])}",
        ]
    )
    b = t.get("baseline")
    if b:
        first = next(r for r in b["startup"] if r["what"] == baseline_mod.FIRST)
        per = [r["ratio"] for r in b["rates"]]
        rows.append(
            [
                f"this code against {b['short']} (`--baseline {b['ref']}`), new / old",
                f"start-up {first['ratio']:.2f}x; time per impact {_span(per, '.2f', 'x')}",
                "-",
            ]
        )
    return rows


def report_throughput_targets() -> dict:
    from bench.throughput import TARGETS

    return TARGETS


# ---------------------------------------------------------------------------- sections


def section_speed(wp: dict, command: str) -> str:
    parts = [
        "## 1. Speed against accuracy\n",
        "All methods start from one state on each scene's attractor and make the same "
        "impacts, each at several settings (tolerance or step); the error is the distance of "
        "the n-th impact's time and point from a reference run's (the default method, "
        "exact without drag, at rtol 1e-13 with it), the work the CPU time of the run. "
        "In the chaotic scenes rounding-sized changes of the start grow too: the grey "
        f"line is that floor ({_tables('workprecision')}).\n",
    ]
    for scene in wp["scenes"]:
        name = scene["scene"]
        parts.append(
            figure(
                f"workprecision-{name}.png",
                f"work against precision, {name}",
                f"{command} --only workprecision",
            )
        )
    checkpoint = min(wp["scenes"][0]["rows"][0]["errors"]["t"], key=int)
    rows = []
    ratios = report.speed_ratios(wp)
    for key in dict.fromkeys((r["scene"], r["drag"]) for r in ratios):
        mine = {r["method"]: r for r in ratios if (r["scene"], r["drag"]) == key}
        first = next(iter(mine.values()))
        row = [key[0], DRAG[key[1]], num(first["event"]["cost"], 3)]
        for method in ("rk4", "DOP853", "DOP853 careful"):
            r = mine.get(method)
            verdict = report.speed_verdict(report.like_for_like(r)) if r else "-"
            row.append("never reaches it" if verdict.startswith("only the default") else verdict)
        rows.append(row)
    parts.append(
        f"How much more CPU each method needs than the default method to reach an "
        f"impact-time error of 1e-9 s after {checkpoint} impacts (rk4 against the compiled "
        "default method, the scipy peers against the same kernels interpreted):\n"
    )
    parts.append(
        table(
            [
                "scene",
                "drag",
                "default method, CPU s per 1,000 impacts",
                "rk4 (compiled)",
                "DOP853 (interpreted)",
                "DOP853 careful (interpreted)",
            ],
            rows,
        )
        + "\n"
    )
    like = [report.like_for_like(r) for r in ratios]
    cheaper = sum(
        1
        for r in like
        if r["event"]["kind"] != "not reached"
        and (r["other"]["kind"] == "not reached" or r["ratio"] > 1.0)
    )
    parts.append(
        "What it means:\n\n"
        f"* The default method needs less CPU than the other method at equal accuracy in "
        f"{cheaper} of {len(like)} comparisons, and it is the only one exact to rounding "
        "without drag.\n" + SPEED_CONCLUSIONS
    )
    return "\n".join(parts)


SPEED_CONCLUSIONS = """* In most cases rk4's coarsest step already reaches 1e-9 s, so its ratio is
  an upper bound: a coarser step would cost less, and section 2 shows what coarse steps
  cost in missed and spurious impacts.
* The typical DOP853 cannot reach 1e-9 s where the ball chatters or hops (it misses
  impacts, section 2); with a bounded step (careful) it gets there, at a higher cost.
* An error below the grey floor of a chaotic scene cannot be told from rounding: past a
  few hundred impacts every method only samples the attractor, and the statistics of
  section 3 are what a run can promise.
"""


def section_failures(f: dict, command: str) -> str:
    parts = [
        "## 2. Where methods fail\n",
        "One flight at a time from thousands of real states (the first impacts of each "
        "scene from rest: lying, chattering, lifting off; and balls dropped into the "
        "wedge's vertex), each method's next impact compared with a trusted one. *Missed*: "
        "the ball went through the wall; *spurious*: an impact that is not there; "
        f"penetration: how deep inside the wall the reported impact lies "
        f"({_tables('failures')}).\n",
        figure("failures.png", "where methods fail", f"{command} --only failures"),
    ]
    rows = []
    for g in _failure_summary(f):
        rows.append(
            [
                g["method"],
                DRAG[g["drag"]],
                _settings(g["settings"]),
                ", ".join(f"{1000 * s['failed'] / s['flights']:.3g}" for s in g["settings"]),
                num(g["settings"][-1]["penetration"]),
                f"{g['settings'][0]['flights']:,}",
            ]
        )
    parts.append("Missed plus spurious impacts per 1,000 flights, all sets of states together:\n")
    parts.append(
        table(
            [
                "method",
                "drag",
                "settings (coarse to fine)",
                "failures per 1,000 flights",
                "deepest penetration at the finest (m)",
                "flights per setting",
            ],
            rows,
        )
        + "\n"
    )
    parts.append(figure("low-velocity.png", "the low-velocity rule", f"{command} --only failures"))
    parts.append(FAILURE_CONCLUSIONS)
    return "\n".join(parts)


FAILURE_CONCLUSIONS = """What it means:

* **The default method** misses no impact and finds none twice, with or without drag;
  by an independent Euclidean clearance its impact points lie on the wall to ~1e-16 m.
* **DOP853** misses impacts that follow an impact closely: its first step already ends
  past the next impact, the gap has the same sign at both ends, and the ball flies
  through the wall. No tolerance cures it. **DOP853 careful** removes those misses and
  keeps the grazing ones, where the path dips into a wall and out within one step.
* **rk4** finds the impact it has just resolved a second time when the next hop is
  shorter than its step; below a step of about 1e-4 s that disappears.
* **The low-velocity rule** (`contact.elastic_below`) is part of the model, not a
  safeguard: with 0 every run from rest ends in an inelastic collapse, and in the
  chaotic scenes its value changes the share of elastic impacts and so the statistics.
"""


def section_ladder(lad: dict, command: str) -> str:
    return "\n".join(
        [
            "## 3. The model ladder\n",
            "Each physical term switched off in turn, each scene run from rest as a user "
            "runs it; compared is what the paper reports: the period-one orbit's height, "
            "or the statistics of the impact heights and flight times, within their "
            f"standard errors ({_tables('ladder')}).\n",
            figure("ladder.png", "model ladder", f"{command} --only ladder"),
            "Terms whose removal changes nothing (or little) of what is reported:\n",
            report.recommendations(lad) + "\n",
            LADDER_CONCLUSIONS,
        ]
    )


LADDER_CONCLUSIONS = """What it means:

* **Air drag** is the only term that changes nothing measurable in the chaotic scenes,
  and the only one that costs time (with it, flights are integrated instead of exact).
  In the periodic scenes it moves the orbit by under half a per cent, but the built-in
  drive amplitudes were calibrated with it: switching it off there means calibrating
  again.
* **Friction and spin** change what is reported (the parabola's orbit height doubles
  without them), and so does **the finite radius** in most scenes; none of them costs
  time.
* **The low-velocity rule** cannot be switched off: every scene collapses from rest.
"""


def section_throughput(t: dict, command: str) -> str:
    parts = [
        "## 4. Throughput, start-up and memory\n",
        "The compiled engine against the same kernels interpreted, on each scene from "
        "rest; whole runs in fresh processes, start-up included; a run of 10^6 impacts; "
        f"peak memory ({_tables('throughput')}).\n",
        figure("throughput.png", "throughput and memory", f"{command} --only throughput"),
    ]
    if "compiled_startup" in t:
        rows = [
            [
                r["scene"],
                DRAG[r["drag"]],
                f"{r['compiled']['cpu_per_impact'] * 1e6:.2f}",
                f"{r['interpreted']['cpu_per_impact'] * 1e6:.0f}",
                f"{r['ratio']:.0f}x",
            ]
            for r in t["rates"]
        ]
        parts.append("CPU per impact of the run loop, median:\n")
        parts.append(
            table(["scene", "drag", "compiled (us)", "interpreted (us)", "ratio"], rows) + "\n"
        )
        s = t["compiled_startup"]
        runs = [r["median"] for r in t["runs"] if r["how"] == "billiard run"]
        streamed = [m for m in t["million"] if not m["how"].startswith("in memory")]
        line = (
            f"A fresh process reaches its first impact in {s['warm_median']:.2f} s with the "
            f"kernels in numba's cache; with an empty cache it compiles them first "
            f"({s['cold']:.0f} s, once until the kernels' sources or numba change)."
        )
        if runs:
            line += (
                f" A `billiard run` of {t['runs'][0]['impacts']:,} impacts takes "
                f"{_span(runs, '.2f', ' s')}, start-up included"
            )
            line += (
                f"; {streamed[0]['impacts']:,} impacts streamed to `collisions.csv` take "
                f"{streamed[0]['wall']:.2f} s and {streamed[0]['peak_mb']:.0f} MB at the peak."
                if streamed
                else "."
            )
        parts.append(line + "\n")
    if t.get("baseline"):
        parts.append(section_baseline(t["baseline"]))
    parts.append(THROUGHPUT_CONCLUSIONS)
    return "\n".join(parts)


def section_baseline(b: dict) -> str:
    """Before and after: this code against the commit of ``--baseline``, measured
    alternately in the same bench run."""
    rows = [
        [
            f"{r['what']} ({r['scene']}), s",
            f"{r['new']['median']:.3f}",
            f"{r['old']['median']:.3f}",
            f"{r['ratio']:.2f}x",
        ]
        for r in b["startup"]
    ]
    rows += [
        [
            f"time per impact, {r['scene']} drag {DRAG[r['drag']]}, us",
            f"{r['new']['per_impact'] * 1e6:.2f}",
            f"{r['old']['per_impact'] * 1e6:.2f}",
            f"{r['ratio']:.2f}x",
        ]
        for r in b["rates"]
    ]
    return (
        "### Before and after\n\n"
        f"This code ({b['new']}) against commit {b['short']} ({b['subject']}; "
        f"`--baseline {b['ref']}`), both measured alternately in the same bench run, "
        "through the public API and the command line, medians "
        f"({_tables('baseline')}):\n\n"
        + table(["what", "new", "old", "new / old"], rows)
        + "\nA ratio above 1 means this code takes longer. What the kernels' start-up and "
        "time per impact owe to how numba is called is in "
        "[design.md](design.md#numba).\n"
    )


THROUGHPUT_CONCLUSIONS = """What it means:

* Compiled, an impact costs a few microseconds of arithmetic: libm's sine and cosine of
  the drive angle in the wedge, and in the curved scenes the square roots and divisions
  of the offset-curve foot's Newton iterations and, with drag, of the Dormand-Prince
  stages (section 5).
* A short run is mostly start-up: importing numpy and numba and loading the cached
  kernels take longer than 25,000 impacts. A long run kept in memory holds 18 float64
  per impact (144 MB at 10^6 impacts); streamed to disk its memory stays flat, the rows
  formatted on a thread of their own while the engine makes the next ones.
* Numba's reference counting is skipped, through its public API: every entry kernel
  borrows the arrays its caller owns (`numba.extending.intrinsic`: the same array with a
  null memory-info pointer, whose counts LLVM folds away), which halves a wedge impact
  (1.2 us with the counting in `run_chunk`, 0.5 us without); and a wall table reaches a
  kernel as its functions' addresses (a numba type of its own) instead of being unboxed
  function by function (4 us per call of a kernel from Python instead of 40 us). How, and
  why not otherwise: [design.md](design.md#numba).
"""


def section_profile(p: dict) -> str:
    shares = []
    for prof in p["profiles"]:
        loop = sum(r["share"] for r in prof["top"] if "run_chunk" in r["function"])
        shares.append(f"{prof['scene']} {100 * loop:.0f} %")
    return "\n".join(
        [
            "## 5. Where the time goes\n",
            "`cProfile` of one run of each scene after the kernels are loaded: the share "
            "of the profiled time inside the compiled impact loop (`run_chunk`) is "
            + ", ".join(shares)
            + f"; the rest is building the simulation and handing out the rows "
            f"({_tables('profile')}).\n",
            PROFILE_CONCLUSIONS,
        ]
    )


PROFILE_CONCLUSIONS = """What would make it shorter:

* **Inside the kernels** (timed alone, `python -m bench.compiled --no-startup`): in the
  wedge about 40 % of the time is libm's sine and cosine of the drive angle; in the
  parabola an impact takes about 39 Newton iterations for the offset-curve foot, each a
  square root, three divisions and two wall-function calls, and with drag about 66
  evaluations of the drag. Fewer foot iterations (a better warm start) is the largest
  gain left; carrying the drive's sine and cosine and the last slope from one kernel to
  the next would save a few per cent.
* **Start-up** is most of a short run: the imports of numpy and numba, then loading each
  cached kernel.
* **Building the simulation** (the boundary's checks and bounds, the resting position)
  takes milliseconds once per run: it matters only for runs of a few hundred impacts.
"""


def section_contact(c: dict, command: str) -> str:
    parts = [
        "## 6. Contact phases against the hops they replace\n",
        'Under `contact.model = "impacts"` (the paper\'s model) a ball lying on a wall is '
        'relaunched by every impact and hops; `"phases"` replaces the hops by rolling, '
        "sliding and held phases. Each case is run under both models for the same "
        "simulated time, alternately; the ratio is the CPU per simulated second of the "
        f"impacts over that of the phases ({_tables('contact')}).\n",
        figure("contact.png", "contact phases against impacts", f"{command} --only contact"),
    ]
    rows = [
        [
            r["case"],
            f"{100 * r['impacts']['resting_share']:.0f} %",
            report.ratio_text(r.get("ratio")),
            _case_verdict(r),
        ]
        for r in c["rows"]
    ]
    parts.append(
        table(["case", 'impacts that relaunch a resting ball ("impacts")', "ratio", "target"], rows)
        + "\n"
    )
    parts.append(report.contact_findings(c) + "\n")
    parts.append(CONTACT_CONCLUSIONS)
    return "\n".join(parts)


def _case_verdict(row: dict) -> str:
    """A case's ratio target and whether it is met."""
    target = contact_mod.case_target(row)
    if row.get("ratio") is None:
        return f">= {target:g}x: not compared"
    return f">= {target:g}x: {'met' if row['ratio'] >= target else 'not met'}"


CONTACT_CONCLUSIONS = """What it means: a contact phase pays where it replaces the hops of a
ball that lies still or is held on a wall: one phase instead of hundreds of located
flights per simulated second. On the compiled state machine a phase costs its
integration steps and a few microseconds besides, so in the paper's scenes, where the
ball is seldom in contact, the two models cost about the same, and the one with many
landings (hyperbola-5.8hz) is cheaper with phases. It pays least where the phase itself
must be integrated finely (rolling oscillations in the bowl: a few times cheaper, not
ten) or where one short phase is the whole run (the slide: a run's 0.15 ms set-up).
"""


def render(results: dict, command: str) -> str:
    """The whole of performance.md (the sweep section is added by bench/sweep.py)."""
    s = results["sections"]
    out = [intro(results, command), key_figures(results)]
    if "workprecision" in s:
        out.append(section_speed(s["workprecision"], command))
    if "failures" in s:
        out.append(section_failures(s["failures"], command))
    if "ladder" in s:
        out.append(section_ladder(s["ladder"], command))
    if "throughput" in s:
        out.append(section_throughput(s["throughput"], command))
    if "profile" in s:
        out.append(section_profile(s["profile"]))
    if "contact" in s:
        out.append(section_contact(s["contact"], command))
    if "io" in s:
        out.append(runio.page_section(s["io"], _tables("io")))
    return "\n".join(out).rstrip() + "\n"
