"""Numerical faults stop a run with a one-line reason that names the impact and the time,
and every row before the fault is kept (in memory and in the streamed CSV).

Faults are injected into the kernels (:mod:`billiard.kernels`) in a fresh interpreter
with ``NUMBA_DISABLE_JIT=1``, where the kernels run as Python and a kernel looks up the
functions it calls as attributes of its module at each call: patching
``billiard.kernels.impact.impact_stick`` reaches the impact law, and so on. The faults
that need no patch (an overflow, a collapse) run on the compiled engine in this process.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

from billiard.run.simulate import CHECKPOINT_NAME, COLLAPSE_COUNT, CSV_NAME, resume, simulate
from billiard.runfile.checkpoint import read_checkpoint
from billiard.runfile.tables import read_collisions
from billiard.scene.checks import LIMITS, Limit
from billiard.scene.scene import load_scene, with_values
from billiard.status import Status

K = 37  # the impact at which a fault is injected

# the harness of every fault: ``nan_after`` and ``patch``; the case's code follows and
# puts what the test checks into ``out``, printed as JSON on the last line
_PRELUDE = """
import importlib, json, math, sys
from billiard import jit
assert not jit.ENABLED

def nan_after(function, calls):
    count = [0]
    def wrapped(*args):
        count[0] += 1
        value = function(*args)
        if count[0] < calls:
            return value
        return tuple(math.nan for _ in value) if isinstance(value, tuple) else math.nan
    return wrapped

def patch(module, name, value):
    setattr(importlib.import_module(module), name, value)

out = {}
"""
_EPILOGUE = "\nprint(json.dumps(out))\n"


def interpreted(code: str, *args: str) -> dict:
    """Run ``code`` after the harness in a fresh interpreter with the JIT disabled."""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    done = subprocess.run(
        [sys.executable, "-c", _PRELUDE + code + _EPILOGUE, *args],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def time_of_impact(scene, k: int) -> str:
    """The time of impact k of an undisturbed run, as the messages print it."""
    return f"{simulate(scene, collisions=k).columns['t'][k - 1]:.9g}"


def assert_kept(result, out: Path, rows: int) -> None:
    assert result["rows"] == rows
    assert read_collisions(out / CSV_NAME)["n"].tolist() == list(range(1, rows + 1))
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    assert checkpoint["status"] == "stopped" and checkpoint["csv"]["rows"] == rows
    assert checkpoint["stop_reason"] == result["reason"]


_STREAMED_NAN_IMPACT = """
from billiard.scene.scene import load_scene
from billiard.run.simulate import simulate
kernel_ball = importlib.import_module("billiard.kernels.impact")
stick = nan_after(kernel_ball.impact_stick, int(sys.argv[1]))
patch("billiard.kernels.impact", "impact_stick", stick)
result = simulate(load_scene("hyperbola-5.8hz"), collisions=200, out_dir=sys.argv[2])
out = {"reason": result.stop_reason, "rows": len(result)}
"""


def test_non_finite_impact_result(tmp_path):
    """The impact map returns NaN at impact K: the run stops there, K - 1 rows kept."""
    when = time_of_impact(load_scene("hyperbola-5.8hz"), K)
    result = interpreted(_STREAMED_NAN_IMPACT, str(K), str(tmp_path))
    assert result["reason"] == f"non-finite state at impact {K} (t = {when} s): v1 = nan"
    assert_kept(result, tmp_path, K - 1)
    # and resuming it says so rather than running into the fault again
    assert resume(tmp_path).already_finished


def test_non_finite_energy_is_named():
    when = time_of_impact(load_scene("wedge-6.6hz"), K)
    result = interpreted(
        """
from billiard.scene.scene import load_scene
from billiard.run.simulate import simulate
loop = importlib.import_module("billiard.kernels.loop")
patch("billiard.kernels.loop", "energy", nan_after(loop.energy, int(sys.argv[1])))
result = simulate(load_scene("wedge-6.6hz"), collisions=100)
out = {"reason": result.stop_reason, "rows": len(result)}
""",
        str(K),
    )
    assert result["reason"] == f"non-finite state at impact {K} (t = {when} s): energy = nan"
    assert result["rows"] == K - 1


def test_root_solver_failure_in_the_offset_inversion():
    """The curve's slope turns NaN after impact 100 (a generated function gone bad):
    Newton on the offset curve cannot converge, the run stops after impact 100."""
    when = time_of_impact(load_scene("parabola-5.4hz"), 100)
    result = interpreted(
        """
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
from billiard.run.simulate import Simulation
walls = importlib.import_module("billiard.geometry.wall_functions")
loop = importlib.import_module("billiard.kernels.loop")
from billiard.kernels.layout import EN_IMPACTS
boxed, step = walls.phase_wall_functions, loop.step
broken = [False]

def phase_wall_functions(sim):
    f, df, d2f, d3f = boxed(sim)
    bad = tuple(
        (lambda s, p, good=good: math.nan if broken[0] else good(s, p)) for good in df
    )
    return f, bad, d2f, d3f

def counting(ctx, *args):
    # the slope turns bad once impact 100 is done
    broken[0] = broken[0] or ctx[EN_IMPACTS] >= 100
    return step(ctx, *args)

patch("billiard.geometry.wall_functions", "phase_wall_functions", phase_wall_functions)
patch("billiard.kernels.loop", "step", counting)

recorder = MemoryRecorder()
reason = Simulation(load_scene("parabola-5.4hz")).run(300, recorder)
out = {"reason": reason, "rows": len(recorder)}
"""
    )
    assert re.fullmatch(
        rf"offset-curve inversion did not converge at x = \S+ m after impact 100 "
        rf"\(t = {re.escape(when)} s\)",
        result["reason"],
    ), result["reason"]
    assert result["rows"] == 100


def test_root_solver_failure_in_the_impact_time():
    """The impact-time root solve gives up (as after 200 iterations without converging)."""
    times = simulate(load_scene("wedge-6.6hz"), collisions=100).columns["t"]
    result = interpreted(
        """
from billiard.kernels import layout
from billiard.scene.scene import load_scene
from billiard.run.simulate import simulate
locate = importlib.import_module("billiard.kernels.locate")
original = locate.root
calls = [0]

def failing(*args):
    calls[0] += 1
    if calls[0] >= int(sys.argv[1]):
        raise layout.KernelError(layout.E_ROOT)
    return original(*args)

patch("billiard.kernels.locate", "root", failing)
result = simulate(load_scene("wedge-6.6hz"), collisions=100)
out = {"reason": result.stop_reason, "rows": len(result)}
""",
        str(K),
    )
    done = result["rows"]
    assert done >= 1
    assert result["reason"] == (
        f"the impact time did not converge after impact {done} (t = {times[done - 1]:.9g} s)"
    )


def test_flight_integrator_failure():
    """The drag right-hand side turns NaN in the flight after impact K - 1: the step-size
    control rejects every step; the run stops with a message, no traceback."""
    scene = load_scene("hyperbola-5.8hz", overrides=["air.drag=fowles"])  # adaptive flight
    when = time_of_impact(scene, K - 1)
    result = interpreted(
        """
from billiard.runfile.record import MemoryRecorder
from billiard.scene.scene import load_scene
from billiard.run.simulate import Simulation
from billiard.kernels.layout import EN_IMPACTS
flight = importlib.import_module("billiard.kernels.flight")
good = flight.rhs
last = int(sys.argv[1]) - 1

def rhs(ctx, u1, u2):
    # NaN from the flight after impact K - 1 on
    return (math.nan, math.nan) if ctx[EN_IMPACTS] >= last else good(ctx, u1, u2)

patch("billiard.kernels.flight", "rhs", rhs)
rows = MemoryRecorder()
sim = Simulation(load_scene("hyperbola-5.8hz", overrides=["air.drag=fowles"]))
reason = sim.run(200, rows)
out = {"reason": reason, "rows": len(rows)}
""",
        str(K),
    )
    reason = result["reason"]
    assert reason.startswith(
        "the flight's step-size control failed (Dormand-Prince, 200 rejected steps from tau = "
    )
    assert reason.endswith(f"after impact {K - 1} (t = {when} s)")
    assert result["rows"] == K - 1


def test_overflow_is_a_numerical_failure(monkeypatch):
    # a scene refuses such a start (initial.v1 is at most 100 m/s); lift the scene's
    # limit to test the engine's own guard
    monkeypatch.setitem(LIMITS, "initial.v1", Limit(-math.inf, math.inf, "m/s"))
    scene = with_values(load_scene("parabola-5.4hz"), {"initial.v1": 1e200})
    result = simulate(scene, collisions=10)
    # the generated code squares by multiplying, which overflows to inf (pow raised
    # OverflowError): the guard on every record's values stops the run there
    assert result.status is Status.NON_FINITE and len(result) == 0
    assert result.stop_reason == "non-finite state at impact 1 (t = 0 s): energy = inf"


def test_unresolvable_collapse_keeps_rows_on_disk(tmp_path):
    """Without the low-velocity rule a ball lying on the shaken bottom cannot be lifted:
    zero-time flights pile up and the run stops, every row kept (the 200 impacts within
    1e-6 s come before the 1,000 consecutive zero flights)."""
    scene = load_scene("parabola-5.4hz", overrides=["contact.elastic_below=0"])
    result = simulate(scene, collisions=5000, out_dir=tmp_path)
    assert result.stop_reason == (
        "inelastic collapse: 200 impacts within 1e-06 s of simulated time, at impact 201 (t = 0 s)"
    )
    assert_kept({"reason": result.stop_reason, "rows": len(result)}, tmp_path, 201)


# every flight lasts 1e-12 s and ends where it began: impacts pile up in time
_HOPPING_IN_PLACE = """
from billiard.kernels import flight, layout
from billiard.kernels.locate import relative
from billiard.kernels.surfaces import contact

def locate(ctx, p, walls, theta0, q1, q2, u1, u2, u3):
    ctx[layout.THETA0] = theta0
    flight.begin(ctx, q1, q2, u1, u2, u3)
    px = relative(ctx, 0.0, q1, q2, u1, u2)[0]
    s, z = contact(ctx, p, walls, 0, px)
    return 1e-12, 0, q1, q2, u1, u2, theta0, s, z

patch("billiard.kernels.loop", "locate", locate)
"""


def test_collapse_in_time_is_detected_and_survives_a_checkpoint(tmp_path):
    """200 impacts within 1e-6 s stop the run; the detector's window is part of the
    engine state, so a run interrupted in the middle of the pile-up stops at the same
    impact after resuming."""
    result = interpreted(
        _HOPPING_IN_PLACE
        + """
from pathlib import Path
from billiard.runfile.checkpoint import read_checkpoint
from billiard.engine.interrupt import signal_after
from billiard.scene.scene import load_scene
from billiard.run.simulate import RunInterrupted, resume, simulate
work = Path(sys.argv[1])
scene = load_scene("parabola-5.4hz")
whole = simulate(scene, collisions=20000, out_dir=work / "whole")
try:
    simulate(scene, collisions=20000, out_dir=work / "parts", on_record=signal_after(120))
    out["interrupted"] = False
except RunInterrupted:
    out["interrupted"] = True
out["recent"] = len(read_checkpoint(work / "parts" / "checkpoint.json")["engine"]["recent"])
out["whole"] = whole.stop_reason
out["parts"] = resume(work / "parts").stop_reason
""",
        str(tmp_path),
    )
    assert result["whole"].startswith(
        f"inelastic collapse: {COLLAPSE_COUNT} impacts within 1e-06 s of simulated time, "
        f"at impact {COLLAPSE_COUNT + 1} (t = "
    )
    assert result["interrupted"] and result["recent"] == 120
    assert result["parts"] == result["whole"]
    assert (tmp_path / "parts" / CSV_NAME).read_bytes() == (
        tmp_path / "whole" / CSV_NAME
    ).read_bytes()


def test_command_line_reports_a_fault_in_one_line(tmp_path):
    when = time_of_impact(load_scene("wedge-6.6hz"), K)
    out = tmp_path / "run"
    result = interpreted(
        """
import contextlib, io
from billiard.cli import main
kernel_ball = importlib.import_module("billiard.kernels.impact")
stick = nan_after(kernel_ball.impact_stick, int(sys.argv[1]))
patch("billiard.kernels.impact", "impact_stick", stick)
stdout, stderr = io.StringIO(), io.StringIO()
with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
    code = main(["run", "wedge-6.6hz", "--collisions", "100", "--out", sys.argv[2], "--no-plot"])
out = {"code": code, "out": stdout.getvalue(), "err": stderr.getvalue()}
""",
        str(K),
        str(out),
    )
    assert result["code"] == 3
    assert result["err"] == (
        f"billiard: stopped: non-finite state at impact {K} (t = {when} s): v1 = nan\n"
    )
    assert f"{K - 1} impacts" in result["out"]
    assert len(read_collisions(out / CSV_NAME)["n"]) == K - 1
