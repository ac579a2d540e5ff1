"""The uncertainty exponent: the estimator against label functions whose exponent is
known in closed form, and the shape of a short real estimate."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from billiard.scene.scene import load_scene, with_values
from billiard.sweep.uncertainty import (
    fit_exponent,
    run_uncertainty,
    uncertain_counts,
    uncertainty_figure,
    write_results,
)


def _counts(label, x, y, eps):
    """Uncertain starts of the label function ``label(x, y)`` per eps."""
    centre = label(x, y)
    plus = np.array([label(x + e, y) for e in eps])
    minus = np.array([label(x - e, y) for e in eps])
    return uncertain_counts(centre, plus, minus)


def test_a_straight_boundary_has_alpha_one_exactly():
    """Starts on an even grid, boundary x = b: the uncertain ones are those within eps
    of b, 2 eps n of them up to the grid's rounding, so f = 2 eps and alpha = 1."""
    n = 100_000
    x = (np.arange(n) + 0.5) / n
    eps = np.geomspace(1e-4, 1e-1, 7)
    counts = _counts(lambda x, y: x < 0.3137, x, None, eps)
    assert np.all(np.abs(counts - 2 * eps * n) <= 1)
    alpha, se, used = fit_exponent(eps, counts / n)
    assert used.all()
    assert abs(alpha - 1.0) < 1e-3 and se < 1e-3


def test_a_smooth_closed_boundary_gives_f_proportional_to_eps():
    """Inside or outside a circle of radius R in the unit square: the uncertain starts
    lie within eps (along x) of the circle, an area of 8 R eps less a sliver at the
    circle's top and bottom, integral of min(4 eps, 2 w + 2 eps) dy with w the chord's
    half-width."""
    radius = 0.3
    rng = np.random.default_rng(7)
    n = 200_000
    x, y = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    eps = np.geomspace(1e-3, 3e-2, 5)

    def inside(x, y):
        return (x - 0.5) ** 2 + (y - 0.5) ** 2 < radius**2

    counts = _counts(inside, x, y, eps)
    h = np.linspace(-radius, radius, 200_001)
    w = np.sqrt(np.maximum(radius**2 - h**2, 0.0))
    for e, c in zip(eps, counts, strict=True):
        area = np.trapezoid(np.minimum(4 * e, 2 * w + 2 * e), h)
        assert abs(area - 8 * radius * e) < 0.01 * area  # the sliver is small
        expected = n * area
        assert abs(c - expected) < 4 * math.sqrt(expected)  # binomial, 4 sigma
    alpha, se, _ = fit_exponent(eps, counts / n)
    assert abs(alpha - 1.0) < 0.03


def _cantor_label(x, y):
    """Parity of the place of the first ternary digit 1 of x mod 1 (2 for none): the
    boundary between the labels is the middle-thirds Cantor set."""
    x = np.mod(x, 1.0)
    label = np.full(x.shape, 2, dtype=np.int64)
    for place in range(1, 34):
        x = 3.0 * x
        digit = np.floor(x)
        x -= digit
        label = np.where((digit == 1.0) & (label == 2), place % 2, label)
    return label


def test_a_cantor_boundary_gives_one_minus_its_dimension():
    """Boundary: the middle-thirds Cantor set, dimension ln 2 / ln 3 on the line, so
    alpha = 1 - ln 2 / ln 3 = 0.369 (d = 1.631 for its product with a line in the
    plane); at eps = 3^-k the uncertain share shrinks by 2/3 per step."""
    rng = np.random.default_rng(3)
    n = 200_000
    x = rng.uniform(0, 1, n)
    eps = 3.0 ** -np.arange(5, 13)
    counts = _counts(_cantor_label, x, None, eps)
    alpha, se, used = fit_exponent(eps, counts / n)
    assert used.all()
    exact = 1.0 - math.log(2) / math.log(3)
    assert abs(alpha - exact) < 0.015
    assert se < 0.005


def test_the_fit():
    eps = np.geomspace(1e-6, 1e-2, 6)
    alpha, se, used = fit_exponent(eps, 0.3 * eps**0.7)
    assert abs(alpha - 0.7) < 1e-12 and se < 1e-12 and used.all()
    # f = 0 or f = 1 have no logarithm to fit: left out
    fraction = np.concatenate(([0.0], 0.3 * eps[1:-1] ** 0.5, [1.0]))
    alpha, se, used = fit_exponent(eps, fraction)
    assert abs(alpha - 0.5) < 1e-12 and used.tolist() == [False] + [True] * 4 + [False]
    alpha, se, _ = fit_exponent(eps[:2], [0.01, 0.1])
    assert abs(alpha - math.log(10) / math.log(eps[1] / eps[0])) < 1e-12 and math.isnan(se)
    alpha, se, _ = fit_exponent(eps, [0.0] * 5 + [0.2])
    assert math.isnan(alpha) and math.isnan(se)


def test_a_short_estimate_on_the_wedge(tmp_path):
    """The shape of the output (a few impacts: transients still tell starts apart)."""
    scene = load_scene("wedge-6.6hz")
    eps = np.geomspace(1e-4, 1e-2, 3)
    result = run_uncertainty(
        scene, (-0.04, 0.04), (0.02, 0.12), samples=40, eps=eps, impacts=30, transient=50
    )
    assert result.samples == 40 and result.q1.shape == result.q2.shape == (40,)
    assert np.all((result.q1 >= -0.04) & (result.q1 <= 0.04))
    assert np.all((result.q2 >= 0.02) & (result.q2 <= 0.12))
    assert result.uncertain.shape == (3,) and np.all(result.uncertain <= 40)
    assert sum(result.counts) == 40 and len(result.counts) == len(result.labels)
    assert result.drawn >= 40 + result.dropped
    assert math.isfinite(result.alpha) and 0.0 <= result.alpha <= 1.5
    assert result.dimension == 2.0 - result.alpha
    table, summary = write_results(result, tmp_path)
    with open(table) as f:
        rows = list(csv.DictReader(f))
    assert [float(r["eps_m"]) for r in rows] == list(eps)
    assert [int(r["uncertain"]) for r in rows] == result.uncertain.tolist()
    saved = json.loads(summary.read_text())
    assert saved["alpha"] == result.alpha and saved["samples"] == 40
    assert saved["dropped_for_invalid_neighbour"] == result.dropped
    figure = uncertainty_figure(result, tmp_path / "u.png")
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the same seed draws the same starts and gives the same counts
    again = run_uncertainty(
        scene, (-0.04, 0.04), (0.02, 0.12), samples=40, eps=eps, impacts=30, transient=50
    )
    assert np.array_equal(again.q1, result.q1)
    assert np.array_equal(again.uncertain, result.uncertain)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"q1": (0.01, -0.01)}, "LO < HI"),
        ({"samples": 1}, "samples must be >= 2, got 1: with one start"),
        ({"eps": [1e-3]}, "at least 2"),
        ({"eps": [0.0, 1e-3]}, "all > 0"),
        ({"q2": (5.0, 6.0), "samples": 10}, "is the box inside the container"),
    ],
)
def test_bad_estimates_are_refused(kwargs, match):
    scene = load_scene("wedge-6.6hz")
    args = {"q1": (-0.01, 0.01), "q2": (0.03, 0.05)} | kwargs
    q1, q2 = args.pop("q1"), args.pop("q2")
    with pytest.raises(ValueError, match=match):
        run_uncertainty(scene, q1, q2, impacts=5, transient=0, **args)


def test_a_scene_the_ensemble_kernel_does_not_take():
    scene = with_values(load_scene("wedge-6.6hz"), {"run.method": "rk4"})
    with pytest.raises(ValueError, match="run.method = 'rk4'"):
        run_uncertainty(scene, (-0.01, 0.01), (0.03, 0.05))


def test_the_public_name_takes_a_scene_name():
    import billiard

    assert billiard.run_uncertainty is run_uncertainty
    result = billiard.run_uncertainty(
        "wedge-6.6hz", (-0.02, 0.02), (0.03, 0.06), samples=5, eps=[1e-4, 1e-3], impacts=5
    )
    assert result.scene.name == "wedge-6.6hz" and result.samples == 5
