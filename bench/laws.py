"""Cost per impact of every impact law against Kane and Levinson's, on the paper scenes.

    python -m bench.laws [--impacts N] [--repeats R]

A law's cost is measured on the motion Kane and Levinson's law makes, so that the
comparison is of the laws and not of the different flights they lead to: each law runs
at the parameters of its limit that is a Kane-Levinson law (``PAIRS``: Walton's beta0 = 0
with one friction coefficient, the power law's exponent 0, the viscoelastic law without
dissipation against e = 1, the energy-dependent law at a vanishing energy scale, the
angle-dependent law without slope, the point particle against a frictionless ball), and
beside it that Kane-Levinson law. Each pair runs compiled on each paper scene from the
scene's start for N impacts (default 20,000), the two alternating R times (default 7),
each keeping its fastest run (the least disturbed by other work on the machine), in
CPU time of the process. Printed: the CPU time per impact of each law and its ratio to
its Kane-Levinson pair. Exits 1 when a ratio exceeds ``TARGET`` (1.3), 0 otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time

from billiard.run.simulate import simulate
from billiard.scene.scene import PAPER_SCENES, Scene, load_scene, with_values

#: the largest cost per impact of a law, as a multiple of Kane and Levinson's
TARGET = 1.3

#: each law's scene keys at its Kane-Levinson limit, and that Kane-Levinson law's keys
PAIRS: dict[str, tuple[dict, dict]] = {
    "walton": (
        {"contact.law": "walton", "contact.beta0": 0.0, "contact.mu_static": 0.47},
        {"contact.mu_static": 0.47},
    ),
    "power-law": (
        {"contact.law": "power-law", "contact.e_ref": 0.393, "contact.v_ref": 1.0},
        {},
    ),
    "viscoelastic": (
        {"contact.law": "viscoelastic", "contact.viscous": 0.0},
        {"contact.restitution": 1.0},
    ),
    "energy-dependent": ({"contact.law": "energy-dependent", "contact.energy_scale": 1e-30}, {}),
    "angle-dependent": ({"contact.law": "angle-dependent", "contact.angle_slope": 0.0}, {}),
    "point-particle": (
        {"contact.law": "point-particle"},
        {"contact.mu_static": 0.0, "contact.mu_kinetic": 0.0},
    ),
}


def _scene(name: str, values: dict) -> Scene:
    values = {**values}
    if values.get("contact.law") == "power-law":
        values["contact.exponent"] = 0.0
    return with_values(load_scene(name), values)


def _per_impact(scene: Scene, impacts: int) -> float:
    # CPU time of this process: the runs are single-threaded, and on a shared machine
    # the wall time measures the other work too
    started = time.process_time()
    result = simulate(scene, collisions=impacts)
    return (time.process_time() - started) / max(1, len(result))


def measure(impacts: int, repeats: int) -> dict[tuple[str, str], tuple[float, float]]:
    """The fastest CPU time per impact (s) of each law and of its Kane-Levinson pair, by
    (law, scene)."""
    best: dict[tuple[str, str], tuple[float, float]] = {}
    for name in PAPER_SCENES:
        for law, (values, kane) in PAIRS.items():
            pair = (_scene(name, values), _scene(name, kane))
            for scene in pair:  # compile and warm up
                simulate(scene, collisions=100)
            times = [float("inf"), float("inf")]
            for _ in range(repeats):
                for i, scene in enumerate(pair):
                    times[i] = min(times[i], _per_impact(scene, impacts))
            best[law, name] = (times[0], times[1])
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.laws", description=__doc__)
    parser.add_argument("--impacts", type=int, default=20_000, help="impacts per run")
    parser.add_argument("--repeats", type=int, default=7, help="runs of each, fastest kept")
    args = parser.parse_args(argv)
    best = measure(args.impacts, args.repeats)
    worst = 0.0
    print(f"{'law':<18}" + "".join(f"{name:>24}" for name in PAPER_SCENES))
    for law in PAIRS:
        cells = []
        for name in PAPER_SCENES:
            own, kane = best[law, name]
            worst = max(worst, own / kane)
            cells.append(f"{1e6 * own:9.3f} us ({own / kane:4.2f}x)")
        print(f"{law:<18}" + "".join(f"{cell:>24}" for cell in cells))
    print(f"largest ratio to kane-levinson: {worst:.2f} (target <= {TARGET})")
    return 0 if worst <= TARGET else 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
