"""Run the measurements, save them, draw the figures and write performance.md and its
appendix of full tables, performance-tables.md.

Results are kept in ``FIGURES/results.json``; ``--only`` re-measures some sections and
takes the others from that file.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path

from bench import baseline as baseline_bench
from bench import (
    charts,
    compiled,
    contact,
    failures,
    ladder,
    page,
    report,
    runio,
    throughput,
    workprecision,
)
from bench import ensemble as ensemble_bench
from bench import sweep as sweep_bench
from bench.common import Config, start_scene
from bench.version import code_version
from billiard.cli.bench import SECTIONS as BENCH_SECTIONS

#: The sections of the page (``sweep`` keeps its own results, docs/figures/sweeps/bench.json,
#: and its own part of the page, between markers).
SECTIONS = BENCH_SECTIONS


class Starts(dict):
    """Attractor start scenes, computed on first use."""

    def __init__(self, cfg: Config):
        super().__init__()
        self.cfg = cfg

    def __missing__(self, name: str):
        self[name] = start_scene(name, self.cfg.transient)
        return self[name]


def measure(section: str, cfg: Config, starts: Starts, baseline: dict | None = None) -> dict:
    """One section's measurements; ``baseline`` (a commit, see bench.baseline.resolve)
    adds the throughput section's before and after."""
    if section == "workprecision":
        return {"scenes": [workprecision.measure_scene(n, cfg) for n in cfg.scenes]}
    if section == "failures":
        for name in cfg.scenes:
            starts[name]
        return {"rows": failures.measure(cfg), "thresholds": failures.threshold_scan(cfg, starts)}
    if section == "ladder":
        rows = []
        for name in cfg.scenes:
            rows += ladder.measure_scene(name, cfg.ladder_impacts, starts[name])
        return {"rows": rows}
    if section == "throughput":
        # first: a commit that cannot be checked out or run fails the section early
        before = (
            baseline_bench.measure(
                Path(__file__).resolve().parent.parent,
                baseline,
                cfg.scenes,
                cfg.throughput_impacts,
                cfg.throughput_repeats,
                cfg.throughput_repeats,
                cfg.startup_repeats,
            )
            if baseline
            else None
        )
        rates = [
            throughput.impact_rate(n, cfg.throughput_impacts, cfg.throughput_repeats, drag)
            for drag in ("fowles", "none")
            for n in cfg.scenes
        ]
        section = {
            "engine": throughput.engine_info(),
            "rates": rates,
            "bytecode": throughput.bytecode_state(),
            "runs": throughput.whole_runs(cfg.scenes, 25000, cfg.startup_repeats),
            "million": throughput.million("wedge-6.6hz", cfg.million_impacts),
            "compiled_startup": throughput.compiled_startup("wedge-6.6hz", cfg.startup_repeats),
            "refcount": compiled.refcount(cfg.throughput_repeats),
            "startup": throughput.startup(cfg.startup_repeats),
            "memory": throughput.memory("wedge-6.6hz", cfg.memory_sizes),
        }
        if before:
            section["baseline"] = before
        return section
    if section == "profile":
        return {"profiles": [throughput.profile(n, cfg.profile_impacts) for n in cfg.scenes]}
    if section == "contact":
        return {**contact.measure(cfg), "code": code_version()}
    if section == "io":
        return {**runio.measure(cfg.quick), "code": code_version()}
    raise ValueError(f"unknown section {section!r}")


def draw(results: dict, figures: Path, command: str) -> None:
    sections = results["sections"]
    if "workprecision" in sections:
        for scene in sections["workprecision"]["scenes"]:
            charts.work_precision(
                scene,
                figures / f"workprecision-{scene['scene']}.png",
                f"{command} --only workprecision",
            )
    if "failures" in sections:
        f = sections["failures"]
        charts.failures(f["rows"], figures / "failures.png", f"{command} --only failures")
        charts.low_velocity(
            f["thresholds"], figures / "low-velocity.png", f"{command} --only failures"
        )
    if "ladder" in sections:
        charts.ladder(
            sections["ladder"]["rows"], figures / "ladder.png", f"{command} --only ladder"
        )
    if "throughput" in sections:
        t = sections["throughput"]
        charts.throughput(
            t["rates"],
            t["memory"],
            figures / "throughput.png",
            f"{command} --only throughput",
            t.get("million", ()),
        )
    if "contact" in sections:
        charts.contact(
            sections["contact"]["rows"], figures / "contact.png", f"{command} --only contact"
        )


def _plain(value):
    """numpy scalars as Python numbers for json."""
    return value.item() if hasattr(value, "item") else str(value)


def machine() -> dict:
    load = os.getloadavg() if hasattr(os, "getloadavg") else (0.0, 0.0, 0.0)
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "load": load,
        "code": code_version(),
    }


def main(
    cfg: Config, out: Path, only: tuple[str, ...] = SECTIONS, baseline: dict | None = None
) -> Path:
    """Measure the sections in ``only``, then write ``out/performance.md``, its appendix
    of full tables and its figures in ``out/figures/performance``; ``baseline``: the
    commit the throughput section is compared with (bench.baseline)."""
    figures = out / "figures" / "performance"
    figures.mkdir(parents=True, exist_ok=True)
    saved = figures / "results.json"
    results = json.loads(saved.read_text()) if saved.exists() and only != SECTIONS else {}
    results.setdefault("sections", {})
    if only:
        results.update(
            mode="quick" if cfg.quick else "full",
            machine=machine(),
            date=time.strftime("%Y-%m-%d %H:%M"),
        )
    starts = Starts(cfg)
    command = "billiard bench --quick" if cfg.quick else "billiard bench"
    for section in only:
        if section in ("sweep", "ensemble"):
            continue  # measured after the page is written, into its own section
        began = time.perf_counter()
        print(f"bench: {section} ...", flush=True)
        results["sections"][section] = measure(section, cfg, starts, baseline)
        results["sections"][section]["elapsed"] = time.perf_counter() - began
        results["sections"][section]["mode"] = results["mode"]
        results["sections"][section]["load"] = list(os.getloadavg())
        print(f"bench: {section} took {time.perf_counter() - began:.0f} s", flush=True)
        saved.write_text(json.dumps(results, indent=1, default=_plain))
    if baseline and "throughput" in only:
        print(baseline_bench.summary(results["sections"]["throughput"]["baseline"]), flush=True)
    draw(results, figures, command)
    path = out / "performance.md"
    path.write_text(page.render(results, command))
    (out / page.TABLES).write_text(report.render_tables(results, command))
    # the page is written whole: put the sweep section back (measured again if asked)
    sweep_bench.publish(out, sweep_bench.measure(cfg.quick) if "sweep" in only else None)
    # and the ensemble section of sweeps.md (docs/sweeps.md, beside the page), with its
    # part of the page (put back as the sweep section is)
    ensemble_bench.publish(out, ensemble_bench.measure(cfg.quick) if "ensemble" in only else None)
    return path
