"""The io section of the bench (bench/runio.py): its verdicts follow the measurements
and the targets, the times judged on 10^6 impacts only."""

from __future__ import annotations

from bench import runio


def results(impacts: int, npy_seconds: float, read: float, plot: float) -> dict:
    return {
        "scene": "wedge-6.6hz",
        "impacts": impacts,
        "repeats": 1,
        "writes": {h: [1.0] for h in runio.WRITES},
        "write_median": {"discard": 1.0, "memory": 1.05, "npy": npy_seconds, "csv": 2.0},
        "bytes": {"npy": 137 * impacts + 448, "csv": 321 * impacts},
        "reads": {label: [read] for label, _, _ in runio.READS},
        "read_median": {label: read for label, _, _ in runio.READS},
        "plots": {"npy": [plot], "csv": [plot]},
        "plot_median": {"npy": plot, "csv": plot},
        "pandas": None,
        "numpy": "2",
        "targets": runio.TARGETS,
    }


def verdicts(io: dict) -> list[str]:
    return [row[2] for row in runio.target_rows(io)]


def test_verdicts_follow_the_targets():
    assert verdicts(results(10**6, 1.15, 0.5, 4.0)) == ["met"] * 4
    # 0.25 us per impact beyond the physics, reading 1.2 s, plotting 6 s
    assert verdicts(results(10**6, 1.25, 1.2, 6.0)) == ["missed", "missed", "met", "missed"]


def test_quick_mode_judges_only_what_does_not_depend_on_the_size():
    io = results(50_000, 1.0 + 50_000 * 0.1e-6, 0.01, 2.5)
    assert verdicts(io) == ["-", "met", "met", "-"]
    rows = runio.target_rows(io)
    assert "50,000 impacts: judged at 10^6 only" in rows[0][1]
    text = runio.page_section(io, "[full tables](x)")
    assert "2 of the 2 targets judged are met" in text
