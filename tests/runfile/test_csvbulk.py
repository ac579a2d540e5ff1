"""collisions.csv parsed in bulk (billiard/runfile/csvbulk.py): on the files billiard
writes it gives the careful line-by-line reader's values bit for bit, with the same
dtypes; anything else it leaves to the careful reader (same values, same messages);
files written before ``wall`` was an integer (the lid as ``lid``) still read."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

from billiard import jit
from billiard.run.simulate import simulate
from billiard.runfile import csvbulk
from billiard.runfile.record import (
    COLUMNS,
    LID_WALL,
    REQUIRED_COLUMNS,
    RunDataError,
    read_collisions_csv,
    write_collisions,
)
from billiard.scene.scene import load_scene

record = importlib.import_module("billiard.runfile.record")


def careful(path: Path) -> dict[str, np.ndarray]:
    """The line-by-line reader alone."""
    with open(path, newline="", encoding="utf-8") as handle:
        return record._read_blocks(path, handle)


def bulk(path: Path) -> dict[str, np.ndarray] | None:
    return csvbulk.read_bulk(path, COLUMNS, REQUIRED_COLUMNS)


def assert_same(a: dict, b: dict) -> None:
    assert list(a) == list(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, (name, a[name].dtype, b[name].dtype)
        if a[name].dtype.kind == "f":
            assert np.array_equal(a[name].view(np.uint64), b[name].view(np.uint64)), name
        else:
            assert np.array_equal(a[name], b[name]), name


@pytest.fixture(autouse=True, params=["compiled", "fromstring"])
def parser(request, monkeypatch) -> str:
    """Each test with both bulk parsers: the compiled one (where the kernels are
    compiled) and numpy's ``fromstring`` (interpreted runs)."""
    if request.param == "fromstring":
        monkeypatch.setattr(csvbulk, "_parse_compiled", lambda *args: None)
    elif not jit.ENABLED:
        pytest.skip(f"the kernels are not compiled: {jit.numba_problem()}")
    return request.param


@pytest.fixture(scope="module")
def wedge_csv(tmp_path_factory) -> Path:
    """A run with impacts on both walls and on the lid (from impact 113)."""
    out = tmp_path_factory.mktemp("wedge")
    simulate(load_scene("wedge-6.6hz"), collisions=500, out_dir=out)
    return out / "collisions.csv"


def test_a_run_s_file_reads_in_bulk_as_line_by_line(wedge_csv, monkeypatch):
    monkeypatch.setattr(csvbulk, "CHUNK_BYTES", 4096)  # many chunks, rows split between
    fast = bulk(wedge_csv)
    assert fast is not None
    assert_same(fast, careful(wedge_csv))
    assert_same(read_collisions_csv(wedge_csv), fast)
    assert fast["wall"].dtype == np.int64 and LID_WALL in fast["wall"]
    assert b",-1," in wedge_csv.read_bytes() and b"lid" not in wedge_csv.read_bytes()


def test_random_doubles_read_back_bit_for_bit(tmp_path):
    """Every bit pattern of a finite double (subnormals, huge, tiny, -0.0) survives the
    file in both readers."""
    rng = np.random.default_rng(26)
    rows = 3000
    bits = rng.integers(0, 2**64, size=(rows, len(COLUMNS)), dtype=np.uint64)
    values = bits.view(np.float64)
    values[~np.isfinite(values)] = -0.0
    values[:50] = rng.random((50, len(COLUMNS))) * 1e-310  # subnormals
    columns: dict[str, object] = {name: values[:, i] for i, name in enumerate(COLUMNS)}
    columns["n"] = np.arange(1, rows + 1)
    columns["t"] = np.sort(np.abs(values[:, 1]))
    columns["regime"] = rng.choice(["stick", "slip", "elastic"], size=rows)
    columns["wall"] = rng.choice([0, 1, 2, 11, LID_WALL], size=rows)
    path = write_collisions(tmp_path / "collisions.csv", columns)
    fast = bulk(path)
    assert fast is not None
    assert_same(fast, careful(path))
    for name in COLUMNS:
        expected = np.asarray(columns[name])
        if expected.dtype.kind == "f":
            assert np.array_equal(fast[name].view(np.uint64), expected.view(np.uint64)), name
        else:
            assert fast[name].tolist() == expected.tolist(), name


def old_file(wedge_csv: Path, tmp_path: Path, line_end: bytes = b"\n") -> Path:
    """The wedge's file as billiard wrote it before ``wall`` was an integer."""
    data = wedge_csv.read_bytes().replace(b",-1,", b",lid,").replace(b"\n", line_end)
    path = tmp_path / "old.csv"
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("line_end", [b"\n", b"\r\n"])
def test_old_files_with_the_word_lid_still_read(wedge_csv, tmp_path, line_end):
    path = old_file(wedge_csv, tmp_path, line_end)
    assert b",lid," in path.read_bytes()
    fast = bulk(path)
    assert fast is not None
    assert_same(fast, careful(path))
    assert_same(read_collisions_csv(path), read_collisions_csv(wedge_csv))


# edits that take a file off the bulk path: each must still read as the careful
# reader reads it (the same values), or fail with its message
EDITS = {
    "comment line": lambda t: t.replace("\n", "\n# a note\n", 1),
    "blank line": lambda t: t.replace("\n", "\n\n", 2),
    "spaces in a cell": lambda t: t.replace(",stick,", ", stick ,", 1),
    "n written 0012": lambda t: t.replace("\n12,", "\n0012,", 1),
    "n written 12.0": lambda t: t.replace("\n12,", "\n12.0,", 1),
    "wall written 1.0": lambda t: t.replace(",1,", ",1.0,", 1),
    "a regime not known": lambda t: t.replace(",slip,", ",sliding,", 1),
    "an extra column": lambda t: "\n".join(line + ",x" for line in t.split("\n")[:-1]) + "\n",
    "quoted field": lambda t: t.replace(",stick,", ',"stick",', 1),
    "a row short of a field": lambda t: t.replace(",stick,", ",", 1),
    "a word for a number": lambda t: t.replace(",0.", ",zero", 1),
    "an empty cell": lambda t: t.replace(",stick,", ",,", 1),
    "unterminated last row": lambda t: t + "501,0.5",
    "a wall that is a word": lambda t: t.replace(",1,", ",left,", 1),
}


@pytest.mark.parametrize("edit", list(EDITS))
def test_other_files_are_left_to_the_careful_reader(wedge_csv, tmp_path, edit):
    path = tmp_path / "collisions.csv"
    path.write_text(EDITS[edit](wedge_csv.read_text()))
    if edit == "unterminated last row":
        assert bulk(path) is not None  # the part row is dropped, as by the careful reader
    else:
        assert bulk(path) is None
    try:
        expected = careful(path)
    except RunDataError as exc:
        with pytest.raises(RunDataError) as caught:
            read_collisions_csv(path)
        assert str(caught.value) == str(exc)
        return
    assert_same(read_collisions_csv(path), expected)


def test_decreasing_times_are_refused_with_the_line(wedge_csv, tmp_path):
    lines = wedge_csv.read_text().split("\n")
    lines[40], lines[41] = lines[41], lines[40]
    path = tmp_path / "collisions.csv"
    path.write_text("\n".join(lines))
    assert bulk(path) is not None
    with pytest.raises(RunDataError) as fast:
        read_collisions_csv(path)
    with pytest.raises(RunDataError) as slow:
        careful(path)
    assert str(fast.value) == str(slow.value)
    assert str(fast.value).endswith(
        "line 42: impact times decrease (column t must be non-decreasing)"
    )


def test_the_compiled_parser_needs_no_fromstring(wedge_csv, tmp_path, monkeypatch, parser):
    """Compiled, a run's file is parsed in one pass, not by numpy's ``fromstring`` (4.1 s
    of CPU for 10^6 rows against 1.3 s); a chunk with more fields
    for :func:`float` than the kernel lists is parsed by ``fromstring``, to the same
    values."""
    if parser != "compiled":
        pytest.skip("the compiled parser's own test")

    def refuse(*args, **kwargs):
        raise AssertionError("fromstring called")

    monkeypatch.setattr(csvbulk.np, "fromstring", refuse)
    fast = bulk(wedge_csv)
    assert fast is not None
    assert_same(fast, careful(wedge_csv))
    monkeypatch.undo()
    # every float written as float() reads it but the kernel does not: "+0.5"
    text = wedge_csv.read_text()
    edited = tmp_path / "collisions.csv"
    edited.write_text(text.replace(",0.", ",+0."))
    monkeypatch.setattr(csvbulk, "FALLBACK_FIELDS", 8)
    assert_same(bulk(edited), careful(edited))
