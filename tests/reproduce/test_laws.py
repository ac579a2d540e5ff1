"""Impact laws compared (billiard.reproduce.laws), the one command that writes
docs/impact-laws.md and its figures, at small size: two laws, 150 impacts a scene."""

from __future__ import annotations

import re

import numpy as np
import pytest
from matplotlib.image import imread

from billiard.cli import main
from billiard.reproduce.laws import law_names
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import PAPER_SCENES, load_scene

LAWS = ("kane-levinson", "point-particle")


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    out = tmp_path_factory.mktemp("laws")
    args = ["reproduce", "--laws", ",".join(LAWS), "--collisions", "150"]
    assert main([*args, "--runs", str(out / "runs"), "--docs", str(out / "docs")]) == 0
    return out, (out / "docs" / "impact-laws.md").read_text()


def _calibrated(text: str, law: str) -> float:
    row = next(line for line in text.splitlines() if line.startswith(f"| `{law}` | `contact."))
    return float(row.split("|")[3])


def test_the_page_has_every_law_calibrated_and_every_scene_drawn(compared):
    out, text = compared
    # the paper's e with rotation and friction, a lower one without
    kane, point = _calibrated(text, "kane-levinson"), _calibrated(text, "point-particle")
    assert kane == pytest.approx(0.393, abs=5e-4)
    assert 0.1 < point < kane - 0.1
    assert f"needs e = {point:.3f}, against {kane:.3f}" in text
    for name in PAPER_SCENES:
        figure = out / "docs" / "figures" / "laws" / f"{name}.png"
        assert f"![{name} under each impact law](figures/laws/{name}.png)" in text
        assert imread(figure).shape[1] > 400
        for law in LAWS:
            run = out / "runs" / law / name
            assert load_scene(str(run / "scene.toml")).contact.law == law
            assert read_collisions(run / "collisions.csv")["n"].size == 150


def test_the_regime_shares_are_the_records(compared):
    out, text = compared
    for law in LAWS:
        regimes = read_collisions(out / "runs" / law / "wedge-6.6hz" / "collisions.csv")["regime"]
        section = text.split("## wedge-6.6hz")[1]
        row = next(line for line in section.splitlines() if line.startswith(f"| `{law}` |"))
        cells = [c.strip() for c in row.split("|")[4:7]]
        shares = [float(re.sub(" %", "", c)) / 100 for c in cells]
        expected = [np.mean(np.asarray(regimes) == r) for r in ("stick", "slip", "elastic")]
        assert shares == pytest.approx(expected, abs=5e-4)
        assert sum(shares) == pytest.approx(1.0, abs=2e-3)


def test_a_misspelled_law_is_refused_in_one_line(tmp_path, capsys):
    args = ["reproduce", "--laws", "kane-levinson,walten", "--runs", str(tmp_path / "r")]
    assert main(args) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "unknown impact law 'walten'; choose from kane-levinson" in err[0]
    assert not (tmp_path / "r").exists()


def test_law_names():
    assert law_names(None) == law_names("all") == list(law_names("all"))
    assert law_names(" walton , point-particle ") == ["walton", "point-particle"]
    with pytest.raises(ValueError, match="unknown impact law"):
        law_names(",")
