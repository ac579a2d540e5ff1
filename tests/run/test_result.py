"""A Result shows itself: a one-line ``repr`` (scene, status, impacts, final time with
its unit) and an HTML table for notebooks, from the run's computed values; its side
tables keep the dict access they always had."""

from __future__ import annotations

import numpy as np
import pytest

from billiard import load_scene, simulate, with_values
from billiard.run.frames import Table
from billiard.status import Status


@pytest.fixture(scope="module")
def result():
    return simulate(load_scene("parabola-5.4hz"), collisions=150)


def test_repr_is_one_line_with_the_computed_values(result):
    text = repr(result)
    assert text == (
        f"<Result 'parabola-5.4hz': complete, {len(result)} impacts, t = {result.final_time:.6g} s>"
    )
    assert len(result) == 150 and result.final_time == result.columns["t"][-1]
    assert "\n" not in text


def test_repr_names_a_stop():
    scene = with_values(load_scene("parabola-5.4hz"), {"run.duration": 0.2})
    ended = simulate(scene, collisions=10_000)
    assert ended.status is Status.TIME_LIMIT
    assert repr(ended) == f"<Result 'parabola-5.4hz': time_limit, {len(ended)} impacts, t = 0.2 s>"


def test_html_shows_the_scene_and_the_outcome(result):
    page = result._repr_html_()
    assert page.startswith("<table>") and page.endswith("</table>")
    assert "<td style='text-align:left'>complete</td>" in page
    assert f"<td style='text-align:left'>{len(result)}</td>" in page
    assert f"{result.final_time:.6g} s" in page
    counts = ", ".join(f"{v} {k}" for k, v in result.counts.items())
    assert counts in page and "0.02543 m at 5.4 Hz" in page


def test_contacts_and_samples_are_tables_with_the_old_dict_access():
    scene = with_values(load_scene("parabola-5.4hz"), {"contact.model": "phases"})
    run = simulate(scene, collisions=20, sample=0.05)
    for table, name in ((run.contacts, "contacts"), (run.trajectory, "samples")):
        assert isinstance(table, Table) and isinstance(table, dict) and table.name == name
        assert table is run.table(name)  # read once, then kept
    samples = run.trajectory
    assert np.array_equal(samples["t"], samples.t)
    assert np.allclose(np.diff(samples["t"]), 0.05)
    assert set(samples["mode"]) <= {"flight", "roll", "slide", "held"}
