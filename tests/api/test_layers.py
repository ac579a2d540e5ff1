"""The layering rule (docs/design.md, "Layout"): imports flow one way.

`lint-imports` (import-linter, configured in .importlinter) checks the wings of
billiard/ in CI; these tests check what it cannot see (derivation/ and generated/ live
beside billiard/, and the public API module), and that the contract does fail on an
upward import.
"""

from __future__ import annotations

import ast
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WINGS = (
    "analysis", "cli", "engine", "geometry", "kernels", "models", "plot", "reproduce",
    "run", "runfile", "scene", "sweep",
)  # fmt: skip


def _imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, module, names) of every import in ``path``, nested ones included."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name, []) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module, [a.name for a in node.names]))
    return found


@pytest.mark.parametrize("folder", ["derivation", "generated"])
def test_the_derivation_and_generated_code_import_no_wing(folder):
    """The lowest layers: the derivation and the code it generates import nothing of
    the runtime (only each other, sympy, numpy and the standard library)."""
    upward = [
        f"{path.relative_to(ROOT)}:{line}: {module}"
        for path in sorted((ROOT / folder).rglob("*.py"))
        for line, module, _ in _imports(path)
        if module.startswith("billiard")
        and not module.startswith(("billiard.derivation", "billiard.generated"))
    ]
    assert upward == []


def test_no_wing_imports_the_public_api_module():
    """billiard/__init__.py is the public API, built from the wings: a wing below the
    command line that imported it would import every wing (the base module ``jit`` is
    imported by name)."""
    offending = []
    for wing in set(WINGS) - {"cli"}:
        for path in sorted((ROOT / "billiard" / wing).rglob("*.py")):
            for line, module, names in _imports(path):
                if module == "billiard" and names != ["jit"]:
                    offending.append(f"{path.relative_to(ROOT)}:{line}: {names}")
    assert offending == []


@pytest.mark.skipif(
    importlib.util.find_spec("importlinter") is None, reason="import-linter not installed"
)
def test_the_import_contract_fails_on_an_upward_import(tmp_path):
    """A copy of the package with one planted upward import (a kernel importing the
    command line) breaks the layers contract; the copy as it is keeps it."""
    copy = tmp_path / "tree"
    shutil.copytree(ROOT / "billiard", copy / "billiard", ignore=shutil.ignore_patterns("*.nb*"))
    shutil.copy(ROOT / ".importlinter", copy / ".importlinter")

    def lint() -> subprocess.CompletedProcess:
        env = {"PYTHONPATH": str(copy), "PATH": "/usr/bin:/bin"}
        command = [sys.executable, "-c", "from importlinter.cli import lint_imports_command;"
                   " lint_imports_command()"]  # fmt: skip
        return subprocess.run(command, cwd=copy, env=env, capture_output=True, text=True)

    kept = lint()
    assert kept.returncode == 0, kept.stdout + kept.stderr
    layout = copy / "billiard" / "kernels" / "layout.py"
    layout.write_text(layout.read_text() + "\nimport billiard.cli.run  # planted\n")
    broken = lint()
    assert broken.returncode != 0
    assert "billiard.kernels is not allowed to import billiard.cli" in broken.stdout
