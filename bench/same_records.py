"""Do two commits write the same records? A restructuring must not change results: this
runs the paper scenes and their rk4 and contact-phases runs, phases runs on a gently
shaken and a still boundary, sampled runs in every motion state, drag runs and
interpreted runs (``NUMBA_DISABLE_JIT=1``) in this checkout and in the commit REF
(checked out in a temporary git worktree, as ``billiard bench --baseline`` does), and
compares every record file (collisions, contacts and trajectory) byte for byte.

    python -m bench.same_records REF [--quick] [--keep DIR]

Each run is ``python -m billiard.cli run`` in a fresh process of the tree measured (the
same interpreter and environment; ``billiard.derivation`` and ``billiard.generated``
from the tree's own folders). Exits 0 when every file is the same, 1 when one differs
(each named, with the first line that differs), 2 when a run could not be made.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import tempfile
from pathlib import Path

from bench import baseline

#: (name, arguments of ``billiard run``, interpreted): the runs compared
PHASES = ("--set", "contact.model=phases")
PAPER = ("wedge-6.6hz", "parabola-5.4hz", "hyperbola-4.5hz", "hyperbola-5.8hz")
RUNS: tuple[tuple[str, tuple[str, ...], bool], ...] = (
    *((f"paper-{s}", (s, "--collisions", "20000"), False) for s in PAPER),
    *((f"rk4-{s}", (s, "--collisions", "1500", "--method", "rk4"), False) for s in PAPER),
    *((f"phases-{s}", (s, "--collisions", "3000", *PHASES), False) for s in PAPER),
    *(
        (f"phases-rk4-{s}", (s, "--collisions", "400", "--method", "rk4", *PHASES), False)
        for s in PAPER
    ),  # fmt: skip
    *(
        (f"sampled-{s}", (s, "--collisions", "300", "--sample", "0.0007", *PHASES), False)
        for s in PAPER
    ),  # fmt: skip
    (
        "gentle",
        ("parabola-5.4hz", "--duration", "4", *PHASES, "--set", "drive.amplitude=0.002"),
        False,
    ),  # fmt: skip
    (
        "still",
        (
            "parabola-5.4hz",
            "--duration",
            "2",
            *PHASES,
            "--set",
            "drive.amplitude=0",
            "--set",
            "initial.v1=0.05",
        ),
        False,
    ),  # fmt: skip
    (
        "held",
        ("wedge-6.6hz", "--duration", "3", *PHASES, "--set", "drive.amplitude=0.005"),
        False,
    ),  # fmt: skip
    (
        "sampled-held",
        (
            "wedge-6.6hz",
            "--duration",
            "1",
            "--sample",
            "0.0005",
            *PHASES,
            "--set",
            "drive.amplitude=0.005",
        ),
        False,
    ),  # fmt: skip
    (
        "sampled-impacts",
        ("hyperbola-5.8hz", "--collisions", "300", "--sample", "0.0005"),
        False,
    ),  # fmt: skip
    (
        "drag-phases",
        (
            "parabola-5.4hz",
            "--collisions",
            "500",
            "--set",
            "air.drag=fowles",
            "--sample",
            "0.002",
            *PHASES,
        ),
        False,
    ),  # fmt: skip
    ("drag", ("wedge-6.6hz", "--collisions", "500", "--set", "air.drag=fowles"), False),
    ("interpreted", ("wedge-6.6hz", "--collisions", "300"), True),
    ("interpreted-phases", ("parabola-5.4hz", "--collisions", "150", *PHASES), True),
    (
        "interpreted-sampled",
        (
            "wedge-6.6hz",
            "--duration",
            "0.5",
            "--sample",
            "0.001",
            *PHASES,
            "--set",
            "drive.amplitude=0.005",
        ),
        True,
    ),  # fmt: skip
)
#: the runs of ``--quick``: one of each kind
QUICK = {"paper-wedge-6.6hz", "rk4-parabola-5.4hz", "phases-wedge-6.6hz", "sampled-held",
         "interpreted-phases"}  # fmt: skip
RECORDS = ("collisions", "contacts", "trajectory")


def run_all(tree: Path, out: Path, runs: tuple) -> None:
    """Every run of ``runs`` in ``tree``, its files in ``out/NAME``."""
    for name, args, interpreted in runs:
        env_before = os.environ.get("NUMBA_DISABLE_JIT")
        if interpreted:
            os.environ["NUMBA_DISABLE_JIT"] = "1"
        try:
            command = ["-m", "billiard.cli", "run", *args, "--no-plot", "--store", "csv"]
            baseline._python(tree, [*command, "--out", str(out / name)])
        finally:
            if env_before is None:
                os.environ.pop("NUMBA_DISABLE_JIT", None)
            else:
                os.environ["NUMBA_DISABLE_JIT"] = env_before
        print(f"  {tree.name}: {name}", flush=True)


def _first_difference(a: bytes, b: bytes) -> str:
    for n, (x, y) in enumerate(zip(a.splitlines(), b.splitlines(), strict=False)):
        if x != y:
            return f"line {n + 1}"
    return f"{len(a)} against {len(b)} bytes"


def compare(new: Path, old: Path, runs: tuple) -> list[str]:
    """The files that differ (or exist in one tree only), each with where."""
    differ = []
    for name, _, _ in runs:
        for record in RECORDS:
            a, b = new / name / f"{record}.csv", old / name / f"{record}.csv"
            if not a.exists() and not b.exists():
                continue
            if a.exists() != b.exists():
                differ.append(f"{name}/{record}.csv: written by one commit only")
                continue
            x, y = a.read_bytes(), b.read_bytes()
            if hashlib.sha256(x).digest() != hashlib.sha256(y).digest():
                differ.append(f"{name}/{record}.csv: {_first_difference(x, y)}")
    return differ


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ref", help="the commit to compare with (a git ref)")
    parser.add_argument("--quick", action="store_true", help="one run of each kind")
    parser.add_argument("--keep", type=Path, help="keep both trees' files in DIR")
    args = parser.parse_args(argv)
    root = Path(__file__).resolve().parents[1]
    runs = tuple(r for r in RUNS if not args.quick or r[0] in QUICK)
    try:
        commit = baseline.resolve(root, args.ref)
        with (
            tempfile.TemporaryDirectory() as scratch,
            baseline.worktree(root, commit["commit"]) as old,
        ):
            out = args.keep or Path(scratch)
            print(f"same records: this checkout against {commit['short']} ({len(runs)} runs)")
            run_all(root, out / "new", runs)
            run_all(old, out / "old", runs)
            differ = compare(out / "new", out / "old", runs)
            made = [out / "new" / name / f"{r}.csv" for name, _, _ in runs for r in RECORDS]
            files = sum(path.exists() for path in made)
    except baseline.TreeError as exc:
        print(f"same records: {exc}", file=sys.stderr)
        return 2
    if differ:
        print(f"{len(differ)} of {files} record files differ:", *differ, sep="\n  ")
        return 1
    print(f"the same bytes in all {files} record files of {len(runs)} runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
