"""The package's papers: licence, citation, changelog and the documentation index agree
with the project's metadata and with the documents that exist."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _metadata() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def test_license_file_is_the_license_the_metadata_names() -> None:
    licence = _metadata()["license"]["text"]
    text = (ROOT / "LICENSE").read_text()
    assert text.splitlines()[0] == f"{licence} License"


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
