"""The throughput section of performance.md: the compiled engine against the interpreted
one, whole runs with start-up, 10^6 impacts, start-up and compile, memory; and its rows
of the targets table."""

from __future__ import annotations

from bench.throughput import TARGETS
from billiard.runfile.rows import NCOL

FIG = "figures/performance"


def _table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def _us(seconds: float) -> str:
    us = seconds * 1e6
    return f"{us:.2f}" if us < 10 else f"{us:.1f}"


def _verdict(ok: bool, miss: str = "missed") -> str:
    return "met" if ok else miss


def _cpu_target(r: dict) -> float | None:
    """The CPU-per-impact bound for this scene and drag setting, if any: the wedge as
    shipped (drag off), the parabola with drag (as shipped)."""
    if r["scene"] == "wedge-6.6hz" and r["drag"] == "none":
        return TARGETS["cpu_wedge"]
    if r["scene"] == "parabola-5.4hz" and r["drag"] == "fowles":
        return TARGETS["cpu_parabola_drag"]
    return None


def target_rows(t: dict) -> list[list[str]]:
    """One row per target of the compiled engine: what it asks, what was measured, met."""
    if "compiled_startup" not in t:  # results of an earlier, interpreted-only bench
        return []
    rows = []
    for r in t["rates"]:
        fast = r["compiled"]["cpu_per_impact"]
        ratio = r["ratio"]
        drag = "drag on" if r["drag"] == "fowles" else "drag off"
        rows.append(
            [
                f"CPU per impact >= {TARGETS['ratio']:.0f}x lower, {r['scene']}, {drag}",
                f"{_us(fast)} us against {_us(r['interpreted']['cpu_per_impact'])} us "
                f"({ratio:.0f}x)",
                _verdict(ratio >= TARGETS["ratio"]),
            ]
        )
        bound = _cpu_target(r)
        if bound is not None:
            rows.append(
                [
                    f"{r['scene']}, {drag}: <= {bound * 1e6:.0f} us per impact",
                    f"{_us(fast)} us",
                    _verdict(fast <= bound, f"missed, {fast / bound:.1f}x"),
                ]
            )
    for run in t["runs"]:
        if run["how"] != "billiard run":
            continue
        med = run["median"]
        bound = TARGETS["wall_25000"]
        rows.append(
            [
                f"25,000 impacts <= {TARGETS['wall_25000']} s wall with start-up, {run['scene']}",
                f"{med:.2f} s (`billiard run --no-plot`)",
                _verdict(med <= bound, f"missed, {med / bound:.1f}x"),
            ]
        )
    for m in t["million"]:
        rows.append(
            [
                f"{m['impacts']:,} wedge impacts ({m['how']}) <= {TARGETS['wall_million']:.0f} s",
                f"{m['wall']:.2f} s",
                _verdict(m["wall"] <= TARGETS["wall_million"]),
            ]
        )
        if m["how"].startswith("in memory"):
            # the rows a run keeps are NCOL float64 per impact: 144 MB at 10^6 impacts
            # on top of the process (numba's LLVM alone maps about 100 MB), so the bound
            # applies to the streamed run, as `billiard run` runs
            rows_mb = m["impacts"] * NCOL * 8 / 1e6
            rows.append(
                [
                    f"memory at {m['impacts']:,} impacts ({m['how']}; not bounded: the "
                    f"rows alone are {rows_mb:.0f} MB)",
                    f"{m['peak_mb']:.0f} MB",
                    "-",
                ]
            )
            continue
        rows.append(
            [
                f"peak memory <= {TARGETS['peak_million_mb']:.0f} MB at {m['impacts']:,} impacts "
                f"({m['how']})",
                f"{m['peak_mb']:.0f} MB",
                _verdict(m["peak_mb"] <= TARGETS["peak_million_mb"]),
            ]
        )
    s = t["compiled_startup"]
    rows.append(
        [
            f"warm start-up <= {TARGETS['warm_start']} s before the first impact",
            f"{s['warm_median']:.2f} s",
            _verdict(s["warm_median"] <= TARGETS["warm_start"]),
        ]
    )
    rows.append(
        [
            f"cold first compile <= {TARGETS['cold_compile']:.0f} s",
            f"{s['cold']:.1f} s",
            _verdict(s["cold"] <= TARGETS["cold_compile"]),
        ]
    )
    return rows


def _engine_line(t: dict) -> str:
    e = t.get("engine", {})
    if e.get("compiled"):
        return f"Compiled engine: numba {e.get('numba', '?')}."
    return f"The engine ran interpreted ({e.get('problem')}): no compiled figures."


def section_throughput(t: dict, command: str) -> str:
    """The compiled-engine part of the throughput section (the earlier start-up and
    streamed-memory tables follow it, written by report.section_throughput)."""
    parts = [
        f"![throughput and memory]({FIG}/throughput.png)\n\n"
        f"*Reproduce: `{command} --only throughput`*\n",
        _engine_line(t) + "\n",
        "CPU per impact of the run loop (records kept in memory, building the simulation "
        "excluded), median of the runs; the interpreted engine is the same kernels run by "
        "CPython (`NUMBA_DISABLE_JIT=1`), in a fresh process of the same bench run:\n",
    ]
    rows = []
    for r in t["rates"]:
        c, i = r["compiled"], r["interpreted"]
        rows.append(
            [
                r["scene"],
                "on" if r["drag"] == "fowles" else "off",
                f"{r['impacts']:,}",
                ", ".join(_us(x / c["impacts"]) for x in c["cpus"]),
                _us(c["cpu_per_impact"]),
                ", ".join(_us(x / i["impacts"]) for x in i["cpus"]),
                _us(i["cpu_per_impact"]),
                f"{r['ratio']:.0f}x",
                f"{r['rate']:,.0f}",
            ]
        )
    parts.append(
        _table(
            [
                "scene",
                "drag",
                "impacts per run",
                "compiled, us/impact (runs)",
                "compiled median (us)",
                "interpreted, us/impact (runs)",
                "interpreted median (us)",
                "ratio",
                "compiled impacts / s of wall time",
            ],
            rows,
        )
        + "\n"
    )
    parts.append(
        "Whole runs of a fresh process, start-up included (wall seconds, median of the runs):\n"
    )
    code = t.get("bytecode")
    if code:
        unset = "set" if code["dont_write"] else "not set"
        parts.append(
            f"billiard's bytecode was current for {code['current']} of its {code['modules']} "
            f"modules (`PYTHONDONTWRITEBYTECODE` {unset}); a module without it is compiled "
            "from source at every start, about 0.1 s for all of them, as in a fresh "
            "checkout run with `PYTHONDONTWRITEBYTECODE` set (`python -m compileall "
            "billiard` writes it once; an installed package has it).\n"
        )
    rows = [
        [
            run["scene"],
            f"`{run['how']}`",
            f"{run['impacts']:,}",
            ", ".join(f"{x:.2f}" for x in run["times"]),
            f"{run['median']:.2f}",
        ]
        for run in t["runs"]
    ]
    parts.append(_table(["scene", "how", "impacts", "runs (s)", "median (s)"], rows) + "\n")
    parts.append("A long wedge run in a fresh process (the run call; start-up excluded):\n")
    rows = [
        [
            f"{m['impacts']:,}",
            m["how"],
            f"{m['wall']:.2f}",
            f"{m['peak_mb']:.0f}",
            f"{m['file_mb']:.0f}" if "file_mb" in m else "",
            f"{m['anon_mb']:.0f}" if "anon_mb" in m else "",
        ]
        for m in t["million"]
    ]
    header = ["impacts", "how", "wall (s)", "peak RSS, VmHWM (MB)"]
    header += ["at the end: mapped files, RssFile (MB)", "own memory, RssAnon (MB)"]
    parts.append(_table(header, rows) + "\n")
    parts.append(
        "Mapped files are mostly numba's LLVM library (libllvmlite.so, about 100 MB once "
        "loaded), shared by every process that imports numba; the process's own memory "
        "is the rest.\n"
    )
    s = t["compiled_startup"]
    parts.append(
        f"Start-up of a fresh process to the first impact of `{s['scene']}`, kernels "
        f"loaded from numba's cache: {', '.join(f'{x:.2f}' for x in s['warm'])} s "
        f"(median {s['warm_median']:.2f} s). With an empty cache (`NUMBA_CACHE_DIR` a new "
        f"folder) the first run compiles the kernels: {s['cold']:.1f} s.\n"
    )
    rc = t["refcount"]
    parts.append(
        "Reference counting: a call that numba does not inline and that reads two numbers "
        f"from an array argument costs {rc['array_ns']:.2f} ns, one taking the two numbers "
        f"{rc['scalar_ns']:.2f} ns ({rc['share']:.0%} of the call is the count of the "
        "array's references).\n"
    )
    return "\n".join(parts)


def section_baseline(b: dict) -> str:
    """The full before-and-after tables of ``--baseline``: every run of both trees."""
    drag = {"fowles": "on", "none": "off"}
    parts = [
        "### Before and after\n",
        f"`--baseline {b['ref']}`: this code ({b['new']}) against commit {b['short']} "
        f"({b['subject']}), checked out in a temporary git worktree. Both run in fresh "
        "processes of the same Python, each tree alone on `PYTHONPATH` (every process "
        "checks that the billiard modules it loaded are its tree's), through the public "
        "API (`simulate`, `load_scene`, `with_values`) and `python -m billiard.cli run`; "
        "the two trees alternate, the order swapped each round, so that the machine's load "
        "falls on both. Engine: "
        + ("compiled" if b["engine"].get("compiled") else f"interpreted ({b['engine']['problem']})")
        + ".\n",
        f"Start-up, {b['startup_rounds']} rounds (seconds):\n",
    ]
    rows = [
        [
            r["what"],
            r["scene"],
            ", ".join(f"{x:.3f}" for x in r["new"]["times"]),
            f"{r['new']['median']:.3f}",
            ", ".join(f"{x:.3f}" for x in r["old"]["times"]),
            f"{r['old']['median']:.3f}",
            f"{r['ratio']:.2f}x",
        ]
        for r in b["startup"]
    ]
    header = ["what", "scene", "new, runs", "new, median", "old, runs", "old, median"]
    parts.append(_table([*header, "new / old"], rows) + "\n")
    parts.append(
        f"Time per impact: the run loop of `simulate()`, records in memory "
        f"(`Result.wall_time`), {b['rounds']} rounds of one fresh process per tree, each "
        "making a short run to load the kernels and then the timed runs; the median of all "
        "runs. The CPU time of the whole `simulate()` call (building the simulation "
        "included) gives the last column:\n"
    )
    rows = []
    for r in b["rates"]:
        pairs = r["round_ratios"]
        rows.append(
            [
                r["scene"],
                drag[r["drag"]],
                f"{r['impacts']:,} x {r['repeats']}",
                ", ".join(_us(x / r["impacts"]) for x in r["new"]["loops"]),
                _us(r["new"]["per_impact"]),
                ", ".join(_us(x / r["impacts"]) for x in r["old"]["loops"]),
                _us(r["old"]["per_impact"]),
                f"{r['ratio']:.2f}x",
                f"{min(pairs):.2f}x to {max(pairs):.2f}x",
                f"{r['cpu_ratio']:.2f}x",
            ]
        )
    header = ["scene", "drag", "impacts x runs per process", "new, us/impact (runs)"]
    header += ["new, median (us)", "old, us/impact (runs)", "old, median (us)", "new / old"]
    header += ["new / old, each round", "new / old, CPU of the call"]
    parts.append(_table(header, rows) + "\n")
    return "\n".join(parts)
