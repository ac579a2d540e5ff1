"""The state vector's table of docs/compiled-engine.md is generated from the layout
(``billiard.kernels.layout.markdown()``): the page holds it as the layout declares it.

``python -m tests.docs.test_layout_table`` (in the checkout's root) writes it again.
"""

from __future__ import annotations

from pathlib import Path

from billiard.kernels import layout as L

DOC = Path(__file__).resolve().parents[2] / "docs" / "compiled-engine.md"
BEGIN, END = "<!-- layout -->", "<!-- /layout -->"


def section() -> str:
    """The page's section between the markers, the markers included."""
    return f"{BEGIN}\n{L.markdown()}\n{END}"


def test_the_page_holds_the_layout_table():
    text = DOC.read_text()
    assert text.count(BEGIN) == text.count(END) == 1
    shown = text[text.index(BEGIN) : text.index(END) + len(END)]
    assert shown == section(), "run `python -m tests.docs.test_layout_table`"


def test_the_table_lists_every_quantity_at_its_slots():
    """What the table is made from: every quantity of describe(), at its slots."""
    cells = [line.split(" | ") for line in L.markdown().splitlines() if line.startswith("| ")]
    rows = {c[1].strip("`"): " | ".join(c) for c in cells if len(c) == 5 and c[1][0] == "`"}
    described = [line.split() for line in L.describe().splitlines() if line.strip()]
    slots = [row for row in described if row[0].isdigit()]
    assert len(slots) == len(L.CTX.slots) + len(L.SURFACE.slots) == len(rows)
    for index, size, constant, *_ in slots:
        first, last = int(index), int(index) + int(size) - 1
        span = str(first) if first == last else f"{first}-{last}"
        assert rows[constant].startswith(f"| {span} | `{constant}` |"), constant
    assert f"`ctx` holds {L.SIZE:,} slots" in L.markdown()


if __name__ == "__main__":
    from bench.markdown import write_section

    write_section(DOC, section(), BEGIN, END)
    print(f"{DOC}: the state vector's table written ({L.SIZE:,} slots)")
