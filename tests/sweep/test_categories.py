"""Colours of category maps: distinct however many categories, never a class's own."""

from __future__ import annotations

import pytest
from matplotlib.colors import to_rgb

from billiard.sweep.categories import CLASS_COLOURS, distinct_colours


@pytest.mark.parametrize("count", [1, 5, 40, 150])
def test_colours_are_distinct_and_leave_the_classes_own(count):
    taken = list(CLASS_COLOURS.values())
    colours = distinct_colours(count, taken=taken)
    assert len(colours) == count
    assert len(set(colours)) == count
    reserved = {to_rgb(colour) for colour in taken}
    assert not reserved & set(colours)


def test_the_first_colours_are_the_qualitative_palettes():
    assert distinct_colours(2) == [to_rgb("tab:blue"), to_rgb("tab:orange")]
    # a taken colour is skipped, the next one used
    assert distinct_colours(1, taken=["tab:blue"]) == [to_rgb("tab:orange")]
