"""plot_branch (branch.png): a branch and the period-2N branch switched onto at its
period doubling, each its own line, solid where stable and dashed where not."""

from __future__ import annotations

import matplotlib
import numpy as np

from billiard.plot import branch as branch_plot

matplotlib.use("Agg")


def test_a_switched_branch_is_drawn_apart_from_the_continued_one(tmp_path, monkeypatch):
    drawn = {}

    def keep(fig, path):  # the figure as drawn, before save clears it
        drawn["lines"] = [
            (line.get_label(), line.get_color(), line.get_linestyle(), line.get_xdata().tolist())
            for line in fig.axes[0].get_lines()
        ]
        return path

    monkeypatch.setattr(branch_plot, "save", keep)
    # a period-one branch losing its stability at 2.0, the period-two branch from there
    arrays = {
        "drive_amplitude": np.array([1.0, 1.5, 2.0, 2.5, 2.0, 2.2, 2.4]),
        "q2": np.array([1.0, 1.2, 1.4, 1.6, 1.4, 1.3, 1.2]) * 1e-3,
        "stable": np.array([1, 1, 0, 0, 1, 1, 1], dtype=np.int8),
        "bifurcation": np.array([0, 0, 2, 0, 0, 0, 0], dtype=np.int8),
        "period": np.array([1, 1, 1, 1, 2, 2, 2], dtype=np.int32),
        "branch": np.array([0, 0, 0, 0, 1, 1, 1], dtype=np.int32),
    }
    branch_plot.plot_branch(arrays, "drive.amplitude", tmp_path / "branch.png")
    lines = {label: rest for label, *rest in drawn["lines"]}
    assert lines["stable period 1 orbit"][2] == [1.0, 1.5, 2.0]
    assert lines["unstable period 1 orbit"][1] == "--"
    assert lines["unstable period 1 orbit"][2] == [2.0, 2.5]
    # the doubled branch: its own colour, not joined to the end of the continued one
    assert lines["stable period 2 orbit"][2] == [2.0, 2.2, 2.4]
    assert lines["stable period 2 orbit"][1] == "-"
    assert lines["stable period 2 orbit"][0] != lines["stable period 1 orbit"][0]
