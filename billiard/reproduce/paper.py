"""Reproduce the paper: calibration, the four runs, the figures and docs/paper-reproduction.md.

``billiard reproduce`` runs everything; each number in the document is computed here from
the runs it makes, nothing is typed in by hand except the paper's own claims.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from billiard.analysis.calibrate import CalibrationError
from billiard.plot import paper_figure, paper_models_figure, paper_phase_figure, plot_run
from billiard.reproduce.runs import (
    CAMERA_FRAME,
    PhasesCalibration,
    calibrate_paper,
    compare_models,
    run_scene,
)
from billiard.reproduce.text import ENDING, markdown, models_section
from billiard.scene.scene import PAPER_SCENES, load_scene

FIG2_SCENES = ("wedge-6.6hz", "hyperbola-5.8hz", "hyperbola-4.5hz")


def reproduce(
    docs: Path, runs_dir: Path, collisions: int = 25000, lyapunov_impacts: int = 0
) -> Path:
    started = time.perf_counter()
    figures = docs / "figures" / "paper"
    figures.mkdir(parents=True, exist_ok=True)
    print("calibrating drive.amplitude on parabola-5.4hz ...", flush=True)
    parabola = load_scene("parabola-5.4hz")
    cal = calibrate_paper(parabola)
    print('calibrating it again under contact.model = "phases" ...', flush=True)
    t0 = time.perf_counter()
    try:
        cal_ph = PhasesCalibration(calibrate_paper(parabola, "phases"), None, 0.0)
    except CalibrationError as exc:
        cal_ph = PhasesCalibration(None, str(exc), 0.0)
    cal_ph.wall_time = time.perf_counter() - t0
    stats, phases = [], []
    for name in PAPER_SCENES:
        print(f"running {name} ({collisions} impacts) ...", flush=True)
        s = run_scene(name, runs_dir, collisions)
        stats.append(s)
        print(f'running {name} under "phases" for {s.simulated_time:.1f} s ...', flush=True)
        phases.append(compare_models(name, runs_dir, collisions, impacts=s)[1])
    if lyapunov_impacts:
        try:
            from billiard.analysis.lyapunov import lyapunov_exponent
        except ImportError:  # pragma: no cover - analysis module absent
            lyapunov_exponent = None
        if lyapunov_exponent is not None:
            for s in stats:
                print(f"Lyapunov exponent of {s.scene} ...", flush=True)
                s.lyapunov = lyapunov_exponent(
                    load_scene(s.scene), impacts=lyapunov_impacts
                ).per_impact
    fig2 = paper_figure([runs_dir / n for n in FIG2_SCENES], figures / "fig2-maps.png")
    fig2c = paper_figure(
        [runs_dir / n for n in FIG2_SCENES],
        figures / "fig2-maps-camera.png",
        frame_interval=CAMERA_FRAME,
    )
    fig3 = paper_phase_figure([runs_dir / n for n in FIG2_SCENES], figures / "fig3-phase.png")
    models = paper_models_figure(
        [runs_dir / n for n in PAPER_SCENES],
        [runs_dir / "phases" / n for n in PAPER_SCENES],
        figures / "maps-impacts-vs-phases.png",
    )
    fig3p = paper_phase_figure(
        [runs_dir / "phases" / n for n in FIG2_SCENES], figures / "fig3-phase-phases.png"
    )
    par = plot_run(runs_dir / "parabola-5.4hz", figures / "parabola-5.4hz", gif=False)
    for name in FIG2_SCENES:
        plot_run(runs_dir / name, figures / name, gif=False)
    fig = {
        "fig2": fig2,
        "fig2c": fig2c,
        "fig3": fig3,
        "models": models,
        "fig3p": fig3p,
        "parabola": {p.stem: p for p in par},
    }
    elapsed = time.perf_counter() - started
    text = markdown(cal, stats, parabola, collisions, docs, fig, elapsed)
    text += models_section(stats, phases, cal, cal_ph, docs, fig)
    text += ENDING
    path = docs / "paper-reproduction.md"
    path.write_text(text)
    return path


class ReproduceError(ValueError):
    """Arguments of ``billiard reproduce`` that cannot work; the message is one line."""


#: The full reproduction, the only one whose report goes into the committed docs.
FULL_COLLISIONS = 25000
FULL_LYAPUNOV = 2000


def check_writable(folder: Path, what: str) -> None:
    """Refuse, before any work, a folder that cannot be created or written.

    Raises:
        ReproduceError: the folder, or the nearest existing folder above it, is not a
            writable folder (or an existing report or figure in it is read-only).
    """
    probe = folder
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        raise ReproduceError(f"{what} {folder}: {probe} is not a folder")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ReproduceError(f"{what} {folder}: cannot write in {probe} (read-only)")


def check_outputs(runs: Path, docs: Path, page: str, figures: str) -> None:
    """Refuse, before any work, output folders that cannot be written, or a page
    ``docs/page`` or figure folder ``docs/figures/figures`` that exists read-only.

    Raises:
        ReproduceError: one line naming the folder or file.
    """
    check_writable(runs, "--runs")
    check_writable(docs, "--docs")
    for path in (docs / page, docs / "figures" / figures):
        if path.exists() and not os.access(path, os.W_OK):
            raise ReproduceError(f"--docs {docs}: {path} is read-only")


def run_reproduce(args: argparse.Namespace) -> int:
    if isinstance(args.collisions, bool) or args.collisions < 1:
        raise ReproduceError(f"reproduce: --collisions must be >= 1, got {args.collisions}")
    if args.lyapunov < 0:
        raise ReproduceError(f"reproduce: --lyapunov must be >= 0 (0 skips), got {args.lyapunov}")
    full = args.collisions == FULL_COLLISIONS and args.lyapunov == FULL_LYAPUNOV
    runs = Path(args.runs)
    if args.docs is not None:
        docs = Path(args.docs)
    elif full:
        docs = Path("docs")
    else:
        docs = runs
    check_outputs(runs, docs, "paper-reproduction.md", "paper")
    if args.docs is None and not full:
        print(
            f"billiard: note: not the full reproduction (--collisions {args.collisions}, "
            f"--lyapunov {args.lyapunov}): the report goes to {docs / 'paper-reproduction.md'} "
            f"and its figures to {docs / 'figures' / 'paper'}, not to docs/ "
            "(give --docs DIR to choose)",
            file=sys.stderr,
        )
    started = time.perf_counter()
    path = reproduce(docs, runs, args.collisions, args.lyapunov)
    print(f"wrote {path} ({time.perf_counter() - started:.0f} s)")
    return 0
