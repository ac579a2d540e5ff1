"""``collisions.csv`` ends its lines with ``\\n`` (line tools see ``0.5``, not ``0.5\\r``);
files written with ``\\r\\n`` by older versions still read, and resume in their own style."""

from __future__ import annotations

import numpy as np

from billiard.engine.interrupt import signal_after
from billiard.run.simulate import CHECKPOINT_NAME, CSV_NAME, RunInterrupted, resume, simulate
from billiard.runfile.checkpoint import read_checkpoint, write_checkpoint
from billiard.runfile.record import write_collisions
from billiard.runfile.stream import CsvRecorder
from billiard.runfile.tables import read_collisions
from billiard.scene.scene import load_scene


def _lines_end_with_newline_only(data: bytes) -> bool:
    return data.endswith(b"\n") and b"\r" not in data


def test_streamed_run_writes_plain_newlines(tmp_path):
    simulate(load_scene("wedge-6.6hz"), collisions=40, out_dir=tmp_path)
    data = (tmp_path / CSV_NAME).read_bytes()
    assert _lines_end_with_newline_only(data)
    assert data.count(b"\n") == 41
    # a line tool sees plain numbers in the last column
    last_fields = [line.rsplit(b",", 1)[1] for line in data.split(b"\n")[1:-1]]
    assert all(float(field) == float(field.decode()) for field in last_fields)
    mark = read_checkpoint(tmp_path / CHECKPOINT_NAME)["csv"]
    assert mark["last_line"].endswith("\n") and "\r" not in mark["last_line"]


def test_recorder_header_and_write_collisions_use_plain_newlines(tmp_path):
    recorder = CsvRecorder(tmp_path / "a.csv")
    recorder.close()
    assert _lines_end_with_newline_only((tmp_path / "a.csv").read_bytes())
    result = simulate(load_scene("wedge-6.6hz"), collisions=10)
    result.to_csv(tmp_path / "b.csv")
    write_collisions(tmp_path / "c.csv", {"n": [1, 2], "t": [0.5, 1.0]})
    for name in ("b.csv", "c.csv"):
        assert _lines_end_with_newline_only((tmp_path / name).read_bytes())


def test_old_crlf_file_still_reads(tmp_path):
    simulate(load_scene("wedge-6.6hz"), collisions=30, out_dir=tmp_path / "run")
    data = (tmp_path / "run" / CSV_NAME).read_bytes()
    (tmp_path / "old.csv").write_bytes(data.replace(b"\n", b"\r\n"))
    new, old = read_collisions(tmp_path / "run" / CSV_NAME), read_collisions(tmp_path / "old.csv")
    assert new.keys() == old.keys()
    for name in new:
        np.testing.assert_array_equal(new[name], old[name])
    # an old file cut in the middle of its last line terminator still reads its whole rows
    (tmp_path / "cut.csv").write_bytes(data.replace(b"\n", b"\r\n")[:-1])
    assert len(read_collisions(tmp_path / "cut.csv")["n"]) == 29


def test_old_crlf_run_resumes_in_its_own_line_ending(tmp_path):
    scene = load_scene("wedge-6.6hz")
    simulate(scene, collisions=120, out_dir=tmp_path / "ref")
    expected = (tmp_path / "ref" / CSV_NAME).read_bytes().replace(b"\n", b"\r\n")
    out = tmp_path / "old"
    try:
        simulate(scene, collisions=120, out_dir=out, on_record=signal_after(50))
    except RunInterrupted:
        pass
    # make it what an older version left: CRLF rows and a checkpoint describing them
    csv_path = out / CSV_NAME
    csv_path.write_bytes(csv_path.read_bytes().replace(b"\n", b"\r\n"))
    body = read_checkpoint(out / CHECKPOINT_NAME)
    body.pop("format"), body.pop("version")
    body["csv"]["bytes"] = csv_path.stat().st_size
    body["csv"]["last_line"] = body["csv"]["last_line"].replace("\n", "\r\n")
    del body["csv"]["crc32"]  # the versions that wrote CRLF kept no checksum of the rows
    write_checkpoint(out / CHECKPOINT_NAME, body)
    resume(out)
    assert csv_path.read_bytes() == expected
