"""Synthetic runs and checks shared by the plotting tests (tests/plot/).

The main synthetic run is physically consistent: a ball bouncing vertically at the vertex
x = 0 of the parabola f(x) = 26 x^2 + 0.0063 (m) while the boundary is shaken vertically,
D(t) = A sin(2 pi f t). At the vertex the contact is the bottom point (tangent angle 0, the
radius of curvature 1/(2a) = 19 mm exceeds the ball's radius), so the centre's height at
impact n is known: q2,n = c + r + D(t_n).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
from matplotlib.figure import Figure
from PIL import Image
from scipy.optimize import brentq

from billiard.runfile.record import REQUIRED_COLUMNS, write_collisions
from billiard.scene.scene import Scene, scene_from_toml

A_CURVE, C_CURVE = 26.0, 0.0063  # parabola a (1/m), c (m)
RADIUS, MASS, K = 1.55e-3, 1.3028e-4, 0.4
G = 9.81
COLUMN_NAMES = list(REQUIRED_COLUMNS) + ["wall", "Rt", "Rn"]


def scene_toml(
    *,
    curve: str = "parabola",
    amplitude: float = 1e-3,
    frequency: float = 25.0,
    direction: str = "vertical",
    restitution: float = 0.5,
    name: str = "bounce",
) -> str:
    params = "[boundary.parameters]\na = 26.0\nc = 0.0063\n" if curve == "parabola" else ""
    return f"""name = "{name}"
description = "synthetic run for the plotting tests"

[boundary]
curve = "{curve}"
ceiling = 0.15
escape_height = 1.0

{params}
[drive]
amplitude = {amplitude}
frequency = {frequency}
direction = "{direction}"
phase = 0.0

[ball]
radius = {RADIUS}
mass = {MASS}
inertia_factor = {K}

[contact]
restitution = {restitution}
mu_static = 0.61
mu_kinetic = 0.47
elastic_below = 0.01

[air]
drag = "none"

[run]
gravity = {G}
"""


def bouncing_ball(
    impacts: int,
    *,
    amplitude: float,
    frequency: float,
    e: float,
    elastic_below: float = 0.01,
    drop: float = 0.004,
) -> dict[str, np.ndarray]:
    """Impacts of a ball dropped from rest, `drop` m above contact, onto the vertex of the
    vertically shaken parabola (drag off, no spin: the tangential velocity stays 0)."""
    w = 2 * math.pi * frequency
    rest = C_CURVE + RADIUS

    def plate(t):
        return rest + amplitude * np.sin(w * t)

    t, q2, v2 = 0.0, rest + drop, 0.0
    t_prev = 0.0
    rows = []
    step = 2e-5
    for n in range(1, impacts + 1):
        tau = np.arange(1, 200_001) * step
        gap = q2 + v2 * tau - 0.5 * G * tau**2 - plate(t + tau)
        first_open = int(np.argmax(gap > 0))
        j = first_open + int(np.argmax(gap[first_open:] < 0))
        assert gap[j] < 0, "no impact found"

        def h(s, t=t, q2=q2, v2=v2):
            return q2 + v2 * s - 0.5 * G * s * s - plate(t + s)

        s = brentq(h, tau[j - 1], tau[j], xtol=1e-15)
        t += s
        v2 -= G * s
        q2 = float(plate(t))
        vb = amplitude * w * math.cos(w * t)
        relative = v2 - vb
        elastic = abs(relative) < elastic_below
        v2 = vb - (1.0 if elastic else e) * relative
        energy = 0.5 * MASS * v2**2 + MASS * G * q2
        rows.append(
            (
                n,
                t,
                0.0,
                q2,
                0.0,
                v2,
                0.0,
                0.0,
                v2,
                t - t_prev,
                "elastic" if elastic else "stick",
                0.0,
                energy,
                0,
                0.0,
                MASS * (v2 - (relative + vb)),
            )
        )
        t_prev = t
    return {name: np.array([row[i] for row in rows]) for i, name in enumerate(COLUMN_NAMES)}


def make_run(directory: Path, columns: dict[str, np.ndarray], toml: str) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    write_collisions(directory / "collisions.csv", columns)
    (directory / "scene.toml").write_text(toml)
    return directory


def single_axes() -> tuple[Figure, object]:
    fig = Figure()
    return fig, fig.add_subplot()


def check_png(path: Path, min_width: int = 500, dpi: int = 100) -> None:
    """A non-blank PNG at least ``min_width`` px wide at 100 dpi and 2.5 to 10 inches
    high, at ``dpi`` pixels per inch."""
    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    height, width = image.shape[:2]
    assert width >= min_width * dpi / 100 and 2.5 * dpi <= height <= 10 * dpi
    assert image[..., :3].std() > 0.02  # not blank


def check_gif(path: Path) -> None:
    assert path.stat().st_size <= 2_000_000
    with Image.open(path) as gif:
        assert gif.format == "GIF"
        assert 2 <= gif.n_frames <= 150
        assert 200 <= gif.size[0] <= 800


def scene_of(toml: str) -> Scene:
    return scene_from_toml(toml)


def static_columns() -> dict[str, np.ndarray]:
    """A ball bouncing on the vertex of a still boundary at the constant height c + r."""
    return bouncing_ball(40, amplitude=0.0, frequency=5.4, e=0.8, drop=0.02)


def static_toml() -> str:
    """The still scene, its curve given as an expression."""
    return scene_toml(
        curve="26*x**2 + 0.0063",
        amplitude=0.0,
        frequency=5.4,
        direction="horizontal",
        restitution=0.8,
        name="still",
    )


def engine_run(out: Path, collisions: int = 300) -> Path:
    """A real run of the parabola at 5.4 Hz (air drag on), written by ``billiard run``."""
    from billiard.cli import main

    args = ["run", "parabola-5.4hz", "--collisions", str(collisions), "--out", str(out)]
    assert main([*args, "--no-plot"]) == 0
    return out
