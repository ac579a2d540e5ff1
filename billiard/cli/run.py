"""billiard run: simulate a scene into a run folder, with progress and plots."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import time
from pathlib import Path

from billiard.cli.common import UserError, _note, add_set_argument, name_too_long
from billiard.cli.figure_options import add_figure_arguments, figure_options


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
        #: the simulated time (s) the engine last reported (see :meth:`at_time`)
        self.simulated: float | None = None

    def at_time(self, t: float) -> None:
        """The engine's report of the simulated time reached (s): it advances while the
        ball rolls, slides or is held, when the impact count stands still."""
        self.simulated = t

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
            counted = done - self.first_done
            rate = f", {counted / max(now - self.first_time, 1e-9):,.0f}/s" if counted else ""
            simulated = self._simulated()
            clock = f", t = {simulated:.6g} s" if simulated is not None else ""
            self.stream.write(
                f"\r[{'#' * filled}{'.' * (self.width - filled)}] {done}/{total} impacts"
                f"{rate}{clock} "
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
        parts = [f"billiard: {done:,}/{total:,} impacts"]
        simulated = self._simulated()
        if simulated is not None:
            parts.append(f"t = {simulated:.6g} s simulated")
        counted = done - (self.first_done or 0)
        if counted > 0:
            # a rate needs two counts: the first one may come after a compile
            rate = counted / max(now - self.first_time, 1e-9)
            parts.append(f"{rate:,.0f} impacts/s")
            from billiard.engine.progress import duration_text

            parts.append(f"about {duration_text((total - done) / rate)} left")
        return ", ".join(parts)

    def _simulated(self) -> float | None:
        """The latest simulated time known (s): the engine's report or the clock's."""
        known = [t for t in (self.simulated, self.clock() if self.clock else None) if t is not None]
        return max(known) if known else None

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _frame_interval(text: str | None) -> float | None:
    """``--frame-interval`` in seconds (a number or a fraction such as 1/30), or None."""
    from billiard.analysis.camera import parse_frame_interval

    return None if text is None else parse_frame_interval(text)


def _holds_run(folder: Path) -> bool:
    """Whether a folder holds a run's files (impacts, CSV or binary; scene; checkpoint)."""
    from billiard.run.persist import CHECKPOINT_NAME, CSV_NAME, NPY_NAME, SCENE_NAME

    return folder.is_dir() and any(
        (folder / name).exists() for name in (CSV_NAME, NPY_NAME, SCENE_NAME, CHECKPOINT_NAME)
    )


def _remove_plots(folder: Path) -> list[str]:
    """Delete the figures ``plot_run`` and the view ``billiard view`` wrote into a run
    folder (they no longer match its data); returns the names removed."""
    from billiard.runfile.figure_files import all_figure_names
    from billiard.runfile.folder import VIEW_NAME

    removed = []
    for name in (*all_figure_names(), VIEW_NAME):  # figures in whichever format were drawn
        path = folder / name
        if path.is_file():
            path.unlink()
            removed.append(name)
    return removed


def _data_file(folder: Path) -> Path:
    """The file of a run's impacts in ``folder``: collisions.npy where the run stores
    binary rows, else collisions.csv."""
    from billiard.runfile.folder import data_file

    return data_file(folder)


def _checkpoint_clock(folder: Path):
    """A clock for the progress line of a streamed run: the simulated time (s) of the
    run's last checkpoint (written every second, so at most a second behind), or None
    while there is none."""
    import json

    from billiard.run.persist import CHECKPOINT_NAME
    from billiard.runfile.checkpoint import MAX_CHECKPOINT_BYTES
    from billiard.scene.userfile import read_limited

    def clock() -> float | None:
        try:
            data = json.loads(read_limited(folder / CHECKPOINT_NAME, MAX_CHECKPOINT_BYTES))
            return float(data["engine"]["ball"]["t"])
        except (OSError, ValueError, KeyError, TypeError):
            return None

    return clock


def _report(text: str, out: Path) -> None:
    """Print a line of the report of a run whose files are complete.

    Standard output may fail after the run (a reader that closed the pipe, a full disk
    under a redirection): that is one line on stderr, not a traceback (Python's exit
    status 1 after a summary was printed), and standard output is pointed at the null
    device so that flushing it at exit cannot fail again.

    Raises:
        UserError: standard output could not be written.
    """
    try:
        print(text, flush=True)
    except OSError as exc:
        with contextlib.suppress(OSError, ValueError):
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, sys.stdout.fileno())
            os.close(null)
        raise UserError(
            f"cannot write to standard output ({exc.strerror or exc}); the run's files "
            f"in {out} are complete"
        ) from None


def cmd_run(args: argparse.Namespace) -> int:
    import shlex
    import signal

    from billiard.run.output_size import OutputSizeError
    from billiard.run.persist import SCENE_NAME, resume
    from billiard.run.simulate import RunInterrupted, simulate
    from billiard.runfile.checkpoint import CheckpointError

    # every argument is checked before any work
    frame_interval = _frame_interval(args.frame_interval)
    figures = figure_options(args, "run")
    if args.sample is not None and not (math.isfinite(args.sample) and args.sample > 0):
        raise UserError(f"run: --sample must be a number > 0 (s), got {args.sample!r}")
    bar = ProgressBar()
    stale: list[str] = []  # plots removed because the data changed under them
    changed = False  # whether the run folder's data was changed
    if args.resume is not None:
        if (
            args.scene or args.set or args.method or args.out or args.duration
            or args.overwrite or args.sample is not None or args.store is not None
        ):  # fmt: skip
            raise UserError(
                "run --resume DIR continues a run as it was set up: give no SCENE, --out, "
                "--set, --method, --duration, --sample, --store or --overwrite with it"
            )
        out = Path(args.resume)
        if args.collisions is not None and args.collisions < 1:
            raise UserError(f"run: --collisions must be >= 1, got {args.collisions}")
    else:
        if not args.scene:
            raise UserError("run: give a SCENE (a built-in name or a .toml file), or --resume DIR")
        from billiard.scene.scene import load_scene, with_values

        scene = load_scene(args.scene, overrides=args.set, notify=_note)
        if args.duration is not None:
            with_values(scene, {"run.duration": args.duration})  # checks it
        out = Path(args.out) if args.out else Path("runs") / scene.name
        why = name_too_long(out, "--out")
        if why is not None:
            raise UserError(f"run: {why}")
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
                        allow_large=args.yes,
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
                    _report(
                        f"billiard: {out}: the run is already complete ({len(result)} impacts); "
                        f"nothing to resume (--collisions N extends it)",
                        out,
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
                        sample=args.sample,
                        allow_large=args.yes,
                        store=args.store or "auto",
                        notify=lambda line: print(f"billiard: {line}", file=sys.stderr),
                    )
                except CheckpointError as exc:  # another process is writing a run in DIR
                    changed = False
                    raise UserError(f"cannot run in {out}: {exc}") from None
        finally:  # end the progress bar's line before anything else is printed
            if bar.enabled:
                bar.stream.write("\n")
            if changed and out.is_dir():
                stale = _remove_plots(out)
    except OutputSizeError as exc:
        raise UserError(f"run: {exc.confirmed_by('--yes')}") from None
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
            f"{_data_file(where)}; continue with `{again}`{after}{removed}",
            file=sys.stderr,
        )
        return 128 + exc.signum
    except OSError as exc:
        where = f": {exc.filename}" if exc.filename else ""
        raise UserError(f"cannot write the run: {exc.strerror or exc}{where}") from None
    _report(result.summary(), out)
    extra = result.side_files
    names = ", ".join(str(p) for p in (result.path or _data_file(out), *extra))
    _report(f"wrote {names} and {out / SCENE_NAME}", out)
    if not args.no_plot and len(result) > 1:
        from billiard.plot import plot_run

        try:
            paths = plot_run(out, frame_interval=frame_interval, **figures)
        except KeyboardInterrupt:
            print(
                f"billiard: interrupted while drawing the plots; the run is complete in "
                f"{out}; draw them with `billiard plot {shlex.quote(str(out))}`",
                file=sys.stderr,
            )
            return 130
        _report(f"plots: {', '.join(p.name for p in paths)} in {out}", out)
    elif stale:
        _report(
            f"removed the plots of the earlier data ({', '.join(stale)}) from {out}; "
            f"draw new ones with `billiard plot {shlex.quote(str(out))}`",
            out,
        )
    if result.stop_reason:
        print(f"billiard: stopped: {result.stop_reason}", file=sys.stderr)
        return 3
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
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
    p.add_argument(
        "--sample",
        type=float,
        metavar="DT",
        help="also write DIR/trajectory.csv: the state every DT seconds of simulated time "
        "(refused when it may exceed 1 GB, estimated before the run, unless --yes; "
        "default: no trajectory.csv)",
    )
    p.add_argument(
        "--yes",
        action="store_true",
        help="go ahead when the estimate of trajectory.csv exceeds 1 GB (with --sample; "
        "also with --resume)",
    )
    p.add_argument(
        "--store",
        choices=["auto", "csv", "npy"],
        help="how the rows are stored: csv (DIR/collisions.csv), npy (DIR/collisions.npy, "
        "typed binary rows, 137 bytes per impact; `billiard export DIR --csv` writes the "
        "CSV files from them), or auto: csv unless the run's CSV files are estimated "
        "over 100 MB (about 310,000 impacts), then npy, said on stderr (default: auto)",
    )
    p.add_argument("--out", help="output directory (default: runs/SCENE)")
    add_set_argument(p, "override a scene key, e.g. --set drive.frequency=6.0 (repeatable)")
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
        "would record (default: no camera view)",
    )
    add_figure_arguments(p)
    p.set_defaults(func=cmd_run)
