"""The package's papers: licence, citation, changelog and the documentation index agree
with the project's metadata and with the documents that exist."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _metadata() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_license_file_is_the_license_the_metadata_names() -> None:
    """An SPDX expression and the licence file (PEP 639): the table form
    ``license = {text = ...}`` is refused by setuptools from 2027."""
    licence = _metadata()["license"]
    assert isinstance(licence, str) and re.fullmatch(r"[A-Za-z0-9.\-]+", licence), licence
    assert _metadata()["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.splitlines()[0] == f"{licence} License"
    # setuptools reads both fields from release 77 on
    [backend] = [r for r in _pyproject()["build-system"]["requires"] if r.startswith("setuptools")]
    minimum = re.fullmatch(r"setuptools>=(\d+)(?:\.\d+)*", backend)
    assert minimum is not None and int(minimum.group(1)) >= 77, backend
    # a licence classifier beside an SPDX expression is an error for setuptools
    assert not [c for c in _metadata()["classifiers"] if c.startswith("License ::")]


def test_the_package_says_what_it_is_and_that_it_is_typed() -> None:
    classifiers = _metadata()["classifiers"]
    assert "Typing :: Typed" in classifiers
    assert "Topic :: Scientific/Engineering :: Physics" in classifiers
    minimum = re.fullmatch(r">=3\.(\d+)", _metadata()["requires-python"])
    assert minimum is not None
    # the versions named are those the package allows
    named = re.findall(
        r"^Programming Language :: Python :: 3\.(\d+)$", "\n".join(classifiers), re.M
    )
    assert named and all(int(v) >= int(minimum.group(1)) for v in named)
    # PEP 561: the marker is in the package and shipped with it
    assert (ROOT / "billiard" / "py.typed").is_file()
    assert "py.typed" in _pyproject()["tool"]["setuptools"]["package-data"]["billiard"]
    # no project URL: the project names no homepage or repository anywhere (CITATION.cff
    # has no repository-code), and a URL that points nowhere is worse than none
    assert "repository-code" not in (ROOT / "CITATION.cff").read_text()


def _requirement(requirements: list[str], name: str) -> str:
    [found] = [r for r in requirements if re.match(rf"{name}\b", r)]
    return found


def test_sympy_is_pinned_for_the_tests_only() -> None:
    """At run time any recent sympy derives a user's curve; the byte-for-byte check of
    generated/ needs the release that wrote it, which the test extra pins."""
    from billiard.derivation.build import generating_sympy

    runtime = _requirement(_metadata()["dependencies"], "sympy")
    assert "==" not in runtime and re.fullmatch(r"sympy>=1\.\d+", runtime), runtime
    for extra in ("test", "dev"):
        pinned = _requirement(_metadata()["optional-dependencies"][extra], "sympy")
        assert pinned == f"sympy=={generating_sympy()}", extra


def test_the_dask_extra_serves_the_dashboard_it_links() -> None:
    """The sweep prints the scheduler's dashboard link; bokeh draws that page, at a
    release the installed distributed accepts."""
    extra = _metadata()["optional-dependencies"]["dask"]
    bokeh = _requirement(extra, "bokeh")
    minimum = re.fullmatch(r"bokeh>=([\d.]+)", bokeh)
    assert minimum is not None, bokeh
    versions = pytest.importorskip("distributed.versions")
    accepted = versions.BOKEH_REQUIREMENT.specifier
    assert accepted.contains(minimum.group(1)), (bokeh, str(accepted))


def test_derive_check_under_another_sympy_names_the_release_it_needs(monkeypatch, capsys) -> None:
    import sympy
    from billiard.derivation import build

    from billiard.cli import main

    needed = build.generating_sympy()
    assert needed is not None and re.fullmatch(r"\d+\.\d+(\.\d+)?", needed)
    monkeypatch.setattr(sympy, "__version__", "1.12")
    monkeypatch.setattr(build, "_expected_texts", lambda: pytest.fail("derived anyway"))
    assert main(["derive", "--check"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("billiard: error: derive --check: "), err
    assert f"written by sympy {needed}" in err[0] and "sympy 1.12 is installed" in err[0]
    assert f'pip install "sympy=={needed}"' in err[0]


def test_citation_names_this_version_and_the_paper() -> None:
    text = (ROOT / "CITATION.cff").read_text()
    version = re.search(r'^version:\s*"?([^"\s]+)"?\s*$', text, re.M)
    assert version is not None and version.group(1) == _metadata()["version"]
    assert re.search(r"^cff-version: 1\.2\.0$", text, re.M)
    assert "Dynamic Modeling and Simulation of a Real World Billiard" in text


def test_changelog_has_a_section_for_this_version() -> None:
    headings = re.findall(r"^## \[([^\]]+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert _metadata()["version"] in headings


def test_docs_index_links_every_document_and_only_existing_ones() -> None:
    index = (ROOT / "docs" / "index.md").read_text()
    links = set(re.findall(r"\]\(([^)#]+\.(?:md|cff))\)", index)) | set(
        re.findall(r"\]\((\.\./LICENSE)\)", index)
    )
    for link in links:
        assert (ROOT / "docs" / link).resolve().is_file(), link
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} - {"index.md"}
    assert pages <= links, f"not in docs/index.md: {sorted(pages - links)}"
