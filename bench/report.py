"""performance.md from the saved results: tables, figure links, verdicts on the targets."""

from __future__ import annotations

import math

from bench import contact as contact_mod
from bench import ladder as ladder_mod
from bench import report_throughput, runio
from bench.markdown import table
from bench.workprecision import cost_at

FIG = "figures/performance"
TARGET_ERROR = 1e-9
SPEED_TARGET = 30.0


def num(x, digits: int = 2) -> str:
    """A float for a table: 0, inf and nan spelled out, else d significant digits."""
    if x is None:
        return "-"
    if isinstance(x, float) and math.isnan(x):
        return "-"
    if x == 0:
        return "0"
    if math.isinf(x):
        return "inf"
    return f"{x:.{digits}g}" if 1e-3 <= abs(x) < 1e5 else f"{x:.{digits - 1}e}"


def figure(name: str, alt: str, command: str) -> str:
    return f"![{alt}]({FIG}/{name})\n\n*Reproduce: `{command}`*\n"


# ---------------------------------------------------------------------------- targets


def speed_ratios(wp: dict) -> list[dict]:
    """Cost of each method at an impact-time error of 1e-9 s after the first checkpoint,
    and its ratio to the default method's."""
    out = []
    for scene in wp["scenes"]:
        k = min(scene["rows"][0]["errors"]["t"], key=int)
        for drag in ("fowles", "none"):
            rows = scene["rows"]
            event = cost_at(rows, "event", drag, int(k), TARGET_ERROR)
            # the default method interpreted, for the methods that run interpreted (the
            # solve_ivp peer; rk4 before it ran on the kernels), so that the ratio compares
            # methods, not interpreters (absent from results of an earlier bench)
            slow = cost_at(rows, "event", drag, int(k), TARGET_ERROR, "cpu_per_1000_interpreted")
            compiled = {r["method"] for r in rows if r.get("compiled")}
            for method in ("rk4", "DOP853", "DOP853 careful"):
                other = cost_at(rows, method, drag, int(k), TARGET_ERROR)
                out.append(
                    {
                        "scene": scene["scene"],
                        "drag": drag,
                        "k": k,
                        "method": method,
                        "compiled": method in compiled,
                        "event": event,
                        "other": other,
                        "ratio": other["cost"] / event["cost"],
                        "event_interpreted": slow,
                        "ratio_interpreted": other["cost"] / slow["cost"],
                    }
                )
    return out


def target_rows(results: dict) -> list[list[str]]:
    """The targets table's rows: target, what was measured, verdict ("-": none)."""
    s = results["sections"]
    rows = []
    if "throughput" in s:
        t = s["throughput"]
        rows += report_throughput.target_rows(t) or old_throughput_targets(t)
    if "contact" in s:
        rows += contact_targets(s["contact"])
    if "io" in s:
        rows += runio.target_rows(s["io"])
    if "workprecision" in s:
        ratios = speed_ratios(s["workprecision"])
        for method in dict.fromkeys(r["method"] for r in ratios):
            rows.append(speed_target(method, [r for r in ratios if r["method"] == method]))
    return rows


def targets(results: dict) -> str:
    return table(["target", "measured", "verdict"], target_rows(results))


def old_throughput_targets(t: dict) -> list[list[str]]:
    """The targets of an earlier, interpreted-only bench."""
    rows = []
    for r in (r for r in t["rates"] if r["drag"] == "fowles"):
        ok = r["per_25000"] < 2.0
        verdict = "met" if ok else f"missed, {r['per_25000'] / 2.0:.1f}x too slow"
        rows.append(
            [
                f"25,000 impacts < 2 s wall, {r['scene']}",
                f"{r['per_25000']:.2f} s ({r['rate']:,.0f} impacts/s)",
                verdict,
            ]
        )
    label = "billiard run parabola-5.4hz --collisions 1 --no-plot"
    med = t["startup"][label]["median"]
    rows.append(
        ["start-up < 1 s", f"{med:.2f} s", "met" if med < 1.0 else f"missed by {med - 1:.2f} s"]
    )
    big = max(t["memory"], key=lambda m: m["impacts"])
    rows.append(
        [
            f"peak memory < 200 MB ({big['impacts']:,} impacts)",
            f"{big['peak_mb']:.0f} MB",
            "met" if big["peak_mb"] < 200 else "missed",
        ]
    )
    return rows


def speed_verdict(r: dict) -> str:
    """One scene and drag setting: the ratio, or why there is none."""
    event_ok = r["event"]["kind"] != "not reached"
    other_ok = r["other"]["kind"] != "not reached"
    if not other_ok:
        return "only the default reaches 1e-9 s" if event_ok else "neither reaches 1e-9 s"
    if not event_ok:
        return "only the other reaches 1e-9 s"
    return f"{r['ratio']:.1f}x"


def like_for_like(r: dict) -> dict:
    """The ratio of like to like: against the compiled default method for a method that
    ran compiled (rk4), else against the default method interpreted too, when that was
    measured (an earlier bench's results have no interpreted costs: nan)."""
    slow = r["event_interpreted"]
    if r.get("compiled") or math.isnan(slow["cost"]):
        return r
    return {**r, "event": slow, "ratio": r["ratio_interpreted"]}


def compared_how(r: dict) -> str:
    return "both compiled" if r.get("compiled") else "both interpreted"


def speed_target(method: str, ratios: list[dict]) -> list[str]:
    """A targets-table row: the ratio per scene and drag setting, methods compared like
    for like (the default method interpreted as the others are, when measured), and the
    verdict."""
    ratios = [like_for_like(r) for r in ratios]
    cases = [
        f"{r['scene']} {'on' if r['drag'] == 'fowles' else 'off'}: {speed_verdict(r)}"
        for r in ratios
    ]
    both = [r["ratio"] for r in ratios if "x" in speed_verdict(r)]
    short = [x for x in both if x < SPEED_TARGET]
    if not both:
        verdict = "no case where both reach 1e-9 s"
    elif not short:
        verdict = "met"
    else:
        verdict = (
            f"missed in {len(short)} of {len(both)} comparable cases: "
            f"{min(short):.1f}x to {max(short):.1f}x, up to {SPEED_TARGET / min(short):.0f}x"
            " short"
        )
    how = compared_how(ratios[0]) if ratios else "both interpreted"
    return [
        f">= 30x faster than {method} at equal accuracy (1e-9 s), {how}",
        "; ".join(cases),
        verdict,
    ]


# ---------------------------------------------------------------------------- sections


def section_workprecision(wp: dict, command: str) -> str:
    parts = []
    checkpoints = list(wp["scenes"][0]["rows"][0]["errors"]["t"])
    for scene in wp["scenes"]:
        name = scene["scene"]
        parts.append(f"### {name}\n")
        parts.append(
            figure(
                f"workprecision-{name}.png",
                f"work-precision {name}",
                f"{command} --only workprecision",
            )
        )
        header = ["drag", "method", "setting", "CPU s / 1000 impacts"]
        header += [f"time err. @{k} (s)" for k in checkpoints]
        header += [f"point err. @{k} (m)" for k in checkpoints] + ["note"]
        rows = []
        for r in scene["rows"]:
            note = r["stop"][:50] if r["stop"] else ""
            if r["method"] == "event" and r["drag"] == "none":
                note = "the reference"
            rows.append(
                [
                    "on" if r["drag"] == "fowles" else "off",
                    r["method"],
                    r["setting"],
                    num(r["cpu_per_1000"], 3),
                ]
                + [num(r["errors"]["t"][k]) for k in checkpoints]
                + [num(r["errors"]["pos"][k]) for k in checkpoints]
                + [note]
            )
        floor = scene["floor"]
        for drag in ("fowles", "none"):
            rows.append(
                ["on" if drag == "fowles" else "off", "start moved by 1e-15 m", "", ""]
                + [num(floor[drag]["t"][k]) for k in checkpoints]
                + [num(floor[drag]["pos"][k]) for k in checkpoints]
                + ["chaos floor"]
            )
        check = scene["reference"]["fowles"].get("dop853_check")
        if check:
            rows.append(
                ["on", "DOP853 careful rtol 1e-13", "vs reference", ""]
                + [num(check["t"][k]) for k in checkpoints]
                + [num(check["pos"][k]) for k in checkpoints]
                + ["reference check"]
            )
        parts.append(table(header, rows) + "\n")
    ratio_rows = []
    for r in speed_ratios(wp):
        slow = r["event_interpreted"]
        ratio_rows.append(
            [
                r["scene"],
                "on" if r["drag"] == "fowles" else "off",
                r["method"],
                f"{num(r['event']['cost'], 3)} ({r['event']['kind']})",
                f"{num(slow['cost'], 3)}",
                f"{num(r['other']['cost'], 3)} ({r['other']['kind']})",
                speed_verdict(r),
                f"{speed_verdict(like_for_like(r))} ({compared_how(r)})",
            ]
        )
    parts.append("### Cost at equal accuracy\n")
    parts.append(
        f"CPU s per 1,000 impacts at which each method reaches an impact-time error of "
        f"1e-9 s after {checkpoints[0]} impacts (log-log interpolation between the two "
        'settings that bracket it; "cheapest setting" when every setting is already '
        'better; "not reached" when none is, with the cost of its most accurate '
        "setting). The default method and rk4 run compiled; the solve_ivp peer runs "
        "interpreted (scipy's integrator, the engine's impact law), so the last column "
        "compares methods alone: rk4 against the compiled default method, the peer "
        "against the default method's kernels interpreted too (`NUMBA_DISABLE_JIT=1`, "
        "the same results to the bit), at the same accuracy.\n"
    )
    header = [
        "scene",
        "drag",
        "method",
        "default method, compiled",
        "default method, interpreted",
        "method",
        "ratio to compiled",
        "ratio, like for like",
    ]
    parts.append(table(header, ratio_rows) + "\n")
    return "\n".join(parts)


def section_failures(f: dict, command: str) -> str:
    parts = [figure("failures.png", "failures", f"{command} --only failures")]
    rows = []
    for r in f["rows"]:
        rows.append(
            [
                r["set"],
                "on" if r["drag"] == "fowles" else "off",
                r["method"],
                r["setting"],
                r["flights"],
                r["missed"],
                r["spurious"],
                num(r["penetration"]),
                num(r["median_dtau"]),
                num(r["median_energy"]),
                num(r["max_energy"]),
            ]
        )
    parts.append(
        table(
            [
                "states",
                "drag",
                "method",
                "setting",
                "flights",
                "missed",
                "spurious",
                "deepest penetration (m)",
                "median abs(dt) (s)",
                "median rel. energy error",
                "max rel. energy error",
            ],
            rows,
        )
        + "\n"
    )
    parts.append("### The low-velocity rule\n")
    parts.append(figure("low-velocity.png", "low-velocity rule", f"{command} --only failures"))
    rows = []
    for r in f["thresholds"]:
        ended = "collapse" if r["collapse"] else (r["stop"][:40] or "ran to the end")
        rows.append(
            [
                r["scene"],
                r["start"],
                num(r["elastic_below"]),
                r["impacts"],
                num(r["sim_time"], 3),
                num(r["rate"], 3),
                f"{100 * r['elastic']:.0f} %" if math.isfinite(r["elastic"]) else "-",
                num(r["mean_q2"], 3),
                ended,
            ]
        )
    parts.append(
        table(
            [
                "scene",
                "start",
                "elastic_below (m/s)",
                "impacts",
                "simulated time (s)",
                "impacts per simulated s",
                "elastic impacts",
                "mean q2 (m)",
                "end",
            ],
            rows,
        )
        + "\n"
    )
    return "\n".join(parts)


def _pm(row: dict, key: str, se: str, scale: float = 1.0, digits: int = 4) -> str:
    if key not in row:
        return "-"
    err = row.get(se, math.nan)
    text = f"{scale * row[key]:.{digits}f}"
    return text + (f" +- {scale * err:.{digits}f}" if math.isfinite(err) else "")


def section_ladder(lad: dict, command: str) -> str:
    parts = [figure("ladder.png", "model ladder", f"{command} --only ladder")]
    rows = lad["rows"]
    for name in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == name]
        full = mine[0]
        body = []
        for r in mine:
            orbit = (
                f"{1e3 * r['orbit_height']:.2f} mm" if r.get("orbit_height") is not None else "none"
            )
            verdict = "" if r is full else ladder_mod.verdict(r, full)
            if r.get("collapsed"):
                orbit = "collapse"
            if r["variant"].endswith("started in flight"):
                verdict = f"{verdict} (vs full from rest)" if verdict else ""
            body.append(
                [
                    r["variant"],
                    r["impacts"],
                    orbit,
                    _pm(r, "mean_q2", "se_q2", 1e3, 2),
                    f"{1e3 * r['std_q2']:.2f}" if "std_q2" in r else "-",
                    _pm(r, "above", "se_above", 1.0, 3),
                    _pm(r, "mean_tof", "se_tof", 1e3, 2),
                    f"{100 * r['elastic']:.0f} %" if "elastic" in r else "-",
                    f"{r['wall_time']:.2f} s ({r['wall_time'] / full['wall_time']:.2f}x)",
                    verdict or r["stop"][:40],
                ]
            )
        parts.append(f"### {name}\n")
        parts.append(
            table(
                [
                    "model",
                    "impacts",
                    "period-one orbit q2",
                    "mean q2 (mm)",
                    "std q2 (mm)",
                    "fraction above diagonal",
                    "mean time of flight (ms)",
                    "elastic impacts",
                    "wall time (vs full)",
                    "verdict",
                ],
                body,
            )
            + "\n"
        )
    return "\n".join(parts)


def recommendations(lad: dict) -> str:
    """Per scene, the terms whose removal changes nothing (or little) of what is reported."""
    rows = lad["rows"]
    lines = []
    for name in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == name]
        full = mine[0]
        terms = [r for r in mine[1:] if not r["variant"].endswith("in flight")]
        hits = [r for r in terms if ladder_mod.verdict(r, full).startswith(("no change", "small"))]
        items = "; ".join(
            f"{r['variant']}: {ladder_mod.verdict(r, full)}, wall time "
            f"{r['wall_time'] / full['wall_time']:.2f}x of the full model"
            for r in hits
        )
        lines.append(f"- **{name}**: " + (items or "every term changes what is reported") + ".")
    return "\n".join(lines)


def _rates_table(t: dict) -> str:
    """The table of an earlier bench: wall and CPU of the in-memory runs."""
    rows = [
        [
            r["scene"],
            "on" if r["drag"] == "fowles" else "off",
            r["impacts"],
            ", ".join(f"{x:.2f}" for x in r["times"]),
            f"{r['median']:.2f}",
            f"{r['cpu']:.2f}" if "cpu" in r else "-",
            f"{r['rate']:,.0f}",
            f"{r['per_25000']:.2f}",
        ]
        for r in t["rates"]
    ]
    header = [
        "scene",
        "drag",
        "impacts per run",
        "wall times (s)",
        "median wall (s)",
        "median CPU (s)",
        "impacts / s of wall time",
        "s per 25,000",
    ]
    return table(header, rows)


def section_throughput(t: dict, command: str) -> str:
    if "compiled_startup" in t:
        parts = [report_throughput.section_throughput(t, command)]
    else:  # results of an earlier bench, interpreted only
        parts = [figure("throughput.png", "throughput and memory", f"{command} --only throughput")]
        parts.append(_rates_table(t) + "\n")
    ratios = []
    for on in (r for r in t["rates"] if r["drag"] == "fowles"):
        off = next(
            (r for r in t["rates"] if r["scene"] == on["scene"] and r["drag"] == "none"), None
        )
        if off:
            ratios.append(f"{on['scene']} {on['median'] / off['median']:.1f}x")
    if ratios:
        parts.append("Drag on costs, relative to drag off (same run): " + ", ".join(ratios) + ".\n")
    parts.append("Start-up, wall time of a fresh process (median):\n")
    rows = [
        [f"`{label}`", ", ".join(f"{x:.2f}" for x in v["times"]), f"{v['median']:.2f}"]
        for label, v in t["startup"].items()
        if label != "imports"
    ]
    parts.append(table(["command", "runs (s)", "median (s)"], rows) + "\n")
    parts.append(
        "Slowest top-level imports of that `billiard run` (`python -X importtime`, cumulative):\n"
    )
    rows = [
        [f"`{r['module']}`", f"{r['cumulative_us'] / 1e3:.0f}"] for r in t["startup"]["imports"]
    ]
    parts.append(table(["module", "ms"], rows) + "\n")
    parts.append(
        "Peak memory of a fresh process running `wedge-6.6hz` with the rows "
        "streamed to `collisions.csv`:\n"
    )
    rows = [
        [
            f"{m['impacts']:,}" if m["impacts"] else "0 (imports only)",
            f"{m['peak_mb']:.1f}",
            f"{m['maxrss_mb']:.1f}",
            f"{m['wall']:.1f}",
            f"{m['csv_mb']:.0f}",
        ]
        for m in t["memory"]
    ]
    parts.append(
        table(
            ["impacts", "peak RSS, VmHWM (MB)", "ru_maxrss (MB)", "wall time (s)", "CSV size (MB)"],
            rows,
        )
        + "\n"
    )
    big = max(t["memory"], key=lambda m: m["impacts"])
    mem = next(
        (r for r in t["rates"] if r["scene"] == "wedge-6.6hz" and r["drag"] == "fowles"), None
    )
    if big["impacts"] and mem:
        small = min((m for m in t["memory"] if m["impacts"]), key=lambda m: m["impacts"])
        parts.append(
            f"Peak memory stays flat: the rows stream to disk; from {small['impacts']:,} to "
            f"{big['impacts']:,} impacts the peak grows by "
            f"{big['peak_mb'] - small['peak_mb']:.0f} MB, to "
            f"{big['peak_mb'] - t['memory'][0]['peak_mb']:.0f} MB above the bare imports. "
            f"Streaming costs time, though: the streamed run "
            f"makes {big['impacts'] / big['wall']:,.0f} impacts/s against "
            f"{mem['rate']:,.0f} in memory (each row's 18 values are formatted with `repr` "
            "straight from the rows). `ru_maxrss` (the brief's measure) is not usable here: on "
            "Linux it keeps the peak of the address space the process had before `exec`, "
            "i.e. of the benchmark process that forked it; `VmHWM` from `/proc/self/status` "
            "is the peak of the process's own address space.\n"
        )
    if t.get("baseline"):
        parts.append(report_throughput.section_baseline(t["baseline"]))
    return "\n".join(parts)


def loads(results: dict) -> str:
    """Load average (1 min) at the end of each section: how busy the machine was."""
    items = [f"{name} {v['load'][0]:.1f}" for name, v in results["sections"].items() if "load" in v]
    return "Load average at the end of each section: " + ", ".join(items) + ".\n" if items else ""


def section_profile(p: dict) -> str:
    parts = []
    for prof in p["profiles"]:
        parts.append(
            f"**{prof['scene']}**, {prof['impacts']:,} impacts, "
            f"{prof['total']:.2f} s under the profiler:\n"
        )
        rows = [
            [
                f"`{r['function']}`",
                f"{r['calls']:,}",
                f"{r['own']:.2f}",
                f"{r['cumulative']:.2f}",
                f"{100 * r['share']:.0f} %",
            ]
            for r in prof["top"]
        ]
        parts.append(
            table(["function", "calls", "own s", "cumulative s", "own share"], rows) + "\n"
        )
    return "\n".join(parts)


def render_tables(results: dict, command: str) -> str:
    """The whole of performance-tables.md, the appendix of full tables (the prose lives
    in bench/text.py; performance.md is bench/page.py's)."""
    from bench import text

    s = results["sections"]
    out = [
        text.INTRO.format(
            command=command,
            mode=results["mode"],
            date=results["date"],
            machine=_machine(results["machine"]),
            elapsed=sum(v.get("elapsed", 0.0) for v in s.values()),
        )
    ]
    if results["mode"] == "quick":
        out.append(
            "**Quick mode**: every measurement is smaller (fewer impacts, settings and "
            "states); the prose between the tables describes the full run's findings.\n"
        )
    out.append(loads(results))
    out.append("## Targets\n\n" + targets(results) + "\n\n" + text.TARGETS)
    if "workprecision" in s:
        out.append(text.WORKPRECISION + "\n" + section_workprecision(s["workprecision"], command))
    if "failures" in s:
        out.append(
            text.FAILURES
            + "\n"
            + section_failures(s["failures"], command)
            + "\n"
            + text.FAILURES_AFTER
        )
    if "ladder" in s:
        out.append(text.LADDER + "\n" + section_ladder(s["ladder"], command))
    if "throughput" in s:
        out.append(text.THROUGHPUT + "\n" + section_throughput(s["throughput"], command))
    if "profile" in s:
        out.append(text.PROFILE + "\n" + section_profile(s["profile"]))
    if "contact" in s:
        out.append(text.CONTACT + "\n" + section_contact(s["contact"], command))
    if "io" in s:
        out.append(runio.tables_section(s["io"], command))
    return "\n".join(out).rstrip() + "\n"


def ratio_text(x) -> str:
    """A ratio for a table: 'inf', '1,234x' or three significant digits."""
    if x is None:
        return "-"
    if math.isinf(x):
        return "inf"
    return f"{x:,.0f}x" if x >= 100 else f"{x:.3g}x"


def _rate(x: float) -> str:
    return f"{x:,.0f}" if x >= 100 else f"{x:.3g}"


def _paired(row: dict) -> str:
    pairs = contact_mod.paired_ratios(row)
    return f"{ratio_text(min(pairs))} to {ratio_text(max(pairs))}" if pairs else "-"


def _ratio_verdict(t: dict) -> str:
    if not t["compared"]:
        return "not measured: no comparable case"
    if t["met"]:
        return "met"
    missed = t["short"] + [f"{n} (not compared)" for n in t["not_compared"]]
    return f"not met in {len(missed)} of {len(t['compared']) + len(t['not_compared'])}: " + (
        ", ".join(missed)
    )


def contact_targets(c: dict) -> list[list[str]]:
    """The targets-table rows of the contact section: the ratio impacts / phases on the
    paper's scenes and on the closed-form cases, the CPU of one contact phase and the
    first-use compile (results saved before it was measured: without that row)."""
    rows = c["rows"]
    by = {r["case"]: r for r in rows}
    out = []
    for kind, what in (
        ("paper", "on the four paper scenes: phases never dearer than the hops they replace"),
        ("closed form", "where chatter, rest or one phase dominates (the closed-form cases)"),
    ):
        t = contact_mod.ratio_targets(rows, kind)
        measured = "; ".join(f"{n}: {ratio_text(by[n]['ratio'])}" for n in t["compared"])
        if t["not_compared"]:
            measured += "; not compared: " + ", ".join(t["not_compared"])
        out.append(
            [
                f"CPU per simulated second, impacts / phases >= {t['target']:g}x {what}",
                measured or "-",
                _ratio_verdict(t),
            ]
        )
    costs = contact_mod.phase_costs(rows)
    target = contact_mod.PHASE_TARGET_US
    out.append(
        [
            f"one contact phase <= {target:g} us of CPU, all in (the phases run's CPU less its "
            f"impacts' at the impact model's cost, over its phases; cases with >= "
            f"{contact_mod.PHASE_COUNT} phases)",
            "; ".join(f"{n}: {us:,.0f} us" for n, us in costs) or "-",
            (
                "not measured: no case with enough phases"
                if not costs
                else "met"
                if all(us <= target for _, us in costs)
                else f"not met in {sum(us > target for _, us in costs)} of {len(costs)}"
            ),
        ]
    )
    if "compile" in c:
        k = c["compile"]
        ok = all(r["ok"] for r in k["runs"])
        out.append(
            [
                f"first-use compile of every kernel <= {k['target']:g} s, in one wait (wall "
                "time, empty numba cache)",
                f"{k['compile_s']:.1f} s; {k['waits']} wait(s) over {len(k['runs'])} runs",
                (
                    "not measured: a run failed"
                    if not ok
                    else "met"
                    if k["compile_s"] <= k["target"] and k["waits"] <= 1
                    else "not met"
                ),
            ]
        )
    if "sampled" in c:
        m = c["sampled"]
        out.append(
            [
                f"a sampled run's engine <= {m['target']:g}x the run without samples "
                f"({m['scene']} under phases, {m['impacts']:,} impacts, a sample every "
                f"{m['dt']:g} s: {m['samples']:,} samples)",
                f"{m['ratio']:.2f}x: {m['per_sample_us']:.2f} us a sample; handing each "
                f"to Python {m['handout_us']:.2f} us more",
                "met" if m["ratio"] <= m["target"] else "not met",
            ]
        )
    return out


def _in_contact(m: dict) -> float:
    """Share of the simulated time spent in contact (rolling, sliding or held)."""
    t = m["times"]
    return (t["roll"] + t["slide"] + t.get("held", 0.0)) / m["simulated"]


def _times(m: dict) -> str:
    t = m["times"]
    return f"{t['flight']:.3g} / {t['roll']:.3g} / {t['slide']:.3g} / {t.get('held', 0.0):.3g}"


def _ended(m: dict) -> str:
    if m["ended"] == "time":
        return "duration"
    if m["ended"] == "at rest":
        return "at rest: ended early, counted to the duration"
    return f"{m['ended']} at t = {m['reached']:.3g} s"


def section_contact(c: dict, command: str) -> str:
    parts = [figure("contact.png", "contact phases against impacts", f"{command} --only contact")]
    parts.append(
        f"Measured {c.get('date', '')}: paper scenes {c['paper_duration']:g} s of simulated "
        f"time, closed-form cases {c['duration']:g} s (or less where the case says so), "
        f"each model run {c['repeats']} times, alternately; at most "
        f"{c['max_impacts']:,} impacts per run; code: {c.get('code', 'unknown')}. Load "
        "average at the end: "
        f"{', '.join(f'{x:.1f}' for x in c['load'])} (1, 5, 15 min).\n"
    )
    body = []
    for r in c["rows"]:
        for model in contact_mod.MODELS:
            m = r[model]
            ok = m["comparable"] and math.isfinite(m["cpu_per_s"])
            body.append(
                [
                    r["case"] if model == "impacts" else "",
                    model,
                    f"{m['simulated']:.3g}",
                    f"{1e3 * m['cpu_per_s']:.3g}" if ok else "-",
                    ", ".join(_rate(1e3 * x) for x in m["cpus"]),
                    _rate(m["impacts_per_s"]) if ok else f"({m['impacts']} impacts)",
                    f"{m['resting']} ({100 * m['resting_share']:.0f} %)",
                    m["phases"],
                    _times(m),
                    _ended(m),
                    ratio_text(r.get("ratio")) if model == "phases" else "",
                    _paired(r) if model == "phases" else "",
                ]
            )
    parts.append(
        table(
            [
                "case",
                "contact.model",
                "simulated s",
                "CPU ms per simulated s",
                "CPU ms of each run",
                "impacts per simulated s",
                "resting relaunches",
                "contact phases",
                "flying / rolling / sliding / held (s)",
                "ended",
                "CPU ratio impacts / phases (of the medians)",
                "ratio of each repeat's pair",
            ],
            body,
        )
        + "\n"
    )
    parts.append(
        "Cases: "
        + "; ".join(f"**{r['case']}**: {r['what']} ({r['duration']:.3g} s)" for r in c["rows"])
        + ".\n"
    )
    parts.append(contact_findings(c) + "\n")
    if "compile" in c:
        parts.append(compile_table(c["compile"]))
    parts.append(text_contact_after())
    return "\n".join(parts)


def compile_table(k: dict) -> str:
    """The first-use compile's runs: each a fresh process, the numba cache empty before
    the first."""
    body = [
        [
            f"`billiard run {r['run']} --collisions 100`",
            f"{r['wall']:.1f}",
            "; ".join(r["notices"]) or "none",
        ]
        for r in k["runs"]
    ]
    return (
        "First use, from an empty numba cache (`NUMBA_CACHE_DIR` in a new folder), each run "
        "a fresh process, one after another; the compile is the first run's wall time less "
        f"the last's (the same run, warm): **{k['compile_s']:.1f} s** in {k['waits']} "
        "wait(s).\n\n" + table(["run", "wall s", "compile notices"], body) + "\n"
    )


def contact_findings(c: dict) -> str:
    """The verdict on the target and the cases where the phases do not pay, as a list."""
    v = contact_mod.verdict(c["rows"])
    by = {r["case"]: r for r in c["rows"]}

    def listed(names: list[str]) -> str:
        return ", ".join(f"{n} {ratio_text(by[n]['ratio'])}" for n in names)

    lines = []
    for kind, where in (("paper", "the paper scenes"), ("closed form", "the closed-form cases")):
        t = contact_mod.ratio_targets(c["rows"], kind)
        if not t["compared"]:
            continue
        ratios = [by[n]["ratio"] for n in t["compared"]]
        state = "met" if t["met"] else "not met"
        lines.append(
            f"- **Target {t['target']:g}x on {where}: {state}**: "
            f"{len(t['compared']) - len(t['short'])} of {len(t['compared'])} compared cases "
            f"reach it (ratios {ratio_text(min(ratios))} to {ratio_text(max(ratios))})"
            + (f"; short: {listed(t['short'])}" if t["short"] else "")
            + "."
        )
    for name in v["not_compared"]:
        m = by[name]["phases"]
        lines.append(
            f'- **{name}** is not compared: under "phases" the run ended with '
            f"{_ended(m)} ({m['stop'][:90]})."
        )
    if v["equal"]:
        shares = ", ".join(f"{100 * _in_contact(by[n]['phases']):.2g} %" for n in v["equal"])
        lines.append(
            f"- **About equal** (ratio within {100 * contact_mod.NOISE:.0f} % of 1, the noise "
            f"of these times): {listed(v['equal'])}; the ball is in contact {shares} of the "
            'time there under "phases".'
        )
    for name in v["slower"]:
        a, b = by[name]["impacts"], by[name]["phases"]
        lines.append(
            f"- **{name}**: phases are slower ({ratio_text(by[name]['ratio'])}; the repeats' "
            f"pairs {_paired(by[name])}): the ball is in "
            f'contact {100 * _in_contact(b):.1f} % of the time; "phases" makes '
            f'{b["impacts"]:,} impacts and {b["phases"]} contact phases where "impacts" makes '
            f"{a['impacts']:,} ({100 * a['resting_share']:.0f} % resting relaunches)."
        )
    return "\n".join(lines)


def text_contact_after() -> str:
    from bench import text

    return text.CONTACT_AFTER


def _machine(m: dict) -> str:
    load = ", ".join(f"{x:.1f}" for x in m["load"])
    return (
        f"Python {m['python']} on {m['platform']} ({m['cpus']} CPUs, load average "
        f"{load} (1, 5, 15 min) at the end); code: {m.get('code', 'unknown')}"
    )
