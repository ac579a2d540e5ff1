"""The throughput section of ``billiard bench`` (bench/throughput.py): each engine is
measured in its own fresh process, the interpreted one with NUMBA_DISABLE_JIT=1, and
the targets' verdicts follow from the measured numbers. No timing is asserted."""

from __future__ import annotations

import pytest

from bench import throughput
from bench.report_throughput import section_throughput, target_rows
from billiard import jit


def test_each_engine_runs_in_its_own_process():
    slow = throughput.engine_rate("wedge-6.6hz", "none", 40, 2, interpreted=True)
    fast = throughput.engine_rate("wedge-6.6hz", "none", 40, 2, interpreted=False)
    assert slow["compiled"] is False
    assert fast["compiled"] is jit.ENABLED
    for r in (slow, fast):
        assert len(r["cpus"]) == 2
        assert r["cpu"] == pytest.approx(sum(r["cpus"]) / 2)  # the median of two runs
        assert r["cpu_per_impact"] == pytest.approx(r["cpu"] / 40)
        assert r["impacts"] == 40 and all(c > 0 for c in r["cpus"])


def _rate(scene: str, drag: str, fast_us: float, slow_us: float) -> dict:
    def engine(us: float, compiled: bool) -> dict:
        return {
            "compiled": compiled,
            "impacts": 1000,
            "cpus": [us * 1e-3],
            "walls": [us * 1e-3],
            "cpu": us * 1e-3,
            "cpu_per_impact": us * 1e-6,
            "wall": us * 1e-3,
        }

    return {
        "scene": scene,
        "drag": drag,
        "impacts": 1000,
        "compiled": engine(fast_us, True),
        "interpreted": engine(slow_us, False),
        "ratio": slow_us / fast_us,
        "times": [fast_us * 1e-3],
        "median": fast_us * 1e-3,
        "cpu": fast_us * 1e-3,
        "rate": 1000 / (fast_us * 1e-3),
        "per_25000": 25 * fast_us * 1e-3,
    }


def _results(wedge_fast_us: float, parabola_fast_us: float) -> dict:
    return {
        "engine": {"compiled": True, "numba": "x"},
        "rates": [
            _rate("wedge-6.6hz", "none", wedge_fast_us, 30.0),
            _rate("parabola-5.4hz", "fowles", parabola_fast_us, 100.0),
        ],
        "runs": [
            {"scene": "wedge-6.6hz", "how": "billiard run", "impacts": 25000, "times": [0.5]}
            | {"median": 0.5},
        ],
        "million": [
            {"scene": "wedge-6.6hz", "how": "in memory", "impacts": 10**6}
            | {"wall": 2.5, "peak_mb": 290.0},
            {"scene": "wedge-6.6hz", "how": "streamed to collisions.csv", "impacts": 10**6}
            | {"wall": 1.5, "peak_mb": 150.0},
        ],
        "compiled_startup": {"scene": "wedge-6.6hz", "warm": [0.7], "warm_median": 0.7}
        | {"cold": 12.0},
        "refcount": {"array_ns": 1.0, "scalar_ns": 0.9, "share": 0.1},
    }


def _verdicts(results: dict) -> dict[str, str]:
    return {row[0]: row[2] for row in target_rows(results)}


def test_verdicts_follow_the_measurements():
    v = _verdicts(_results(wedge_fast_us=0.8, parabola_fast_us=4.0))
    assert v["CPU per impact >= 30x lower, wedge-6.6hz, drag off"] == "met"  # 37.5x
    assert v["wedge-6.6hz, drag off: <= 1 us per impact"] == "met"
    assert v["CPU per impact >= 30x lower, parabola-5.4hz, drag on"] == "missed"  # 25x
    assert v["parabola-5.4hz, drag on: <= 3 us per impact"] == "missed, 1.3x"
    assert v["25,000 impacts <= 0.6 s wall with start-up, wedge-6.6hz"] == "met"
    assert v["1,000,000 wedge impacts (in memory) <= 2 s"] == "missed"
    assert v["1,000,000 wedge impacts (streamed to collisions.csv) <= 2 s"] == "met"
    # the bound is the streamed run's: kept in memory, the rows alone are 144 MB
    streamed = "peak memory <= 200 MB at 1,000,000 impacts (streamed to collisions.csv)"
    assert v[streamed] == "met"
    in_memory = "memory at 1,000,000 impacts (in memory; not bounded: the rows alone are 144 MB)"
    assert v[in_memory] == "-"
    assert not any(k.startswith("peak memory") and "in memory" in k for k in v)
    assert v["warm start-up <= 0.6 s before the first impact"] == "missed"
    assert v["cold first compile <= 20 s"] == "met"
    v = _verdicts(_results(wedge_fast_us=1.2, parabola_fast_us=2.0))
    assert v["CPU per impact >= 30x lower, wedge-6.6hz, drag off"] == "missed"  # 25x
    assert v["wedge-6.6hz, drag off: <= 1 us per impact"] == "missed, 1.2x"
    assert v["CPU per impact >= 30x lower, parabola-5.4hz, drag on"] == "met"  # 50x
    results = _results(wedge_fast_us=1.2, parabola_fast_us=2.0)
    results["million"][1]["peak_mb"] = 250.0
    assert _verdicts(results)[streamed] == "missed"


def test_the_section_shows_every_ratio():
    text = section_throughput(_results(0.8, 4.0), "billiard bench")
    assert "| 38x |" in text and "| 25x |" in text
    assert "billiard bench --only throughput" in text
