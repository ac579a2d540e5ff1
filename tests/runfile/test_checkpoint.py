"""Atomic files and checkpoints (``billiard/runfile/checkpoint.py``): a replaced file is
the old one or the new one, never a mixture, even when the write fails; a checkpoint
reads back bit for bit, and a damaged one is refused with its documented one-line
message."""

from __future__ import annotations

import json
import random
import re
import struct
import threading
from pathlib import Path

import pytest

from billiard.runfile import checkpoint
from billiard.runfile.checkpoint import (
    CHECKPOINT_FORMAT,
    CHECKPOINT_VERSION,
    CheckpointError,
    read_checkpoint,
    write_checkpoint,
    write_text_atomic,
)


def _random_doubles(seed: int, count: int) -> list[float]:
    """Finite doubles from random bit patterns: every exponent, subnormals, both zeros."""
    rng = random.Random(seed)
    out = [0.0, -0.0, 5e-324, -1.7976931348623157e308]
    while len(out) < count:
        (x,) = struct.unpack("<d", rng.getrandbits(64).to_bytes(8, "little"))
        if x == x and abs(x) != float("inf"):
            out.append(x)
    return out


def _body() -> dict:
    return {
        "csv": {"rows": 1234, "crc32": 0xDEADBEEF},
        "engine": {"clock": 1811.2912345678901, "state": _random_doubles(5, 200)},
        "scene": 'name = "é \\" \\n"\n',
        "flags": [True, False, None],
    }


def _bits(value):
    """The value with every float replaced by its exact hex spelling (so -0.0 != 0.0)."""
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, list):
        return [_bits(v) for v in value]
    if isinstance(value, dict):
        return {k: _bits(v) for k, v in value.items()}
    return value


# ----------------------------------------------------------------------------------------
# atomic files


def test_an_atomic_write_replaces_the_file_with_the_exact_text(tmp_path):
    path = tmp_path / "f.txt"
    path.write_text("old")
    text = "line one\r\nline two\né\n"  # line endings kept as given
    write_text_atomic(path, text)
    assert path.read_bytes() == text.encode("utf-8")
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]  # no temporary file left


def test_a_reader_sees_the_old_or_the_new_file_never_a_mixture(tmp_path):
    path = tmp_path / "f.txt"
    texts = ["a" * 50_000, "b" * 70_000]  # of different lengths: a torn read shows
    path.write_text(texts[0])
    seen: list[bytes] = []
    done = threading.Event()

    def read() -> None:
        while not done.is_set():
            seen.append(path.read_bytes())

    reader = threading.Thread(target=read)
    reader.start()
    try:
        for i in range(60):
            write_text_atomic(path, texts[i % 2])
    finally:
        done.set()
        reader.join()
    assert seen
    allowed = {t.encode() for t in texts}
    assert all(data in allowed for data in seen)


@pytest.mark.parametrize("failure", ["encode", "sync", "interrupt"])
def test_a_failed_write_leaves_the_old_file_and_no_temporary_file(tmp_path, monkeypatch, failure):
    path = tmp_path / "f.txt"
    path.write_text("old")
    text = "new"
    if failure == "encode":
        text = "new \ud800"  # a lone surrogate: UTF-8 cannot write it
        expected: type[BaseException] = UnicodeEncodeError
    elif failure == "sync":

        def no_sync(fd: int) -> None:
            raise OSError(5, "Input/output error")

        monkeypatch.setattr(checkpoint.os, "fsync", no_sync)
        expected = OSError
    else:

        def interrupted(src, dst) -> None:
            raise KeyboardInterrupt

        monkeypatch.setattr(checkpoint.os, "replace", interrupted)
        expected = KeyboardInterrupt
    with pytest.raises(expected):
        write_text_atomic(path, text)
    monkeypatch.undo()
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]


# ----------------------------------------------------------------------------------------
# checkpoints


def test_a_checkpoint_reads_back_bit_for_bit(tmp_path):
    path = tmp_path / "checkpoint.json"
    body = _body()
    write_checkpoint(path, body)
    data = read_checkpoint(path)
    assert data["format"] == CHECKPOINT_FORMAT and data["version"] == CHECKPOINT_VERSION
    assert "sha256" not in data
    assert _bits({k: v for k, v in data.items() if k not in ("format", "version")}) == _bits(body)
    # the file is plain JSON a reader can open
    assert json.loads(path.read_text())["csv"]["rows"] == 1234


def test_a_checkpoint_replaces_the_previous_one(tmp_path):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"rows": 1})
    write_checkpoint(path, {"rows": 2})
    assert read_checkpoint(path)["rows"] == 2
    assert [p.name for p in tmp_path.iterdir()] == ["checkpoint.json"]


@pytest.mark.parametrize("x", [float("inf"), float("-inf"), float("nan")])
def test_non_finite_floats_are_refused_and_the_old_checkpoint_kept(tmp_path, x):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"clock": 1.5})
    with pytest.raises(ValueError):
        write_checkpoint(path, {"clock": x})
    assert read_checkpoint(path)["clock"] == 1.5


def _refused(path: Path, message: str) -> None:
    with pytest.raises(CheckpointError) as info:
        read_checkpoint(path)
    text = str(info.value)
    assert "\n" not in text  # one line, as documented
    assert re.fullmatch(re.escape(str(path)) + " " + message, text), text


def _tampered(value):
    """A value that differs from ``value`` (and still is JSON)."""
    if isinstance(value, bool) or value is None:
        return not value
    if isinstance(value, (int, float)):
        return value + 1
    if isinstance(value, str):
        return value + "x"
    if isinstance(value, list):
        return [*value[:-1], _tampered(value[-1])]
    return {**value, "added": 1}


@pytest.mark.parametrize("key", ["csv", "engine", "scene", "flags", "sha256"])
def test_any_changed_field_fails_the_checksum(tmp_path, key):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, _body())
    data = json.loads(path.read_text())
    data[key] = _tampered(data[key])
    path.write_text(json.dumps(data))
    _refused(path, re.escape("is corrupt (its checksum does not match its content)"))


def test_a_changed_float_bit_fails_the_checksum(tmp_path):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"clock": 0.1})
    text = path.read_text()
    assert "0.1," in text or "0.1\n" in text
    path.write_text(text.replace("0.1", repr(0.1 + 2**-56)))  # the next double up
    _refused(path, re.escape("is corrupt (its checksum does not match its content)"))


def test_a_checkpoint_without_its_checksum_is_corrupt(tmp_path):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"rows": 3})
    data = json.loads(path.read_text())
    del data["sha256"]
    path.write_text(json.dumps(data))
    _refused(path, re.escape("is corrupt (its checksum does not match its content)"))


def test_a_truncated_checkpoint_is_corrupt(tmp_path):
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, _body())
    path.write_bytes(path.read_bytes()[:-40])
    _refused(path, r"is corrupt \(not valid JSON: .+\)")


def test_a_missing_checkpoint(tmp_path):
    _refused(tmp_path / "checkpoint.json", "is missing")


def test_a_checkpoint_that_is_not_utf8(tmp_path):
    path = tmp_path / "checkpoint.json"
    path.write_bytes(b'{"format": "\xff"}')
    _refused(path, "cannot be read: .+")


def test_a_folder_is_not_read(tmp_path):
    path = tmp_path / "checkpoint.json"
    path.mkdir()
    _refused(path, re.escape("is not a regular file (a folder)"))


@pytest.mark.parametrize(
    "data",
    [[1, 2], {"version": 3}, {"format": "other", "version": 3}],
    ids=["list", "no-format", "other-format"],
)
def test_other_json_is_not_a_checkpoint(tmp_path, data):
    path = tmp_path / "checkpoint.json"
    path.write_text(json.dumps(data))
    _refused(path, "is not a billiard checkpoint")


@pytest.mark.parametrize("version", [1, 4, True, "3"])
def test_an_unknown_version_is_refused(tmp_path, monkeypatch, version):
    # a checkpoint written by another release (a valid file of its own version)
    monkeypatch.setattr(checkpoint, "CHECKPOINT_VERSION", version)
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"rows": 3})
    _refused(
        path,
        re.escape(
            f"has checkpoint version {version!r}; this version of billiard reads versions 2 and 3"
        ),
    )


def test_a_version_2_checkpoint_is_still_read(tmp_path, monkeypatch):
    monkeypatch.setattr(checkpoint, "CHECKPOINT_VERSION", 2)
    path = tmp_path / "checkpoint.json"
    write_checkpoint(path, {"rows": 3})
    assert read_checkpoint(path) == {"format": CHECKPOINT_FORMAT, "version": 2, "rows": 3}
