"""The sweep folder's points file: chunks appended durably as packed rows, a torn chunk
cut off when the folder is opened again, the size per point, refusals, and the
checksums that find an edited point or reason."""

from __future__ import annotations

import re

import numpy as np
import pytest

from billiard.runfile.npyfile import header_bytes, header_size
from billiard.sweep.columns import STATUSES, ChunkResult, disk_dtype, empty_columns
from billiard.sweep.store import (
    CHECKSUMS_NAME,
    POINTS_NAME,
    REASONS_NAME,
    ChunkStore,
    StoreError,
    stored_points,
)


def _chunk(indices: list[int], keep: int, failed: int | None = None) -> ChunkResult:
    columns = empty_columns(len(indices), keep)
    columns["index"][:] = indices
    columns["impacts"][:] = 7
    columns["height_mean"][:] = np.asarray(indices) * 0.01
    columns["last_height"][:, -2:] = [[0.1, 0.2]]
    reasons = {}
    if failed is not None:
        columns["status"][indices.index(failed)] = STATUSES.index("failed")
        reasons[failed] = "ball escaped"
    return ChunkResult(columns, reasons)


def test_chunks_are_appended_and_read_back(tmp_path):
    with ChunkStore(tmp_path, 10, keep=3) as store:
        store.append(_chunk([4, 5, 6], 3, failed=5))
        store.append(_chunk([0, 1], 3))
        assert store.count == 5 and 5 in store and 2 not in store
        rows = store.stored()
        assert rows["index"].tolist() == [4, 5, 6, 0, 1]
        assert rows["height_mean"].tolist() == [0.04, 0.05, 0.06, 0.0, 0.01]
        assert np.isnan(rows["last_height"][0, 0]) and rows["last_height"][0, 2] == 0.2
        assert list(store.reasons()) == [(5, "ball escaped")]
    # any NumPy reads the file, the rows its header counts
    loaded = np.load(tmp_path / POINTS_NAME)
    assert loaded.dtype == disk_dtype(3) and len(loaded) == 5


def test_points_file_size_per_point_is_within_the_budget(tmp_path):
    keep = 10
    with ChunkStore(tmp_path, 4096, keep=keep) as store:
        store.append(_chunk(list(range(4096)), keep))
    size = (tmp_path / POINTS_NAME).stat().st_size
    per_point = (size - header_size(disk_dtype(keep))) / 4096
    # beyond the kept impacts (2 x K x 8 bytes) at most 100 bytes per point
    assert per_point - 2 * keep * 8 <= 100
    assert per_point == 96 + 16 * keep


def test_a_torn_chunk_is_cut_when_the_folder_is_opened_again(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([0, 1, 2], 2))
    path = tmp_path / POINTS_NAME
    whole = path.stat().st_size
    with open(path, "ab") as f:  # a kill while the next chunk's rows were written
        f.write(_chunk([3, 4], 2).rows(2).tobytes()[:-7])
    with open(tmp_path / REASONS_NAME, "ab") as f:
        f.write(b'{"index": 3, "reason": "ball esc')
    with ChunkStore(tmp_path, 10, keep=2) as store:
        assert store.count == 3 and 3 not in store
        assert path.stat().st_size == whole
        assert (tmp_path / REASONS_NAME).read_bytes() == b""
        store.append(_chunk([3, 4], 2, failed=3))
        assert store.stored()["index"].tolist() == [0, 1, 2, 3, 4]
        assert list(store.reasons()) == [(3, "ball escaped")]


def test_rows_written_but_not_counted_are_not_points(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([0], 2))
    with open(tmp_path / POINTS_NAME, "ab") as f:  # whole rows, the header not yet rewritten
        f.write(_chunk([1, 2], 2).rows(2).tobytes())
    with ChunkStore(tmp_path, 10, keep=2) as store:
        assert store.count == 1 and store.stored()["index"].tolist() == [0]


def test_another_sweeps_points_file_is_refused(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([0, 9], 2))
        with pytest.raises(StoreError, match="another sweep is writing"):
            ChunkStore(tmp_path, 10, keep=2)
    with pytest.raises(StoreError, match="rows of another kind"):
        ChunkStore(tmp_path, 10, keep=3)
    with pytest.raises(StoreError, match="point 9 is not in the sweep"):
        ChunkStore(tmp_path, 5, keep=2)


def _edit(path, offset: int, data: bytes) -> None:
    with open(path, "r+b") as handle:
        handle.seek(offset)
        handle.write(data)


def test_an_edited_value_in_points_npy_is_refused(tmp_path):
    """One float of a stored point changed: the folder is refused in one line naming the
    file, and nothing is changed (the files are read, not cut)."""
    keep = 2
    with ChunkStore(tmp_path, 10, keep=keep) as store:
        store.append(_chunk([4, 5, 6], keep, failed=5))
        store.append(_chunk([0, 1], keep))
    dtype = disk_dtype(keep)
    path = tmp_path / POINTS_NAME
    where = header_size(dtype) + 3 * dtype.itemsize + dtype.fields["height_mean"][1]
    _edit(path, where, np.float64(0.5).tobytes())  # point 0's mean height
    before = path.read_bytes()
    message = f"{path} differs from what {CHECKSUMS_NAME} stores: the CRC-32 of its 5 points"
    with pytest.raises(StoreError, match=re.escape(message)):
        ChunkStore(tmp_path, 10, keep=keep)
    with pytest.raises(StoreError, match=re.escape(message)):
        stored_points(tmp_path, 10, keep)
    assert path.read_bytes() == before


def test_an_edited_reason_is_refused(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([4, 5, 6], 2, failed=5))
    path = tmp_path / REASONS_NAME
    path.write_bytes(path.read_bytes().replace(b"escaped", b"at rest"))
    with pytest.raises(StoreError, match=f"{REASONS_NAME} differs from what {CHECKSUMS_NAME}"):
        ChunkStore(tmp_path, 10, keep=2)


def test_a_points_file_shorter_than_committed_is_refused(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([0, 1, 2], 2))
    path = tmp_path / POINTS_NAME
    path.write_bytes(path.read_bytes()[: -disk_dtype(2).itemsize])
    with pytest.raises(StoreError, match="holds 2 whole rows, fewer than the 3 points"):
        ChunkStore(tmp_path, 10, keep=2)


def test_a_chunk_counted_but_not_committed_is_cut(tmp_path):
    """A kill after a chunk's rows were counted in the header, before its checksums were
    written: the chunk is not stored (it is computed again), the file cut back."""
    keep = 2
    with ChunkStore(tmp_path, 10, keep=keep) as store:
        store.append(_chunk([0], keep))
    path = tmp_path / POINTS_NAME
    committed = path.read_bytes()
    with open(path, "ab") as f:
        f.write(_chunk([1, 2], keep).rows(keep).tobytes())
    _edit(path, 0, header_bytes(disk_dtype(keep), 3))
    with ChunkStore(tmp_path, 10, keep=keep) as store:
        assert store.count == 1 and 1 not in store
        assert path.read_bytes() == committed
        store.append(_chunk([1, 2], keep))
    with ChunkStore(tmp_path, 10, keep=keep) as store:
        assert store.stored()["index"].tolist() == [0, 1, 2]


def test_a_sweep_written_before_the_checksums_is_resumed_with_a_notice(tmp_path):
    with ChunkStore(tmp_path, 10, keep=2) as store:
        store.append(_chunk([0, 1], 2, failed=1))
    (tmp_path / CHECKSUMS_NAME).unlink()
    with ChunkStore(tmp_path, 10, keep=2) as store:
        assert store.unverified == (
            f"{tmp_path} was written before {CHECKSUMS_NAME}: its 2 stored points are not "
            f"verified (they are from now on)"
        )
        assert store.count == 2
    # from then on the folder is verified
    with ChunkStore(tmp_path, 10, keep=2) as store:
        assert store.unverified is None and list(store.reasons()) == [(1, "ball escaped")]
    _edit(tmp_path / POINTS_NAME, header_size(disk_dtype(2)) + 4, b"\x07")
    with pytest.raises(StoreError, match="differs from what"):
        ChunkStore(tmp_path, 10, keep=2)


def test_checksums_need_no_second_read_of_the_files(tmp_path, monkeypatch):
    """Each chunk continues the CRC-32s from their stored values: appending reads
    nothing of points.npy or reasons.jsonl."""
    import billiard.sweep.store as store_module

    with ChunkStore(tmp_path, 100, keep=2) as store:
        reads = []
        monkeypatch.setattr(store_module, "iter_rows", lambda *a, **k: reads.append(a) or iter(()))
        monkeypatch.setattr(store_module, "crc32_range", lambda *a, **k: reads.append(a) or 0)
        for start in range(0, 100, 10):
            store.append(_chunk(list(range(start, start + 10)), 2, failed=start))
        assert reads == []
    monkeypatch.undo()
    with ChunkStore(tmp_path, 100, keep=2) as store:  # and they match the files
        assert store.count == 100
