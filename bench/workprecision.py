"""Work against precision: CPU time per 1,000 impacts against the error of the impact
times and points after a few impacts, for every method and setting, drag on and off.

References, started from the same state: with drag off the default method (the exact
parabola, impacts located to rounding); with drag on the default method at rtol 1e-13,
cross-checked against the careful DOP853 peer at rtol 1e-13.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

from bench.common import (
    Config,
    engine_run,
    first_difference,
    position_difference,
    start_scene,
    timed,
)
from bench.peer import SolveIvpPeer
from billiard import jit
from billiard.run.simulate import Simulation
from billiard.scene.scene import Scene, with_values

REFERENCE_RTOL = 1e-13
#: start perturbation (m) whose effect after n impacts is the "chaos floor"
NUDGE = 1e-15


def settings(cfg: Config, drag: str) -> list[tuple[str, str, object]]:
    """(method, setting label, how to run) for every method and setting."""
    rows: list[tuple[str, str, object]] = []
    if drag == "none":
        rows.append(("event", "exact flight", ("event", {})))
    else:
        rows += [("event", f"rtol {r:g}", ("event", {"run.rtol": r})) for r in cfg.event_rtols]
    rows += [("rk4", f"step {h:g} s", ("rk4", {"run.step": h})) for h in cfg.rk4_steps]
    for careful, label in ((False, "DOP853"), (True, "DOP853 careful")):
        rows += [(label, f"rtol {r:g}", ("peer", (r, careful))) for r in cfg.peer_rtols]
    return rows


def run_setting(scene: Scene, how: tuple, impacts: int, repeats: int) -> tuple[dict, float, str]:
    kind, arg = how
    if kind == "peer":
        rtol, careful = arg
        peer = SolveIvpPeer(scene, rtol, careful=careful)
        state = Simulation(scene).initial
        return timed(lambda: peer.run(state, impacts), repeats)
    changed = with_values(scene, arg) if arg else scene
    return timed(lambda: engine_run(changed, impacts, kind), repeats)


# The default method's settings timed again with the kernels interpreted (a fresh process
# with NUMBA_DISABLE_JIT=1): the solve_ivp peer runs interpreted, so these are the costs a
# comparison of methods, not of interpreters, takes. The results are the same bits.
_INTERPRETED = """
import json, sys
from bench.common import Config, engine_run, start_scene, timed
from bench.workprecision import settings
from billiard.scene.scene import with_values
name, quick = sys.argv[1], sys.argv[2] == "1"
cfg = Config.quick_mode() if quick else Config.full()
start = start_scene(name, cfg.transient)
out = {}
for drag in ("fowles", "none"):
    scene = with_values(start, {"air.drag": drag})
    for method, label, (kind, arg) in settings(cfg, drag):
        if method != "event":
            continue
        changed = with_values(scene, arg) if arg else scene
        run, cpu, _ = timed(lambda: engine_run(changed, max(cfg.checkpoints), kind), cfg.repeats)
        out[drag + "|" + label] = 1000.0 * cpu / max(len(run["t"]), 1)
print(json.dumps(out))
"""


def interpreted_event_costs(name: str, cfg: Config) -> dict[str, float]:
    """CPU s per 1,000 impacts of the default method's settings, kernels interpreted."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"}
    env["NUMBA_DISABLE_JIT"] = "1"
    done = subprocess.run(
        [sys.executable, "-c", _INTERPRETED, name, "1" if cfg.quick else "0"],
        cwd=Path(__file__).resolve().parent.parent,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.splitlines()[-1])


def errors(run: dict, ref: dict, checkpoints: tuple[int, ...]) -> dict:
    return {
        "t": {str(k): first_difference(run["t"], ref["t"], k) for k in checkpoints},
        "pos": {str(k): position_difference(run, ref, k) for k in checkpoints},
    }


def measure_scene(name: str, cfg: Config) -> dict:
    """All rows of one scene, plus the reference checks and the chaos floor."""
    start = start_scene(name, cfg.transient)
    impacts = max(cfg.checkpoints)
    out: dict = {"scene": name, "rows": [], "reference": {}, "floor": {}}
    event_rows: list[dict] = []
    for drag in ("fowles", "none"):
        scene = with_values(start, {"air.drag": drag})
        if drag == "fowles":
            ref_scene = with_values(scene, {"run.rtol": REFERENCE_RTOL})
            check, _, _ = SolveIvpPeer(scene, REFERENCE_RTOL, careful=True).run(
                Simulation(scene).initial, impacts
            )
        else:
            ref_scene = scene
        ref, _, ref_stop = engine_run(ref_scene, impacts)
        # the chaos floor: what moving the start by 1e-15 m does to the reference
        q1 = ref_scene.initial.q1
        nudged, _, _ = engine_run(with_values(ref_scene, {"initial.q1": q1 + NUDGE}), impacts)
        out["floor"][drag] = errors(nudged, ref, cfg.checkpoints)
        out["reference"][drag] = {"stop": ref_stop, "impacts": len(ref["t"])}
        if drag == "fowles":
            out["reference"][drag]["dop853_check"] = errors(check, ref, cfg.checkpoints)
        for method, label, how in settings(cfg, drag):
            run, cpu, stop = run_setting(scene, how, impacts, cfg.repeats)
            done = len(run["t"])
            out["rows"].append(
                {
                    "drag": drag,
                    "method": method,
                    "setting": label,
                    "impacts": done,
                    "stop": stop,
                    "cpu_per_1000": 1000.0 * cpu / max(done, 1),
                    # the engine's methods run on the compiled kernels when numba is there
                    "compiled": jit.ENABLED and how[0] != "peer",
                    "errors": errors(run, ref, cfg.checkpoints),
                }
            )
            if method == "event":
                event_rows.append(out["rows"][-1])
            print(
                f"  {name} drag={drag} {method} {label}: {done} impacts, "
                f"{1000 * cpu / max(done, 1):.3g} s/1000, "
                f"t-err {out['rows'][-1]['errors']['t']}",
                flush=True,
            )
    interpreted = interpreted_event_costs(name, cfg)
    for row in event_rows:
        row["cpu_per_1000_interpreted"] = interpreted[row["drag"] + "|" + row["setting"]]
    return out


def cost_at(
    rows: list[dict], method: str, drag: str, k: int, target: float, key: str = "cpu_per_1000"
) -> dict:
    """CPU s per 1,000 impacts (the rows' ``key``) at which ``method`` reaches an
    impact-time error of ``target`` after k impacts: log-log interpolation between the
    two settings that bracket it, or the cheapest setting already below it. ``kind``
    says which."""
    pts = sorted(
        (r[key], r["errors"]["t"][str(k)])
        for r in rows
        if r["method"] == method and r["drag"] == drag and key in r
    )
    below = [(c, e) for c, e in pts if e <= target]
    if not below:
        best = min(pts, key=lambda p: p[1]) if pts else (math.nan, math.nan)
        return {"cost": best[0], "error": best[1], "kind": "not reached"}
    cheapest = below[0]
    above = [(c, e) for c, e in pts if c < cheapest[0] and e > target and math.isfinite(e)]
    if not above:
        return {"cost": cheapest[0], "error": cheapest[1], "kind": "cheapest setting"}
    c0, e0 = above[-1]
    c1, e1 = cheapest
    if e1 <= 0.0:
        return {"cost": c1, "error": e1, "kind": "cheapest setting"}
    w = math.log(target / e0) / math.log(e1 / e0)
    cost = math.exp(math.log(c0) + w * (math.log(c1) - math.log(c0)))
    return {"cost": cost, "error": target, "kind": "interpolated"}
