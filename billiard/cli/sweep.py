"""billiard sweep: parameter sweeps on local processes or a Dask cluster."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from billiard.cli.common import UserError, add_set_argument


def cmd_sweep(args: argparse.Namespace) -> int:
    from billiard.sweep.definition import (
        Sweep,
        SweepError,
        check_keys,
        is_sweep_file,
        parse_vary,
        read_sweep_file,
    )
    from billiard.sweep.execute import SweepInterrupted, run_sweep

    settings = {
        name: getattr(args, name)
        for name in ("impacts", "transient", "keep", "duration")
        if getattr(args, name) is not None
    }
    if args.lyapunov:
        settings["lyapunov"] = True
    if args.skip_invalid:
        settings["skip_invalid"] = True
    try:
        if args.resume is not None:
            given = args.scene or args.file or args.vary or args.set or args.out or settings
            if given:
                raise UserError(
                    "sweep --resume DIR continues a sweep as it was set up: give no SCENE, "
                    "--file, --vary, --set, --out or measurement options with it"
                )
            directory = Path(args.resume)
            sweep = None
        else:
            if args.scene and args.file:
                raise UserError("sweep: give SCENE or --file SWEEP.toml, not both")
            source = args.file or args.scene
            if not source:
                raise UserError(
                    "sweep: give a SCENE and --vary KEY=START:STOP:N, a sweep file, or --resume DIR"
                )
            axes = [parse_vary(text) for text in args.vary]
            changes = list(args.set)
            if args.file or is_sweep_file(source):
                scene, file_axes, file_settings, changes = read_sweep_file(source, args.set)
                axes = [*file_axes, *axes]
                settings = {**file_settings, **settings}
            else:
                from billiard.scene.scene import load_scene

                scene = load_scene(source, overrides=args.set)
            if not axes:
                raise UserError("sweep: nothing to vary; give --vary KEY=START:STOP:N")
            check_keys(scene, axes)
            sweep = Sweep(scene, tuple(axes), **settings, changes=tuple(changes))
            directory = Path(args.out) if args.out else Path("runs") / f"sweep-{scene.name}"
        outcome = run_sweep(
            sweep,
            directory,
            workers=args.workers,
            dask=args.dask,
            resume=args.resume is not None,
            plots=not args.no_plot,
            yes=args.yes,
            device=args.device,
        )
    except SweepError as exc:
        raise UserError(str(exc)) from None
    except SweepInterrupted as exc:
        again = f"billiard sweep --resume {exc.directory}"
        print(
            f"billiard: interrupted: {exc.done} of {exc.total} points kept in "
            f"{exc.directory}; continue with `{again}`",
            file=sys.stderr,
        )
        return 130
    except OSError as exc:
        where = f": {exc.filename}" if exc.filename else ""
        raise UserError(f"cannot write the sweep: {exc.strerror or exc}{where}") from None
    total = sum(outcome.statuses.values())
    kinds = ", ".join(f"{n} {name}" for name, n in sorted(outcome.classes.items()))
    print(
        f"sweep: {total} points ({len(outcome.computed)} computed now on {outcome.where}): {kinds}"
    )
    print(
        f"wrote {outcome.result} (open with xarray.open_dataset or scipy.io.netcdf_file)"
        + (f"; plots: {', '.join(p.name for p in outcome.plots)}" if outcome.plots else "")
    )
    failed = outcome.statuses.get("failed", 0)
    for record in outcome.failed_examples:
        print(f"billiard: point {record['index']} failed: {record['reason']}", file=sys.stderr)
    if failed > len(outcome.failed_examples):
        more = failed - len(outcome.failed_examples)
        print(f"billiard: ... {more} more failed (see status, reason)", file=sys.stderr)
    if not outcome.measured:
        # nothing was measured: not a result to pass on as a success
        counts = " and ".join(f"{n} {name}" for name, n in sorted(outcome.statuses.items()))
        print(
            f"billiard: error: no point of the sweep was measured ({counts}); the reasons "
            f"are in {outcome.result} (status, reason)",
            file=sys.stderr,
        )
        return 3
    return 0


def _add_sweep_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="vary scene keys over a grid; attractor, heights, times of flight per point",
        description="Run a scene over a grid of values of one or more scene keys (any "
        "dotted key; initial.* gives a basin map), in parallel, and write DIR/sweep.nc "
        "(netCDF) and plots. Every finished chunk of points is kept in DIR/points.npy; after "
        "Ctrl-C or a kill, `billiard sweep --resume DIR` computes only the rest. "
        "See docs/sweeps.md.",
    )
    p.add_argument(
        "scene",
        nargs="?",
        help="built-in scene name, a scene .toml file, or a sweep .toml file (one with "
        "a [vary] table)",
    )
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=START:STOP:N",
        help="a swept key: N values from START to STOP, or KEY=v1,v2,... (repeatable: a grid)",
    )
    p.add_argument("--file", metavar="SWEEP.toml", help="a sweep file (see docs/sweeps.md)")
    add_set_argument(p, "override a key of the base scene (repeatable)")
    p.add_argument(
        "--impacts",
        type=int,
        help="impacts measured per point, after the transient (default: 2000)",
    )
    p.add_argument(
        "--transient", type=int, help="impacts simulated first, not measured (default: 500)"
    )
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="simulated time per point at most (s, up to 1e9; default: none, or the "
        "scene's run.duration)",
    )
    p.add_argument(
        "--keep",
        type=int,
        metavar="K",
        help="last K impact heights and times stored (default: 100)",
    )
    p.add_argument(
        "--lyapunov",
        action="store_true",
        help="also the largest Lyapunov exponent per point (about three times the cost)",
    )
    p.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: all cores)"
    )
    p.add_argument(
        "--device",
        choices=("cpu", "gpu"),
        default="cpu",
        help="where the points' trajectories run: cpu (default: the worker processes) or "
        'gpu (an NVIDIA GPU through numba-cuda, pip install "realworld-billiard[gpu]"; '
        "the same physics, not the same bits: docs/sweeps.md)",
    )
    p.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run the points on this dask.distributed scheduler, e.g. tcp://host:8786",
    )
    p.add_argument(
        "--resume", metavar="DIR", help="compute the points an interrupted sweep in DIR lacks"
    )
    p.add_argument("--out", metavar="DIR", help="output folder (default runs/sweep-SCENE)")
    p.add_argument(
        "--skip-invalid",
        action="store_true",
        help="record points whose scene is invalid (e.g. a start inside the wall) as "
        "invalid instead of refusing the sweep (kept for --resume)",
    )
    p.add_argument("--no-plot", action="store_true", help="do not draw the plots")
    p.add_argument(
        "--yes",
        action="store_true",
        help="run a sweep beyond 100,000 points or about 1 GB of output files (refused "
        "without it, naming the estimate)",
    )
    p.set_defaults(func=cmd_sweep)
