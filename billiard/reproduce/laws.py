"""Impact laws compared: ``billiard reproduce --laws`` calibrates each impact law's main
parameter to the paper's period-one orbit (0.075 m on the parabola at 5.4 Hz), runs the
four paper scenes under every law at its calibrated value, draws their return maps, time
maps and phase plots side by side, and writes docs/impact-laws.md. Every number on the
page is computed here from the runs it makes.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from billiard.analysis.calibrate import CalibrationError, Orbit, calibrate_law
from billiard.analysis.dissipation import impact_dissipation, relative_energy
from billiard.models.impact import IMPACT_LAWS, with_law
from billiard.plot import paper_laws_figure
from billiard.reproduce.paper import FULL_COLLISIONS, ReproduceError, check_outputs
from billiard.reproduce.runs import RunStats, run_scene
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import PAPER_SCENES, Scene, load_scene, with_values

__all__ = ["LAW_ORBIT", "LawFit", "LawRun", "compare_laws", "law_names", "run_laws"]

#: the paper's period-one orbit on the parabola at 5.4 Hz: its impact height (m)
LAW_ORBIT = 0.075
#: the paper's normalized point of that orbit, (q2/q2max, u4/u4max)
PAPER_POINT = (0.376, 0.0372)
#: the impact regimes a record names, in the tables' order
REGIMES = ("stick", "slip", "elastic")


@dataclass
class LawFit:
    """One law calibrated on the parabola: its main parameter's value (None: no
    period-one orbit at the height in the law's range, ``error`` says why; the runs then
    take the law's default), the orbit and the calibration's wall time (s)."""

    law: str
    parameter: str
    value: float | None
    error: str | None
    orbit: Orbit | None
    wall_time: float

    def scene(self, name: str) -> Scene:
        """The paper scene ``name`` under this law at its calibrated value."""
        scene = with_law(load_scene(name), self.law)
        if self.value is None:
            return scene
        return with_values(scene, {self.parameter: self.value})

    @property
    def label(self) -> str:
        key = self.parameter.removeprefix("contact.")
        shown = "not calibrated" if self.value is None else f"{key} = {self.value:.4g}"
        return f"{self.law}\n{shown}"


@dataclass
class LawRun:
    """A paper scene run under one law: its measures, and the energy (J) the law removed
    per impact (mean over the run, in the boundary's frame) with its mean share of the
    ball's kinetic energy relative to the boundary."""

    law: str
    stats: RunStats
    dissipated: float
    dissipated_share: float

    def share(self, regime: str) -> float:
        """Fraction of the run's impacts in ``regime``."""
        return self.stats.counts.get(regime, 0) / self.stats.impacts if self.stats.impacts else 0.0


def law_names(text: str | None) -> list[str]:
    """The laws of ``--laws``: all for None or ``"all"``, else a comma-separated list.

    Raises:
        ValueError: a name that is no law (one line naming the choices).
    """
    if text is None or text == "all":
        return list(IMPACT_LAWS)
    names = [part.strip() for part in text.split(",") if part.strip()]
    unknown = [name for name in names if name not in IMPACT_LAWS]
    if unknown or not names:
        raise ValueError(
            f"--laws {text!r}: unknown impact law {', '.join(map(repr, unknown)) or '(none)'}; "
            f"choose from {', '.join(IMPACT_LAWS)} (comma-separated) or all"
        )
    return names


def fit_law(parabola: Scene, law: str, impacts: int) -> LawFit:
    """Calibrate ``law``'s main parameter on the parabola to the paper's orbit."""
    started = time.perf_counter()
    parameter = f"contact.{IMPACT_LAWS[law].main}"
    try:
        _, fit = calibrate_law(parabola, LAW_ORBIT, law=law, impacts=impacts)
    except CalibrationError as exc:
        return LawFit(law, parameter, None, str(exc), None, time.perf_counter() - started)
    return LawFit(law, parameter, fit.value, None, fit.orbit, time.perf_counter() - started)


def run_law(fit: LawFit, name: str, runs_dir: Path, collisions: int) -> LawRun:
    """The paper scene ``name`` under the fitted law, in ``runs_dir / law / name``."""
    scene = fit.scene(name)
    stats = run_scene(name, runs_dir / fit.law, collisions, scene=scene)
    columns = read_collisions(runs_dir / fit.law / name / "collisions.csv")
    lost = impact_dissipation(columns, scene)
    before = relative_energy(columns, scene)
    moving = before > 0.0
    share = float(np.mean(lost[moving] / before[moving])) if moving.any() else math.nan
    return LawRun(fit.law, stats, float(np.mean(lost)), share)


def compare_laws(
    docs: Path,
    runs_dir: Path,
    collisions: int,
    laws: Sequence[str],
    calibration_impacts: int = 1500,
) -> Path:
    """Calibrate, run and draw every law of ``laws``; write ``docs / impact-laws.md``
    and its figures in ``docs / figures / laws``. Returns the page's path."""
    started = time.perf_counter()
    figures = docs / "figures" / "laws"
    figures.mkdir(parents=True, exist_ok=True)
    parabola = load_scene("parabola-5.4hz")
    fits = []
    for law in laws:
        print(f"calibrating {law} on parabola-5.4hz ...", flush=True)
        fits.append(fit_law(parabola, law, calibration_impacts))
    runs: dict[str, list[LawRun]] = {}
    paths: dict[str, Path] = {}
    for name in PAPER_SCENES:
        print(f"running {name} under {len(fits)} impact laws ({collisions} impacts) ...")
        runs[name] = [run_law(fit, name, runs_dir, collisions) for fit in fits]
        paths[name] = paper_laws_figure(
            [runs_dir / fit.law / name for fit in fits],
            [fit.label for fit in fits],
            figures / f"{name}.png",
            f"{name}: heights, flights, phase; one law a column",
        )
    path = docs / "impact-laws.md"
    path.write_text(page(fits, runs, paths, docs, collisions, time.perf_counter() - started))
    return path


def run_laws(args: argparse.Namespace) -> int:
    """``billiard reproduce --laws [NAMES]``: the page goes to docs/ for the full
    comparison (every law at the default --collisions), else to the --runs folder, or
    to --docs."""
    if isinstance(args.collisions, bool) or args.collisions < 1:
        raise ReproduceError(f"reproduce: --collisions must be >= 1, got {args.collisions}")
    try:
        laws = law_names(args.laws)
    except ValueError as exc:
        raise ReproduceError(f"reproduce {exc}") from None
    full = args.collisions == FULL_COLLISIONS and laws == list(IMPACT_LAWS)
    runs = Path(args.runs)
    docs = Path(args.docs) if args.docs is not None else Path("docs") if full else runs
    check_outputs(runs, docs, "impact-laws.md", "laws")
    if args.docs is None and not full:
        print(
            f"billiard: note: not the full comparison: the page goes to "
            f"{docs / 'impact-laws.md'} (give --docs DIR to choose)",
            file=sys.stderr,
        )
    started = time.perf_counter()
    # the calibration's trial runs need the orbit to lock (about 120 impacts at most)
    calibration = min(1500, max(300, args.collisions))
    path = compare_laws(docs, runs, args.collisions, laws, calibration)
    print(f"wrote {path} ({time.perf_counter() - started:.0f} s)")
    return 0


def _pct(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{100.0 * x:.1f} %"


def _fit_row(fit: LawFit) -> str:
    o = fit.orbit
    if fit.value is None or o is None:
        return (
            f"| `{fit.law}` | `{fit.parameter}` | none: {_reason(fit.error)} | - | - | "
            f"{fit.wall_time:.1f} s |"
        )
    return (
        f"| `{fit.law}` | `{fit.parameter}` | {fit.value:.4f} | "
        f"({o.q2_normalized:.3f}, ±{abs(o.u4_normalized):.4f}) | "
        f"{o.dissipated:.4e} J ({_pct(o.dissipated / o.relative_energy)}) | "
        f"{fit.wall_time:.1f} s |"
    )


def _reason(error: str | None) -> str:
    """A calibration's error without its scan of orbit heights; the page says the
    default the law's runs take instead."""
    text = (error or "").split(" (orbit heights")[0]
    return f"{text}; the runs take the law's default"


def _run_row(run: LawRun) -> str:
    s = run.stats
    shares = " | ".join(_pct(run.share(regime)) for regime in REGIMES)
    locked = "-" if s.period_one is None else f"{1000.0 * s.period_one:.2f} mm"
    return (
        f"| `{run.law}` | {s.impacts} | {s.simulated_time:.1f} s | {shares} | "
        f"{run.dissipated:.3e} J | {_pct(run.dissipated_share)} | {1000.0 * s.q2_mean:.1f} mm | "
        f"{locked} |"
    )


def page(
    fits: Sequence[LawFit],
    runs: dict[str, list[LawRun]],
    figures: dict[str, Path],
    docs: Path,
    collisions: int,
    elapsed: float,
) -> str:
    """The text of docs/impact-laws.md."""
    by_law = {fit.law: fit for fit in fits}
    lines = [
        "# Impact laws compared",
        "",
        "<!-- Written by `billiard reproduce --laws`; edit billiard/reproduce/laws.py, not "
        "this file. -->",
        "",
        "The paper ends on an open question: the coefficient of restitution brings the most "
        "uncertainty into the model, and its optimum value differs when rotation-induced "
        "friction is left out. The simulator answers it with a ladder of impact laws, each "
        "compiled in the kernels (`contact.law`, its parameters under `[contact]`), each "
        "calibrated here to the paper's period-one orbit (impacts at q2 = "
        f"{LAW_ORBIT} m on the parabola at 5.4 Hz) and run on the four paper scenes "
        f'({collisions} impacts each, `contact.model = "impacts"`). This page, its tables '
        f"and figures are made by one command, `billiard reproduce --laws` "
        f"({elapsed:.0f} s).",
        "",
        "## The ladder",
        "",
        "| `contact.law` | what changes | parameters (`[contact]`) | reference |",
        "| --- | --- | --- | --- |",
        "| `kane-levinson` (default) | Newton's e on the contact point's normal velocity; "
        "stick if the no-slip impulse lies in mu_s Rn, else slip with mu_k | `restitution`, "
        "`mu_static`, `mu_kinetic` | T. R. Kane, D. A. Levinson, *Dynamics: Theory and "
        "Applications* (1985); the paper's |",
        "| `walton` | a sticking impact reverses the contact point's tangential velocity, "
        "wt+ = -beta0 wt- (derived with Kane's method, `derivation/ball.py`); it slides "
        "when that needs more than mu Rn | `restitution` (e), `mu_kinetic` (mu), `beta0` "
        "in [-1, 1] | O. R. Walton (1993); S. F. Foerster, M. Y. Louge, H. Chang, K. "
        "Allia, Phys. Fluids 6, 1108 (1994) |",
        "| `power-law` | e(v) = min(1, e_ref (v / v_ref)^-p), v the normal impact speed | "
        "`e_ref`, `v_ref` (m/s), `exponent` | e ~ v^-1/4 of elastic-plastic impacts (K. L. "
        "Johnson, *Contact Mechanics*, 1985) |",
        "| `viscoelastic` | e(v) = 1 - C1 x + C2 x^2, x = A alpha^(2/5) v^(1/5), C1 = "
        "1.15344, C2 = 0.79826; held at its minimum 0.583 beyond x = C1 / (2 C2) | "
        "`viscous` = A alpha^(2/5) ((s/m)^(1/5)) | N. V. Brilliantov, F. Spahn, J.-M. "
        "Hertzsch, T. Poeschel, Phys. Rev. E 53, 5382 (1996); second order: J. Ramirez, T. "
        "Poeschel, N. V. Brilliantov, T. Schwager, Phys. Rev. E 60, 4465 (1999) |",
        "| `energy-dependent` | e = e_inf + (1 - e_inf) exp(-E / E0), E = m wn^2 / 2 | "
        "`restitution` (e_inf), `energy_scale` (E0, J) | stands for Gorski and Srokowski's "
        "energy-dependent e, whose published form we could not retrieve: this form is "
        "ours (elastic for slow impacts, e_inf for energetic ones) |",
        "| `angle-dependent` | e = min(1, e0 + slope \\|wt\\| / \\|wn\\|), rising with the "
        "tangent of the contact point's angle of incidence | `restitution` (e0), "
        "`angle_slope` | after M. Y. Louge, M. E. Adams, Phys. Rev. E 65, 021303 (2002); "
        "the linear form is ours |",
        "| `point-particle` | no friction, no change of spin: e on the normal velocity "
        "only | `restitution`; optional `energy_scale` (energy-dependent e) | the model "
        "of Gorski and Srokowski |",
        "",
        "The tangential part of the speed-, energy- and angle-dependent laws is Kane and "
        "Levinson's with their e(v) in place of e. Every law keeps the low-velocity rule "
        '(`elastic_below`); under `contact.model = "phases"` the landing test and the '
        "chatter sum take `contact.restitution` as their e under every law, and the rolling "
        "and sliding phases keep their friction (`mu_static`, `mu_kinetic`: set them to 0 "
        "for a point particle that never rubs). Each law "
        "reduces to the simpler one in its limit (beta0 = 0: Kane and Levinson's sticking "
        "impact; beta0 = -1: a smooth sphere; exponent = 0: constant e; mu = 0 and a "
        "vanishing radius: the point particle) and none creates energy at an impact on a "
        "still boundary: `tests/models/test_impact_laws.py` checks these against the "
        "references' closed forms, `python -m bench.soak` audits every law's impacts. "
        "Every law costs about what Kane and Levinson's does per impact: `python -m "
        "bench.laws` measures each on the motion of its Kane-Levinson limit and fails "
        "above 1.3 times.",
        "",
        "## Calibration on the paper's orbit",
        "",
        "Each law's main parameter fitted so that the ball locks into the period-one orbit "
        f"at {LAW_ORBIT} m (`billiard calibrate parabola-5.4hz --law NAME --target-height "
        f"{LAW_ORBIT}`; the other parameters at the law's defaults). The normalized point "
        f"is the paper's (q2/q2max, u4/u4max), ({PAPER_POINT[0]}, ±{PAPER_POINT[1]}) in the "
        "experiment; the energy removed is what the law dissipates at one impact of the "
        "orbit, in the wall's frame, and its share of the ball's kinetic energy relative "
        "to the wall.",
        "",
        "| law | parameter | calibrated | normalized point | energy removed per impact | time |",
        "| --- | --- | --- | --- | --- | --- |",
        *(_fit_row(fit) for fit in fits),
        "",
    ]
    lines += _answer(by_law)
    for name, law_runs in runs.items():
        rel = figures[name].relative_to(docs).as_posix()
        lines += [
            f"## {name}",
            "",
            "| law | impacts | simulated | stick | slip | elastic | energy lost per impact | "
            "share of relative energy | mean q2 | period-one orbit |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
            *(_run_row(run) for run in law_runs),
            "",
            f"![{name} under each impact law]({rel})",
            "",
        ]
    lines += _limits()
    return "\n".join(lines) + "\n"


def _answer(by_law: dict[str, LawFit]) -> list[str]:
    """The paper's remark answered with the numbers, where both laws were fitted."""
    kane, point = by_law.get("kane-levinson"), by_law.get("point-particle")
    if kane is None or point is None or kane.orbit is None or point.orbit is None:
        return []
    k, p = kane.orbit, point.orbit
    return [
        "**The paper's remark, with numbers.** Without rotation and friction the same orbit "
        f"needs e = {point.value:.3f}, against {kane.value:.3f} with them. A period-one "
        "orbit at a fixed height and drive needs the impact to remove exactly the energy "
        f"the drive puts in: {k.dissipated:.3e} J per impact with rotation and friction, "
        f"{p.dissipated:.3e} J for the point particle. The rotating ball loses part of it "
        "to friction in the tangential direction (the contact point is stopped or slowed "
        "at each impact), so Newton's e need not remove it all: with friction the impact "
        f"removes {_pct(k.dissipated / k.relative_energy)} of the ball's kinetic energy "
        "relative to the wall, normal and tangential together; the point particle's normal "
        f"restitution alone removes {_pct(p.dissipated / p.relative_energy)}, which takes "
        "a lower e.",
        "",
    ]


def _limits() -> list[str]:
    return [
        "## What each law changes, and what it cannot",
        "",
        "- A law changes the energy removed per impact and how it splits between the normal "
        "and the tangential direction; on a period-one orbit the drive's work fixes the "
        "total, so the laws fitted to the same orbit remove energies of the same order "
        "there (the calibration table) and differ elsewhere (the tables above: regimes, "
        "maps, mean heights).",
        "- Walton's beta0 > 0 returns part of the tangential energy to the ball's "
        "rebound; the spin then reverses the contact point's slip as real spheres do, which "
        "Kane and Levinson's sticking impact (beta0 = 0) cannot.",
        "- The speed-dependent laws make slow impacts nearly elastic: a ball coming to "
        "rest chatters longer and the low-velocity rule takes over sooner. The "
        "viscoelastic series cannot go below e = 0.583 (its minimum), so it cannot remove "
        "the energy of the paper's orbit when that needs a lower e: its calibration says so "
        "rather than return a value.",
        "- No law here models the wall's vibration, a rough or wearing surface or the "
        "scatter of e from impact to impact (Montaine et al.); none changes the flight "
        "between impacts.",
    ]
