"""billiard export: the CSV files of a run stored as binary rows (``--store npy``)."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from billiard.cli.common import UserError, check_output_folder


def cmd_export(args: argparse.Namespace) -> int:
    from billiard.run.verify import verify_run
    from billiard.runfile.npyfile import TABLES, export_csv

    folder = Path(args.dir)
    if not folder.is_dir():
        raise UserError(f"export: {folder} is not a folder")
    first = TABLES[0]
    if not (folder / first.npy_name).is_file():
        if (folder / first.csv_name).is_file():
            print(
                f"billiard: {folder} holds a CSV run already ({first.csv_name}): nothing to export"
            )
            return 0
        raise UserError(
            f"export: {folder} holds no run ({first.npy_name} not found; "
            f"`billiard run SCENE --store npy --out {folder}` writes one)"
        )
    # the binary files are the run's, as its checkpoint recorded them
    verify_run(folder, absent_ok=True)
    out = Path(args.out) if args.out else folder
    check_output_folder(out, "--out")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for table in TABLES:
        source = folder / table.npy_name
        if source.is_file():
            rows = export_csv(source, out / table.csv_name, table)
            written.append(f"{out / table.csv_name} ({rows:,} rows)")
    scene = folder / "scene.toml"
    if out.resolve() != folder.resolve() and scene.is_file():
        shutil.copyfile(scene, out / scene.name)
        written.append(str(out / scene.name))
    print(f"wrote {', '.join(written)}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "export",
        help="write the CSV files of a run stored as binary rows",
        description="Write DIR/collisions.csv (and contacts.csv, trajectory.csv where the "
        "run has them) from the binary files of a run made with `billiard run --store npy` "
        "(or --store auto, for a large run): the same bytes a run storing CSV writes.",
    )
    p.add_argument("dir", metavar="DIR", help="the run folder (holding collisions.npy)")
    p.add_argument(
        "--csv",
        action="store_true",
        required=True,
        help="write CSV files (the one format exported)",
    )
    p.add_argument("--out", metavar="OUTDIR", help="where to write them (default: DIR)")
    p.set_defaults(func=cmd_export)
