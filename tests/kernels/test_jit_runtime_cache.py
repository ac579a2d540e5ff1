"""numba's runtime (NRT) read from the kernels' cache instead of compiled in every
process (billiard.jit._runtime_library): written once, read back, compiled anew when
the file is damaged, and compiled without a file in a read-only folder."""

from __future__ import annotations

import os

import pytest

from billiard import jit

pytestmark = pytest.mark.skipif(not jit.ENABLED, reason=f"numba unavailable: {jit.numba_problem()}")


@pytest.fixture
def runtime_library():
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.registry import cpu_target
    from numba.core.runtime import rtsys

    # the C helpers the runtime's functions call are registered with LLVM here
    rtsys.initialize(cpu_target.target_context)

    def build(folder):
        with global_compiler_lock:
            return jit._runtime_library(cpu_target.target_context, str(folder))

    return build


def _functions(library) -> list[int]:
    names = ("NRT_MemInfo_data_fast", "NRT_incref", "NRT_decref")
    return [library.get_pointer_to_function(name) for name in names]


def _no_compiling(monkeypatch):
    from numba.core.runtime import nrtdynmod

    def fail(ctx):
        raise AssertionError("the runtime was compiled, not read from the cache")

    monkeypatch.setattr(nrtdynmod, "create_nrt_module", fail)


def test_written_once_then_read(tmp_path, runtime_library, monkeypatch):
    compiled = runtime_library(tmp_path)
    (cached,) = tmp_path.glob("nrt-*.nbo")
    assert all(_functions(compiled))
    _no_compiling(monkeypatch)
    loaded = runtime_library(tmp_path)
    assert all(_functions(loaded))
    assert [p.name for p in tmp_path.iterdir()] == [cached.name]  # no stray part file


def test_damaged_file_is_compiled_anew(tmp_path, runtime_library, monkeypatch):
    runtime_library(tmp_path)
    (cached,) = tmp_path.glob("nrt-*.nbo")
    good = cached.read_bytes()
    cached.write_bytes(good[: len(good) // 2])
    assert all(_functions(runtime_library(tmp_path)))
    assert cached.read_bytes() == good  # rewritten whole
    _no_compiling(monkeypatch)
    runtime_library(tmp_path)


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes anywhere")
def test_read_only_folder_compiles_without_a_file(tmp_path, runtime_library):
    tmp_path.chmod(0o555)
    try:
        assert all(_functions(runtime_library(tmp_path)))
        assert list(tmp_path.iterdir()) == []
    finally:
        tmp_path.chmod(0o755)


def test_unwritable_folder_compiles_without_a_file(tmp_path, runtime_library):
    missing = tmp_path / "not-there"  # writing fails as in a read-only folder, even for root
    assert all(_functions(runtime_library(missing)))
    assert not missing.exists()
