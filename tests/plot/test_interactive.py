"""The interactive view (billiard.plot.interactive, ``billiard view DIR``): the data the
page holds, that it loads nothing from outside, its size for long runs, its display in a
notebook, and, in headless Chromium, that moving the selection draws the ball where the
run says it was.

The browser tests need Debian's Chromium and ChromeDriver (README.md, "Interactive
view"; .ci/run installs them) and are skipped, with the reason, where they are missing.
"""

from __future__ import annotations

import html
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import billiard
from billiard import plot
from billiard.cli import main
from billiard.plot import interactive
from billiard.plot.common import lid_mask
from billiard.plot.contacts import phase_path
from billiard.plot.flights import flight_positions
from billiard.plot.outline import drive_offset
from billiard.plot.phase import phase_coordinates
from billiard.runfile.record import RunDataError
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene
from tests import browser
from tests.plot_support import A_CURVE, C_CURVE, bouncing_ball, make_run, scene_toml

_DATA = re.compile(r'<script type="application/json" id="billiard-data">(.*?)</script>', re.S)

# the wedge shaken at 5 Hz from rest in its vertex (tests/plot/test_contacts.py): it is
# held, rolls, slides, lifts off and lands within 0.7 s
PHASES = {
    "contact.model": "phases",
    "drive.frequency": 5.0,
    "drive.amplitude": 0.0239,
    "initial.v1": 0.0239 * 2 * math.pi * 5.0,
}


@pytest.fixture(scope="module", autouse=True)
def private_curve_cache(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard-home")))
        yield


@pytest.fixture(scope="module")
def bounce_run(tmp_path_factory) -> Path:
    """A ball bouncing on the vertex of a vertically shaken parabola, without drag: its
    flights are exact parabolas."""
    columns = bouncing_ball(60, amplitude=1e-3, frequency=25.0, e=0.5)
    return make_run(tmp_path_factory.mktemp("bounce") / "run", columns, scene_toml())


@pytest.fixture(scope="module")
def phases_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("phases") / "wedge"
    sets = [a for k, v in PHASES.items() for a in ("--set", f"{k}={v!r}")]
    args = ["run", "wedge-6.6hz", *sets, "--duration", "0.7", "--sample", "0.005"]
    assert main([*args, "--out", str(out), "--no-plot"]) == 0
    return out


def page_data(page: str) -> dict:
    """The JSON the page holds."""
    (text,) = _DATA.findall(page)
    return json.loads(text)


# --- the page, without a browser -----------------------------------------------------------


def test_the_page_holds_the_runs_impacts_exactly(bounce_run, capsys):
    assert main(["view", str(bounce_run)]) == 0
    path = bounce_run / "view.html"
    assert capsys.readouterr().out == f"wrote {path}\n"
    data = page_data(path.read_text(encoding="utf-8"))
    columns = read_collisions(bounce_run / "collisions.csv")
    impacts = data["impacts"]
    for name in ("n", "t", "q1", "q2", "v1", "v2"):
        assert np.array_equal(np.array(impacts[name], dtype=float), columns[name]), name
    scene = plot.read_scene(bounce_run / "scene.toml")
    px, py = phase_coordinates(columns, scene)
    # null on the page where the point cannot be normalized (NaN)
    shipped_x = np.array(impacts["phase_x"], dtype=float)
    shipped_y = np.array(impacts["phase_y"], dtype=float)
    assert np.isfinite(shipped_x).sum() > 40
    np.testing.assert_allclose(shipped_x, px, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(shipped_y, py, rtol=1e-7)
    assert impacts["lid"] == lid_mask(columns).astype(int).tolist()
    regimes = [data["regimes"][code] for code in impacts["regime"]]
    assert regimes == [str(r).strip() for r in columns["regime"]]
    # the boundary's outline in its own frame: the parabola a x^2 + c (m)
    x = np.array(data["boundary"]["x"])
    np.testing.assert_allclose(data["boundary"]["y"], A_CURVE * x**2 + C_CURVE, rtol=1e-7)
    assert data["scene"]["radius"] == scene.ball.radius
    assert data["scene"]["drive"]["omega"] == scene.drive.omega
    assert data["run"] == {
        "impacts": 60,
        "first": 1,
        "last": 60,
        "shown": 60,
        "cap": interactive.MAX_IMPACTS,
        "limited": False,
        "note": "",
        "phase_problem": None,
    }
    assert data["pieces"] is None  # an impacts-only run: the page rebuilds its flights


def test_the_page_loads_nothing_from_outside(bounce_run):
    page = billiard.view(bounce_run).html
    # no address at all: no script, style, image or link from elsewhere
    assert re.search(r"(?i)https?:|//[a-z0-9.-]+\.[a-z]{2,}/|ftp:|wss?:", page) is None
    sources = re.findall(r'(?i)\b(?:src|href)\s*=\s*"([^"]*)"', page)
    assert sources == ["data:,"]  # the empty icon, so that no favicon is asked for
    assert "<script src" not in page.lower() and "@import" not in page
    (policy,) = re.findall(r'http-equiv="Content-Security-Policy"\s+content="([^"]*)"', page)
    assert "default-src 'none'" in policy
    # the template's one script is inline, and the data are not executable
    assert page.count("<script>") == 1 and page.count('<script type="application/json"') == 1


def test_a_value_cannot_end_the_data_script(bounce_run):
    columns = read_collisions(bounce_run / "collisions.csv")
    scene = plot.read_scene(bounce_run / "scene.toml")
    data = interactive.view_data(columns, scene)
    data["title"] = "</script><script>alert(1)</script><!--"
    page = interactive.page_from_data(data)
    assert page.count("</script>") == 2  # the data's and the program's
    assert page_data(page)["title"] == data["title"]


def test_a_long_run_is_cut_to_the_cap_and_says_so(bounce_run, monkeypatch):
    """A run longer than the cap: the page holds its last MAX_IMPACTS impacts, says so,
    and its size grows with the cap, not with the run."""
    monkeypatch.setattr(interactive, "MAX_IMPACTS", 500)
    base = read_collisions(bounce_run / "collisions.csv")
    scene = plot.read_scene(bounce_run / "scene.toml")
    size = {}
    for repeats in (10, 40):  # 600 and 2400 impacts
        columns = {k: np.tile(v, repeats) for k, v in base.items()}
        columns["n"] = np.arange(1, columns["n"].size + 1)
        columns["t"] = np.concatenate([base["t"] + i * base["t"][-1] for i in range(repeats)])
        page = interactive.view_page(columns, scene)
        data = page_data(page)
        assert data["impacts"]["n"] == list(range(columns["n"].size - 499, columns["n"].size + 1))
        assert data["run"]["limited"] and data["run"]["shown"] == 500
        assert "a page holds at most 500 impacts" in data["run"]["note"]
        size[repeats] = len(page.encode())
    assert abs(size[40] - size[10]) < 0.01 * size[10]
    # about 140 bytes per impact of a real run (docs/design.md), less here: q1 = v1 = 0
    template = len(interactive._template().encode())
    assert size[40] - template < 200 * 500 + 40_000


def test_a_window_of_impacts(bounce_run, capsys):
    out = bounce_run / "w.html"
    assert main(["view", str(bounce_run), "--window", "10:20", "--out", str(out)]) == 0
    data = page_data(out.read_text(encoding="utf-8"))
    assert data["impacts"]["n"] == list(range(10, 20))
    assert (data["run"]["first"], data["run"]["last"], data["run"]["impacts"]) == (10, 19, 60)


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["--window", "5"], "window '5': expected N0:N1"),
        (["--window", "500:600"], "window 500:600 holds no impacts"),
    ],
)
def test_bad_window(bounce_run, capsys, args, problem):
    assert main(["view", str(bounce_run), *args, "--out", str(bounce_run / "x.html")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1 and problem in err
    assert not (bounce_run / "x.html").exists()


def test_bad_folder(tmp_path, capsys):
    assert main(["view", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing: not a directory" in err
    (tmp_path / "empty").mkdir()
    assert main(["view", str(tmp_path / "empty")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "collisions.csv" in err


def test_a_page_that_cannot_be_written(bounce_run, tmp_path, capsys):
    out = tmp_path / "no-such-folder" / "view.html"
    assert main(["view", str(bounce_run), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out}: cannot write the view" in err


def test_the_notebook_shows_the_page_in_a_sandboxed_frame(bounce_run):
    shown = billiard.view(str(bounce_run))
    frame = shown._repr_html_()
    assert frame.startswith("<iframe srcdoc=") and 'sandbox="allow-scripts"' in frame
    (srcdoc,) = re.findall(r'srcdoc="([^"]*)"', frame)
    assert html.unescape(srcdoc) == shown.html
    assert repr(shown).startswith("<billiard View of 'bounce': impacts 1 to 60 of 60, ")


def test_the_view_of_a_result_is_that_of_its_folder(tmp_path):
    scene = load_scene("parabola-5.4hz")
    result = billiard.simulate(scene, collisions=40, out_dir=tmp_path / "run")
    from_result = billiard.view(result).data
    from_folder = billiard.view(tmp_path / "run").data
    assert from_result["impacts"] == from_folder["impacts"]
    assert from_result["impacts"]["q2"] == result.columns["q2"].tolist()
    with pytest.raises(RunDataError, match="expected a Result or a run folder, got int"):
        billiard.view(3)


def test_a_run_with_contact_phases_ships_its_path(phases_run):
    data = billiard.view(phases_run).data
    pieces = data["pieces"]
    kinds = {p["kind"] for p in pieces}
    assert kinds == {"flight", "roll", "slide", "held"}
    starts = [p["t"][0] for p in pieces]
    assert starts == sorted(starts)
    columns, scene = plot.load_run(phases_run)
    contacts, samples = plot.load_sides(phases_run)
    path = phase_path(columns, np.arange(columns["t"].size), scene, contacts, samples)
    assert len(pieces) == len(path.pieces)
    for shipped, piece in zip(pieces, path.pieces, strict=True):
        most = 3 if piece.kind == "flight" else interactive.MAX_STRETCH_POINTS
        assert len(shipped["t"]) <= most
        # every point shipped is a point of the path, at the time shipped
        x, y = piece.positions(np.array(shipped["t"]))
        np.testing.assert_allclose(shipped["x"], x, rtol=1e-7, atol=1e-10)
        np.testing.assert_allclose(shipped["y"], y, rtol=1e-7, atol=1e-10)
        assert (shipped["t"][0], shipped["t"][-1]) == (piece.t[0], piece.t[-1])


def test_a_rerun_removes_the_outdated_view(tmp_path):
    out = tmp_path / "run"
    args = ["run", "parabola-5.4hz", "--out", str(out), "--no-plot", "--collisions"]
    assert main([*args, "20"]) == 0
    assert main(["view", str(out)]) == 0 and (out / "view.html").is_file()
    assert main([*args, "30", "--overwrite"]) == 0
    assert not (out / "view.html").exists()


# --- the page in a browser -----------------------------------------------------------------


@pytest.fixture(scope="module")
def driver():
    reason = browser.missing()
    if reason:
        pytest.skip(f"the browser test of the interactive view needs Chromium: {reason}")
    with browser.chromium() as chromium:
        yield chromium


def open_page(driver, run: Path) -> dict:
    """Load the run's view; returns the page's data."""
    path = interactive.write_view(run)
    driver.get(path.resolve().as_uri())
    assert browser.console_errors(driver) == []
    return driver.execute_script("return billiardView.data")


def call(driver, script: str, *args):
    return driver.execute_script(f"return billiardView.{script}", *args)


def drawn_at(state: dict) -> tuple[float, float]:
    """Where the first panel's axes put the ball's centre (viewBox units)."""
    view = state["container"]
    left, top, width, height = view["box"]
    (x0, x1), (y0, y1) = view["xlim"], view["ylim"]
    return (
        left + (state["x"] * 1e3 - x0) / (x1 - x0) * width,
        top + height - (state["y"] * 1e3 - y0) / (y1 - y0) * height,
    )


def test_moving_the_selection_moves_what_is_drawn(driver, bounce_run):
    data = open_page(driver, bounce_run)
    columns = read_collisions(bounce_run / "collisions.csv")
    scene = plot.read_scene(bounce_run / "scene.toml")
    q1, q2, t = columns["q1"], columns["q2"], columns["t"]
    first = call(driver, "state()")
    assert (first["n"], first["t"], first["mode"]) == (1, t[0], "impact")
    for n in (7, 30, 60):
        state = call(driver, "select(arguments[0])", n)
        i = n - 1
        assert (state["n"], state["index"], state["t"], state["mode"]) == (n, i, t[i], "impact")
        assert (state["x"], state["y"]) == (q1[i], q2[i])  # the run's position, exactly
        cx, cy = drawn_at(state)
        ball = state["drawn"]["ball"]
        assert ball["cx"] == pytest.approx(cx, abs=1e-9)
        assert ball["cy"] == pytest.approx(cy, abs=1e-9)
        width = state["container"]["box"][2] / np.ptp(state["container"]["xlim"])
        assert ball["r"] == pytest.approx(scene.ball.radius * 1e3 * width, rel=1e-12)
        assert state["offset"] == pytest.approx(float(drive_offset(scene, t[i])), abs=1e-15)
        ring = state["drawn"]["returnMap"]
        if n < 60:
            assert ring == pytest.approx([q2[i] * 1e3, q2[i + 1] * 1e3], rel=1e-12)
        else:
            assert ring is None  # the last impact has no successor
        phase = state["drawn"]["phase"]
        assert phase == pytest.approx(
            [data["impacts"]["phase_x"][i], data["impacts"]["phase_y"][i]], rel=1e-9, abs=1e-12
        )
        assert state["drawn"]["series"] == pytest.approx([t[i], q2[i] * 1e3], rel=1e-12)
        assert state["drawn"]["slider"] == i
    # between impacts: on the flight, here the exact parabola (no drag)
    for i in (4, 41):
        for fraction in (0.25, 0.6):
            time = t[i] + fraction * (t[i + 1] - t[i])
            state = call(driver, "setTime(arguments[0])", time)
            x, y = flight_positions(columns, i, np.array([time - t[i]]), scene)
            assert state["mode"] == "flight" and state["index"] == i
            assert state["x"] == pytest.approx(x[0], abs=1e-12)
            assert state["y"] == pytest.approx(y[0], abs=1e-12)
            assert state["drawn"]["ball"]["cy"] == pytest.approx(drawn_at(state)[1], abs=1e-9)
    # the keyboard steps through the impacts
    call(driver, "select(10)")
    driver.find_element("tag name", "body").send_keys("\ue014")  # the right arrow
    assert call(driver, "state()")["n"] == 11
    assert browser.console_errors(driver) == []


def test_the_ball_follows_the_contact_phases(driver, phases_run):
    open_page(driver, phases_run)
    contacts, samples = plot.load_sides(phases_run)
    for mode in ("roll", "slide", "held"):
        k = int(np.flatnonzero(contacts["mode"] == mode)[0])
        t0, t1 = contacts["t_start"][k], contacts["t_end"][k]
        inside = np.flatnonzero((samples["t"] > t0) & (samples["t"] < t1))
        times = samples["t"][inside] if inside.size else [0.5 * (t0 + t1)]
        state = call(driver, "setTime(arguments[0])", float(times[len(times) // 2]))
        assert state["mode"] == mode
        if inside.size:  # a sample's time: the ball at the sample's position
            j = inside[len(inside) // 2]
            assert state["x"] == pytest.approx(samples["q1"][j], rel=1e-7, abs=1e-10)
            assert state["y"] == pytest.approx(samples["q2"][j], rel=1e-7, abs=1e-10)
    assert browser.console_errors(driver) == []


def test_drag_flights_stay_within_micrometres(driver, tmp_path):
    """With air drag the page's flight (constant acceleration, ending at the next impact)
    is within 6 um of the integrated one (docs/design.md, "The interactive view")."""
    out = tmp_path / "run"
    args = ["run", "parabola-5.4hz", "--collisions", "60", "--out", str(out), "--no-plot"]
    assert main(args) == 0
    open_page(driver, out)
    columns, scene = plot.load_run(out)
    t = columns["t"]
    worst = 0.0
    for i in range(0, 59, 3):
        time = 0.5 * (t[i] + t[i + 1])
        state = call(driver, "setTime(arguments[0])", time)
        x, y = flight_positions(columns, i, np.array([time - t[i]]), scene)
        worst = max(worst, math.hypot(state["x"] - x[0], state["y"] - y[0]))
    assert 0 < worst < 6e-6  # not the parabola's exactness: the drag is there


def test_the_notebook_frame_runs_the_page(driver, bounce_run, tmp_path):
    """The page in the sandboxed frame a notebook shows runs as it does from disk."""
    notebook = tmp_path / "notebook.html"
    frame = billiard.view(bounce_run)._repr_html_()
    notebook.write_text(f"<!DOCTYPE html><html><body>{frame}</body></html>", encoding="utf-8")
    driver.get(notebook.as_uri())
    driver.switch_to.frame(driver.find_element("tag name", "iframe"))
    try:
        state = call(driver, "select(25)")
        q1, q2 = (read_collisions(bounce_run / "collisions.csv")[k][24] for k in ("q1", "q2"))
        assert (state["n"], state["x"], state["y"]) == (25, q1, q2)
        assert browser.console_errors(driver) == []
    finally:
        driver.switch_to.default_content()
