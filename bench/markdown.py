"""Markdown pieces shared by the bench's pages and sections (no import of any section,
so that every section can use them)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table of ``rows`` under ``header``; cells formatted with ``str``."""
    lines = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def write_section(doc: Path, section: str, begin: str, end: str) -> None:
    """Put ``section`` (which starts with the marker ``begin`` and ends with ``end``) in
    place of the text between those markers in ``doc``, or append it."""
    text = doc.read_text() if doc.exists() else ""
    if begin in text and end in text:
        head, rest = text.split(begin, 1)
        tail = rest.split(end, 1)[1].lstrip("\n")
        text = head + section + ("\n" + tail if tail else "")
    else:
        text = text.rstrip("\n") + "\n\n" + section
    doc.write_text(text)


def publish_section(
    saved: Path,
    doc: Path,
    render: Callable[[dict], str],
    begin: str,
    end: str,
    results: dict | None = None,
) -> bool:
    """Save ``results`` (when given) as JSON to ``saved`` and write the section between
    ``begin`` and ``end`` of ``doc``, rendered from the saved results; False when there
    are none."""
    if results is not None:
        saved.parent.mkdir(parents=True, exist_ok=True)
        saved.write_text(json.dumps(results, indent=1))
    elif not saved.exists():
        return False
    write_section(doc, render(json.loads(saved.read_text())), begin, end)
    return True
