"""Python started in a source checkout imports the checkout's ``billiard/`` folder (the
current directory comes first on ``sys.path``), also where the package is installed
with ``pip install .``; the subpackages that pyproject.toml maps from folders beside it
(``billiard.derivation`` from ``derivation/``, ``billiard.generated`` from
``generated/``) are found there (``billiard._CheckoutFinder``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import billiard

ROOT = Path(__file__).resolve().parents[2]

# The editable install's finder maps the two subpackages itself: without it, the
# checkout is imported as after a non-editable install (or with none).
WITHOUT_EDITABLE_FINDER = """
import sys
sys.meta_path[:] = [
    f for f in sys.meta_path if not str(getattr(f, "__module__", "")).startswith("__editable__")
]
import billiard, billiard.derivation.build, billiard.generated.curves.wedge
for module in (billiard, billiard.derivation.build, billiard.generated.curves.wedge):
    print(module.__file__)
print(billiard.derivation.build.repo_root())
"""


def test_the_checkout_imports_its_mapped_subpackages_without_an_editable_install():
    done = subprocess.run(
        [sys.executable, "-c", WITHOUT_EDITABLE_FINDER],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        str(ROOT / "billiard" / "__init__.py"),
        str(ROOT / "derivation" / "build.py"),
        str(ROOT / "generated" / "curves" / "wedge.py"),
        str(ROOT),
    ]


def _layout(root: Path, *, pyproject: bool = True, installed: bool = False) -> Path:
    """A checkout's layout (empty modules): billiard/, derivation/, generated/."""
    for folder in ("billiard", "derivation", "generated"):
        (root / folder).mkdir(parents=True)
        (root / folder / "__init__.py").write_text("")
    if installed:  # an installed copy: the subpackages inside billiard/
        for folder in ("derivation", "generated"):
            (root / "billiard" / folder).mkdir()
            (root / "billiard" / folder / "__init__.py").write_text("")
    if pyproject:
        (root / "pyproject.toml").write_text('[project]\nname = "realworld-billiard"\n')
    return root / "billiard"


def test_the_folders_beside_a_checkouts_package_are_mapped(tmp_path):
    package = _layout(tmp_path)
    assert billiard._checkout_folders(str(package)) == {
        "billiard.derivation": str(tmp_path / "derivation"),
        "billiard.generated": str(tmp_path / "generated"),
    }


def test_an_installed_copy_or_a_folder_that_is_no_checkout_is_left_alone(tmp_path):
    assert billiard._checkout_folders(str(_layout(tmp_path / "a", installed=True))) == {}
    assert billiard._checkout_folders(str(_layout(tmp_path / "b", pyproject=False))) == {}
    package = _layout(tmp_path / "c")
    (tmp_path / "c" / "generated" / "__init__.py").unlink()
    assert billiard._checkout_folders(str(package)) == {}


def test_the_finder_answers_for_the_two_subpackages_only_and_is_added_once():
    billiard._find_checkout_subpackages()
    billiard._find_checkout_subpackages()
    finders = [f for f in sys.meta_path if f is billiard._CheckoutFinder]
    assert len(finders) == 1 and sys.meta_path[0] is billiard._CheckoutFinder
    spec = billiard._CheckoutFinder.find_spec("billiard.generated")
    assert spec is not None and spec.origin == str(ROOT / "generated" / "__init__.py")
    assert list(spec.submodule_search_locations) == [str(ROOT / "generated")]
    for name in ("billiard.tests", "billiard.cli.bench", "billiard.docs", "derivation"):
        assert billiard._CheckoutFinder.find_spec(name) is None
