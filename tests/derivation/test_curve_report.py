"""The per-curve report (``billiard derive --name --curve --report DIR``,
billiard.derivation.curve_report): what it says about a smooth user curve, a curve with a
kink, a curve too tight for the ball and a curve refused for its smooth join; that a wrong
textbook form shows as a failed check; bad options; and, in headless Chromium with the
network off, that its equations render from the file alone.

The browser test needs Debian's Chromium and ChromeDriver (README.md, "Interactive view")
and is skipped, with the reason, where they are missing.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import sympy as sm
from billiard.derivation import curve_report

from billiard.cli import main
from tests import browser

RADIUS = 1.55e-3  # m, the default scene's ball (BallSpec.radius)


@pytest.fixture(autouse=True)
def private_curve_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path / "home"))


def derive(tmp_path, name: str, curve: str, *extra: str) -> int:
    args = ["derive", "--name", name, "--curve", curve, "--dir", str(tmp_path / "curves")]
    return main([*args, "--report", str(tmp_path / name), *extra])


def checks(markdown: str) -> dict[str, str]:
    """check name -> result, from the report's table of checks."""
    table = markdown.split("## Checks", 1)[1]
    rows = [line.split(" | ") for line in table.splitlines() if line.startswith("| ")][1:]
    return {row[0].removeprefix("| "): row[-1].removesuffix(" |") for row in rows}


def number(markdown: str, pattern: str) -> float:
    (value,) = re.findall(pattern, markdown)
    return float(value)


def test_the_report_of_a_user_curve(tmp_path, capsys):
    assert derive(tmp_path, "bowl", "30*x**4 + 0.0063") == 0
    out = capsys.readouterr().out
    assert "all 11 checks passed" in out
    text = (tmp_path / "bowl" / "report.md").read_text()
    assert (tmp_path / "bowl" / "report.html").is_file()
    assert "| 0 | all x | `30*x**4 + 63/10000` |" in text
    assert "One wall: the curve has no join." in text
    for section in ("## Flight", "## Contact: rolling and sliding", "## Impact", "## Checks"):
        assert section in text
    # the wall's geometry and the impact's short forms, as sympy prints them
    assert "f' = 120 s^{3}" in text and "f''' = 720 s" in text
    assert "R_{n} = - m w_{n} \\left(e + 1\\right)" in text
    assert "R_{t} = - \\frac{k m w_{t}}{k + 1}" in text
    rolling = text.split("## Contact: rolling and sliding", 1)[1].split("## Impact", 1)[0]
    assert rolling.count("$$") == 2 * 7  # rolling: u3, s'', F, N; sliding: s'', u3', N
    results = checks(text)
    assert len(results) == 11 and set(results.values()) == {"passed"}
    assert "stick impact: R_n = m*w_n*(-e - 1)" in results
    assert "the curve: as r -> 0 the offset curve is the curve" in results
    # the smallest radius of curvature: (1 + f'^2)^(3/2) / f'' on a fine grid of its own
    xs = np.linspace(1e-3, 0.3, 300001)
    rho = (1 + (120 * xs**3) ** 2) ** 1.5 / (360 * xs**2)
    smallest = number(text, r"smallest radius of curvature is ([0-9.e-]+) m")
    assert smallest == pytest.approx(rho.min(), rel=1e-5)  # the report's 4001 points
    assert "Valid on the whole range" in text


def test_the_report_of_a_curve_with_a_kink(tmp_path, capsys):
    assert derive(tmp_path, "kinked", "20*x**2 + 2*abs(x) + 0.0063") == 0
    text = (tmp_path / "kinked" / "report.md").read_text()
    assert "| 0 | x < 0 m | `20*x**2 - 2*x + 63/10000` |" in text
    assert "| 1 | x > 0 m | `20*x**2 + 2*x + 63/10000` |" in text
    # the slopes either side of x = 0
    assert "| 0 | -2 | 2 | kink: a corner: the slope jumps up (a valley) |" in text
    results = checks(text)
    assert set(results.values()) == {"passed"}
    for wall in ("wall 0", "wall 1"):
        assert results[f"{wall}: as r -> 0 the offset curve is the curve"] == "passed"
    assert results["the maximum of the walls is the curve (joins)"] == "passed"


def test_the_report_of_the_wedge_with_parameters(tmp_path):
    curve = ("b*abs(x) + c", "--param", "b=1.85", "--param", "c=0.0063")
    assert derive(tmp_path, "wedgelike", *curve) == 0
    text = (tmp_path / "wedgelike" / "report.md").read_text()
    assert "Parameters: b = 1.85, c = 0.0063 (SI)." in text
    assert "| 0 | -1.85 | 1.85 | kink: a corner: the slope jumps up (a valley) |" in text
    assert text.count("\\rho = \\infty") == 2  # straight walls: f'' = 0
    assert "The walls are straight" in text
    assert set(checks(text).values()) == {"passed"}


def test_a_curve_too_tight_for_the_ball_is_marked_where(tmp_path):
    # f = a x^2 has rho = (1 + 4 a^2 x^2)^(3/2) / (2 a): 0.25 mm at its bottom, below r
    a = 2000.0
    assert derive(tmp_path, "tight", "2000*x**2") == 0
    text = (tmp_path / "tight" / "report.md").read_text()
    lo = number(text, r"\*\*Not valid\*\* \(rho <= r\) on ([0-9.e-]+) m <= x")
    hi = number(text, r"\*\*Not valid\*\* \(rho <= r\) on [0-9.e-]+ m <= x <= ([0-9.e-]+) m")
    edge = np.sqrt((2 * a * RADIUS) ** (2 / 3) - 1) / (2 * a)  # rho(edge) = r
    left, right = (
        number(text, r"reach, ([0-9.e-]+) m <= x"),
        number(text, r"reach, [0-9.e-]+ m <= x <= ([0-9.e-]+) m"),
    )
    spacing = (right - left) / 4000
    assert lo == pytest.approx(-edge, abs=spacing) and hi == pytest.approx(edge, abs=spacing)
    assert number(text, r"smallest radius of curvature is ([0-9.e-]+) m") == pytest.approx(
        1 / (2 * a), rel=1e-3
    )


def test_a_smooth_join_is_reported_with_its_class(tmp_path, capsys):
    assert derive(tmp_path, "smoothjoin", "20*x**2 + 10*x*abs(x)") == 0
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    text = (tmp_path / "smoothjoin" / "report.md").read_text()
    assert "**Refused:**" not in text
    assert "| 0 | 0 | 0 | C1: smooth: height and slope continuous, f'' jumps |" in text
    results = checks(text)
    (join,) = [name for name in results if name.startswith("the maximum of the walls")]
    assert results[join] == "passed"
    assert (tmp_path / "curves" / "smoothjoin.py").exists()


def test_a_join_with_a_jump_in_height_is_refused_with_a_report(tmp_path, capsys):
    assert derive(tmp_path, "jump", "Piecewise((x**2, x < 0), (x**2 + 0.001, True))") == 2
    captured = capsys.readouterr()
    assert "the height jumps by 0.001 m at the join x = 0 m" in captured.err
    assert "Traceback" not in captured.err
    assert not (tmp_path / "curves" / "jump.py").exists()


def test_a_curve_refused_for_its_shape_gets_a_report(tmp_path, capsys):
    # x**1.5 is not real left of 0: the shape check refuses the curve, and the report
    # counts those points as not valid instead of failing on them
    assert derive(tmp_path, "halfreal", "x**1.5 + abs(x)") == 2
    captured = capsys.readouterr()
    assert "cannot hold a ball" in captured.err and "Traceback" not in captured.err
    text = (tmp_path / "halfreal" / "report.md").read_text()
    assert checks(text)["the curve can hold a ball"] == "**FAILED**"
    left = number(text, r"reach, ([0-9.e-]+) m <= x")
    right = number(text, r"reach, [0-9.e-]+ m <= x <= ([0-9.e-]+) m")
    xs = np.linspace(left, right, curve_report.POINTS)
    undefined = number(text, r"At ([0-9]+) of the points f' or f'' is not real")
    assert undefined == np.count_nonzero(xs <= 0)  # f'' = 0.75/sqrt(x): 1/0 at 0 too
    assert number(text, r"\*\*Not valid\*\* \(rho <= r\) on ([0-9.e-]+) m") == left


def test_a_wrong_textbook_form_shows_as_failed(tmp_path, capsys, monkeypatch):
    right = curve_report.TEXTBOOK

    def planted(wt, wn):
        forms = right(wt, wn)
        k, m = sm.symbols("k m", positive=True)
        forms["stick R_t"] = -k * m * wt / (1 + 2 * k)  # not the sphere's sticking impulse
        return forms

    monkeypatch.setattr(curve_report, "TEXTBOOK", planted)
    assert derive(tmp_path, "bowl", "30*x**4 + 0.0063") == 1
    out = capsys.readouterr().out
    assert "1 of 11 checks FAILED: stick impact: R_t" in out
    results = checks((tmp_path / "bowl" / "report.md").read_text())
    failed = [name for name, result in results.items() if result != "passed"]
    assert failed == ["stick impact: R_t = -k*m*w_t/(2*k + 1)"]
    page = (tmp_path / "bowl" / "report.html").read_text()
    assert page.count('class="failed">FAILED') == 1


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["--report", "R"], "--report DIR goes with --name and --curve"),
        (["--name", "a", "--curve", "x**2", "--report", "R", "--radius", "0"], "--radius"),
        (["--name", "a", "--curve", "x**2", "--report", "FILE"], "not a directory"),
        (["--name", "a", "--curve", "x**2", "--report", "no/such/R"], "does not exist"),
    ],
)
def test_bad_report_options(tmp_path, capsys, monkeypatch, args, problem):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "FILE").write_text("")
    assert main(["derive", "--dir", str(tmp_path / "curves"), *args]) == 2
    err = capsys.readouterr().err
    assert problem in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "curves").exists()  # refused before deriving anything


# --- the page in a browser -------------------------------------------------------------------


def test_the_page_loads_nothing_from_outside(tmp_path):
    assert derive(tmp_path, "kinked", "20*x**2 + 2*abs(x) + 0.0063") == 0
    page = (tmp_path / "kinked" / "report.html").read_text()
    assert re.search(r"(?i)https?:|//[a-z0-9.-]+\.[a-z]{2,}/|ftp:|wss?:", page) is None
    assert re.findall(r'(?i)\b(?:src|href)\s*=\s*"([^"]*)"', page) == ["data:,"]
    assert "<script" not in page.lower() and "@import" not in page
    # every symbol is MathML, not LaTeX left in a token (\\ddot{s} printed as text)
    assert re.search(r"<m[ino]>[^<]*\\", page) is None
    (policy,) = re.findall(r'http-equiv="Content-Security-Policy"\s+content="([^"]*)"', page)
    assert "default-src 'none'" in policy


@pytest.fixture(scope="module")
def driver():
    reason = browser.missing()
    if reason:
        pytest.skip(f"the browser test of the report needs Chromium: {reason}")
    with browser.chromium() as chromium:
        # no network at all: the page must render from the file alone
        chromium.set_network_conditions(
            offline=True, latency=0, download_throughput=0, upload_throughput=0
        )
        yield chromium


# Every equation's box, and for each fraction the boxes of its numerator and denominator:
# rendered as MathML, a fraction stacks them; as unknown inline elements they would sit on
# one line.
_LAYOUT = """
return Array.from(document.querySelectorAll("math")).map(m => {
  const box = m.firstElementChild.getBoundingClientRect();
  const fractions = Array.from(m.querySelectorAll("mfrac")).map(f => {
    const [top, bottom] = Array.from(f.children).map(c => c.getBoundingClientRect());
    return [top.bottom, bottom.top, top.left < bottom.right && bottom.left < top.right];
  });
  return {width: box.width, height: box.height, fractions: fractions,
          kind: m.constructor.name};
});
"""


def test_the_equations_render_offline_in_a_browser(driver, tmp_path):
    assert derive(tmp_path, "kinked", "20*x**2 + 2*abs(x) + 0.0063") == 0
    markdown = (tmp_path / "kinked" / "report.md").read_text()
    driver.get((tmp_path / "kinked" / "report.html").resolve().as_uri())
    assert browser.console_errors(driver) == []
    layout = driver.execute_script(_LAYOUT)
    assert len(layout) == markdown.count("$$") // 2  # every equation of the Markdown
    assert {eq["kind"] for eq in layout} == {"MathMLElement"}
    assert all(eq["width"] > 0 and eq["height"] > 0 for eq in layout)
    fractions = [f for eq in layout for f in eq["fractions"]]
    assert len(fractions) > 10
    for numerator_bottom, denominator_top, overlap in fractions:
        assert numerator_bottom <= denominator_top + 0.5 and overlap  # stacked, one column
    text = driver.execute_script("return document.body.innerText")
    assert "kink" in text and "FAILED" not in text
