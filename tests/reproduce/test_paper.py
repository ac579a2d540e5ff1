"""The reproduction's side-by-side of the two contact models (billiard.reproduce.paper), on a
tiny run of the wedge at 6.6 Hz: the ball starts at rest in the vertex, where the impact
model relaunches it by the low-velocity rule and the phases model lets it roll."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from billiard.analysis.camera import camera_filter
from billiard.reproduce.runs import (
    CAMERA_FRAME,
    DIAGONAL_TOL,
    PHASES_IMPACT_CAP,
    _above,
    _hop_time,
    compare_models,
)
from billiard.reproduce.text import _maps_text, models_section
from billiard.runfile.sidecsv import read_side_csv
from billiard.runfile.tables import read_collisions

IMPACTS = 300


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    runs = tmp_path_factory.mktemp("runs")
    return runs, *compare_models("wedge-6.6hz", runs, IMPACTS)


def test_same_start_and_same_simulated_time(compared):
    runs, imp, ph = compared
    assert (imp.model, ph.model) == ("impacts", "phases")
    assert imp.impacts == IMPACTS
    last = read_collisions(runs / "wedge-6.6hz" / "collisions.csv")["t"][-1]
    assert imp.simulated_time == last
    # the phases run ends at the impact run's last impact, well before its impact cap
    assert ph.simulated_time == pytest.approx(imp.simulated_time, rel=1e-12)
    assert ph.stop_reason is None and 0 < ph.impacts < PHASES_IMPACT_CAP * IMPACTS
    ph_cols = read_collisions(runs / "phases" / "wedge-6.6hz" / "collisions.csv")
    assert ph.impacts == ph_cols["t"].size and ph_cols["t"][-1] <= ph.simulated_time
    scene = (runs / "phases" / "wedge-6.6hz" / "scene.toml").read_text()
    assert 'model = "phases"' in scene


@pytest.mark.parametrize("which", [1, 2])
def test_measures_recomputed_from_the_files(compared, which):
    runs, *stats = compared
    s = stats[which - 1]
    folder = runs / ("wedge-6.6hz" if s.model == "impacts" else "phases/wedge-6.6hz")
    cols = read_collisions(folder / "collisions.csv")
    cam = camera_filter(cols, CAMERA_FRAME)
    assert s.camera_impacts == cam["t"].size <= s.impacts
    assert s.above_diagonal == float(np.mean(cols["q2"][1:] > cols["q2"][:-1] + DIAGONAL_TOL))
    assert s.camera_above_diagonal == _above(cam["q2"])
    assert s.tof_median == float(np.median(cols["tof"]))
    assert s.short_flights == float(np.mean(cols["tof"] < CAMERA_FRAME))
    assert s.impacts_per_second == pytest.approx(s.impacts / s.simulated_time)
    assert s.relaunch_share == s.counts.get("resting", 0) / s.impacts
    elastic = cols["regime"] == "elastic"
    assert s.hop_time == pytest.approx(float(cols["tof"][1:][elastic[:-1]].sum()))


def test_the_impact_model_hops_where_the_phases_model_rolls(compared):
    runs, imp, ph = compared
    # impacts: no contact phases, the lying ball relaunched again and again
    assert imp.roll_time is None and imp.contact_time is None and imp.contact_phases is None
    assert imp.counts["resting"] > 0 and imp.hop_time > 0
    # phases: rolling and sliding time, one row of contacts.csv per phase
    contacts = read_side_csv(runs / "phases" / "wedge-6.6hz" / "contacts.csv")
    assert ph.contact_phases == len(contacts["t_start"]) > 0
    durations = contacts["t_end"] - contacts["t_start"]
    assert ph.roll_time == pytest.approx(durations[contacts["mode"] == "roll"].sum(), abs=1e-9)
    assert ph.slide_time == pytest.approx(durations[contacts["mode"] == "slide"].sum(), abs=1e-9)
    assert 0 < ph.contact_time < ph.simulated_time
    # the contact phases take the place of hops: fewer impacts in the same time
    assert ph.impacts < imp.impacts
    assert ph.relaunch_share < imp.relaunch_share


def test_side_by_side_section_reports_the_computed_numbers(compared, tmp_path):
    runs, imp, ph = compared
    fig = {"models": tmp_path / "m.png", "fig3p": tmp_path / "p.png"}

    class Cal:  # the calibration's fields the section reads
        value = 0.025
        orbit = type("O", (), {"impacts_to_lock": 60})()

    class PhCal:
        calibration = None
        error = "no orbit (test)"
        wall_time = 1.0

    text = models_section([imp], [ph], Cal(), PhCal(), tmp_path, fig)
    rows = [line for line in text.splitlines() if line.startswith("| wedge-6.6hz |")]
    assert rows[0].startswith(f"| wedge-6.6hz | impacts | {imp.impacts} |")
    assert rows[1].startswith(f"| wedge-6.6hz | phases | {ph.impacts} |")
    # the impacts model's extra impacts (beyond its camera count) that phases do without
    extra_impacts = imp.impacts - imp.camera_impacts
    extra_phases = ph.impacts - ph.camera_impacts
    assert rows[2].endswith(f"| {(extra_impacts - extra_phases) / extra_impacts:.0%} |")
    assert "same calibration failed" in text and "no orbit (test)" in text
    assert f"{imp.tof_median * 1000:.2f} ms -> {ph.tof_median * 1000:.2f} ms" in _maps_text(
        [imp], [ph]
    )


def test_models_figure(compared, tmp_path):
    from billiard.plot import paper_models_figure

    runs, imp, ph = compared
    path = paper_models_figure(
        [runs / "wedge-6.6hz"], [runs / "phases" / "wedge-6.6hz"], tmp_path / "models.png"
    )
    image = imread(Path(path))
    assert image.shape[0] > image.shape[1] > 300  # one column of four panels
    with pytest.raises(ValueError, match="same scenes"):
        paper_models_figure([runs / "wedge-6.6hz"], [], tmp_path / "x.png")


def test_hop_time_counts_the_flights_after_the_low_velocity_rule():
    cols = {
        "regime": np.array(["stick", "elastic", "elastic", "stick", "slip"]),
        "tof": np.array([0.5, 0.1, 0.002, 0.003, 0.2]),
    }
    assert _hop_time(cols) == pytest.approx(0.002 + 0.003)
