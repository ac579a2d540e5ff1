"""Sweep plots: labelled colour bars, a constant map drawn as one value, periods and
attractors in one distinct colour per category with a legend, basin maps over starting
positions with the container's wall, and titles that name the base scene's --set
changes."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from billiard import load_scene
from billiard.geometry.curves import load_curve
from billiard.sweep import Sweep, parse_vary
from billiard.sweep.plots import (
    basins_figure,
    bifurcation_figure,
    constant_value,
    heatmaps_figure,
    plot_sweep,
)
from billiard.sweep.units import variable_name

matplotlib.use("Agg")


def _sweep(changes=("contact.model=phases",), **settings) -> Sweep:
    scene = load_scene("parabola-5.4hz", overrides=list(changes))
    axes = (parse_vary("drive.frequency=5.0:5.4:3"), parse_vary("drive.amplitude=0.02,0.025"))
    return Sweep(scene, axes, impacts=300, transient=100, changes=tuple(changes), **settings)


def _data(sweep: Sweep, **fields) -> dict:
    """Result-file arrays of a sweep whose points are all ok (fields override)."""
    shape = sweep.shape
    data = {variable_name(a.key): np.asarray(a.values, dtype=float) for a in sweep.axes} | {
        "status": np.full(shape, "ok", dtype=object),
        "attractor": np.full(shape, "periodic", dtype=object),
        "period": np.full(shape, 2.0),  # as read_result gives it: NaN where none
        "height_mean": np.full(shape, 0.075),
        "lyapunov": np.full(shape, np.nan),
        "rest_height": np.full(shape, 0.00785),
        "last_height": np.full((*shape, 4), 0.075),
        "last_tof": np.full((*shape, 4), 0.0926),
    }
    return data | fields


def _colour_bars(fig) -> list:
    """The figure's colour bar axes (matplotlib marks them with ``_colorbar``)."""
    return [ax for ax in fig.axes if getattr(ax, "_colorbar", None) is not None]


def _cell_colours(fig, panel: int) -> set:
    """The distinct colours of a map's drawn cells (masked cells are not drawn)."""
    fig.canvas.draw()
    mesh = fig.axes[panel].collections[0]
    shown = ~np.ma.getmaskarray(mesh.get_array()).ravel()
    return {tuple(c) for c in mesh.to_rgba(mesh.get_array().ravel())[shown]}


def test_constant_value_detects_rounding_only():
    # the same orbit at two masses without air drag: equal to 6e-11 relative
    noisy = np.array([[0.0753465998259358, 0.0753465998305629], [np.nan, 0.0753465998259358]])
    assert constant_value(noisy) == pytest.approx(0.0753465998, rel=1e-9)
    assert constant_value(np.array([0.075, 0.0751])) is None
    # within a resolution: 2 nm apart, one value to a sweep that resolves 10 um
    near = np.array([0.07534659, 0.075346592])
    assert constant_value(near) is None
    assert constant_value(near, 1e-5) == pytest.approx(0.075346591)
    assert constant_value(np.zeros(4)) == 0.0
    assert constant_value(np.full(3, np.nan)) is None


def test_constant_height_map_is_one_colour_with_its_value_and_unit():
    sweep = _sweep()
    heights = 0.0753465998259358 + np.array([[0.0, 4.6e-12], [1e-13, 0.0], [2e-12, 3e-12]])
    fig = heatmaps_figure(sweep, _data(sweep, height_mean=heights))
    bars = _colour_bars(fig)
    assert len(bars) == 1  # the height's; the period map has a legend of categories
    assert fig.axes[0].get_legend() is not None
    height_bar = bars[0]._colorbar
    assert height_bar.ax.get_ylabel() == "mean impact height q2 (m)"
    ticks = [t.get_text() for t in height_bar.ax.get_yticklabels()]
    assert ticks == ["0.0753466"]
    notes = [t.get_text() for t in fig.axes[1].texts]
    assert notes == ["one value: 0.0753466\n(all within 1e-05 m, the sweep's tolerance)"]
    assert len(_cell_colours(fig, 1)) == 1  # one colour, no noise


def test_varying_height_map_keeps_a_continuous_labelled_bar():
    sweep = _sweep()
    heights = np.array([[0.03, 0.05], [0.06, 0.075], [0.08, 0.11]])
    fig = heatmaps_figure(sweep, _data(sweep, height_mean=heights))
    bar = _colour_bars(fig)[0]._colorbar
    assert bar.ax.get_ylabel() == "mean impact height q2 (m)"
    assert len(_cell_colours(fig, 1)) == 6


def _legend_texts(ax) -> list[str]:
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def test_period_map_is_categorical_one_colour_per_period_with_a_legend():
    sweep = _sweep()
    period = np.array([[2, 2], [3, 8], [np.nan, 2]])  # NaN: no period, blank
    fig = heatmaps_figure(sweep, _data(sweep, period=period))
    assert _legend_texts(fig.axes[0]) == [
        "period 2 (3 points)",
        "period 3 (1 point)",
        "period 8 (1 point)",
    ]
    assert fig.axes[0].get_legend().get_title().get_text().startswith("impacts per repetition")
    mesh = fig.axes[0].collections[0]
    assert mesh.cmap.N == 3  # one colour per period present, none for 4 to 7
    assert len(_cell_colours(fig, 0)) == 3  # 2, 3 and 8 (the blank cell is masked)
    # the legend's patches are the colours of the cells
    patches = {tuple(p.get_facecolor()) for p in fig.axes[0].get_legend().get_patches()}
    assert patches == _cell_colours(fig, 0)


def test_a_map_of_many_periods_names_the_most_common_and_greys_the_rest():
    """Dozens of periods (a 10^6-point parameter map finds 56): the most common are named,
    each in its colour, the others drawn together in one grey and one legend line."""
    from billiard.sweep.plots import OTHER_PERIODS, PERIODS_SHOWN

    scene = load_scene("parabola-5.4hz")
    axes = (parse_vary("drive.frequency=5.0:5.4:10"), parse_vary("drive.amplitude=0.02:0.03:6"))
    sweep = Sweep(scene, axes, impacts=300, transient=100)
    # 20 periods in the 60 cells, the lower the more common (ties: the lower first)
    counts = [8, 7, 6, 5, 5, 4, 4, 3, 3, 2, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1]
    cells = np.concatenate([np.full(n, float(k)) for k, n in enumerate(counts, start=1)])
    fig = heatmaps_figure(sweep, _data(sweep, period=cells.reshape(sweep.shape)))
    texts = _legend_texts(fig.axes[0])
    assert len(texts) == PERIODS_SHOWN
    common = range(1, PERIODS_SHOWN)  # the most cells
    assert texts[:-1] == [f"period {k} ({int((cells == k).sum())} points)" for k in common]
    rest = cells[cells >= PERIODS_SHOWN]
    others = 20 - (PERIODS_SHOWN - 1)
    assert texts[-1] == f"{others} other periods, {PERIODS_SHOWN} to 20 ({rest.size} points)"
    colours = _cell_colours(fig, 0)
    assert len(colours) == PERIODS_SHOWN
    assert (*OTHER_PERIODS, 1.0) in colours


def test_period_map_without_any_period_says_so():
    sweep = _sweep()
    fig = heatmaps_figure(sweep, _data(sweep, period=np.full(sweep.shape, np.nan)))
    assert fig.axes[0].get_legend() is None
    assert [t.get_text() for t in fig.axes[0].texts] == ["no period found"]


def test_lyapunov_bar_is_labelled():
    sweep = _sweep()
    lyap = np.array([[0.1, -0.2], [0.05, 0.0], [0.3, -0.01]])
    fig = heatmaps_figure(sweep, _data(sweep, lyapunov=lyap))
    labels = [ax._colorbar.ax.get_ylabel() for ax in _colour_bars(fig)]
    assert labels[1] == "Lyapunov exponent (1/impact)"
    assert all(labels)


def test_titles_name_the_set_changes():
    sweep = _sweep(changes=("contact.model=phases", "drive.phase=0.5"))
    fig = heatmaps_figure(sweep, _data(sweep))
    title = " ".join(fig._suptitle.get_text().split())
    assert "parabola-5.4hz with contact.model=phases, drive.phase=0.5" in title
    one = Sweep(sweep.scene, (sweep.axes[0],), impacts=300, transient=100, changes=sweep.changes)
    data = _data(one)
    fig = bifurcation_figure(one, data)
    title = " ".join(fig.axes[0].get_title().split())
    assert "with contact.model=phases, drive.phase=0.5" in title


def test_bifurcation_draws_a_ball_without_impacts_at_its_resting_height(tmp_path):
    one = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=5.0:5.4:3"),))
    shape = one.shape
    heights = np.full((*shape, 4), np.nan)
    heights[2] = 0.075
    data = _data(
        one,
        attractor=np.array(["rolling", "resting", "periodic"], dtype=object),
        last_height=heights,
        last_tof=np.where(np.isnan(heights), np.nan, 0.0926),
    )
    fig = bifurcation_figure(one, data)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "rolling, no impacts: at the resting height" in labels
    assert "resting, no impacts: at the resting height" in labels
    assert "periodic (1)" in labels
    paths = plot_sweep(one, data, tmp_path)
    assert [p.name for p in paths] == ["bifurcation.png"] and paths[0].stat().st_size > 0


# --- basin maps ------------------------------------------------------------------------


def _basin_sweep(first="initial.q1=-0.04:0.04:5", second="initial.q2=0.01:0.09:5") -> Sweep:
    scene = load_scene("parabola-5.4hz")
    return Sweep(scene, (parse_vary(first), parse_vary(second)), impacts=300, transient=100)


def _basin_data(sweep: Sweep) -> dict:
    """Starts inside the wall invalid; the others two orbits (period 2 at two heights),
    a chaotic start and a resting one."""
    shape = sweep.shape
    attractor = np.full(shape, "periodic", dtype=object)
    period = np.full(shape, 2.0)
    height = np.full(shape, 0.075)
    height[:, 3:] = 0.11
    attractor[0, 0] = attractor[-1, 0] = "invalid"
    attractor[2, 1] = "chaotic"
    attractor[2, 0] = "resting"
    period[attractor != "periodic"] = np.nan
    status = np.where(attractor == "invalid", "invalid", "ok").astype(object)
    return _data(sweep, attractor=attractor, period=period, height_mean=height, status=status)


def _wall_line(ax):
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "container wall at the start"]
    return np.asarray(line.get_xdata()), np.asarray(line.get_ydata())


def test_basin_map_over_positions_draws_the_container_wall():
    sweep = _basin_sweep()
    fig = basins_figure(sweep, _basin_data(sweep))
    ax = fig.axes[0]
    x, y = _wall_line(ax)
    curve = load_curve("parabola", dict(sweep.scene.boundary.parameters))
    # drive phase 0 at t = 0: the wall is f itself, over the map's whole width
    assert x.min() == pytest.approx(-0.05) and x.max() == pytest.approx(0.05)
    assert np.array_equal(y, [curve.f(float(v)) for v in x])
    # the view is the map's cells, at equal scales (positions in the same unit)
    assert ax.get_xlim() == pytest.approx((-0.05, 0.05))
    assert ax.get_ylim() == pytest.approx((0.0, 0.1))
    assert ax.get_aspect() == 1.0
    assert _legend_texts(ax)[-1] == "container wall at the start"


def test_basin_map_with_q2_horizontal_draws_the_wall_transposed():
    sweep = _basin_sweep("initial.q2=0.01:0.09:5", "initial.q1=-0.04:0.04:5")
    fig = basins_figure(sweep, _basin_data(sweep))
    q2, q1 = _wall_line(fig.axes[0])
    curve = load_curve("parabola", dict(sweep.scene.boundary.parameters))
    assert np.array_equal(q2, [curve.f(float(v)) for v in q1])


def test_basin_map_over_other_keys_has_no_wall():
    sweep = _basin_sweep("initial.v1=-0.1:0.1:5", "initial.q2=0.01:0.09:5")
    fig = basins_figure(sweep, _basin_data(sweep))
    assert fig.axes[0].get_lines() == []


def test_basin_map_colours_are_one_per_attractor_present():
    sweep = _basin_sweep()
    fig = basins_figure(sweep, _basin_data(sweep))
    texts = _legend_texts(fig.axes[0])
    classes = texts[:-1]
    assert classes == [
        "resting (1 start)",
        "period 2, mean q2 0.0750 m (11 starts)",
        "period 2, mean q2 0.1100 m (10 starts)",
        "chaotic (1 start)",
        "invalid (2 starts)",
    ]
    assert texts[-1] == "container wall at the start"
    fig.canvas.draw()
    mesh = fig.axes[0].collections[0]
    drawn = {tuple(c) for c in mesh.to_rgba(mesh.get_array().ravel())}
    assert len(drawn) == len(classes)  # discrete: one colour per class, none shared


def test_many_orbits_still_get_colours_of_their_own():
    sweep = _basin_sweep("initial.q1=-0.04:0.04:5", "initial.q2=0.01:0.2:20")
    data = _basin_data(sweep)
    data["height_mean"] = np.linspace(0.02, 0.4, sweep.size).reshape(sweep.shape)  # 5 mm apart
    data["attractor"][:] = "periodic"
    data["status"][:] = "ok"
    data["period"] = np.full(sweep.shape, 2.0)
    fig = basins_figure(sweep, data)
    fig.canvas.draw()
    mesh = fig.axes[0].collections[0]
    drawn = {tuple(c) for c in mesh.to_rgba(mesh.get_array().ravel())}
    assert len(drawn) == sweep.size == 100  # more orbits than any one palette has colours


def test_a_large_bifurcation_diagram_is_drawn_as_counts_per_bin():
    """80,000 impacts (400 values x 200 kept): images of counts, every impact counted
    once, the classes' counts in the title; a small one stays dots."""
    one = Sweep(
        load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=5.0:5.8:400"),), keep=200
    )
    rng = np.random.default_rng(0)
    heights = 0.07 + 0.01 * rng.random((400, 200))
    heights[:10, :50] = np.nan  # a shorter tail
    data = _data(one, last_height=heights, last_tof=0.09 + 0.01 * rng.random((400, 200)))
    fig = bifurcation_figure(one, data)
    images = fig.axes[0].get_images()
    assert len(images) == 1
    counts = np.nan_to_num(np.asarray(images[0].get_array(), dtype=float))
    assert counts.sum() == np.isfinite(heights).sum() == 80_000 - 500
    assert "periodic 400" in fig.axes[0].get_title().replace("\n", " ")
    assert fig.axes[1].get_images()
    small = Sweep(one.scene, (parse_vary("drive.frequency=5.0:5.8:4"),), keep=200)
    fig = bifurcation_figure(small, _data(small, last_height=heights[:4], last_tof=heights[:4]))
    assert not fig.axes[0].get_images() and fig.axes[0].collections
