"""``python -m bench.same_records``: the comparison of two trees' record files."""

from __future__ import annotations

from pathlib import Path

from bench.same_records import QUICK, RUNS, compare


def _write(root: Path, name: str, record: str, text: str) -> None:
    folder = root / name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{record}.csv").write_text(text)


def test_equal_files_pass_and_each_difference_is_named(tmp_path):
    runs = (("a", (), False), ("b", (), False))
    for tree in ("new", "old"):
        _write(tmp_path / tree, "a", "collisions", "n,t\n1,0.5\n2,0.75\n")
        _write(tmp_path / tree, "b", "contacts", "t_start\n0.25\n")
    assert compare(tmp_path / "new", tmp_path / "old", runs) == []
    _write(tmp_path / "new", "a", "collisions", "n,t\n1,0.5\n2,0.7500000000000001\n")
    _write(tmp_path / "new", "b", "trajectory", "t\n0.0\n")
    assert compare(tmp_path / "new", tmp_path / "old", runs) == [
        "a/collisions.csv: line 3",
        "b/trajectory.csv: written by one commit only",
    ]


def test_the_quick_runs_are_runs_of_the_whole_list():
    names = [name for name, _, _ in RUNS]
    assert len(names) == len(set(names)) and QUICK <= set(names)
    # every kind of run is there: impacts, rk4, phases, samples, interpreted
    flags = {flag for _, args, _ in RUNS for flag in args if flag.startswith("--")}
    assert {"--method", "--sample", "--set", "--duration", "--collisions"} <= flags
    assert any(interpreted for _, _, interpreted in RUNS)
