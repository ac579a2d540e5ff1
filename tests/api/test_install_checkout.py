"""A real non-editable install (``pip install .``, the README's first line) next to its
source checkout: Python started in the checkout imports the checkout (its mapped
subpackages included), elsewhere the installed copy; ``billiard run`` gives the same
rows from both; ``billiard bench`` measures the checkout's code. Slow (an install, and
the kernels compiled into the new installation's cache, a minute or two); skipped where
pip cannot build the package (no build backend reachable)."""

from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="the venv layout of POSIX (bin/)"),
]

_NOT_COPIED = shutil.ignore_patterns(
    ".git", ".venv", "runs", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", "out"
)


def _install(checkout: Path, venv: Path) -> None:
    """``pip install .`` of ``checkout`` into ``venv`` (its dependencies: this
    environment's, seen through a .pth file)."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    purelib = subprocess.run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    # only the paths: the .pth files there (an editable install's finder) are not read
    Path(purelib, "_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    pip = [sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps"]
    tried = []
    for extra in (["--no-build-isolation", "--no-index"], []):  # offline first
        done = subprocess.run([*pip, *extra, str(checkout)], capture_output=True, text=True)
        if done.returncode == 0:
            return
        tried.append((done.stderr.strip().splitlines() or ["?"])[-1])
    pytest.skip(f"pip cannot install the checkout here: {'; '.join(tried)}")


def test_a_non_editable_install_beside_its_checkout(tmp_path):
    checkout = tmp_path / "checkout"
    shutil.copytree(ROOT, checkout, ignore=_NOT_COPIED)
    venv = tmp_path / "venv"
    _install(checkout, venv)
    python, billiard = venv / "bin" / "python", venv / "bin" / "billiard"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_DISABLE_JIT")}
    env["BILLIARD_HOME"] = str(tmp_path / "home")

    def run(command: list, cwd: Path) -> subprocess.CompletedProcess:
        return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)

    where = (
        "import billiard, billiard.derivation, billiard.generated.curves.wedge as w; "
        "print(billiard.__file__, billiard.derivation.__file__, w.__file__)"
    )
    done = run([python, "-c", where], checkout)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == [
        str(checkout / "billiard" / "__init__.py"),
        str(checkout / "derivation" / "__init__.py"),
        str(checkout / "generated" / "curves" / "wedge.py"),
    ]
    done = run([python, "-c", where], elsewhere)
    assert done.returncode == 0, done.stderr
    installed = Path(done.stdout.split()[0]).parent
    assert installed != checkout / "billiard" and installed.parent.name == "site-packages"

    rows = []
    for cwd in (checkout, elsewhere):
        out = tmp_path / f"run-from-{cwd.name}"
        done = run(
            [billiard, "run", "wedge-6.6hz", "--collisions", "100", "--no-plot", "--out", out],
            cwd,
        )
        assert done.returncode == 0, done.stderr
        rows.append((out / "collisions.csv").read_bytes())
    assert rows[0] == rows[1] and rows[0].count(b"\n") == 101

    done = run([billiard, "--version"], elsewhere)
    assert done.stdout == f"realworld-billiard 0.1.0 (package at {installed})\n", done.stderr

    # bench: started again on the checkout's code, which renders saved results
    saved = tmp_path / "bench" / "figures" / "performance"
    saved.mkdir(parents=True)
    shutil.copy(ROOT / "docs" / "figures" / "performance" / "results.json", saved)
    done = run([billiard, "bench", "--render", "--out", tmp_path / "bench"], checkout)
    assert done.returncode == 0, done.stderr
    assert f"bench measures the source checkout {checkout}" in done.stderr
    assert (tmp_path / "bench" / "performance.md").is_file()
    done = run([billiard, "bench", "--quick"], elsewhere)  # no checkout: one line
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "bench needs a source checkout" in done.stderr
