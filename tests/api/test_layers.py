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


# --- the state vector by name ---------------------------------------------------------
# Outside the kernels and the engine, a wing reads and writes the state vector ``ctx``
# through billiard.kernels.names, never by subscripting it with layout.py's slots.
#: the wings that may subscript it: the kernels and the engine, whose code it is
SUBSCRIPTING = ("kernels", "engine")


def _slot_names() -> frozenset[str]:
    """The constants of layout.py that are slots: each quantity's, the blocks' bounds and
    a surface block's stride."""
    from billiard.kernels import layout as L

    blocks = ("DR", "FL", "IM", "PH", "VX", "RK")
    bounds = (*blocks, *(f"{b}_END" for b in blocks), "SURF_STRIDE", "SIZE")
    return frozenset(s.constant for s in (*L.CTX.slots, *L.SURFACE.slots)) | set(bounds)


def _is_layout(module: str) -> bool:
    return module.startswith("billiard.kernels") and module.rsplit(".", 1)[-1] == "layout"


def slot_subscripts(source: str, filename: str = "<source>") -> list[int]:
    """The lines of ``source`` that subscript something with a slot of layout.py: an
    index that mentions one (``ctx[L.EN_T]``, ``ctx[base + _L.S_WS]``, a slot imported by
    name) or a name assigned or looped over from one (``_WS = _L.SURF + _L.S_WS``, then
    ``ctx[_WS]``). A name counts wherever it is bound in the file."""
    tree = ast.parse(source, filename)
    slots = _slot_names()
    aliases, tainted = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            aliases |= {a.asname or a.name for a in node.names if _is_layout(a.name)}
        elif isinstance(node, ast.ImportFrom) and node.module:
            for a in node.names:
                if _is_layout(f"{node.module}.{a.name}"):
                    aliases.add(a.asname or a.name)
                elif _is_layout(node.module) and a.name in slots:
                    tainted.add(a.asname or a.name)

    def mentions(node: ast.AST | None, values: bool = True) -> bool:
        """Whether ``node`` mentions a slot (not counting ``ctx[slot]``, a value read
        with one, unless ``values``)."""
        stack = [] if node is None else [node]
        while stack:
            sub = stack.pop()
            if isinstance(sub, ast.Name) and sub.id in tainted:
                return True
            if isinstance(sub, ast.Attribute) and sub.attr in slots:
                owner = ast.unparse(sub.value)
                if owner in aliases or owner.rsplit(".", 1)[-1] == "layout":
                    return True
            if isinstance(sub, ast.Subscript) and not values:
                stack.append(sub.value)
            else:
                stack.extend(ast.iter_child_nodes(sub))
        return False

    def bound(target: ast.AST) -> set[str]:
        """The names ``target`` binds (``ctx[i] = ...`` binds none)."""
        if isinstance(target, ast.Name):
            return {target.id}
        if isinstance(target, (ast.Tuple, ast.List)):
            return set().union(*(bound(e) for e in target.elts))
        return bound(target.value) if isinstance(target, ast.Starred) else set()

    bindings = []  # (names bound, the value they are bound from)
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            bindings += [(bound(t), node.value) for t in node.targets]
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign, ast.NamedExpr)):
            bindings.append((bound(node.target), node.value))
        elif isinstance(node, (ast.For, ast.comprehension)):
            bindings.append((bound(node.target), node.iter))
    grown = True
    while grown:  # until no binding taints another name
        grown = False
        for names, value in bindings:
            if not names <= tainted and mentions(value, values=False):
                tainted |= names
                grown = True
    return sorted(
        {node.lineno for node in ast.walk(tree) if isinstance(node, ast.Subscript)
         and mentions(node.slice)}
    )  # fmt: skip


def test_the_slot_scan_finds_each_way_of_subscripting():
    """The scan sees a slot however it reaches the index; a slot used otherwise, a code
    of layout.py, and a name that only shares a slot's name are no subscripts of ctx."""
    planted = """
from billiard.kernels import layout as L
from billiard.kernels.interpreted import layout as _L
from billiard.kernels.layout import EN_Q1, LID_LABEL
import billiard.kernels.layout

ctx[L.EN_T] = 0.0                                   # 7: a slot
x = ctx[_L.SURF + 2 * _L.SURF_STRIDE + _L.S_WS]     # 8: a surface's slot
_WS = _L.SURF + _L.S_WS
warm = ctx[_WS]                                     # 10: through a name
ctxs[:, EN_Q1]                                      # 11: a slot imported by name
{n: ctxs[:, s] for n, s in (("t", L.EN_T),)}        # 12: looped over
ctx[billiard.kernels.layout.EN_U1]                  # 13: the module's full name
q1 = ctx[L.EN_Q1]                                   # 14
xs[q1 > 0.0], ys[int(q1)]                           # a value read with a slot
foot(ctx, _L.SURF)                                  # a slot, not as an index
codes[LID_LABEL], rows[L.NCOL], other.G[0], ctx[self.EN_T]
"""
    assert slot_subscripts(planted) == [7, 8, 10, 11, 12, 13, 14]


def test_no_wing_outside_the_kernels_and_engine_subscripts_the_state_vector():
    """The wings read and write ``ctx`` by name (billiard.kernels.names); the allowed
    wings are the kernels and the engine."""
    found: dict[str, list[str]] = {}
    for path in sorted((ROOT / "billiard").rglob("*.py")):
        wing = path.relative_to(ROOT / "billiard").parts[0]
        lines = slot_subscripts(path.read_text(), str(path))
        if lines:
            found.setdefault(wing, []).append(f"{path.relative_to(ROOT)}: lines {lines}")
    outside = [hit for wing, hits in found.items() if wing not in SUBSCRIPTING for hit in hits]
    assert outside == [], "subscripts ctx with slots; use billiard.kernels.names"
