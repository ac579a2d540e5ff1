"""billiard hysteresis | uncertainty: analyses over many trajectories at once, on the
ensemble kernel (docs/sweeps.md, "Up/down sweeps" and "The uncertainty exponent")."""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from billiard.cli.common import UserError, _note, add_set_argument, check_output_folder


def _scene(args: argparse.Namespace, command: str):
    from billiard.engine.ensemble import supports
    from billiard.scene.scene import load_scene

    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    why = supports(scene)
    if why is not None:
        raise UserError(f"{command}: the ensemble kernel does not take scene {scene.name!r}: {why}")
    return scene


def _counts(args: argparse.Namespace, command: str) -> None:
    from billiard.scene.spec import MAX_COLLISIONS

    if args.impacts < 1:
        raise UserError(f"{command}: --impacts must be >= 1, got {args.impacts}")
    if args.transient < 0:
        raise UserError(f"{command}: --transient must be >= 0, got {args.transient}")
    if args.impacts + args.transient > MAX_COLLISIONS:
        raise UserError(
            f"{command}: --transient + --impacts = {args.transient + args.impacts:,} impacts "
            f"per trajectory; at most {MAX_COLLISIONS:,}"
        )


def _write(command: str, path: Path, write, kept: list[Path]) -> Path:
    """``write()`` (which writes ``path``), with a failure (a full disk, a quota) said
    in one line naming the file, the reason and the files already written."""
    try:
        return write()
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        done = f"; kept {', '.join(str(p) for p in kept)}" if kept else ""
        raise UserError(f"{command}: cannot write {path}: {reason}{done}") from None


def _too_large(command: str, exc: Exception) -> UserError:
    """An estimate over the limit (OutputSizeError), worded with --yes."""
    return UserError(f"{command}: {exc.confirmed_by('--yes')}")


def _progress(label: str):
    """A progress line on stderr when it is a terminal, else nothing."""
    if not sys.stderr.isatty():
        return None

    def report(done: int, total: int) -> None:
        end = "\n" if done >= total else ""
        print(f"\r{label}: {done}/{total}", end=end, file=sys.stderr, flush=True)

    return report


# --- hysteresis ------------------------------------------------------------------------


def cmd_hysteresis(args: argparse.Namespace) -> int:
    from billiard.sweep.definition import SweepError, check_keys, parse_vary

    _counts(args, "hysteresis")
    if args.starts < 1:
        raise UserError(f"hysteresis: --starts must be >= 1, got {args.starts}")
    try:
        axis = parse_vary(args.vary)
    except SweepError as exc:
        raise UserError(f"hysteresis: {exc}") from None
    values = axis.values  # not materialised: a range of 10^9 values is refused by size
    if len(values) < 2:
        raise UserError(f"hysteresis: --vary {args.vary}: an up/down sweep needs >= 2 values")
    if not axis.numeric:
        raise UserError(f"hysteresis: --vary {args.vary}: the values must be numbers")
    if axis.key.startswith("initial."):
        raise UserError(
            f"hysteresis: --vary {axis.key}: the ball's start cannot be swept up and down "
            "(every value continues from the last one's final state)"
        )
    from billiard.sweep.hysteresis import REFUSED

    if axis.key in REFUSED:
        raise UserError(f"hysteresis: --vary {axis.key}: {REFUSED[axis.key]}")
    scene = _scene(args, "hysteresis")
    try:
        check_keys(scene, [axis])
    except SweepError as exc:
        raise UserError(f"hysteresis: {exc}") from None
    from billiard.run.output_size import OutputSizeError
    from billiard.sweep.hysteresis import check_size

    if not args.yes:  # before the scene's set-up: refused at once
        try:
            check_size(len(values), args.starts)
        except OutputSizeError as exc:
            raise _too_large("hysteresis", exc) from None
    out = Path(args.out) if args.out else Path("runs") / f"hysteresis-{scene.name}"
    check_output_folder(out, "--out")

    from billiard.scene.scene import SceneError
    from billiard.sweep.hysteresis import hysteresis_figure, run_hysteresis, write_csv

    report = _progress("hysteresis: values")
    try:
        result = run_hysteresis(
            scene,
            axis.key,
            [float(v) for v in values],
            starts=args.starts,
            impacts=args.impacts,
            transient=args.transient,
            progress=None if report is None else (lambda _d, i, n: report(i + 1, n)),
            allow_large=True,  # checked above, with --yes
        )
    except (ValueError, SceneError) as exc:
        raise UserError(f"hysteresis: {exc}") from None
    _write("hysteresis", out, lambda: out.mkdir(parents=True, exist_ok=True), [])
    path = out / "hysteresis.csv"
    table = _write("hysteresis", path, lambda: write_csv(result, path), [])
    path = out / "hysteresis.png"
    figure = _write("hysteresis", path, lambda: hysteresis_figure(result, path), [table])
    n = result.q1_start.size
    differ = int((result.columns["period"][0] != result.columns["period"][1]).sum())
    print(
        f"hysteresis: {axis.key} up and down over {len(values)} values, {n} start(s), "
        f"{2 * len(values) * n * (args.transient + args.impacts):,} impacts in "
        f"{result.seconds:.1f} s; {differ} of {len(values) * n} (value, start) pairs end "
        "in a different period up and down"
    )
    print(f"wrote {table} and {figure}")
    return 0


# --- uncertainty -----------------------------------------------------------------------


def _interval(text: str, option: str) -> tuple[float, float]:
    parts = text.split(":")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        raise UserError(f"uncertainty: {option} {text}: give LO:HI in metres") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
        raise UserError(f"uncertainty: {option} {text}: give LO:HI with LO < HI (m)")
    return lo, hi


def _eps(text: str) -> tuple[float, float, int]:
    """``--eps LO:HI:N`` read and checked (the N values are made after the size check)."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        lo, hi, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise UserError(
            f"uncertainty: --eps {text}: give LO:HI:N (m, N displacements spaced evenly in log)"
        ) from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not 0.0 < lo < hi or count < 2:
        raise UserError(f"uncertainty: --eps {text}: need 0 < LO < HI (m) and N >= 2")
    return lo, hi, count


def cmd_uncertainty(args: argparse.Namespace) -> int:
    import numpy as np

    from billiard.run.output_size import OutputSizeError
    from billiard.sweep.uncertainty import MIN_SAMPLES, SAMPLES_WHY, check_size

    _counts(args, "uncertainty")
    if args.samples < MIN_SAMPLES:
        raise UserError(
            f"uncertainty: --samples must be >= {MIN_SAMPLES}, got {args.samples}: {SAMPLES_WHY}"
        )
    q1 = _interval(args.q1, "--q1")
    q2 = _interval(args.q2, "--q2")
    lo, hi, count = _eps(args.eps)
    if not args.yes:
        try:
            check_size(args.samples, count)
        except OutputSizeError as exc:
            raise _too_large("uncertainty", exc) from None
    eps = [float(e) for e in np.geomspace(lo, hi, count)]
    scene = _scene(args, "uncertainty")
    out = Path(args.out) if args.out else Path("runs") / f"uncertainty-{scene.name}"
    check_output_folder(out, "--out")

    from billiard.scene.scene import SceneError
    from billiard.sweep.uncertainty import run_uncertainty, uncertainty_figure, write_results

    try:
        result = run_uncertainty(
            scene,
            q1,
            q2,
            samples=args.samples,
            eps=eps,
            impacts=args.impacts,
            transient=args.transient,
            seed=args.seed,
            progress=_progress("uncertainty: trajectories"),
            allow_large=True,  # checked above, with --yes
        )
    except (ValueError, SceneError) as exc:
        raise UserError(f"uncertainty: {exc}") from None
    paths = _write("uncertainty", out, lambda: write_results(result, out), [])
    path = out / "uncertainty.png"
    paths.append(_write("uncertainty", path, lambda: uncertainty_figure(result, path), paths))
    pairs = zip(result.labels, result.counts, strict=True)
    reached = ", ".join(f"{label} {n}" for label, n in pairs)
    print(
        f"uncertainty: {result.samples} starts ({result.dropped} dropped for a neighbour "
        f"q1 +- eps outside the container), {result.samples * (1 + 2 * len(eps)):,} "
        f"trajectories in {result.seconds:.1f} s; attractors of the starts: {reached}"
    )
    for e, u, f in zip(result.eps, result.uncertain, result.fraction, strict=True):
        print(f"  eps {e:.3g} m: {u} uncertain, f = {f:.4g}")
    if math.isfinite(result.alpha):
        se = "" if not math.isfinite(result.alpha_se) else f" +- {result.alpha_se:.3f}"
        print(
            f"alpha = {result.alpha:.3f}{se}, boundary dimension d = 2 - alpha = "
            f"{result.dimension:.3f} (fit over {int(result.used.sum())} eps with 0 < f < 1)"
        )
    else:
        print(
            "alpha: not estimated: fewer than 2 eps have 0 < f < 1 (no start near a basin "
            "boundary at these eps; more samples, another box, or one attractor only)"
        )
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "hysteresis",
        help="up/down sweep of a scene key, each value continuing from the last one's state",
        description="Sweep one numeric scene key up through its values and back down; at "
        "each value every trajectory continues from its own state after the previous value "
        "(time, drive angle, position, velocity, spin) and is measured as a sweep point. "
        "Writes DIR/hysteresis.csv and DIR/hysteresis.png. See docs/sweeps.md.",
    )
    p.add_argument("scene", help="built-in scene name or a scene .toml file")
    p.add_argument(
        "--vary",
        required=True,
        metavar="KEY=START:STOP:N",
        help="the swept key and its values (N >= 2 from START to STOP, or KEY=v1,v2,...; "
        "in the key's unit, e.g. drive.frequency in Hz)",
    )
    p.add_argument(
        "--starts",
        type=int,
        default=1,
        metavar="N",
        help="trajectories: 1 is the scene's own start; more are spread over the "
        "container on a grid (docs/sweeps.md)",
    )
    p.add_argument("--impacts", type=int, default=300, help="impacts measured per value")
    p.add_argument(
        "--transient", type=int, default=300, help="impacts simulated first at each value"
    )
    p.add_argument("--out", metavar="DIR", help="output folder (default runs/hysteresis-SCENE)")
    p.add_argument(
        "--yes",
        action="store_true",
        help="run beyond about 1 GB of memory or of hysteresis.csv (refused without it, "
        "naming the estimate)",
    )
    add_set_argument(p, "override a key of the scene (repeatable)")
    p.set_defaults(func=cmd_hysteresis)

    p = sub.add_parser(
        "uncertainty",
        help="uncertainty exponent of the basin boundaries over starting positions",
        description="Estimate the uncertainty exponent alpha of the basin boundaries "
        "(Grebogi, McDonald, Ott and Yorke 1983): the share f of random starts in the box "
        "whose attractor changes when q1 moves by +-eps, f ~ eps^alpha, and the boundary "
        "dimension d = 2 - alpha. Writes DIR/uncertainty.csv, DIR/uncertainty.json and "
        "DIR/uncertainty.png. See docs/sweeps.md.",
    )
    p.add_argument("scene", help="built-in scene name or a scene .toml file")
    # a range such as -0.04:0.04 is a value, not an option: argparse takes an argument
    # that starts with '-' for a value only when it matches this pattern (negative
    # numbers, by default); LO:HI:N ranges are added to it
    p._negative_number_matcher = re.compile(r"^-\d*\.?\d+([eE][-+]?\d+)?(:[-+.\deE]*)*$")
    p.add_argument("--q1", required=True, metavar="LO:HI", help="the box's q1 range (m)")
    p.add_argument("--q2", required=True, metavar="LO:HI", help="the box's q2 range (m)")
    p.add_argument(
        "--samples", type=int, default=2000, help="random valid starts in the box (>= 2)"
    )
    p.add_argument(
        "--eps",
        default="1e-6:1e-3:7",
        metavar="LO:HI:N",
        help="N displacements (m) from LO to HI, spaced evenly in log",
    )
    p.add_argument("--impacts", type=int, default=300, help="impacts measured per trajectory")
    p.add_argument(
        "--transient", type=int, default=300, help="impacts simulated first per trajectory"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the random starts")
    p.add_argument("--out", metavar="DIR", help="output folder (default runs/uncertainty-SCENE)")
    p.add_argument(
        "--yes",
        action="store_true",
        help="run beyond about 1 GB of memory (refused without it, naming the estimate)",
    )
    add_set_argument(p, "override a key of the scene (repeatable)")
    p.set_defaults(func=cmd_uncertainty)
