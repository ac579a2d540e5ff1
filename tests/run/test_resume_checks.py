"""Resume refuses what it cannot continue exactly: rows edited before the checkpoint (a
CRC-32 of each file's rows is kept in it), an edited scene.toml (its sha256 is kept),
and engine states no run of the scene reaches (a forged checkpoint passes its own
checksum: anyone can recompute it). Each refusal is one line and leaves the files as
they were."""

from __future__ import annotations

import hashlib
import json
import shutil
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import billiard
from billiard.cli import main
from billiard.engine.interrupt import signal_after
from billiard.run.persist import CHECKPOINT_NAME, CSV_NAME, SCENE_NAME
from billiard.run.simulate import RunInterrupted, Simulation, resume, simulate
from billiard.runfile.checkpoint import read_checkpoint, write_checkpoint
from billiard.runfile.npyfile import CONTACTS, header_bytes, header_size
from billiard.runfile.record import NO_WALL
from billiard.scene.scene import load_scene, scene_from_toml, scene_to_toml, with_values

IMPACTS, AT = 400, 150
FILES = ("collisions.csv", "contacts.csv", "trajectory.csv", "scene.toml")


def wedge_phases():
    return with_values(load_scene("wedge-6.6hz"), {"contact.model": "phases"})


def make_runs(base: Path, scene, **kwargs) -> tuple[Path, Path]:
    """An uninterrupted run and the same run interrupted after impact AT."""
    ref = base / "ref"
    simulate(scene, collisions=IMPACTS, out_dir=ref, **kwargs)
    stopped = base / "stopped"
    with pytest.raises(RunInterrupted):
        simulate(scene, collisions=IMPACTS, out_dir=stopped, on_record=signal_after(AT), **kwargs)
    return ref, stopped


@pytest.fixture(scope="module")
def impacts_runs(tmp_path_factory) -> tuple[Path, Path]:
    return make_runs(tmp_path_factory.mktemp("impacts"), load_scene("wedge-6.6hz"))


@pytest.fixture(scope="module")
def phases_runs(tmp_path_factory) -> tuple[Path, Path]:
    return make_runs(tmp_path_factory.mktemp("phases"), wedge_phases(), sample=0.01)


def copy_run(run: Path, tmp_path: Path) -> Path:
    out = tmp_path / "run"
    shutil.copytree(run, out)
    return out


def files_of(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in out.iterdir()}


def refused(out: Path, capsys, *fragments: str) -> str:
    """``billiard run --resume out`` fails in one line naming ``fragments``, and leaves
    every file as it was."""
    before = files_of(out)
    assert main(["run", "--resume", str(out), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"billiard: error: cannot resume {out}: ") and err.count("\n") == 1
    for fragment in fragments:
        assert fragment in err, err
    assert files_of(out) == before
    return err


def edit_middle(path: Path, before: int) -> None:
    """Change one digit in the middle of the first ``before`` bytes of ``path``: the row
    count and the last line before the checkpoint stay as they were."""
    data = bytearray(path.read_bytes())
    i = before // 2
    while not chr(data[i]).isdigit() or chr(data[i]) == "9":
        i += 1
    data[i] += 1
    path.write_bytes(bytes(data))


# ---------------------------------------------------------------------------------
# (a) rows edited before the checkpoint


def test_an_edited_impact_row_is_refused(impacts_runs, tmp_path, capsys):
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    mark = read_checkpoint(out / CHECKPOINT_NAME)["csv"]
    edit_middle(out / CSV_NAME, mark["bytes"])
    refused(out, capsys, f"{out / CSV_NAME} does not match the checkpoint", "CRC-32 differs")


@pytest.mark.parametrize("name", ["contacts.csv", "trajectory.csv"])
def test_an_edited_side_row_is_refused(name, phases_runs, tmp_path, capsys):
    ref, stopped = phases_runs
    out = copy_run(stopped, tmp_path)
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    size = checkpoint["side"][name.removesuffix(".csv")]
    edit_middle(out / name, size)
    refused(out, capsys, f"{out / name} does not match the checkpoint", "CRC-32 differs")


def test_untouched_runs_still_resume_byte_for_byte(phases_runs, tmp_path):
    ref, stopped = phases_runs
    out = copy_run(stopped, tmp_path)
    resume(out)
    for name in FILES:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name


def test_a_version_2_checkpoint_resumes_without_the_checksums(impacts_runs, tmp_path):
    """The decision for checkpoints of the earlier version: resumed, their rows not
    checked, and the note says so; the new checkpoints carry the checksums."""
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    body = read_checkpoint(out / CHECKPOINT_NAME)
    for key in ("format", "version", "side_crc32", "scene_toml_sha256"):
        body.pop(key, None)
    del body["csv"]["crc32"]
    write_checkpoint(out / CHECKPOINT_NAME, body)
    data = (out / CHECKPOINT_NAME).read_text().replace('"version": 3', '"version": 2')
    (out / CHECKPOINT_NAME).write_text(data)
    _rewrite_checksum(out / CHECKPOINT_NAME)
    assert read_checkpoint(out / CHECKPOINT_NAME)["version"] == 2
    notes: list[str] = []
    resume(out, notify=notes.append)
    assert len(notes) == 1 and "without the checksums of the rows before it" in notes[0]
    assert (out / CSV_NAME).read_bytes() == (ref / CSV_NAME).read_bytes()
    assert "crc32" in read_checkpoint(out / CHECKPOINT_NAME)["csv"]


def _rewrite_checksum(path: Path) -> None:
    data = json.loads(path.read_text())
    data.pop("sha256")
    canonical = json.dumps(data, sort_keys=True, allow_nan=False, separators=(",", ":"))
    data["sha256"] = hashlib.sha256(canonical.encode()).hexdigest()
    path.write_text(json.dumps(data, indent=1))


def test_a_row_count_that_disagrees_with_the_file_is_refused(impacts_runs, tmp_path, capsys):
    """Even without a checksum (an earlier version's checkpoint), two rows before the
    checkpoint's place run into one are found by counting them."""
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    body = read_checkpoint(out / CHECKPOINT_NAME)
    lines = (out / CSV_NAME).read_bytes().splitlines(keepends=True)
    lines[50] = lines[50].replace(b"\n", b",")  # same bytes, same last line, a row less
    (out / CSV_NAME).write_bytes(b"".join(lines))
    body = {k: v for k, v in body.items() if k not in ("format", "version")}
    del body["csv"]["crc32"]
    write_checkpoint(out / CHECKPOINT_NAME, body)
    refused(out, capsys, f"({AT - 1} rows before the checkpoint's place, which follows impact")


# ---------------------------------------------------------------------------------
# (b) scene.toml edited


def test_an_edited_scene_file_is_refused(impacts_runs, tmp_path, capsys):
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    text = (out / SCENE_NAME).read_text()
    assert text == scene_to_toml(scene_from_toml(text))  # as billiard writes it
    (out / SCENE_NAME).write_text(text.replace("\n[drive]", "\n# shaken harder?\n[drive]"))
    refused(out, capsys, "scene.toml was edited after the checkpoint was written")


def test_scene_file_with_a_new_impact_count_as_billiard_writes_it(impacts_runs, tmp_path):
    """What an extension leaves if killed before its first checkpoint: scene.toml with a
    new impact count, as billiard writes it; the run continues to that count."""
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    scene = scene_from_toml((out / SCENE_NAME).read_text())
    (out / SCENE_NAME).write_text(scene_to_toml(Simulation(scene).resolved_scene(IMPACTS + 50)))
    result = resume(out)
    assert len(result) == IMPACTS + 50
    assert (out / CSV_NAME).read_bytes().startswith((ref / CSV_NAME).read_bytes())


# ---------------------------------------------------------------------------------
# (c) implausible engine states


def forge(out: Path, change: Callable[[dict], None]) -> None:
    """Change the checkpoint and give it a valid checksum, as a forger would."""
    body = read_checkpoint(out / CHECKPOINT_NAME)
    change(body)
    write_checkpoint(out / CHECKPOINT_NAME, {k: v for k, v in body.items() if k not in (
        "format", "version")})  # fmt: skip


def _set(path: str, value) -> Callable[[dict], None]:
    def change(body: dict) -> None:
        *keys, last = path.split(".")
        node = body
        for key in keys:
            node = node[key]
        node[last] = value(node[last]) if callable(value) else value

    return change


FORGERIES = {
    "speed": (_set("engine.ball.u1", 1e6), "the ball's speed 1e+06 m/s is over"),
    "spin": (_set("engine.ball.u3", 1e12), "the ball's spin 1e+12 rad/s is over"),
    "outside": (_set("engine.ball.q1", 50.0), "is outside its container"),
    "time": (_set("engine.ball.t", lambda t: t + 1.0), "is not the ball's time"),
    "before start": (_set("engine.ball.t", -5.0), "is before the start"),
    "theta": (_set("engine.ball.theta", 7.0), "the drive angle 7.0 rad is not in [0, 2 pi]"),
    "regimes": (_set("engine.counts.stick", lambda n: n + 1), "regime counters add up to"),
    "resting": (_set("engine.counts.resting", 10_000), "relaunches in"),
    "recent": (_set("engine.recent", [5.0, 1.0]), "impact times are not in order"),
    "zero flights": (_set("engine.zero_flights", 10**6), "zero flights in a row, over"),
    "samples": (_set("engine.samples", 7), "7 samples in a run that samples nothing"),
    "phase time": (_set("engine.phase_time.roll", 1e6), "s roll in"),
    "contact": (
        lambda b: (_set("engine.mode", "roll")(b), _set("engine.contact", [0, 0, 0, 0, 0, 0])(b)),
        "in contact (roll) in a scene without contact phases",
    ),
}


@pytest.mark.parametrize("forgery", list(FORGERIES))
def test_an_implausible_state_is_refused(forgery, impacts_runs, tmp_path, capsys):
    ref, stopped = impacts_runs
    out = copy_run(stopped, tmp_path)
    change, fragment = FORGERIES[forgery]
    forge(out, change)
    refused(out, capsys, "its engine state is implausible: ", fragment)


def test_a_sampled_state_must_match_its_samples(phases_runs, tmp_path, capsys):
    ref, stopped = phases_runs
    out = copy_run(stopped, tmp_path)
    forge(out, _set("engine.samples", lambda n: n + 40))
    refused(out, capsys, "samples at t = ", "every 0.01 s from 0.0 s makes")


def test_a_contact_on_no_wall_is_refused(phases_runs, tmp_path, capsys):
    ref, stopped = phases_runs
    out = copy_run(stopped, tmp_path)
    t = read_checkpoint(out / CHECKPOINT_NAME)["engine"]["ball"]["t"]
    forge(
        out,
        lambda b: (_set("engine.mode", "roll")(b), _set("engine.contact", [7, 0, 0, 0, t, t])(b)),
    )
    refused(out, capsys, "the contact's wall (7.0,) is not one of the 2 walls")


def test_the_trajectory_must_hold_the_states_samples(phases_runs, tmp_path, capsys):
    """A checkpoint whose trajectory.csv size and checksum describe fewer rows than its
    engine state's samples."""
    ref, stopped = phases_runs
    out = copy_run(stopped, tmp_path)
    body = read_checkpoint(out / CHECKPOINT_NAME)
    data = (out / "trajectory.csv").read_bytes()[: body["side"]["trajectory"]]
    cut = data[: data.rstrip(b"\n").rfind(b"\n") + 1]  # one sample fewer

    def change(b: dict) -> None:
        b["side"]["trajectory"] = len(cut)
        b["side_crc32"]["trajectory"] = zlib.crc32(cut)

    forge(out, change)
    n = body["engine"]["samples"]
    refused(out, capsys, f"holds {n - 1} samples before the checkpoint, its engine state says {n}")


# ---------------------------------------------------------------------------------
# (d) side files written by an earlier version


def _old_contacts_text(text: str) -> str:
    """contacts.csv lines as written before ``wall`` was an integer: no ``wall_other``,
    ``a+b`` in ``wall`` for a phase held by two walls."""
    lines = []
    for line in text.splitlines(keepends=True):
        cells = line.rstrip("\n").split(",")
        other = cells.pop()
        if other not in ("wall_other", str(NO_WALL)):
            cells[2] = f"{cells[2]}+{other}"
        lines.append(",".join(cells) + "\n")
    return "".join(lines)


def _old_contacts_npy(rows: np.ndarray) -> tuple[bytes, bytes]:
    """(header, rows) of contacts.npy as written before: ``wall`` ``S15`` text."""
    names = [name for name in CONTACTS.columns if name != "wall_other"]
    kinds = {"wall": "S15", "mode": "S5", "end": "S8"}
    dtype = np.dtype([(name, kinds.get(name, "<f8")) for name in names])
    old = np.empty(len(rows), dtype=dtype)
    for name in names:
        old[name] = rows[name]
    old["wall"] = [
        f"{a}+{b}".encode() if b != NO_WALL else str(a).encode()
        for a, b in zip(rows["wall"].tolist(), rows["wall_other"].tolist(), strict=True)
    ]
    return header_bytes(dtype, len(old)), old.tobytes()


@pytest.fixture(scope="module")
def phases_npy_run(tmp_path_factory) -> Path:
    """The phases run stored as binary files, interrupted after impact AT."""
    stopped = tmp_path_factory.mktemp("phases-npy") / "stopped"
    with pytest.raises(RunInterrupted):
        simulate(wedge_phases(), collisions=IMPACTS, out_dir=stopped, store="npy",
                 on_record=signal_after(AT))  # fmt: skip
    return stopped


@pytest.mark.parametrize("store", ["csv", "npy"])
def test_a_run_with_contacts_of_an_earlier_version_is_refused(
    store, phases_runs, phases_npy_run, tmp_path, capsys
):
    """An unfinished run whose contacts file an earlier version wrote (``wall`` text,
    no ``wall_other``), its checkpoint consistent with it: continued, it would get rows
    of the new columns after rows of the old ones. Refused in one line, files as they
    were."""
    out = copy_run(phases_runs[1] if store == "csv" else phases_npy_run, tmp_path)
    path = _as_written_before(out, store)
    # still a run of contact phases to read: the old rows read as rows of now
    assert billiard.read_contacts(path)["wall_other"].dtype == np.int64
    refused(out, capsys, f"{path} has other columns than this version writes", "without --resume")


@pytest.mark.parametrize("store", ["csv", "npy"])
def test_a_run_with_contacts_of_an_earlier_version_opens_verified(
    store, phases_runs, phases_npy_run, tmp_path
):
    """The same run opened to be read: its files match its checkpoint, so it opens
    (no damage reported), its walls integers."""
    out = copy_run(phases_runs[1] if store == "csv" else phases_npy_run, tmp_path)
    _as_written_before(out, store)
    run = billiard.open_run(out)
    contacts = run.contacts
    assert contacts["wall"].dtype == np.int64 and contacts["wall_other"].dtype == np.int64


def _as_written_before(out: Path, store: str) -> Path:
    """Rewrite the run in ``out``'s contacts file as an earlier version wrote it, its
    checkpoint consistent with it; returns the file's path."""
    checkpoint = read_checkpoint(out / CHECKPOINT_NAME)
    size = checkpoint["side"]["contacts"]
    path = out / f"contacts.{store}"
    if store == "csv":
        data = path.read_text()
        before, after = _old_contacts_text(data[:size]), _old_contacts_text(data[size:])
        path.write_text(before + after)
        checkpoint["side"]["contacts"] = len(before.encode())
        checkpoint["side_crc32"]["contacts"] = zlib.crc32(before.encode())
    else:
        rows = np.load(path)
        head = header_size(CONTACTS.dtype)
        kept = (size - head) // CONTACTS.dtype.itemsize
        header, body = _old_contacts_npy(rows)
        path.write_bytes(header + body)
        item = len(body) // max(len(rows), 1)
        checkpoint["side"]["contacts"] = len(header) + kept * item
        checkpoint["side_crc32"]["contacts"] = zlib.crc32(body[: kept * item])
    # the whole files' ends came with a later version than the integer walls
    checkpoint.pop("side_end", None)
    write_checkpoint(out / CHECKPOINT_NAME, checkpoint)
    return path
