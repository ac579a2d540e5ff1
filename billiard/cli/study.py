"""The commands over scenes and runs: scenes, calibrate, plot, lyapunov, bench, reproduce."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from billiard.analysis.phase import DEFAULT_PHASE_REFERENCE
from billiard.cli.common import UserError, _note, add_set_argument, check_output_folder
from billiard.cli.figure_options import add_figure_arguments


def cmd_scenes(args: argparse.Namespace) -> int:
    from billiard.scene.scene import builtin_scenes

    scenes = builtin_scenes()
    width = max(map(len, scenes))
    for name, description in scenes.items():
        print(f"{name:<{width}}  {description}")
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    import json

    from billiard.analysis.calibrate import calibrate_law
    from billiard.scene.scene import load_scene

    if args.impacts < 1:
        raise UserError(f"calibrate: --impacts must be >= 1, got {args.impacts}")
    if args.parameter is None and args.law is None:
        raise UserError("calibrate: give --parameter KEY, or --law NAME to fit its main parameter")
    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    started = time.perf_counter()
    scene, result = calibrate_law(
        scene,
        args.target_height,
        law=args.law,
        parameter=args.parameter,
        low=args.low,
        high=args.high,
        impacts=args.impacts,
    )
    parameter = result.parameter
    if args.json:
        print(json.dumps({**result.as_dict(), "law": scene.contact.law}))
        return 0
    o = result.orbit
    print(
        f"{parameter} = {result.value:.6g}  "
        f"(period-one orbit at q2 = {o.height:.6f} m, target {args.target_height} m; "
        f"impact law {scene.contact.law})"
    )
    print(
        f"orbit: time of flight {o.time_of_flight:.6f} s, locked after {o.impacts_to_lock} "
        f"impacts from the scene's initial state, energy {o.energy:.4e} J"
    )
    print(
        f"normalized point (q2/q2max, u4/u4max) = ({o.q2_normalized:.4f}, "
        f"+-{abs(o.u4_normalized):.4f})   paper: (0.376, +-0.0372)"
    )
    print(
        "q2max = E0/(m g), u4max = sqrt(2 E0/m), E0 the energy after the impact above the "
        f"lowest position of the ball's centre, spin left out (phase reference "
        f"{DEFAULT_PHASE_REFERENCE!r}; the candidates are compared in "
        "docs/paper-reproduction.md)"
    )
    print(
        f"energy the impact law removes per impact at the orbit: {o.dissipated:.4e} J, "
        f"{o.dissipated / o.relative_energy:.1%} of the ball's kinetic energy relative to "
        "the wall"
    )
    print(f"{result.evaluations} runs, {time.perf_counter() - started:.1f} s")
    return 0


# --- plot ------------------------------------------------------------------------------


def cmd_plot(args: argparse.Namespace) -> int:
    from billiard.cli.figure_options import figure_options

    options = figure_options(args, "plot")  # checked before the plotting stack loads
    from billiard.plot import parse_frame_interval, parse_window, plot_run

    interval = None if args.frame_interval is None else parse_frame_interval(args.frame_interval)
    window = None if args.window is None else parse_window(args.window)
    paths = plot_run(
        Path(args.dir),
        Path(args.out) if args.out else None,
        frame_interval=interval,
        window=window,
        gif=not args.no_gif,
        **options,
    )
    for path in paths:
        print(f"wrote {path}")
    return 0


def cmd_lyapunov(args: argparse.Namespace) -> int:
    from billiard.analysis.lyapunov import check_arguments, format_lyapunov, lyapunov_exponent
    from billiard.scene.scene import load_scene

    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    check_arguments(scene, impacts=args.impacts, transient=args.transient, d0=args.d0)
    result = lyapunov_exponent(
        scene, impacts=args.impacts, transient=args.transient, d0=args.d0, method=args.method
    )
    print(format_lyapunov(result))
    return 3 if result.undefined is not None else 0


def cmd_bench(args: argparse.Namespace) -> int:
    from billiard.cli.bench import run_bench

    if args.out:
        check_output_folder(args.out, "bench --out")
    return run_bench(args)


def cmd_reproduce(args: argparse.Namespace) -> int:
    from billiard.reproduce.paper import run_reproduce

    if args.runs is None:
        args.runs = "runs/paper" if args.laws is None else "runs/laws"
    # a folder that cannot be made fails here in one line, not after minutes of work
    check_output_folder(args.runs, "reproduce --runs")
    if args.docs is not None:
        check_output_folder(args.docs, "reproduce --docs")
    if args.laws is not None:
        from billiard.reproduce.laws import run_laws

        return run_laws(args)
    return run_reproduce(args)


def add_scenes_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scenes", help="list the built-in scenes")
    p.set_defaults(func=cmd_scenes)


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "calibrate",
        help="fit a parameter to a period-one orbit's height",
        description="Find the value of a scene parameter for which the ball "
        "locks into a period-one orbit with impacts at the target "
        "height (the paper's calibration).",
    )
    p.add_argument("scene", help="built-in scene name or a .toml file")
    p.add_argument(
        "--parameter",
        help="dotted scene key, e.g. drive.amplitude or contact.restitution (default with "
        "--law: the law's main parameter)",
    )
    p.add_argument(
        "--law",
        metavar="NAME",
        help="run under the impact law NAME (contact.law; its other parameters at their "
        "defaults where the scene has none, docs/impact-laws.md) and fit its main "
        "parameter unless --parameter says another",
    )
    p.add_argument(
        "--target-height",
        type=float,
        required=True,
        metavar="H",
        help="height q2 of the ball centre at the orbit's impacts (m)",
    )
    p.add_argument(
        "--low",
        type=float,
        help="lower end of the scan, in the parameter's unit (default: value/4)",
    )
    p.add_argument(
        "--high",
        type=float,
        help="upper end of the scan, in the parameter's unit (default: 4 x value)",
    )
    p.add_argument("--impacts", type=int, default=1500, help="impacts per trial run (default 1500)")
    add_set_argument(p, "override a scene key first (repeatable)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_calibrate)

    p = sub.add_parser(
        "plot",
        help="draw the paper's plots of a run",
        description="Return map, time-of-flight map, phase plot, trajectory "
        "and animation from DIR/collisions.csv and DIR/scene.toml. The maps and the "
        "phase plot draw each impact as a dot, and above 50,000 impacts a density image "
        "of the impacts per bin with a colour bar.",
    )
    p.add_argument("dir", help="run directory")
    p.add_argument("--out", metavar="DIR", help="where to write the figures (default: DIR)")
    p.add_argument(
        "--frame-interval",
        metavar="S",
        help="also show what a camera with this frame interval (s, e.g. 0.0333 or 1/30) "
        "would record (default: no camera view)",
    )
    p.add_argument(
        "--window",
        metavar="N0:N1",
        help="impacts N0 <= n < N1 drawn in the trajectory and GIF (either may be "
        "left out; default: the last four drive periods)",
    )
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    add_figure_arguments(p)
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser(
        "lyapunov",
        help="largest Lyapunov exponent of a scene's trajectory",
        description="Largest Lyapunov exponent (per impact and per second) "
        "from two nearby trajectories with renormalization. Exit status 3 when the "
        "exponent is undefined (a ball that never flies).",
    )
    p.add_argument("scene", help="built-in scene name or a .toml file")
    p.add_argument("--impacts", type=int, default=5000, help="impacts to average over (>= 1)")
    p.add_argument("--transient", type=int, default=0, help="impacts skipped first (>= 0)")
    p.add_argument(
        "--d0",
        type=float,
        default=1e-9,
        help="initial separation of the two trajectories (m; at most 1e-3 of the ball radius)",
    )
    p.add_argument("--method", choices=["event", "rk4"], help="default: the scene's")
    add_set_argument(p, "override a scene key first (repeatable)")
    p.set_defaults(func=cmd_lyapunov)

    from billiard.cli.bench import add_bench_arguments  # argparse only: cheap

    p = sub.add_parser(
        "bench",
        help="speed against accuracy; writes docs/performance.md",
        description="Work-precision, failure boundaries, model ladder and "
        "throughput; writes docs/performance.md and its charts.",
    )
    add_bench_arguments(p)
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser(
        "reproduce",
        help="regenerate docs/paper-reproduction.md",
        description="Calibrate, run the four paper scenes, draw the paper's "
        "figures and write docs/paper-reproduction.md.",
    )
    p.add_argument(
        "--docs",
        metavar="DIR",
        help="where the report and its figures go (default: docs for the full reproduction "
        "with the default settings, else the --runs folder)",
    )
    p.add_argument(
        "--runs",
        help="where the runs go (default runs/paper; with --laws runs/laws)",
    )
    p.add_argument(
        "--laws",
        nargs="?",
        const="all",
        metavar="NAMES",
        help="instead: compare impact laws (all, or a comma-separated list of contact.law "
        "names): calibrate each on the paper's orbit, run the four paper scenes under each "
        "and write docs/impact-laws.md with its figures",
    )
    p.add_argument(
        "--collisions", type=int, default=25000, help="impacts per scene (default 25000)"
    )
    p.add_argument(
        "--lyapunov",
        type=int,
        default=2000,
        metavar="N",
        help="impacts for each Lyapunov exponent (0 to skip; default 2000)",
    )
    p.set_defaults(func=cmd_reproduce)
