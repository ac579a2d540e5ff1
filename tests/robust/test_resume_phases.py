"""A sampled run with contact phases (``--sample``, ``contact.model = "phases"``) stopped
by SIGINT or SIGTERM in any motion state (flying, rolling, sliding, held in the wedge's
vertex) resumes to the same bytes as an uninterrupted run: collisions.csv, contacts.csv
and trajectory.csv.

A stop inside a contact phase cuts it: the engine's state stays at the phase's start
and the resumed run redoes the phase. The samples the phase reported before the cut
belong to no engine state: the checkpoint counts the samples up to the phase's start
(they used to be counted, and the resume was refused as "engine state is implausible:
N samples at t = ...")."""

from __future__ import annotations

import importlib
import os
import signal
from collections.abc import Callable
from pathlib import Path

import pytest

from billiard.cli import main
from billiard.run.simulate import RunInterrupted, resume, simulate
from billiard.runfile.checkpoint import read_checkpoint
from billiard.runfile.npyfile import TRAJECTORY
from billiard.runfile.npystream import SideNpy
from billiard.runfile.record import TRAJECTORY_COLUMNS
from billiard.runfile.sidecsv import SideCsv
from billiard.scene.scene import load_scene, with_values

persist = importlib.import_module("billiard.run.persist")

SAMPLE = 0.001  # s
DURATION = 2.0  # s
PHASES = {"contact.model": "phases", "run.duration": DURATION}
# (scene, changes): where the ball spends most of the run in the motion state
SCENES = {
    # the chaotic wedge: many short flights
    "flight": ("wedge-6.6hz", {}),
    # a gently shaken bowl: two impacts, then it rolls (1.98 s of 2 s, one phase) ...
    "roll": ("parabola-5.4hz", {"drive.amplitude": 0.002, "initial.q1": 0.02}),
    # ... and slides in a frictionless one (1.98 s of 2 s, one phase)
    "slide": (
        "parabola-5.4hz",
        {
            "drive.amplitude": 0.002,
            "initial.q1": 0.02,
            "contact.mu_static": 0.0,
            "contact.mu_kinetic": 0.0,
        },
    ),
    # a gently shaken wedge: the ball lies in its vertex (2.0 s of 2 s, one hold)
    "held": ("wedge-6.6hz", {"drive.amplitude": 0.001}),
}
#: the sample of the motion state after which the run signals itself
AT = 300
FILES = ("collisions.csv", "contacts.csv", "trajectory.csv", "scene.toml")
NPY_FILES = ("collisions.npy", "contacts.npy", "trajectory.npy", "scene.toml")


def scene_in(mode: str):
    name, changes = SCENES[mode]
    return with_values(load_scene(name), {**PHASES, **changes})


def signal_at_sample(monkeypatch, mode: str, k: int, signum: int) -> list[float]:
    """Make the streamed run send itself ``signum`` right after its ``k``-th sample in
    motion state ``mode``; returns the list that gets that sample's time."""
    original = persist.guard_samples
    when: list[float] = []

    def guard(append: Callable, *args) -> Callable:
        inner = original(append, *args)
        seen = [0]

        def on_sample(*row) -> None:
            inner(*row)
            if row[-1] == mode:
                seen[0] += 1
                if seen[0] == k:
                    when.append(row[0])
                    os.kill(os.getpid(), signum)

        return on_sample

    monkeypatch.setattr(persist, "guard_samples", guard)
    return when


def rows(path: Path) -> int:
    return path.read_bytes().count(b"\n") - 1


@pytest.mark.parametrize(
    ("mode", "signum", "store"),
    [
        ("flight", signal.SIGINT, "csv"),
        ("roll", signal.SIGINT, "csv"),
        ("slide", signal.SIGINT, "csv"),
        ("held", signal.SIGINT, "csv"),
        ("roll", signal.SIGTERM, "csv"),
        ("held", signal.SIGTERM, "npy"),
    ],
    ids=["flight", "roll", "slide", "held", "roll-SIGTERM", "held-SIGTERM-npy"],
)
def test_a_sampled_run_stopped_in_any_motion_state_resumes_to_the_same_bytes(
    mode, signum, store, tmp_path, monkeypatch
):
    scene = scene_in(mode)
    ref = tmp_path / "ref"
    simulate(scene, collisions=10_000, out_dir=ref, sample=SAMPLE, store=store)
    out = tmp_path / "run"
    when = signal_at_sample(monkeypatch, mode, AT, signum)
    with pytest.raises(RunInterrupted) as caught:
        simulate(scene, collisions=10_000, out_dir=out, sample=SAMPLE, store=store)
    assert caught.value.signum == signum and when
    checkpoint = read_checkpoint(out / "checkpoint.json")
    engine = checkpoint["engine"]
    t = engine["ball"]["t"]
    # the checkpoint's samples: those at k dt <= t, where the stop left the engine
    assert engine["samples"] == int(t // SAMPLE) + 1
    if mode != "flight":
        # the stop fell inside a phase of that motion state, which it cut: the engine is
        # at the phase's start, the samples the phase made after the checkpoint's size
        trajectory = out / ("trajectory.npy" if store == "npy" else "trajectory.csv")
        assert engine["mode"] == mode and t < when[0]
        assert trajectory.stat().st_size > checkpoint["side"]["trajectory"]
    monkeypatch.undo()
    resume(out)
    names = FILES if store == "csv" else NPY_FILES
    for name in names:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name


def test_the_command_line_resumes_a_run_stopped_while_rolling(tmp_path, monkeypatch, capsys):
    # `billiard run SCENE --sample DT`, Ctrl-C while the ball rolls, `--resume DIR`
    name, changes = SCENES["roll"]
    sets = [
        arg for key, value in {**PHASES, **changes}.items() for arg in ("--set", f"{key}={value}")
    ]
    args = ["run", name, *sets, "--sample", str(SAMPLE), "--no-plot"]
    ref, out = tmp_path / "ref", tmp_path / "run"
    assert main([*args, "--out", str(ref)]) == 0
    signal_at_sample(monkeypatch, "roll", AT, signal.SIGINT)
    assert main([*args, "--out", str(out)]) == 130
    monkeypatch.undo()
    capsys.readouterr()
    assert main(["run", "--resume", str(out), "--no-plot"]) == 0
    assert "implausible" not in capsys.readouterr().err
    for file in FILES:
        assert (out / file).read_bytes() == (ref / file).read_bytes(), file


@pytest.mark.parametrize("store", ["csv", "npy"])
@pytest.mark.parametrize("spill", [False, True], ids=["buffered", "written"])
def test_a_side_files_mark_before_its_last_rows(store, spill, tmp_path, monkeypatch):
    # the (size, CRC-32) a checkpoint records for the first rows of a side file, the rows
    # after them still buffered or already written (spilled): those of a file holding
    # just these rows; a resume from it cuts the file back and writes on as that file
    if spill:
        monkeypatch.setattr(importlib.import_module("billiard.runfile.sidecsv"), "SPILL_CHARS", 1)
        monkeypatch.setattr(
            importlib.import_module("billiard.runfile.npystream"), "SIDE_SPILL_ROWS", 1
        )

    def opened(path: Path, mark: tuple[int, int] | None = None):
        size, crc = mark if mark is not None else (None, None)
        if store == "npy":
            return SideNpy(path, TRAJECTORY, size, crc)
        return SideCsv(path, TRAJECTORY_COLUMNS, size, crc)

    def sample(i: int) -> tuple:
        return (i * 0.5, 1.0 / (i + 3), -i * 1e-7, 2.0**-i, i, 0.25 * i, 1e-3 * i, "roll")

    short = opened(tmp_path / "short")
    for i in range(12):
        short.append(sample(i))
    expected = short.mark()
    short.close()
    long = opened(tmp_path / "long")
    for i in range(7):
        long.append(sample(i))
    long.mark()  # a checkpoint after 7 rows
    for i in range(7, 40):
        long.append(sample(i))
    assert long.appended == 40
    mark = long.mark(12)
    assert mark == expected
    with pytest.raises(ValueError, match="no mark after 3 rows"):
        long.mark(3)  # before the last flush
    long.close()
    assert (tmp_path / "long").stat().st_size > mark[0]  # the rows after it are kept
    for path, at in ((tmp_path / "long", mark), (tmp_path / "short", expected)):
        side = opened(path, at)
        for i in range(12, 20):
            side.append(sample(i))
        side.close()
    assert (tmp_path / "long").read_bytes() == (tmp_path / "short").read_bytes()
