"""The benchmark's figures (PNG), one function per figure, each from the saved results."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from bench.contact import paired_ratios  # noqa: E402

COLORS = {"event": "C0", "rk4": "C1", "DOP853": "C2", "DOP853 careful": "C3"}
#: errors below this are drawn on it (an error of exactly 0 has no place on a log axis)
FLOOR = 1e-16
TARGET_ERROR = 1e-9
TARGET_RATE = 25000 / 2.0


def _save(fig, path: Path, command: str, bottom: float = 0.02) -> Path:
    fig.text(0.99, 0.005, f"reproduce: {command}", ha="right", va="bottom", fontsize=7, color="0.4")
    fig.tight_layout(rect=(0, bottom, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _clip(values):
    return [max(v, FLOOR) if math.isfinite(v) else math.nan for v in values]


def work_precision(scene: dict, path: Path, command: str) -> Path:
    """2 x 2 panels: (impact time, impact point) error x (after k1, after k2 impacts)."""
    checkpoints = list(scene["rows"][0]["errors"]["t"])
    fig, axes = plt.subplots(2, len(checkpoints), figsize=(11, 8.5), squeeze=False)
    methods = list(dict.fromkeys(r["method"] for r in scene["rows"]))
    for row, (key, unit) in enumerate(
        (("t", "impact-time error (s)"), ("pos", "impact-point error (m)"))
    ):
        for col, k in enumerate(checkpoints):
            ax = axes[row][col]
            for drag, style in (("fowles", "-"), ("none", "--")):
                for method in methods:
                    pts = [r for r in scene["rows"] if r["method"] == method and r["drag"] == drag]
                    if not pts:
                        continue
                    x = _clip([r["errors"][key][k] for r in pts])
                    y = [r["cpu_per_1000"] for r in pts]
                    drag_label = "drag on" if drag == "fowles" else "drag off"
                    ax.plot(
                        x,
                        y,
                        style,
                        marker="o",
                        color=COLORS[method],
                        ms=4,
                        label=f"{method}, {drag_label}",
                    )
                floor = scene["floor"][drag][key][k]
                if floor > 0:
                    ax.axvline(
                        max(floor, FLOOR), color="0.6", ls=":" if drag == "none" else "-.", lw=1
                    )
            if key == "t":
                ax.axvline(TARGET_ERROR, color="k", lw=0.8, alpha=0.5)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(f"{unit} after {k} impacts")
            ax.set_ylabel("CPU time per 1,000 impacts (s)")
            ax.grid(True, which="major", alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, 0.02))
    fig.subplots_adjust(bottom=0.16)
    fig.suptitle(
        f"{scene['scene']}: work against precision (grey lines: effect of moving the "
        f"start by 1e-15 m, drag on -. / off :; black: 1e-9 s)",
        fontsize=10,
    )
    return _save(fig, path, command, bottom=0.09)


def failures(rows: list[dict], path: Path, command: str) -> Path:
    """Missed + spurious impacts per 1,000 flights and deepest penetration, against the
    rk4 step and the DOP853 tolerance, one line per scene."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    sets = list(dict.fromkeys(r["set"] for r in rows))
    panels = ((0, "rk4", "rk4 step (s)"), (1, "DOP853", "DOP853 rtol = atol"))
    for col, method, xlabel in panels:
        for i, name in enumerate(sets):
            for variant, style in ((method, "-"), (method + " careful", "--")):
                pts = sorted(
                    (r["value"], r)
                    for r in rows
                    if r["set"] == name and r["method"] == variant and r["drag"] == "none"
                )
                if not pts:
                    continue
                x = [v for v, _ in pts]
                label = name if variant == method else f"{name} (careful)"
                axes[0][col].plot(
                    x,
                    [r["per_1000"] for _, r in pts],
                    style,
                    marker="o",
                    color=f"C{i}",
                    label=label,
                )
                axes[1][col].plot(
                    x,
                    _clip([r["penetration"] for _, r in pts]),
                    style,
                    marker="o",
                    color=f"C{i}",
                    label=label,
                )
        for row, ylabel in (
            (0, "missed + spurious impacts per 1,000 flights"),
            (1, "deepest penetration into the wall (m)"),
        ):
            ax = axes[row][col]
            ax.set_xscale("log")
            if row == 0:
                ax.set_yscale("symlog", linthresh=1)
                ax.set_ylim(0, 1500)
            else:
                ax.set_yscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(True, alpha=0.3)
        axes[0][col].set_title(f"{method}: one flight from each state, drag off")
    handles, labels = axes[0][1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, bbox_to_anchor=(0.5, 0.02))
    fig.suptitle(
        "Where methods fail: rk4 against its step, solve_ivp (DOP853) against its "
        "tolerance (dashed: careful); penetrations of 0 drawn at 1e-16",
        fontsize=10,
    )
    return _save(fig, path, command, bottom=0.09)


def low_velocity(rows: list[dict], path: Path, command: str) -> Path:
    """Impacts per simulated second against contact.elastic_below; collapses marked."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    positive = sorted({r["elastic_below"] for r in rows if r["elastic_below"] > 0})
    zero_at = positive[0] / 10 if positive else 1e-5
    for ax, start in zip(axes, ("rest", "in flight"), strict=True):
        for i, name in enumerate(dict.fromkeys(r["scene"] for r in rows)):
            pts = [r for r in rows if r["scene"] == name and r["start"] == start]
            x = [r["elastic_below"] or zero_at for r in pts]
            y = [r["rate"] if math.isfinite(r["rate"]) else math.nan for r in pts]
            ax.plot(x, y, "-o", color=f"C{i}", ms=4, label=name)
            bad = [(xi, yi) for xi, yi, r in zip(x, y, pts, strict=True) if r["collapse"]]
            if bad:
                ax.plot(*zip(*bad, strict=True), "x", color="red", ms=10, mew=2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"contact.elastic_below (m/s); 0 drawn at {zero_at:g}")
        ax.set_title(f"started {'at rest' if start == 'rest' else 'in flight'}")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("impacts per simulated second")
    axes[0].legend(fontsize=8)
    fig.suptitle(
        "The low-velocity rule: impact rate (red x: the run ended in inelastic collapse)",
        fontsize=10,
    )
    return _save(fig, path, command)


def ladder(rows: list[dict], path: Path, command: str) -> Path:
    """Change of the mean impact height and wall-time ratio per model variant."""
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    variants = list(dict.fromkeys(r["variant"] for r in rows))[1:]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    height = 0.8 / len(scenes)
    for i, name in enumerate(scenes):
        full = next(r for r in rows if r["scene"] == name and r["variant"] == "full model")
        for j, variant in enumerate(variants):
            r = next(r for r in rows if r["scene"] == name and r["variant"] == variant)
            y = j + (i - (len(scenes) - 1) / 2) * height
            label = name if j == 0 else None
            delta = 1e3 * (r.get("mean_q2", math.nan) - full.get("mean_q2", math.nan))
            axes[0].barh(
                y, delta if math.isfinite(delta) else 0.0, height, color=f"C{i}", label=label
            )
            if r["stop"]:
                axes[0].text(0, y, " run stops", va="center", fontsize=6)
            axes[1].barh(y, r["wall_time"] / full["wall_time"], height, color=f"C{i}")
    axes[0].set_yticks(range(len(variants)), variants, fontsize=8)
    axes[0].set_xlabel("change of the mean impact height q2 from the full model (mm)")
    axes[1].set_xlabel("wall time relative to the full model")
    axes[1].axvline(1.0, color="k", lw=0.8)
    axes[0].axvline(0.0, color="k", lw=0.8)
    axes[0].legend(fontsize=8)
    for ax in axes:
        ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle("Model ladder: one physical term off at a time", fontsize=10)
    return _save(fig, path, command)


def throughput(
    rates: list[dict], memory: list[dict], path: Path, command: str, long: list[dict] = ()
) -> Path:
    """CPU per impact, compiled and interpreted, per scene; peak memory against run length."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    labels = [f"{r['scene']}\ndrag {'on' if r['drag'] == 'fowles' else 'off'}" for r in rates]
    x = list(range(len(rates)))
    if all("compiled" in r for r in rates):
        for k, (engine, color) in enumerate((("interpreted", "C0"), ("compiled", "C1"))):
            axes[0].bar(
                [i + (k - 0.5) * 0.4 for i in x],
                [r[engine]["cpu_per_impact"] * 1e6 for r in rates],
                0.4,
                color=color,
                label=f"{engine} engine",
            )
        for i, r in enumerate(rates):
            axes[0].text(
                i,
                r["interpreted"]["cpu_per_impact"] * 1.3e6,
                f"{r['ratio']:.0f}x",
                ha="center",
                fontsize=7,
            )
        axes[0].set_yscale("log")
        axes[0].set_ylabel("CPU per impact (us), run loop, median")
        axes[0].set_title("compiled against interpreted (ratio above the bars)")
    else:  # an earlier bench: wall-time rate of the one engine
        axes[0].bar(x, [r["rate"] for r in rates], 0.6)
        axes[0].axhline(TARGET_RATE, color="k", ls="--", lw=1, label="target: 25,000 in 2 s")
        axes[0].set_ylabel("impacts per second of wall time")
        axes[0].set_title("default method, median of the repeats")
    axes[0].set_xticks(x, labels, fontsize=6)
    axes[0].legend(fontsize=8)
    runs = [m for m in memory if m["impacts"] > 0]
    base = next((m["peak_mb"] for m in memory if m["impacts"] == 0), None)
    axes[1].plot(
        [m["impacts"] for m in runs],
        [m["peak_mb"] for m in runs],
        "-o",
        label="run streamed to collisions.csv",
    )
    for m, marker in zip(long, "s^", strict=False):
        axes[1].plot([m["impacts"]], [m["peak_mb"]], marker, label=f"wedge, {m['how']}")
    if base is not None:
        axes[1].axhline(base, color="0.5", ls=":", label="modules imported, no run")
    axes[1].axhline(200, color="k", ls="--", lw=1, label="target: 200 MB")
    axes[1].set_xscale("log")
    axes[1].set_ylim(0, max([220.0, *(m["peak_mb"] * 1.1 for m in long)]))
    axes[1].set_xlabel("impacts")
    axes[1].set_ylabel("peak resident memory, VmHWM (MB)")
    axes[1].set_title("peak memory of a fresh process")
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return _save(fig, path, command)


def contact(rows: list[dict], path: Path, command: str) -> Path:
    """CPU per simulated second under each contact model, and their ratio, per case."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
    names = [r["case"] for r in rows]
    x = list(range(len(rows)))
    for k, (model, color) in enumerate((("impacts", "C0"), ("phases", "C1"))):
        values = [r[model]["cpu_per_s"] for r in rows]
        shown = [
            v if math.isfinite(v) and r[model]["comparable"] else 0.0
            for v, r in zip(values, rows, strict=True)
        ]
        axes[0].bar(
            [i + (k - 0.5) * 0.4 for i in x],
            shown,
            0.4,
            color=color,
            label=f'contact.model = "{model}"',
        )
        for i, r in enumerate(rows):
            if not r[model]["comparable"]:
                axes[0].text(
                    i + (k - 0.5) * 0.4,
                    1e-4,
                    f" {r[model]['ended']}",
                    rotation=90,
                    va="bottom",
                    ha="center",
                    fontsize=7,
                    color="red",
                )
    axes[0].set_yscale("log")
    axes[0].set_ylabel("CPU s per simulated s (median)")
    axes[0].set_title("cost of simulated time\n(median of the repeats)", fontsize=10)
    axes[0].legend(fontsize=8)
    ratios = [r.get("ratio") for r in rows]
    colors = ["C3" if r.get("chatter") else "0.6" for r in rows]
    axes[1].bar(x, [v if v is not None else 0.0 for v in ratios], 0.6, color=colors)
    for i, r in enumerate(rows):
        pairs = paired_ratios(r)
        if pairs and r["ratio"] is not None:
            low, high = r["ratio"] - min(pairs), max(pairs) - r["ratio"]
            axes[1].errorbar(
                i, r["ratio"], [[max(low, 0.0)], [max(high, 0.0)]], color="k", lw=1, capsize=3
            )
    for i, v in enumerate(ratios):
        label = "not compared" if v is None else (f"{v:,.0f}x" if v >= 100 else f"{v:.3g}x")
        y = max(paired_ratios(rows[i]) + [v]) * 1.08 if v is not None else 1.0
        axes[1].text(
            i, y, label, ha="center", va="bottom", fontsize=7, rotation=90 if v is None else 0
        )
    axes[1].axhline(10.0, color="k", ls="--", lw=1, label="target: 10x where chatter dominates")
    axes[1].axhline(1.0, color="k", lw=0.8)
    axes[1].set_yscale("log")
    axes[1].set_ylabel(
        'CPU per simulated s, "impacts" / "phases"\n(bars: medians; lines: each repeat\'s pair)'
    )
    axes[1].set_title(
        "speed-up of the contact phases\n(red: most impacts relaunch a resting ball)", fontsize=10
    )
    low = min(
        [v for v in ratios if v is not None]
        + [min(paired_ratios(r) or [1.0]) for r in rows]
        + [1.0]
    )
    axes[1].set_ylim(bottom=low / 2)
    axes[1].legend(fontsize=8)
    labels = [
        f"{n}\n{100 * r['impacts']['resting_share']:.0f} % resting"
        for n, r in zip(names, rows, strict=True)
    ]
    for ax in axes:
        ax.set_xticks(x, labels, fontsize=7, rotation=45, ha="right")
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(
        "Contact phases against the hops they replace: the same start, the same simulated time",
        fontsize=10,
    )
    return _save(fig, path, command)
