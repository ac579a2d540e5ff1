"""Markdown pieces shared by the bench's pages and sections (no import of any section,
so that every section can use them)."""

from __future__ import annotations


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table of ``rows`` under ``header``; cells formatted with ``str``."""
    lines = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
