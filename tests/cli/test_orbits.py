"""billiard orbits: the branch files it writes, bad input in one line with exit status 2,
and Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.io import netcdf_file

from billiard.cli import main
from billiard.orbits.bifurcation import BIFURCATIONS
from tests.orbits import table

TABLE = f"""
[boundary]
curve = "{table.FLOOR}"
escape_height = 10.0
[drive]
amplitude = {table.amplitude(1.3)!r}
frequency = {table.F}
direction = "vertical"
[contact]
model = "impacts"
restitution = 0.5
mu_static = 0.3
mu_kinetic = 0.2
elastic_below = 0.0
[air]
drag = "none"
[initial]
q1 = 0.0
q2 = {table.FLOOR + table.R + 0.001!r}
v2 = 0.3
"""


@pytest.fixture
def table_scene(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path / "home"))
    path = tmp_path / "table.toml"
    path.write_text(TABLE)
    return path


def test_the_bouncing_balls_branch_is_written(table_scene, tmp_path, capsys):
    out = tmp_path / "out"
    lo, hi = table.amplitude(1.0), table.amplitude(1.7)
    code = main(
        [
            "orbits",
            str(table_scene),
            "--continue",
            f"drive.amplitude={lo!r}:{hi!r}",
            "--free",
            "t,v2",
            "--points",
            "60",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "fold at drive.amplitude" in text and "period doubling at drive.amplitude" in text
    assert (out / "branch.png").stat().st_size > 10_000
    f = netcdf_file(out / "branch.nc", "r", mmap=False)
    try:
        v = f.variables
        a = v["drive_amplitude"][:].copy()
        codes = v["bifurcation"][:].copy()
        assert v["drive_amplitude"].units.decode() == "m"
        assert v["bifurcation"].flag_meanings.decode() == " ".join(BIFURCATIONS)
        assert v["multipliers_real"].dimensions == ("point", "multiplier")
        for name in ("t_phase", "q1", "q2", "v1", "v2", "omega", "stable"):
            assert v[name].dimensions == ("point",)
        fold = a[codes == BIFURCATIONS.index("fold")]
        doubling = a[codes == BIFURCATIONS.index("period_doubling")]
    finally:
        f.close()
    unit = table.amplitude(1.0)
    assert fold / unit == pytest.approx([table.onset(0.5)], rel=1e-8)
    assert doubling / unit == pytest.approx([table.period_doubling(0.5)], rel=1e-8)


def test_switch_continues_the_period_two_branch_too(table_scene, tmp_path, capsys):
    """--switch: the period-two branch born at the doubling is in branch.nc, its points
    of period 2 and branch 1, starting at the doubling."""
    out = tmp_path / "out"
    lo, hi = table.amplitude(1.25), table.amplitude(1.7)
    args = ["orbits", str(table_scene), "--continue", f"drive.amplitude={lo!r}:{hi!r}"]
    code = main([*args, "--free", "t,v2", "--points", "160", "--switch", "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "switched onto the branch of 2 impacts at drive.amplitude = " in text
    assert "  period doubling at drive.amplitude" in text  # the period-two orbit's own
    f = netcdf_file(out / "branch.nc", "r", mmap=False)
    try:
        v = f.variables
        a = v["drive_amplitude"][:].copy()
        period, branch = v["period"][:].copy(), v["branch"][:].copy()
        assert v["period"].dimensions == ("point",) and period.dtype.kind == "i"
    finally:
        f.close()
    assert set(branch.tolist()) == {0, 1}
    assert np.array_equal(period, np.where(branch == 0, 1, 2))
    unit = table.amplitude(1.0)
    assert a[branch == 1][0] / unit == pytest.approx(table.period_doubling(0.5), rel=1e-8)
    assert a[branch == 1].min() == a[branch == 1][0]  # from the doubling upwards


@pytest.mark.parametrize(
    "args,message",
    [
        (["--continue", "drive.amplitude=1"], "expected KEY=LO:HI"),
        (["--continue", "drive.amplitude=2:1"], "expected KEY=LO:HI"),
        (["--continue", "drive.amplitude=0.0001:0.0002"], "must lie in the span"),
        (["--continue", "drive.nothing=0:1"], "drive.nothing"),
        (["--continue", "drive.amplitude=0:1", "--period", "0"], "--period must be >= 1"),
        (["--continue", "drive.amplitude=0:1", "--free", "t,x"], "--free"),
        (["--continue", "drive.amplitude=0:1", "--at", "drive.frequency=5"], "--at names"),
        (
            ["--continue", "drive.amplitude=0:1", "--set", "contact.model=phases"]
            + ["--set", "drive.direction=horizontal"],
            "orbits through contact phases need a vertical drive",
        ),
        (
            ["--continue", "drive.amplitude=0:1", "--set", "contact.model=phases"]
            + ["--free", "t,s,v2"],
            "through a contact phase only t and v2 can be free, not s",
        ),
        (["--continue", "drive.amplitude=0:1", "--over", "/nonexistent"], "no sweep.nc"),
    ],
)
def test_bad_input_is_one_line_with_exit_status_2(table_scene, tmp_path, capsys, args, message):
    out = tmp_path / "out"
    code = main(["orbits", str(table_scene), "--free", "t,v2", *args, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    # (a notice of the curve's first derivation may come before it)
    assert err.splitlines()[-1].startswith("billiard: error: ") and "Traceback" not in err, err
    assert message in err
    assert not (out / "branch.nc").exists()


def test_ctrl_c_ends_it_within_a_second(tmp_path):
    """SIGINT during the continuation: exit status 130 within a second, no branch.nc."""
    out = tmp_path / "out"
    command = [
        sys.executable,
        "-m",
        "billiard.cli",
        "orbits",
        "parabola-5.4hz",
        "--period",
        "2",
        "--continue",
        "drive.frequency=4.5:6.5",
        "--points",
        "100000",
        "--out",
        str(out),
    ]
    proc = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=os.environ
    )
    try:
        line = proc.stdout.readline()  # the starting orbit: the continuation starts now
        assert line.startswith("orbits: orbit of 2 impacts"), line + proc.stderr.read()
        time.sleep(0.5)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=10)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert code == 130
    assert took < 1.0
    assert "interrupted; nothing was written" in proc.stderr.read()
    assert not (out / "branch.nc").exists()
    assert np.isfinite(took)


@pytest.mark.parametrize("start", ["at", "from-run"])
def test_the_start_from_another_value_or_from_a_run(table_scene, tmp_path, capsys, start):
    """--at: the orbit the scene's run settles on at that value of the key; --from-run:
    the last impact of a run folder. Either way the stable orbit of the closed form."""
    lo, hi = table.amplitude(1.2), table.amplitude(1.4)
    args = ["--continue", f"drive.amplitude={lo!r}:{hi!r}", "--free", "t,v2", "--points", "6"]
    gamma = 1.3
    if start == "at":
        gamma = 1.25
        args += ["--at", f"drive.amplitude={table.amplitude(gamma)!r}"]
    else:
        run = tmp_path / "run"
        assert main(["run", str(table_scene), "--collisions", "500", "--out", str(run)]) == 0
        args += ["--from-run", str(run)]
    capsys.readouterr()
    out = tmp_path / "out"
    assert main(["orbits", str(table_scene), *args, "--out", str(out)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert f"drive.amplitude = {table.amplitude(gamma):.10g} m" in first and "stable" in first
    f = netcdf_file(out / "branch.nc", "r", mmap=False)
    try:
        a = f.variables["drive_amplitude"][:].copy()
        phase = f.variables["t_phase"][:].copy()
    finally:
        f.close()
    for value, t in zip(a, phase, strict=True):
        expected, _ = table.orbit(value / table.amplitude(1.0), 0.5)
        assert t == pytest.approx(expected, abs=1e-12)


def test_the_locked_orbits_branch_is_written(table_scene, tmp_path, capsys):
    """Under contact phases the table's ball lies on it between flights: the orbit of one
    lift-off, superstable, its branch ending where the chatter meets the next lift-off
    (Gamma 1.5973, tests/orbits/test_phases.py). The ball starts lying on the table (from
    the scene's bounce it settles on the bouncing orbit of Gamma 1.3, which has no contact
    phase)."""
    out = tmp_path / "out"
    lo, hi = table.amplitude(1.1), table.amplitude(1.7)
    lying = [
        f"initial.q2={table.FLOOR + table.R!r}",
        f"initial.v2={table.amplitude(1.3) * table.W!r}",
    ]
    args = ["orbits", str(table_scene), "--set", "contact.model=phases"]
    args += ["--set", lying[0], "--set", lying[1]]
    args += ["--continue", f"drive.amplitude={lo!r}:{hi!r}", "--points", "200", "--out", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert text.startswith("orbits: orbit of 1 lift-off at drive.amplitude")
    assert "stable, multipliers 0, 0" in text and "grazing at drive.amplitude" in text
    f = netcdf_file(out / "branch.nc", "r", mmap=False)
    try:
        v = f.variables
        a, codes = v["drive_amplitude"][:].copy(), v["bifurcation"][:].copy()
        periods = v["drive_periods"][:].copy()
        assert v["period"][:].tolist() == [1] * len(a)
        assert v["multipliers_real"][:].tolist() == [[0.0, 0.0]] * len(a)
    finally:
        f.close()
    assert periods.tolist() == [1] * len(a)
    grazing = a[codes == BIFURCATIONS.index("grazing")] / table.amplitude(1.0)
    assert grazing == pytest.approx([1.59734], abs=2e-5)


def test_an_orbit_rolling_on_a_sloped_wall_is_refused_with_exit_status_2(tmp_path, capsys):
    """The parabola shaken vertically under contact phases, the ball started off its
    bottom: it rolls to and fro and lifts off its sloped wall, a lift-off that depends on
    that motion (docs/orbits.md, scope)."""
    out = tmp_path / "out"
    sets = ["contact.model=phases", "drive.direction=vertical", "drive.amplitude=0.02"]
    sets += ["initial.q1=0.05"]
    args = ["orbits", "parabola-5.4hz", "--continue", "drive.amplitude=0.01:0.03"]
    for item in sets:
        args += ["--set", item]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.splitlines()[-1].startswith("billiard: error: ") and "Traceback" not in err
    assert "where it is not horizontal or moves along it while curved" in err
    assert not out.exists()


def test_the_docs_locked_orbit_command_runs_as_shown(tmp_path, monkeypatch, capsys):
    """docs/orbits.md's table scene and command, as a reader copies them: the orbit of
    one lift-off and the grazing the page states."""
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path / "home"))
    page = (Path(__file__).resolve().parents[2] / "docs" / "orbits.md").read_text()
    after = page.split("With the table as a scene file, `table.toml`:", 1)[1]
    toml = after.split("```toml\n", 1)[1].split("```", 1)[0]
    command = after.split("```bash\n", 1)[1].split("```", 1)[0].split()
    assert command[:3] == ["billiard", "orbits", "table.toml"]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "table.toml").write_text(toml)
    assert main(command[1:]) == 0
    text = capsys.readouterr().out
    assert "orbit of 1 lift-off at drive.amplitude = 0.000808 m" in text
    assert "multipliers 0, 0" in text
    grazing = float(text.split("grazing at drive.amplitude = ")[1].split()[0])
    assert grazing == pytest.approx(0.000992307, abs=1e-9)
    assert (tmp_path / "runs" / "orbits-locked" / "branch.nc").is_file()
