"""Command line: ``billiard derive | run | scenes``.

Errors a user can cause (a bad scene, a bad curve expression, a stop condition) print one
line and exit with status 2; no traceback.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path


class UserError(Exception):
    """An error to report in one line, without a traceback."""


def _user_errors() -> tuple[type[BaseException], ...]:
    """Exception classes that mean bad input or a documented stop, not a bug.

    Only modules already imported are consulted: one never imported cannot have raised,
    and importing them all would load sympy and scipy on every command (half a second).
    """
    errors: list[type[BaseException]] = [UserError]
    for module, names in (
        ("billiard.derivation.expr", ["CurveExpressionError"]),
        ("billiard.curves", ["CurveNotFoundError"]),
        ("billiard.scene", ["SceneError"]),
        ("billiard.errors", ["GeometryError", "SimulationError"]),
        ("billiard.derivation.curve", ["CurveDerivationError"]),
        ("billiard.calibrate", ["CalibrationError"]),
        ("billiard.analysis", ["LyapunovError"]),
        ("billiard.reproduce", ["ReproduceError"]),
        ("billiard.record", ["RunDataError"]),
        ("billiard.checkpoint", ["CheckpointError"]),
    ):
        mod = sys.modules.get(module)
        if mod is not None:
            errors += [getattr(mod, n) for n in names if hasattr(mod, n)]
    return tuple(errors)


# --- derive ----------------------------------------------------------------------------


def cmd_derive(args: argparse.Namespace) -> int:
    from .derivation import build
    from .derivation.expr import CurveExpressionError

    if args.curve is not None or args.name is not None:
        if not (args.curve and args.name):
            raise UserError("derive: --name and --curve go together")
        params = dict(_key_value(p, "--param") for p in args.param)
        from .curves import user_curve_dir

        directory = Path(args.dir) if args.dir else user_curve_dir()
        if args.dir:
            if directory.exists() and not directory.is_dir():
                raise UserError(f"derive --dir {directory}: not a directory")
            if not directory.exists() and not directory.parent.is_dir():
                raise UserError(
                    f"derive --dir {directory}: its parent directory {directory.parent} "
                    "does not exist"
                )
        started = time.perf_counter()
        try:
            path = build.derive_user_curve(
                args.name, args.curve, params, directory, force=args.force
            )
        except CurveExpressionError as exc:
            raise UserError(str(exc)) from None
        except OSError as exc:
            where = "" if args.dir else " (the user curve directory: $BILLIARD_HOME/curves)"
            raise UserError(
                f"derive: cannot write the curve to {directory}{where}: {exc.strerror or exc}"
            ) from None
        print(
            f"curve {args.name!r}: f(x) = {args.curve} -> {path} "
            f"({time.perf_counter() - started:.1f} s); a scene can now use "
            f'curve = "{args.name}"'
        )
        return 0
    root = build.repo_root()
    where = (
        f"{build.GENERATED} (source checkout {root})"
        if root is not None
        else f"{build.GENERATED}: the installed package, not a source checkout"
    )
    if args.check:
        print(f"derive --check: checking {where}")
        problems = build.check()
        for line in problems:
            print(line)
        if problems:
            print(f"derive --check: {len(problems)} file(s) differ; run `billiard derive`")
            return 1
        print("derive --check: generated/ is current")
        return 0
    print(f"derive: regenerating {where}")
    if root is None:
        print(
            "derive: changes made here are lost when the package is reinstalled; "
            "docs/derivation.md is written only in a source checkout"
        )
    started = time.perf_counter()
    written = build.regenerate()
    for path in written:
        print(f"wrote {path}")
    print(f"derive: {len(written)} file(s) changed ({time.perf_counter() - started:.1f} s)")
    return 0


class _DeriveParser(argparse.ArgumentParser):
    """``billiard derive``'s parser: an argument starting with a single '-' that is not
    one of its options is a value, so ``--curve -x**2 + ...`` needs no ``=``."""

    def _parse_optional(self, arg_string):
        if (
            arg_string.startswith("-")
            and not arg_string.startswith("--")
            and len(arg_string) > 1
            and arg_string not in self._option_string_actions
        ):
            return None
        return super()._parse_optional(arg_string)


def _key_value(text: str, flag: str) -> tuple[str, float]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise UserError(f"{flag} {text!r}: expected NAME=VALUE")
    try:
        return key.strip(), float(value)
    except ValueError:
        raise UserError(f"{flag} {text!r}: value is not a number") from None


# --- scenes ----------------------------------------------------------------------------


def cmd_scenes(args: argparse.Namespace) -> int:
    from .scene import builtin_scenes

    scenes = builtin_scenes()
    width = max(map(len, scenes))
    for name, description in scenes.items():
        print(f"{name:<{width}}  {description}")
    return 0


# --- run -------------------------------------------------------------------------------


class ProgressBar:
    """Progress of a run on stderr.

    On a terminal: a one-line bar, redrawn ten times a second. Otherwise (a log file, a
    batch job): one line every ``interval`` seconds with the impacts done, the simulated
    time (s, when ``clock`` is given: a callable returning it), the rate and the
    estimated time left.
    """

    def __init__(self, stream=None, width: int = 30, interval: float = 5.0, clock=None):
        self.stream = sys.stderr if stream is None else stream
        self.width = width
        self.interval = interval
        self.clock = clock
        self.enabled = _isatty(self.stream)
        self.started = time.perf_counter()
        self.last = 0.0 if self.enabled else self.started
        self.first_done: int | None = None
        self.first_time = self.started

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if self.first_done is None:  # a resumed run starts counting where it was
            self.first_done, self.first_time = done, now
        if self.enabled:
            if done < total and now - self.last < 0.1:
                return
            self.last = now
            frac = done / total if total else 1.0
            filled = int(self.width * frac)
            rate = (done - self.first_done) / max(now - self.first_time, 1e-9)
            self.stream.write(
                f"\r[{'#' * filled}{'.' * (self.width - filled)}] "
                f"{done}/{total} impacts, {rate:,.0f}/s "
            )
            if done >= total:
                self.stream.write("\n")
            self.stream.flush()
            return
        if done >= total or now - self.last < self.interval:
            return
        self.last = now
        self.stream.write(self.line(done, total, now) + "\n")
        self.stream.flush()

    def line(self, done: int, total: int, now: float) -> str:
        """The log line: impacts, simulated time, rate and estimated time left."""
        elapsed = max(now - self.first_time, 1e-9)
        rate = (done - (self.first_done or 0)) / elapsed
        parts = [f"billiard: {done:,}/{total:,} impacts"]
        if self.clock is not None:
            simulated = self.clock()
            if simulated is not None:
                parts.append(f"t = {simulated:.6g} s simulated")
        parts.append(f"{rate:,.0f} impacts/s")
        if rate > 0:
            parts.append(f"about {_duration((total - done) / rate)} left")
        return ", ".join(parts)

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _duration(seconds: float) -> str:
    """A wall-clock duration for humans: 42 s, 3 min 5 s, 2 h 10 min."""
    seconds = max(0.0, seconds)
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds // 60:.0f} min {seconds % 60:.0f} s"
    return f"{seconds // 3600:.0f} h {seconds % 3600 // 60:.0f} min"


def _note(line: str) -> None:
    print(f"billiard: note: {line}", file=sys.stderr)


def _frame_interval(text: str | None) -> float | None:
    """``--frame-interval`` in seconds: a number (0.0333) or a fraction (1/30), > 0."""
    if text is None:
        return None
    from fractions import Fraction

    try:
        value = float(Fraction(text.strip())) if "/" in text else float(text)
    except (ValueError, ZeroDivisionError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise UserError(
            f"--frame-interval {text!r} must be a positive number of seconds (e.g. 0.0333 or 1/30)"
        )
    return value


def _holds_run(folder: Path) -> bool:
    """Whether a folder holds a run's files (CSV, scene or checkpoint)."""
    from .persist import CHECKPOINT_NAME, CSV_NAME, SCENE_NAME

    return folder.is_dir() and any(
        (folder / name).exists() for name in (CSV_NAME, SCENE_NAME, CHECKPOINT_NAME)
    )


def _remove_plots(folder: Path) -> list[str]:
    """Delete the figures ``plot_run`` wrote into a run folder (they no longer match its
    data); returns the names removed."""
    from .plot.run import FIGURE_NAMES

    removed = []
    for name in FIGURE_NAMES:
        path = folder / name
        if path.is_file():
            path.unlink()
            removed.append(name)
    return removed


def _checkpoint_clock(folder: Path):
    """A clock for the progress line of a streamed run: the simulated time (s) of the
    run's last checkpoint (written every second, so at most a second behind), or None
    while there is none."""
    import json

    from .persist import CHECKPOINT_NAME

    def clock() -> float | None:
        try:
            data = json.loads((folder / CHECKPOINT_NAME).read_text(encoding="utf-8"))
            return float(data["engine"]["ball"]["t"])
        except (OSError, ValueError, KeyError, TypeError):
            return None

    return clock


def cmd_run(args: argparse.Namespace) -> int:
    import shlex
    import signal

    from .checkpoint import CheckpointError
    from .persist import CSV_NAME, SCENE_NAME, resume
    from .simulate import RunInterrupted, simulate

    # every argument is checked before any work
    frame_interval = _frame_interval(args.frame_interval)
    bar = ProgressBar()
    stale: list[str] = []  # plots removed because the data changed under them
    changed = False  # whether the run folder's data was changed
    if args.resume is not None:
        if args.scene or args.set or args.method or args.out or args.duration or args.overwrite:
            raise UserError(
                "run --resume DIR continues a run as it was set up: give no "
                "SCENE, --out, --set, --method, --duration or --overwrite with it"
            )
        out = Path(args.resume)
        if args.collisions is not None and args.collisions < 1:
            raise UserError(f"run: --collisions must be >= 1, got {args.collisions}")
    else:
        if not args.scene:
            raise UserError("run: give a SCENE (a built-in name or a .toml file), or --resume DIR")
        from .scene import load_scene, with_values

        scene = load_scene(args.scene, overrides=args.set, notify=_note)
        if args.duration is not None:
            with_values(scene, {"run.duration": args.duration})  # checks it
        out = Path(args.out) if args.out else Path("runs") / scene.name
        if _holds_run(out) and not args.overwrite:
            again = shlex.quote(str(out))
            raise UserError(
                f"run: {out} already holds a run; give --overwrite to replace it, or "
                f"continue it with `billiard run --resume {again}`"
            )
        if args.collisions is not None:
            with_values(scene, {"run.collisions": args.collisions})  # checks it
    bar.clock = _checkpoint_clock(out)
    try:
        try:
            if args.resume is not None:
                try:
                    result = resume(
                        out,
                        collisions=args.collisions,
                        progress=bar,
                        notify=lambda line: print(f"billiard: {line}", file=sys.stderr),
                    )
                except CheckpointError as exc:
                    raise UserError(f"cannot resume {out}: {exc}") from None
                if result.already_finished:
                    if result.stop_reason:
                        print(
                            f"billiard: {out}: the run already stopped after impact "
                            f"{len(result)}: {result.stop_reason}",
                            file=sys.stderr,
                        )
                        return 3
                    print(
                        f"billiard: {out}: the run is already complete ({len(result)} impacts); "
                        f"nothing to resume (--collisions N extends it)"
                    )
                    return 0
                changed = True
            else:
                changed = True
                try:
                    result = simulate(
                        scene,
                        collisions=args.collisions,
                        method=args.method,
                        out_dir=out,
                        progress=bar,
                        duration=args.duration,
                    )
                except CheckpointError as exc:  # another process is writing a run in DIR
                    changed = False
                    raise UserError(f"cannot run in {out}: {exc}") from None
        finally:  # end the progress bar's line before anything else is printed
            if bar.enabled:
                bar.stream.write("\n")
            if changed and out.is_dir():
                stale = _remove_plots(out)
    except RunInterrupted as exc:
        where = exc.out_dir or Path(".")
        again = f"billiard run --resume {shlex.quote(str(where))}"
        after = (
            ""
            if exc.checkpoint_rows == exc.rows
            else f" (it restarts after impact {exc.checkpoint_rows}, the last checkpoint)"
        )
        name = signal.Signals(exc.signum).name
        removed = f"; removed its outdated plots ({', '.join(stale)})" if stale else ""
        print(
            f"billiard: interrupted ({name}): {exc.rows} impacts kept in "
            f"{where / CSV_NAME}; continue with `{again}`{after}{removed}",
            file=sys.stderr,
        )
        return 128 + exc.signum
    except OSError as exc:
        where = f": {exc.filename}" if exc.filename else ""
        raise UserError(f"cannot write the run: {exc.strerror or exc}{where}") from None
    print(result.summary())
    print(f"wrote {out / CSV_NAME} and {out / SCENE_NAME}")
    if not args.no_plot and len(result) > 1:
        from .plot import plot_run

        try:
            paths = plot_run(out, frame_interval=frame_interval)
        except KeyboardInterrupt:
            print(
                f"billiard: interrupted while drawing the plots; the run is complete in "
                f"{out}; draw them with `billiard plot {shlex.quote(str(out))}`",
                file=sys.stderr,
            )
            return 130
        print(f"plots: {', '.join(p.name for p in paths)} in {out}")
    elif stale:
        print(
            f"removed the plots of the earlier data ({', '.join(stale)}) from {out}; "
            f"draw new ones with `billiard plot {shlex.quote(str(out))}`"
        )
    if result.stop_reason:
        print(f"billiard: stopped: {result.stop_reason}", file=sys.stderr)
        return 3
    return 0


# --- calibrate -------------------------------------------------------------------------


def cmd_calibrate(args: argparse.Namespace) -> int:
    import json

    from .calibrate import calibrate
    from .scene import load_scene

    if args.impacts < 1:
        raise UserError(f"calibrate: --impacts must be >= 1, got {args.impacts}")
    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    started = time.perf_counter()
    result = calibrate(
        scene,
        args.parameter,
        args.target_height,
        low=args.low,
        high=args.high,
        impacts=args.impacts,
    )
    if args.json:
        print(json.dumps(result.as_dict()))
        return 0
    o = result.orbit
    print(
        f"{args.parameter} = {result.value:.6g}  "
        f"(period-one orbit at q2 = {o.height:.6f} m, target {args.target_height} m)"
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
        "q2max = E/(m g), u4max = sqrt(2 E/m), E the mechanical energy after the impact "
        "(potential zero at q2 = 0, spin included)"
    )
    print(f"{result.evaluations} runs, {time.perf_counter() - started:.1f} s")
    return 0


# --- plot ------------------------------------------------------------------------------


def cmd_plot(args: argparse.Namespace) -> int:
    from .plot import parse_frame_interval, parse_window, plot_run

    interval = None if args.frame_interval is None else parse_frame_interval(args.frame_interval)
    window = None if args.window is None else parse_window(args.window)
    paths = plot_run(
        Path(args.dir),
        Path(args.out) if args.out else None,
        frame_interval=interval,
        window=window,
        gif=not args.no_gif,
    )
    for path in paths:
        print(f"wrote {path}")
    return 0


def cmd_lyapunov(args: argparse.Namespace) -> int:
    from .analysis import check_arguments, format_lyapunov, lyapunov_exponent
    from .scene import load_scene

    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    check_arguments(scene, impacts=args.impacts, transient=args.transient, d0=args.d0)
    result = lyapunov_exponent(
        scene, impacts=args.impacts, transient=args.transient, d0=args.d0, method=args.method
    )
    print(format_lyapunov(result))
    return 3 if result.undefined is not None else 0


def cmd_bench(args: argparse.Namespace) -> int:
    from .bench import run_bench

    return run_bench(args)


def cmd_reproduce(args: argparse.Namespace) -> int:
    from .reproduce import run_reproduce

    return run_reproduce(args)


# --- sweep -----------------------------------------------------------------------------


def cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep.definition import (
        Sweep,
        SweepError,
        check_keys,
        is_sweep_file,
        parse_vary,
        read_sweep_file,
    )
    from .sweep.execute import SweepInterrupted, run_sweep

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
            if args.file or is_sweep_file(source):
                scene, file_axes, file_settings, _ = read_sweep_file(source, args.set)
                axes = [*file_axes, *axes]
                settings = {**file_settings, **settings}
            else:
                from .scene import load_scene

                scene = load_scene(source, overrides=args.set)
            if not axes:
                raise UserError("sweep: nothing to vary; give --vary KEY=START:STOP:N")
            check_keys(scene, axes)
            sweep = Sweep(scene, tuple(axes), **settings)
            directory = Path(args.out) if args.out else Path("runs") / f"sweep-{scene.name}"
        outcome = run_sweep(
            sweep,
            directory,
            workers=args.workers,
            dask=args.dask,
            resume=args.resume is not None,
            plots=not args.no_plot,
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
    from collections import Counter

    classes = Counter(r["attractor"] for r in outcome.records)
    kinds = ", ".join(f"{n} {name}" for name, n in sorted(classes.items()))
    print(
        f"sweep: {len(outcome.records)} points ({len(outcome.computed)} computed now on "
        f"{outcome.where}): {kinds}"
    )
    print(
        f"wrote {outcome.result} (open with xarray.open_dataset or scipy.io.netcdf_file)"
        + (f"; plots: {', '.join(p.name for p in outcome.plots)}" if outcome.plots else "")
    )
    failed = [r for r in outcome.records if r["status"] == "failed"]
    for record in failed[:5]:
        print(f"billiard: point {record['index']} failed: {record['reason']}", file=sys.stderr)
    if len(failed) > 5:
        print(f"billiard: ... {len(failed) - 5} more failed (see status, reason)", file=sys.stderr)
    return 0


def _add_sweep_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="vary scene keys over a grid; attractor, heights, times of flight per point",
        description="Run a scene over a grid of values of one or more scene keys (any "
        "dotted key; initial.* gives a basin map), in parallel, and write DIR/sweep.nc "
        "(netCDF) and plots. Every finished point is kept in DIR/points.jsonl; after "
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
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a key of the base scene (repeatable)",
    )
    p.add_argument(
        "--impacts", type=int, help="impacts measured per point, after the transient (2000)"
    )
    p.add_argument("--transient", type=int, help="impacts simulated first, not measured (500)")
    p.add_argument(
        "--duration", type=float, metavar="S", help="simulated time per point at most (s)"
    )
    p.add_argument(
        "--keep", type=int, metavar="K", help="last K impact heights and times stored (100)"
    )
    p.add_argument(
        "--lyapunov",
        action="store_true",
        help="also the largest Lyapunov exponent per point (about three times the cost)",
    )
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (all cores)")
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
    p.set_defaults(func=cmd_sweep)


# --- entry point -----------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="billiard",
        description="Driven gravitational billiard with a spinning, rubbing ball (SI units).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser(
        "derive",
        help="regenerate the generated code from the derivation",
        description="Regenerate generated/ and docs/derivation.md, check them, "
        "or derive a user's curve.",
    )
    p.add_argument(
        "--check",
        action="store_true",
        help="verify that generated/ equals a fresh regeneration (exit 1 if not)",
    )
    p.__class__ = _DeriveParser  # accept --curve -x**2 ... (same layout: a subclass)
    p.add_argument(
        "--name", help="name of a user curve to derive (with --curve): letters, digits, _ and -"
    )
    p.add_argument(
        "--curve",
        help="curve expression in x, metres, e.g. '30*x**4 + 0.0063'; it must hold a ball "
        "(real, finite, convex and rising on both sides of its bottom)",
    )
    p.add_argument("--force", action="store_true", help="replace a user curve of the same name")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="value of a named parameter of --curve (repeatable)",
    )
    p.add_argument(
        "--dir",
        help="where to write a user curve (default: the user curve directory, "
        "$BILLIARD_HOME/curves, see `billiard.curves.user_curve_dir`)",
    )
    p.set_defaults(func=cmd_derive)

    p = sub.add_parser("scenes", help="list the built-in scenes")
    p.set_defaults(func=cmd_scenes)

    p = sub.add_parser(
        "run",
        help="simulate a scene and write collisions.csv",
        description="Simulate a built-in scene or a scene file (TOML, SI units). "
        "DIR/scene.toml is written first, DIR/collisions.csv grows "
        "row by row and DIR/checkpoint.json follows it every "
        "second; after Ctrl-C or a kill, `billiard run --resume DIR` "
        "finishes the same run.",
    )
    p.add_argument(
        "scene", nargs="?", help="built-in scene name (see `billiard scenes`) or a .toml file"
    )
    p.add_argument(
        "--resume",
        metavar="DIR",
        help="continue the interrupted run in DIR from its checkpoint (the result "
        "equals an uninterrupted run byte for byte)",
    )
    p.add_argument(
        "--collisions",
        type=int,
        help="number of impacts (default: the scene's); with --resume, a larger "
        "total extends a finished run",
    )
    p.add_argument(
        "--method",
        choices=["event", "rk4"],
        help="flight and impact-detection method (default: the scene's, 'event')",
    )
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="stop after S seconds of simulated time (with --collisions: whichever comes "
        "first; default: the scene's run.duration, no limit)",
    )
    p.add_argument("--out", help="output directory (default: runs/SCENE)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene key, e.g. --set drive.frequency=6.0 (repeatable)",
    )
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the run already in the output directory (default: refuse)",
    )
    p.add_argument(
        "--no-plot",
        action="store_true",
        help="do not draw the plots afterwards (plots of earlier data in DIR are removed)",
    )
    p.add_argument(
        "--frame-interval",
        metavar="S",
        help="also plot what a camera with this frame interval (s, e.g. 0.0333 or 1/30) "
        "would record",
    )
    p.set_defaults(func=cmd_run)

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
        required=True,
        help="dotted scene key, e.g. drive.amplitude or contact.restitution",
    )
    p.add_argument(
        "--target-height",
        type=float,
        required=True,
        metavar="H",
        help="height q2 of the ball centre at the orbit's impacts (m)",
    )
    p.add_argument("--low", type=float, help="lower end of the scan (default: value/4)")
    p.add_argument("--high", type=float, help="upper end of the scan (default: 4 x value)")
    p.add_argument("--impacts", type=int, default=1500, help="impacts per trial run (default 1500)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene key first (repeatable)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_calibrate)

    p = sub.add_parser(
        "plot",
        help="draw the paper's plots of a run",
        description="Return map, time-of-flight map, phase plot, trajectory "
        "and animation from DIR/collisions.csv and DIR/scene.toml.",
    )
    p.add_argument("dir", help="run directory")
    p.add_argument("--out", metavar="DIR", help="where to write the figures (default: DIR)")
    p.add_argument(
        "--frame-interval",
        metavar="S",
        help="also show what a camera with this frame interval (s, e.g. 0.0333 or 1/30) "
        "would record",
    )
    p.add_argument(
        "--window",
        metavar="N0:N1",
        help="impacts N0 <= n < N1 drawn in the trajectory and GIF (either may be "
        "left out; default: the last four drive periods)",
    )
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser(
        "lyapunov",
        help="largest Lyapunov exponent of a scene's trajectory",
        description="Largest Lyapunov exponent (per impact and per second) "
        "from two nearby trajectories with renormalization.",
    )
    p.add_argument("scene", help="built-in scene name or a .toml file")
    p.add_argument("--impacts", type=int, default=5000, help="impacts to average over (>= 1)")
    p.add_argument("--transient", type=int, default=0, help="impacts skipped first (>= 0)")
    p.add_argument(
        "--d0",
        type=float,
        default=1e-9,
        help="initial separation of the two trajectories (m; at most 1e-3 of the ball "
        "radius). Exit status 3 when the exponent is undefined (a ball that never flies)",
    )
    p.add_argument("--method", choices=["event", "rk4"], help="default: the scene's")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene key first (repeatable)",
    )
    p.set_defaults(func=cmd_lyapunov)

    from .bench import add_bench_arguments  # argparse only: cheap

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
    p.add_argument("--runs", default="runs/paper", help="where the runs go (default runs/paper)")
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
    _add_sweep_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except Exception as exc:
        if not isinstance(exc, _user_errors()):
            raise
        message = " ".join(str(exc).split())
        print(f"billiard: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"billiard: interrupted; {_interrupted(args)}", file=sys.stderr)
        return 130


def _interrupted(args: argparse.Namespace) -> str:
    """What is true of the files after Ctrl-C in a command (``billiard run`` reports its
    own interruptions while it writes rows; this is any other moment)."""
    command = args.command
    if command == "run":
        return "the run had not started; nothing was written"
    if command in ("calibrate", "lyapunov", "scenes"):
        return "nothing was written"
    if command == "plot":
        where = args.out or args.dir
        return f"the figures in {where} may be missing or partly drawn; draw them again"
    if command == "derive":
        return "`billiard derive --check` names any generated file left out of date"
    if command == "reproduce":
        return "the report was not finished; runs and figures so far may be partly written"
    return "files being written may be incomplete"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
