"""Tests of the figures' file options: formats, dpi and the names in a run folder."""

from __future__ import annotations

import pytest

from billiard.runfile.figure_files import (
    DEFAULT_DPI,
    DPI_RANGE,
    FIGURE_FORMATS,
    all_figure_names,
    check_dpi,
    check_format,
    figure_names,
)
from billiard.runfile.folder import FIGURE_NAMES
from billiard.runfile.record import RunDataError


@pytest.mark.parametrize("text, expected", [("png", "png"), ("SVG", "svg"), (" .pdf", "pdf")])
def test_formats_are_read_in_any_case(text, expected):
    assert check_format(text) == expected


@pytest.mark.parametrize("bad", ["gif", "jpeg", "", "png svg", None, 3])
def test_other_formats_are_refused_in_one_line(bad):
    with pytest.raises(RunDataError) as info:
        check_format(bad, "plot: --format")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("plot: --format must be one of png, svg, pdf")
    assert repr(bad) in message


@pytest.mark.parametrize("value, expected", [(300, 300), ("72", 72), (" 150 ", 150), (20.0, 20)])
def test_dpi_is_a_whole_number(value, expected):
    assert check_dpi(value) == expected


@pytest.mark.parametrize(
    "bad, reason",
    [
        ("12.5", "whole number"),
        ("abc", "whole number"),
        ("nan", "whole number"),
        (True, "whole number"),
        (DPI_RANGE[0] - 1, "between 20 and 1200"),
        (DPI_RANGE[1] + 1, "between 20 and 1200"),
        ("-300", "between 20 and 1200"),
    ],
)
def test_bad_dpi_is_refused_in_one_line(bad, reason):
    with pytest.raises(RunDataError) as info:
        check_dpi(bad, "run: --dpi")
    message = str(info.value)
    assert "\n" not in message and message.startswith("run: --dpi must be")
    assert reason in message and repr(bad) in message


def test_default_dpi_is_in_range():
    assert DPI_RANGE[0] <= DEFAULT_DPI <= DPI_RANGE[1]


def test_figure_names_follow_the_format():
    assert figure_names() == FIGURE_NAMES
    assert figure_names("svg") == (
        "return_map.svg",
        "time_map.svg",
        "phase.svg",
        "trajectory.svg",
        "animation.gif",
    )
    names = all_figure_names()
    for fmt in FIGURE_FORMATS:
        assert set(figure_names(fmt)) <= set(names)
    assert len(names) == len(set(names)) == 4 * len(FIGURE_FORMATS) + 1
    with pytest.raises(RunDataError):
        figure_names("gif")
