"""Units of the scene keys a sweep can vary (``billiard/sweep/units.py``): each is the SI
unit the scene documents for it, in the spec's docstrings, in the range checks and in
README.md's scene reference."""

from __future__ import annotations

import dataclasses
import re
import typing
from pathlib import Path

import pytest

from billiard.scene.checks import LIMITS
from billiard.scene.keys import SECTION_KEYS
from billiard.scene.spec import SECTIONS
from billiard.sweep.units import axis_label, key_unit, variable_name

README = Path(__file__).resolve().parents[2] / "README.md"


def _is_number(annotation: str) -> bool:
    return re.fullmatch(r"(float|int)( \| None)?", annotation) is not None


#: the keys a sweep varies with numbers (every key of a section except the curve
#: parameters' table, whose keys are its own)
NUMERIC_KEYS = [
    f"{section}.{f.name}"
    for section, cls in SECTIONS.items()
    for f in dataclasses.fields(cls)
    if _is_number(str(f.type))
]
#: a unit as the docs write it: "m", "Hz", "m/s^2", "N s/m", "N s^2/m^2"
# "m", "N s^2/m^2", or a quotient to a fractional power: "(s/m)^(1/5)"
UNIT = re.compile(r"[A-Za-z]+(\^\d)?([ /][A-Za-z]+(\^\d)?)*|\([A-Za-z /]+\)\^\(\d+/\d+\)")


def _documented_units() -> dict[str, str]:
    """Key -> the unit its section's docstring states: the first parenthesis of the
    attribute's description, up to a ',' or ';' ("(m)", "(rad/s, counter-clockwise
    positive)", "(dimensionless; 0.4 ...)"); "1" where it states none or calls it
    dimensionless."""
    units: dict[str, str] = {}
    for section, cls in SECTIONS.items():
        doc = typing.cast(str, cls.__doc__)
        attributes = doc.split("Attributes:", 1)[1]
        # "    name: text" or "    q1, q2: text", continued on deeper-indented lines
        for match in re.finditer(r"^ {8}([\w, ]+): (.*(?:\n {12}.*)*)", attributes, re.M):
            text = " ".join(match.group(2).split())
            first = re.search(r"\(((?:[^()]|\([^()]*\))*)\)", text)  # one nesting
            unit = re.split(r"[,;]", first.group(1))[0].strip() if first else ""
            if unit == "dimensionless" or not UNIT.fullmatch(unit):
                unit = "1"
            for name in match.group(1).split(","):
                units[f"{section}.{name.strip()}"] = unit
    return units


DOCUMENTED = _documented_units()


def test_every_numeric_key_is_documented():
    assert set(NUMERIC_KEYS) <= set(DOCUMENTED)
    assert "run.collisions" in NUMERIC_KEYS and "drive.direction" not in NUMERIC_KEYS


@pytest.mark.parametrize("key", NUMERIC_KEYS)
def test_the_unit_is_the_one_the_scene_spec_states(key):
    assert key_unit(key) == DOCUMENTED[key]


@pytest.mark.parametrize("key", sorted(LIMITS))
def test_the_unit_is_the_one_the_range_check_names(key):
    # the range checks print the unit with the bounds ("" for a dimensionless key)
    assert key_unit(key) == (LIMITS[key].unit or "1")


def _readme_units() -> dict[str, str]:
    """Key -> unit from the commented example of README.md's "Scene files": the comment
    after ``key = value`` when it starts with a unit ("# m", "# m/s: ...",
    "# N s/m, ..."), plus the "also q1, q2 (m), ..." list of [initial]."""
    text = README.read_text(encoding="utf-8")
    block = text.split("## Scene files", 1)[1].split("```toml", 1)[1].split("```", 1)[0]
    known = sorted({LIMITS[k].unit for k in LIMITS if LIMITS[k].unit}, key=len, reverse=True)
    units: dict[str, str] = {}
    section = ""
    for line in block.splitlines():
        header = re.match(r"\[(\w+)\]", line)
        if header:
            section = header.group(1)
        entry = re.match(r"#? ?(\w+) = \S+\s+# (.*)", line)
        if not entry or not section:
            continue
        key, comment = entry.groups()
        for unit in known:
            if comment == unit or re.match(re.escape(unit) + r"[,:; ]", comment):
                units[f"{section}.{key}"] = unit
                break
        if comment == "dimensionless":
            units[f"{section}.{key}"] = "1"
        also = re.search(r"also (.*)", comment)
        if also:
            for names, unit in re.findall(r"([\w, ]+?) \(([^)]+)\)", also.group(1)):
                for name in filter(None, (n.strip() for n in names.split(","))):
                    units[f"{section}.{name}"] = unit
    return units


def test_the_unit_is_the_one_the_readme_states():
    documented = _readme_units()
    # the example names most keys' units: a parse that found few would test nothing
    assert len(documented) >= 15, documented
    assert documented["drive.frequency"] == "Hz" and documented["initial.omega"] == "rad/s"
    for key, unit in documented.items():
        assert key_unit(key) == unit, key


def test_curve_parameters_take_the_curve_expressions_units():
    key = "boundary.parameters.a"
    assert key_unit(key) == "as in the curve expression (x, f in m)"
    assert axis_label(key) == "boundary.parameters.a (curve units)"


def test_axis_labels_name_the_key_and_its_unit():
    assert axis_label("drive.frequency") == "drive.frequency (Hz)"
    assert axis_label("air.c_quad") == "air.c_quad (N s^2/m^2)"
    assert axis_label("contact.restitution") == "contact.restitution (1)"


def test_variable_names_are_identifiers_one_per_key():
    keys = [f"{s}.{k}" for s, names in SECTION_KEYS.items() for k in names]
    keys.append("boundary.parameters.my-width")
    names = [variable_name(k) for k in keys]
    assert all(name.isidentifier() for name in names)
    assert len(set(names)) == len(keys)
    assert variable_name("drive.frequency") == "drive_frequency"
