"""The one duration formatter of the progress reports (a run's time left, a sweep's
elapsed time and ETA): rounded to whole seconds before it is split, so that no report
reads "1 min 60 s"."""

from __future__ import annotations

import io

import pytest

from billiard.cli.run import ProgressBar
from billiard.engine.progress import duration_text
from billiard.sweep.progress import SweepProgress


@pytest.mark.parametrize(
    ("seconds", "text"),
    [
        (0.0, "0 s"),
        (-3.0, "0 s"),  # a clock that stepped back: nothing left, not a negative time
        (0.4, "0 s"),
        (42.0, "42 s"),
        (59.4, "59 s"),
        (59.5, "1 min 0 s"),  # round half to even: 60
        (59.6, "1 min 0 s"),
        (60.0, "1 min 0 s"),
        (119.6, "2 min 0 s"),
        (185.0, "3 min 5 s"),
        (3599.4, "59 min 59 s"),
        (3599.6, "1 h 0 min"),
        (7800.0, "2 h 10 min"),
        (float("inf"), "?"),
        (float("nan"), "?"),
    ],
)
def test_durations_round_before_they_split(seconds: float, text: str) -> None:
    assert duration_text(seconds) == text


def test_no_duration_reads_sixty_of_a_unit() -> None:
    for tenths in range(0, 73000, 3):  # 0 to 2 h, in steps of 0.3 s
        text = duration_text(tenths / 10)
        numbers = [int(word) for word in text.split() if word.isdigit()]
        assert all(n < 60 for n in numbers[1:]), text  # the second unit stays below 60


def test_a_run_and_a_sweep_say_the_same_time_left(monkeypatch) -> None:
    """Both reports use the one formatter: 119.6 s left reads 2 min 0 s in a run's log
    line (not "1 min 60 s"), and a sweep writes its minutes and seconds the same way."""
    bar = ProgressBar(io.StringIO(), interval=0.0)
    bar.first_done, bar.first_time = 0, 0.0
    # 100 impacts in 1 s, 11,960 left: 119.6 s
    assert bar.line(100, 12060, 1.0).endswith("100 impacts/s, about 2 min 0 s left")

    import billiard.sweep.progress as sweep_progress

    now = [0.0]
    monkeypatch.setattr(sweep_progress.time, "perf_counter", lambda: now[0])
    sweep = SweepProgress(37 + 10, stream=io.StringIO())
    now[0] = 50.0  # 10 points in 50 s, 37 left: 185 s
    sweep.done = 10
    assert sweep.text().endswith("elapsed 50 s, ETA 3 min 5 s")
