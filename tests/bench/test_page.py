"""docs/performance.md and its appendix of full tables are what ``billiard bench
--render`` writes from the saved results (bench/page.py, bench/report.py), and every
link from the page into the appendix lands on one of its headings."""

from __future__ import annotations

import json
import re
from pathlib import Path

from bench import ensemble as ensemble_bench
from bench import page, report
from bench import sweep as sweep_bench
from bench.markdown import write_section

DOCS = Path(__file__).resolve().parents[2] / "docs"
COMMAND = "billiard bench"


def _results() -> dict:
    return json.loads((DOCS / "figures" / "performance" / "results.json").read_text())


def test_the_committed_pages_are_the_generator_s(tmp_path):
    results = _results()
    doc = tmp_path / "performance.md"
    doc.write_text(page.render(results, COMMAND))
    saved = json.loads(sweep_bench.saved_results(DOCS).read_text())
    write_section(doc, sweep_bench.render(saved), sweep_bench.BEGIN, sweep_bench.END)
    # the ensemble bench's part of the page: a sweep point under contact phases
    saved = json.loads(ensemble_bench.saved_results(DOCS).read_text())
    begin, end = ensemble_bench.PHASES_BEGIN, ensemble_bench.PHASES_END
    write_section(doc, ensemble_bench.render_phases(saved), begin, end)
    assert doc.read_text() == (DOCS / "performance.md").read_text()
    # the ensemble section of sweeps.md is the generator's too
    assert ensemble_bench.render(saved) in (DOCS / "sweeps.md").read_text()
    tables = report.render_tables(results, COMMAND)
    assert tables == (DOCS / page.TABLES).read_text()


def _anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to -."""
    return "#" + re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_every_link_into_the_tables_lands_on_a_heading():
    results = _results()
    text = page.render(results, COMMAND)
    tables = report.render_tables(results, COMMAND)
    headings = {_anchor(h) for h in re.findall(r"^#+ (.+)$", tables, flags=re.M)}
    links = set(re.findall(re.escape(page.TABLES) + r"(#[\w-]+)", text))
    assert links and links <= headings, links - headings
    # the saved results hold every section: each has its link
    assert {page.ANCHORS[s] for s in results["sections"]} <= links


def test_the_page_keeps_the_figures_and_leaves_the_tables_to_the_appendix():
    results = _results()
    text = page.render(results, COMMAND)
    tables = report.render_tables(results, COMMAND)
    figures = set(re.findall(r"\]\((figures/performance/[\w.-]+\.png)\)", text))
    assert figures == {
        f"figures/performance/{p.name}" for p in (DOCS / "figures" / "performance").glob("*.png")
    }
    # one row per run of the full tables, one row per question or case on the page
    assert _rows(text) < _rows(tables) / 3


def _rows(doc: str) -> int:
    return sum(line.startswith("| ") for line in doc.splitlines())
