"""billiard orbits: find a periodic orbit by Newton's method and continue its branch
through a scene key (docs/orbits.md); writes DIR/branch.nc and DIR/branch.png."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from billiard.cli.common import UserError, _note, add_set_argument, check_output_folder

#: Impacts of the scene's own run before its last impact is taken as the guess.
SETTLE = 2000


def _key_value(text: str, option: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key.strip() or not value.strip():
        raise UserError(f"orbits: {option} {text!r}: expected KEY=VALUE")
    return key.strip(), value.strip()


def _span(text: str) -> tuple[str, float, float]:
    key, spec = _key_value(text, "--continue")
    lo_text, sep, hi_text = spec.partition(":")
    try:
        lo, hi = float(lo_text), float(hi_text)
    except ValueError:
        sep = ""
    if not sep or not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
        raise UserError(
            f"orbits: --continue {text!r}: expected KEY=LO:HI with finite numbers LO < HI"
        )
    return key, lo, hi


def _guess(args: argparse.Namespace):
    """The starting guess: the last impact of --from-run DIR, or None (the scene's own
    run settles first)."""
    if args.from_run is None:
        return None
    from billiard.run.load import open_run

    result = open_run(args.from_run)
    cols = result.columns
    if len(cols["t"]) < args.period:
        raise UserError(f"orbits: --from-run {args.from_run}: the run has no impacts to start from")
    from billiard.runfile.record import ImpactRecord

    i = len(cols["t"]) - 1
    return ImpactRecord(*(cols[name][i] for name in ImpactRecord._fields))


def cmd_orbits(args: argparse.Namespace) -> int:
    from billiard.orbits.bifurcation import BIFURCATIONS
    from billiard.orbits.continuation import check_span, continue_branch, scene_value, variable_name
    from billiard.orbits.netcdf import write_branch
    from billiard.orbits.newton import find_orbit
    from billiard.orbits.returnmap import STATE
    from billiard.scene.scene import load_scene, with_values
    from billiard.sweep.units import key_long_name, key_unit

    if args.period < 1:
        raise UserError(f"orbits: --period must be >= 1, got {args.period}")
    if args.points < 2:
        raise UserError(f"orbits: --points must be >= 2, got {args.points}")
    key, lo, hi = _span(args.continue_)
    free = None
    if args.free is not None:
        free = [name.strip() for name in args.free.split(",") if name.strip()]
        unknown = [name for name in free if name not in STATE]
        if unknown or not free:
            raise UserError(
                f"orbits: --free {args.free!r}: a comma-separated subset of {','.join(STATE)}"
            )
    out = Path(args.out or f"runs/orbits-{Path(args.scene).stem}")
    check_output_folder(out, "--out")
    scene = load_scene(args.scene, overrides=args.set, notify=_note)
    if args.at is not None:
        at_key, at_value = _key_value(args.at, "--at")
        if at_key != key:
            raise UserError(f"orbits: --at names {at_key}, but --continue varies {key}")
        try:
            value = float(at_value)
        except ValueError:
            raise UserError(f"orbits: --at {args.at!r}: {at_value!r} is not a number") from None
        scene = with_values(scene, {key: value})
    check_span(scene, key, (lo, hi))
    over = _over(args.over, key) if args.over else None  # read first: refused before the work
    guess = _guess(args)
    start = find_orbit(scene, args.period, guess=guess, free=free, settle=SETTLE)
    counted = "lift-off" if getattr(scene.contact, "model", "impacts") == "phases" else "impact"
    print(
        f"orbits: orbit of {_count(args.period, counted)} at {key} = "
        f"{scene_value(scene, key):.10g} {key_unit(key)}: q2 = {start.lab[1]:.6f} m, "
        f"{'stable' if start.stable else 'unstable'}, multipliers "
        + ", ".join(_complex(m) for m in start.multipliers)
    )
    branch = continue_branch(scene, start, key, (lo, hi), points=args.points, switch=args.switch)
    arrays = branch.arrays()
    out.mkdir(parents=True, exist_ok=True)
    unit = key_unit(key)
    title = f"{scene.name}: orbits of {_count(args.period, counted)} in {key}"
    nc = write_branch(
        out / "branch.nc", arrays, key, title, units=unit, long_name=key_long_name(key)
    )
    from billiard.plot.branch import plot_branch

    png = plot_branch(
        arrays, key, out / "branch.png", label=f"{key} ({unit})", over=over, title=title
    )
    values = arrays[variable_name(key)]
    lo_text, hi_text = f"{values.min():.10g}", f"{values.max():.10g}"
    print(f"orbits: {len(values)} points, {key} from {lo_text} to {hi_text} {unit}")
    for name in BIFURCATIONS[1:]:
        for v in branch.points(name):
            print(f"orbits: {name.replace('_', ' ')} at {key} = {v:.12g} {unit}")
    for k in sorted(set(branch.segment) - {0}):
        rows = [i for i, s in enumerate(branch.segment) if s == k]
        first, period = rows[0], branch.orbits[rows[0]].impacts
        print(
            f"orbits: switched onto the branch of {_count(period, counted)} at {key} = "
            f"{branch.values[first]:.12g} {unit}: {len(rows)} points"
        )
        for name in BIFURCATIONS[1:]:
            for v in branch.points(name, k):
                print(f"orbits:   {name.replace('_', ' ')} at {key} = {v:.12g} {unit}")
    print(f"orbits: wrote {nc} and {png}")
    return 0


def _count(n: int, unit: str) -> str:
    """``1 impact``, ``2 lift-offs``."""
    return f"1 {unit}" if n == 1 else f"{n} {unit}s"


def _complex(m: complex) -> str:
    """A multiplier as text: real ones without an imaginary part."""
    if m.imag == 0.0:
        return f"{m.real:.4g}"
    return f"{m.real:.4g}{m.imag:+.4g}j"


def _over(folder: str, key: str):
    """(values of ``key``, last impact heights) of the sweep in ``folder``."""
    from billiard.sweep.netcdf import RESULT_NAME, read_result

    path = Path(folder) / RESULT_NAME
    if not path.is_file():
        raise UserError(f"orbits: --over {folder}: no {RESULT_NAME} (not a finished sweep folder)")
    name = key.replace(".", "_")
    data = read_result(path, [name, "last_height"])
    if name not in data:
        raise UserError(f"orbits: --over {folder}: the sweep does not vary {key}")
    return data[name], data["last_height"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "orbits",
        help="find a periodic orbit by Newton's method and continue its branch in a key",
        description="Find the period-N orbit (N impacts) of a scene by Newton's method on "
        "its return map, with its Floquet multipliers, and continue it through a scene key "
        "by pseudo-arclength continuation, locating folds, period doublings, "
        "Neimark-Sacker points and grazing (with --switch, continuing the period-2N branches "
        "born at period doublings). Writes DIR/branch.nc and DIR/branch.png. "
        'Under contact.model = "phases": orbits that lie on the shaken table between '
        "flights (N counts lift-offs). See docs/orbits.md.",
    )
    p.add_argument("scene", help="built-in scene name or a scene .toml file")
    p.add_argument(
        "--period",
        type=int,
        default=1,
        metavar="N",
        help='impacts per period (lift-offs under contact.model = "phases")',
    )
    p.add_argument(
        "--continue",
        dest="continue_",
        required=True,
        metavar="KEY=LO:HI",
        help="the scene key continued and its span, in the key's unit "
        "(e.g. drive.frequency=5:6 in Hz)",
    )
    start = p.add_mutually_exclusive_group()
    start.add_argument(
        "--from-run",
        metavar="DIR",
        help="start from the last impact of this run folder (default: the last of "
        f"{SETTLE} impacts of the scene's own run)",
    )
    start.add_argument(
        "--at",
        metavar="KEY=VALUE",
        help="start from the orbit the scene settles on at this value of the continued key",
    )
    p.add_argument(
        "--free",
        metavar="NAMES",
        help="the coordinates Newton varies, comma-separated from t,s,v1,v2,omega "
        '(default all, t,v2 under contact.model = "phases"; e.g. t,v2 for a ball '
        "bouncing straight up)",
    )
    p.add_argument("--points", type=int, default=200, help="most points of the branch")
    p.add_argument(
        "--switch",
        action="store_true",
        help="at each period doubling, switch onto the branch of twice the period born "
        "there and continue it too (branch.nc's period and branch tell them apart)",
    )
    p.add_argument("--over", metavar="SWEEP_DIR", help="draw the branch over this sweep's diagram")
    p.add_argument("--out", metavar="DIR", help="output folder (default runs/orbits-SCENE)")
    add_set_argument(p, "override a key of the scene (repeatable)")
    p.set_defaults(func=cmd_orbits)
