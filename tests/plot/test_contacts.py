"""The trajectory figure and the GIF of a run with contact phases (``contact.model =
"phases"``): flights only where the ball flew, and the stretches where it rolled, slid or
was held drawn along the wall.

The run is the wedge shaken horizontally at 5 Hz with A w^2 = 1.3 g tan(beta), started at
rest relative to the wedge in its vertex: it is held there until the walls can no longer
hold it, then rolls up a wall, slides, lifts off, flies, lands, rolls... (every mode and
the ends ``release``, ``slip``, ``lift-off`` and ``impact``). It starts in contact, so
the window of impacts 1 to 29 starts at t = 0, before the first impact.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from billiard import plot
from billiard.cli import main
from billiard.geometry.curves import load_curve
from billiard.geometry.walls import nearest_newton
from billiard.plot import animation as plot_animation
from billiard.plot import run as plot_run_module
from billiard.plot.flights import arcs
from billiard.run.simulate import simulate
from billiard.runfile.figure_files import DEFAULT_DPI
from billiard.runfile.sidecsv import read_side_csv
from billiard.scene.scene import load_scene, with_values
from tests.plot_support import check_gif, check_png

matplotlib.use("Agg")

G, B = 9.81, 1.85  # the wedge's slope b
FREQUENCY = 5.0
W = 2 * math.pi * FREQUENCY
AMPLITUDE = 0.0239  # A w^2 = 1.3 g b
SETTINGS = {
    "contact.model": "phases",
    "drive.frequency": FREQUENCY,
    "drive.amplitude": AMPLITUDE,
    "initial.v1": AMPLITUDE * W,  # moving with the wedge at t = 0
}
DURATION, SAMPLE = 0.7, 0.005
WINDOW = (1, 30)


@pytest.fixture(scope="module", autouse=True)
def private_curve_cache(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard-home")))
        yield


@pytest.fixture(scope="module")
def phases_run(tmp_path_factory) -> Path:
    """The run folder, with contacts.csv and trajectory.csv."""
    out = tmp_path_factory.mktemp("phases") / "wedge"
    sets = [a for k, v in SETTINGS.items() for a in ("--set", f"{k}={v!r}")]
    args = ["run", "wedge-6.6hz", *sets, "--duration", str(DURATION), "--sample", str(SAMPLE)]
    assert main([*args, "--out", str(out), "--no-plot"]) == 0
    modes = set(read_side_csv(out / "contacts.csv")["mode"].tolist())
    assert modes == {"roll", "slide", "held"}
    return out


@pytest.fixture(scope="module")
def unsampled_run(phases_run, tmp_path_factory) -> Path:
    """The same run folder without trajectory.csv: the stretches are rebuilt."""
    out = tmp_path_factory.mktemp("unsampled") / "wedge"
    shutil.copytree(phases_run, out)
    (out / "trajectory.csv").unlink()
    return out


def drawn_trajectory(run: Path, window=WINDOW) -> tuple[dict, dict, dict, object]:
    columns, scene = plot.load_run(run)
    contacts, samples = plot.load_sides(run)
    ax = Figure().add_subplot()
    drawn = plot.trajectory(columns, scene, ax, window, contacts=contacts, samples=samples)
    return drawn, columns, contacts, scene


def walls_of(contacts, k: int) -> str:
    """Phase k's walls as the figures name them: ``a``, or ``a+b`` for two (held)."""
    wall, other = int(contacts["wall"][k]), int(contacts["wall_other"][k])
    assert (other != -2) == (contacts["mode"][k] == "held")
    return f"{wall}+{other}" if other != -2 else str(wall)


def offset_distance(scene, wall_label: str, t: np.ndarray, x: np.ndarray, y: np.ndarray):
    """Distance (m) of centres at times t from the offset curve of a wall (or, for two
    walls a+b, the larger of the two), relative to the boundary: |nearest distance - r|."""
    walls = load_curve(scene.boundary.curve, dict(scene.boundary.parameters)).walls
    r = scene.ball.radius
    shift = scene.drive.amplitude * np.sin(scene.drive.omega * t + scene.drive.phase)
    assert scene.drive.direction == "horizontal"
    px, py = x - shift, y
    worst = np.zeros(t.shape)
    for label in wall_label.split("+"):
        wall = walls[int(label)]
        for i in range(t.size):
            s, ok = nearest_newton(wall, float(px[i]), float(px[i]), float(py[i]))
            assert ok
            gap = abs(math.hypot(px[i] - s, py[i] - wall.f(s, wall.p)) - r)
            worst[i] = max(worst[i], gap)
    return worst


def test_contact_stretches_are_drawn_along_the_wall_by_mode(phases_run):
    drawn, _, contacts, scene = drawn_trajectory(phases_run)
    path = drawn["path"]
    lines = drawn["stretches"]
    assert set(lines) == {"roll", "slide", "held"}
    labels = {mode: line.get_label() for mode, line in lines.items()}
    assert labels["roll"].startswith("rolling (") and labels["slide"].startswith("sliding (")
    assert labels["held"].startswith("held by two walls (1 phase, ")
    # distinct styles, and the legend names them
    styles = {(line.get_color(), str(line.get_linestyle())) for line in lines.values()}
    assert len(styles) == 3
    legend = [t.get_text() for t in drawn["arcs"].axes.get_legend().texts]
    assert all(label in legend for label in labels.values())
    # every phase of the window is drawn, from the samples, between its recorded ends
    in_window = contacts["t_end"] <= path.t_hi + 1e-12
    assert len(path.stretches) == int(in_window.sum()) >= 10
    for k, piece in enumerate(path.stretches):
        assert piece.kind == contacts["mode"][k] and piece.wall == walls_of(contacts, k)
        assert piece.t[0] == contacts["t_start"][k] and piece.t[-1] == contacts["t_end"][k]
        assert piece.x[0] == contacts["q1_start"][k] and piece.y[-1] == contacts["q2_end"][k]
        assert piece.source in ("samples", "ends")
        # on the wall's offset curve (two walls' when held), relative to the boundary
        assert offset_distance(scene, piece.wall, piece.t, piece.x, piece.y).max() < 1e-9
    held = [p for p in path.stretches if p.kind == "held"][0]
    assert held.t[-1] - held.t[0] == pytest.approx(math.asin(1 / 1.3) / W, abs=2e-4)
    # the lines hold exactly those points (mm), one stretch after another
    for mode, line in lines.items():
        x = np.asarray(line.get_xdata())
        points = np.concatenate([p.x for p in path.stretches if p.kind == mode])
        np.testing.assert_array_equal(x[np.isfinite(x)], points * 1e3)


def positions_at(contacts: dict, which: str) -> dict[float, tuple[float, float]]:
    """Time -> centre position at the start or end of each phase."""
    t, x, y = (contacts[f"{name}_{which}"] for name in ("t", "q1", "q2"))
    return {float(t[k]): (float(x[k]), float(y[k])) for k in range(t.size)}


def test_no_flight_is_drawn_across_a_contact_phase(phases_run):
    drawn, columns, contacts, scene = drawn_trajectory(phases_run)
    path = drawn["path"]
    rows = drawn["rows"]
    impacts = {float(columns["t"][i]): (columns["q1"][i], columns["q2"][i]) for i in rows}
    ends = positions_at(contacts, "end")
    starts = positions_at(contacts, "start")
    lift_offs = 0
    for piece in path.flights:
        t0, t1 = piece.t[0], piece.t[-1]
        # no phase overlaps the flight
        overlap = (contacts["t_start"] < t1) & (contacts["t_end"] > t0)
        assert not overlap.any()
        # it starts at an impact or at a phase's end, exactly there
        begin = impacts.get(t0) if piece.source.startswith("impact") else ends[t0]
        assert (piece.x[0], piece.y[0]) == pytest.approx(begin, abs=1e-15)
        lift_offs += piece.source in ("lift-off", "release", "wall-end")
        # and ends at the next impact or phase start
        target = impacts.get(t1, starts.get(t1))
        assert target is not None
        assert math.hypot(piece.x[-1] - target[0], piece.y[-1] - target[1]) < 1e-6
    assert lift_offs >= 3
    # the flights follow the samples: exact states of the run
    samples = read_side_csv(phases_run / "trajectory.csv")
    checked = 0
    for piece in path.flights:
        inside = (samples["t"] > piece.t[0]) & (samples["t"] < piece.t[-1])
        x, y = piece.positions(samples["t"][inside])
        miss = np.hypot(x - samples["q1"][inside], y - samples["q2"][inside])
        assert np.all(miss < 1e-7)
        checked += int(inside.sum())
    assert checked > 20
    # phases lie between consecutive impacts: an impact-to-impact arc would cross them
    t = columns["t"][rows]
    between = [
        ((contacts["t_start"] > a) & (contacts["t_end"] < b)).sum()
        for a, b in zip(t[:-1], t[1:], strict=True)
    ]
    assert sum(k > 0 for k in between) >= 5


def test_without_samples_the_stretches_are_integrated_again(phases_run, unsampled_run):
    drawn, _, _, scene = drawn_trajectory(unsampled_run)
    samples = read_side_csv(phases_run / "trajectory.csv")
    stretches = drawn["path"].stretches
    assert {p.source for p in stretches} <= {"integrated", "ends"}
    assert {p.kind for p in stretches if p.source == "integrated"} == {"roll", "slide", "held"}
    checked = 0
    for piece in stretches:
        assert offset_distance(scene, piece.wall, piece.t, piece.x, piece.y).max() < 1e-9
        inside = (samples["t"] > piece.t[0]) & (samples["t"] < piece.t[-1])
        if piece.source == "ends" or not inside.any():
            continue
        # the rebuilt phase at the sample times is the run's exact state there
        x, y = piece.positions(samples["t"][inside])
        miss = np.hypot(x - samples["q1"][inside], y - samples["q2"][inside])
        assert miss.max() < 1e-9
        checked += int(inside.sum())
    assert checked > 50
    # the same flights as with the samples
    with_samples = drawn_trajectory(phases_run)[0]["path"].flights
    assert [p.t[0] for p in drawn["path"].flights] == [p.t[0] for p in with_samples]


def test_a_result_in_memory_draws_the_same_path(phases_run):
    scene = with_values(load_scene("wedge-6.6hz"), SETTINGS)
    result = simulate(scene, duration=DURATION, sample=SAMPLE)
    ax = Figure().add_subplot()
    drawn = plot.trajectory(
        result.columns, scene, ax, WINDOW, contacts=result.contacts, samples=result.trajectory
    )
    on_disk = drawn_trajectory(phases_run)[0]
    for mode, line in drawn["stretches"].items():
        np.testing.assert_array_equal(line.get_xydata(), on_disk["stretches"][mode].get_xydata())
    np.testing.assert_array_equal(drawn["arcs"].get_xydata(), on_disk["arcs"].get_xydata())


def test_phases_run_figures_and_gif(phases_run, unsampled_run, tmp_path, monkeypatch):
    legends: dict[str, list[str]] = {}
    labels: dict[str, list[tuple[str, str]]] = {}
    save = plot_run_module.save

    def capture(fig, path, **options):
        legends[Path(path).name] = [t.get_text() for lg in fig.legends for t in lg.texts]
        labels[Path(path).name] = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
        return save(fig, path, **options)

    monkeypatch.setattr(plot_run_module, "save", capture)
    for name, run in (("sampled", phases_run), ("rebuilt", unsampled_run)):
        written = plot.plot_run(run, tmp_path / name, window=WINDOW)
        assert [p.name for p in written] == list(plot.FIGURE_NAMES)
        for path in written[:-1]:
            check_png(path, dpi=DEFAULT_DPI)
        check_gif(written[-1])
        names = " ".join(legends["trajectory.png"])
        assert "rolling (" in names and "sliding (" in names and "held by two walls (" in names
        ((xlabel, ylabel),) = labels["trajectory.png"]
        assert xlabel.endswith("$q_1$ (mm)") and ylabel.endswith("$q_2$ (mm)")
    # the GIF's ball: on the wall's offset curve while in contact, named in the clock
    columns, scene = plot.load_run(phases_run)
    contacts, samples = plot.load_sides(phases_run)
    rows = np.arange(WINDOW[0] - 1, WINDOW[1] - 1)
    path = plot.contacts.phase_path(columns, rows, scene, contacts, None)
    times = np.linspace(path.t_lo, path.t_hi, 150)
    x, y, texts, modes = plot_animation._phase_centres(path, times)
    for k in range(contacts["t_start"].size):
        t0, t1 = contacts["t_start"][k], contacts["t_end"][k]
        inside = (times > t0) & (times < t1)
        if inside.any():
            assert {modes[i] for i in np.flatnonzero(inside)} == {contacts["mode"][k]}
            wall = walls_of(contacts, k)
            gaps = offset_distance(scene, wall, times[inside], x[inside], y[inside])
            assert gaps.max() < 1e-9
    assert any(text.startswith("rolling, wall") for text in texts)
    assert any(text.startswith("held by two walls, wall 0+1") for text in texts)
    assert any(text.startswith("flight after impact") for text in texts)
    with Image.open(tmp_path / "rebuilt" / "animation.gif") as gif:
        assert gif.n_frames == 150


def test_an_impacts_run_draws_as_before(tmp_path):
    # the impacts model writes no contacts.csv: the impact-to-impact arcs, no stretches
    out = tmp_path / "impacts"
    args = ["run", "wedge-6.6hz", "--duration", "1", "--out", str(out), "--no-plot"]
    assert main(args) == 0
    assert plot.load_sides(out) == (None, None)
    columns, scene = plot.load_run(out)
    ax = Figure().add_subplot()
    drawn = plot.trajectory(columns, scene, ax, (1, 20))
    assert "path" not in drawn and "stretches" not in drawn
    x, y = arcs(columns, drawn["rows"], scene)
    np.testing.assert_array_equal(drawn["arcs"].get_xdata(), x * 1e3)
    assert "contact phases" not in ax.get_title()


def test_stretches_that_cannot_be_integrated_follow_the_curve_or_a_segment(unsampled_run):
    columns, scene = plot.load_run(unsampled_run)
    contacts, _ = plot.load_sides(unsampled_run)
    rows = np.arange(WINDOW[0] - 1, WINDOW[1] - 1)
    k = int(np.flatnonzero(contacts["mode"] == "roll")[0])
    t0, t1 = contacts["t_start"][k], contacts["t_end"][k]
    # sliding from the rolling phase's start does not reach its end: along the curve
    changed = {name: values.copy() for name, values in contacts.items()}
    changed["mode"][k] = "slide"
    piece = plot.contacts.phase_path(columns, rows, scene, changed).stretches[k]
    assert piece.source == "curve" and piece.t[0] == t0 and piece.t[-1] == t1
    assert (piece.x[0], piece.y[0]) == (contacts["q1_start"][k], contacts["q2_start"][k])
    assert piece.x[-1] == pytest.approx(contacts["q1_end"][k], abs=1e-12)
    assert offset_distance(scene, piece.wall, piece.t, piece.x, piece.y).max() < 1e-9
    # a wall the curve does not have: the straight segment between the recorded ends
    changed = {name: values.copy() for name, values in contacts.items()}
    changed["wall"][k] = 7
    piece = plot.contacts.phase_path(columns, rows, scene, changed).stretches[k]
    assert piece.source == "segment"
    ends = np.array([[piece.x[0], piece.y[0]], [piece.x[-1], piece.y[-1]]])
    recorded = [[contacts[f"q{i}_{w}"][k] for i in (1, 2)] for w in ("start", "end")]
    np.testing.assert_array_equal(ends, recorded)
    middle = len(piece.t) // 2
    fraction = (piece.t[middle] - t0) / (t1 - t0)
    assert piece.x[middle] == pytest.approx(ends[0, 0] + fraction * (ends[1, 0] - ends[0, 0]))
