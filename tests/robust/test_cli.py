"""Bad input on the command line: one line ``billiard: error: ...``, exit status 2, no
traceback, and no run files left behind. Each case runs in a fresh interpreter, as a
user would run it."""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

BAD_TOML = 'name = "x"\n[drive\namplitude = 1\n'

# case -> (arguments after `billiard run`, a fragment of the message)
CASES: dict[str, tuple[list[str], str]] = {
    "misspelt key": (
        ["--set", "drive.frequncy=5"],
        "unknown scene key 'drive.frequncy'; did you mean 'drive.frequency'?",
    ),
    "unknown section": (
        ["--set", "drvie.amplitude=0.01"],
        "unknown scene section 'drvie'; did you mean 'drive'?",
    ),
    "hostile curve": (
        ["--set", "boundary.curve=__import__('os').system('true')"],
        "is not a valid curve expression: attribute access '.system' is not",
    ),
    "unknown curve parameter": (
        ["--set", "boundary.parameters.zz=1"],
        "curve 'parabola' has no parameter(s) zz",
    ),
    "curve without a bottom": (
        ["--set", "boundary.parameters.a=-26"],
        "the boundary curve has no bottom to rest on",
    ),
    "radius too big": (
        ["--set", "ball.radius=0.02"],
        "ball radius 0.02 m exceeds the boundary's radius of curvature",
    ),
    "walls that are not the curve": (
        # b < 0 flips the wedge's kink: the maximum of its walls would be another wedge
        ["SCENE=wedge-6.6hz", "--set", "boundary.parameters.b=-1.85"],
        "the join at x = 0 m is a concave kink (slope 1.85 -> -1.85)",
    ),
    "start inside the wall": (
        ["--set", "initial.q1=0.01", "--set", "initial.q2=0.005"],
        "puts the ball 0.00506 m into the wall",
    ),
    "start inside the lid": (
        ["--set", "initial.q1=0", "--set", "initial.q2=0.5"],
        "into the lid (ceiling = 0.2 m)",
    ),
    "mu_k above mu_s": (
        ["--set", "contact.mu_kinetic=0.8"],
        "'contact.mu_kinetic' = 0.8 must not exceed contact.mu_static = 0.61",
    ),
    "restitution above 1": (
        ["--set", "contact.restitution=1.5"],
        "'contact.restitution' = 1.5 is out of range [0, 1]",
    ),
    "zero mass": (["--set", "ball.mass=0"], "'ball.mass' = 0.0 kg is out of range (0, 100] kg"),
    "frequency far too high": (
        ["--set", "drive.frequency=1e9"],
        "'drive.frequency' = 1000000000.0 Hz is out of range [0, 1000] Hz",
    ),
    "start far too fast": (
        ["--set", "initial.v1=1e6"],
        "'initial.v1' = 1000000.0 m/s is out of range [-100, 100] m/s",
    ),
    "frame interval nan": (["--frame-interval", "nan"], "frame interval 'nan' must be"),
    "name outside runs": (["--set", "name=../../x"], "scene key 'name' = '../../x' contains"),
    "amplitude without frequency": (
        ["--set", "drive.frequency=0"],
        "'drive.frequency' = 0.0 must be > 0 when drive.amplitude",
    ),
    "zero impacts": (["--collisions", "0"], "'run.collisions' must be an integer >= 1, got 0"),
    "no such scene": (["SCENE=paraboloid"], "scene 'paraboloid' is neither a built-in scene"),
    "invalid TOML": (["SCENE=bad.toml"], "invalid TOML"),
    "output is a file": (["OUT=occupied"], "cannot write the run: File exists"),
}


def _run(case: str, root: Path) -> tuple[subprocess.CompletedProcess, Path]:
    args, _ = CASES[case]
    work = root / case.replace(" ", "-")
    work.mkdir()
    (work / "bad.toml").write_text(BAD_TOML)
    (work / "occupied").write_text("not a directory\n")
    scene, out = "parabola-5.4hz", "run"
    rest = []
    for arg in args:
        if arg.startswith("SCENE="):
            scene = arg.removeprefix("SCENE=")
        elif arg.startswith("OUT="):
            out = arg.removeprefix("OUT=")
        else:
            rest.append(arg)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "billiard.cli",
            "run",
            scene,
            "--out",
            out,
            "--no-plot",
            "--collisions",
            "20",
            *rest,
        ],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ),
    )
    return proc, work


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    root = tmp_path_factory.mktemp("cli")
    with ThreadPoolExecutor(max_workers=4) as pool:
        futures = {case: pool.submit(_run, case, root) for case in CASES}
        return {case: future.result() for case, future in futures.items()}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_is_one_line_exit_2(case, outcomes):
    proc, work = outcomes[case]
    _, fragment = CASES[case]
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("billiard: error: "), proc.stderr
    assert fragment in lines[0], lines[0]
    assert proc.stdout == ""
    # nothing was started: no run directory (or the file in its way is untouched)
    assert not (work / "run").exists()
    assert (work / "occupied").read_text() == "not a directory\n"


def test_a_run_without_plots_does_not_load_the_plotting_stack(tmp_path):
    """Start-up stays short: ``billiard run --no-plot`` imports neither matplotlib nor
    sympy (a run folder's figure names come from ``billiard.runfile.folder``)."""
    code = (
        "import sys\n"
        "from billiard.cli import main\n"
        "main(['run', 'wedge-6.6hz', '--collisions', '3', '--no-plot', '--out', 'r'])\n"
        "main(['run', 'wedge-6.6hz', '--collisions', '3', '--no-plot', '--out', 'r',"
        " '--overwrite'])\n"
        "print(sorted(m for m in ('matplotlib', 'sympy') if m in sys.modules))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"
