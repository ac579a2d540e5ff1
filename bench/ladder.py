"""The model ladder: the effect of each physical term on what the paper reports, and its
cost.

Each term is switched off in turn in the built-in scene, which is run as a user runs it
(from rest, default method). Outputs: the period-one orbit if the run locks into one
(the parabola's reported height), and return-map statistics over the impacts after the
first 10 %: mean and standard deviation of the impact height q2, the fraction of
return-map points above the diagonal (q2 of the next impact higher), and the mean time
of flight. Their statistical noise is the standard error of batch means (10 batches).
Two extra rows start on the attractor, in flight: the full model (how much a different
start moves the statistics) and the model without the low-velocity rule, which cannot
start from rest.
"""

from __future__ import annotations

import math

import numpy as np

from bench.common import full_model
from billiard.analysis.calibrate import find_period_one
from billiard.run.simulate import simulate
from billiard.scene.scene import Scene, with_values

VARIANTS: tuple[tuple[str, dict], ...] = (
    ("full model", {}),
    ("no air drag", {"air.drag": "none"}),
    ("no friction (mu_s = mu_k = 0)", {"contact.mu_static": 0.0, "contact.mu_kinetic": 0.0}),
    ("tiny rotational inertia (k = 0.01)", {"ball.inertia_factor": 0.01}),
    ("near-point ball (r = 0.01 mm)", {"ball.radius": 1e-5}),
    ("no low-velocity rule (elastic_below = 0)", {"contact.elastic_below": 0.0}),
)
IN_FLIGHT: tuple[tuple[str, dict], ...] = (
    ("full model, started in flight", {}),
    ("elastic_below = 0, started in flight", {"contact.elastic_below": 0.0}),
)
BATCHES = 10
#: a mean time of flight below this (s): the ball has come to rest (inelastic collapse)
COLLAPSED_TOF = 1e-6
#: a relative change up to this is "small"
SMALL = 0.02
#: return-map points closer than this (m) to the diagonal count as on it
DIAGONAL = 1e-9


def batch_error(x: np.ndarray) -> float:
    """Standard error of the mean of x from BATCHES batch means."""
    if len(x) < 2 * BATCHES:
        return math.nan
    means = [b.mean() for b in np.array_split(x, BATCHES)]
    return float(np.std(means, ddof=1) / math.sqrt(BATCHES))


def outputs(columns: dict, scene: Scene) -> dict:
    """What the paper reports, from the records of one run."""
    q2, tof = columns["q2"], columns["tof"]
    n = len(q2)
    out: dict = {"impacts": n}
    orbit = find_period_one(columns, scene.ball.mass, scene.run.gravity)
    out["orbit_height"] = orbit.height if orbit else None
    out["orbit_tof"] = orbit.time_of_flight if orbit else None
    keep = slice(n // 10, n)
    q2, tof = q2[keep], tof[keep]
    if len(q2) < 2:
        return out
    out["collapsed"] = bool(tof.mean() < COLLAPSED_TOF)
    if out["collapsed"]:
        out["orbit_height"] = out["orbit_tof"] = None
    # points within DIAGONAL of the diagonal (a periodic orbit) are not above it
    above = (q2[1:] > q2[:-1] + DIAGONAL).astype(float)
    out.update(
        mean_q2=float(q2.mean()),
        se_q2=batch_error(q2),
        std_q2=float(q2.std()),
        above=float(above.mean()),
        se_above=batch_error(above),
        mean_tof=float(tof.mean()),
        se_tof=batch_error(tof),
        elastic=float(np.mean(columns["regime"][keep] == "elastic")),
    )
    return out


def measure_scene(name: str, impacts: int, start: Scene) -> list[dict]:
    rows = []
    cases = [(label, full_model(name), changes) for label, changes in VARIANTS]
    cases += [(label, start, changes) for label, changes in IN_FLIGHT]
    for label, base, changes in cases:
        scene = with_values(base, changes) if changes else base
        result = simulate(scene, collisions=impacts)
        row = {
            "scene": name,
            "variant": label,
            "wall_time": result.wall_time,
            "stop": result.stop_reason or "",
            **outputs(result.columns, scene),
        }
        rows.append(row)
        print(
            f"  {name} {label}: {row['impacts']} impacts in {result.wall_time:.2f} s "
            f"{row['stop'][:60]}",
            flush=True,
        )
    return rows


def verdict(row: dict, full: dict) -> str:
    """Does switching the term off change what the paper reports?

    "no change": a locked orbit's height within 0.1 mm, or every statistic within twice
    the combined standard error; "small": within SMALL (relative) of the full model's
    value; else "changes". A run that stops or collapses changes everything.
    """
    if row["stop"] or row.get("collapsed"):
        return "changes: the ball comes to rest (inelastic collapse)"
    if full.get("orbit_height") is not None or row.get("orbit_height") is not None:
        if full.get("orbit_height") is None or row.get("orbit_height") is None:
            return "changes: locks" if row.get("orbit_height") else "changes: no lock"
        dh = abs(row["orbit_height"] - full["orbit_height"])
        rel = dh / full["orbit_height"]
        if dh <= 1e-4:
            return "no change"
        return f"small ({100 * rel:.1f} %)" if rel <= SMALL else f"changes ({100 * rel:.0f} %)"
    worst = "no change"
    for key, se in (("mean_q2", "se_q2"), ("above", "se_above"), ("mean_tof", "se_tof")):
        if key not in row or key not in full:
            return "changes"
        delta = abs(row[key] - full[key])
        if delta <= 2.0 * math.hypot(row[se], full[se]):
            continue
        rel = delta / abs(full[key])
        if rel > SMALL:
            return f"changes ({key}: {100 * rel:.0f} %)"
        worst = f"small ({key}: {100 * rel:.1f} %)"
    return worst
