"""The keys of a scene: which exist, "did you mean" hints for those that do not, and
whether a scene's data sets any at all."""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Mapping, Sequence
from typing import Any

from billiard.scene.checks import error, shown
from billiard.scene.spec import SECTIONS

__all__ = ["ALL_KEYS", "SECTION_KEYS", "TOP_LEVEL_KEYS", "check_keys", "sets_keys"]

TOP_LEVEL_KEYS = ("name", "description")
SECTION_KEYS: dict[str, tuple[str, ...]] = {
    section: tuple(f.name for f in dataclasses.fields(cls)) for section, cls in SECTIONS.items()
}
ALL_KEYS: tuple[str, ...] = TOP_LEVEL_KEYS + tuple(
    f"{section}.{key}" for section, keys in SECTION_KEYS.items() for key in keys
)


def _hint(candidate: str, options: Sequence[str]) -> str:
    close = difflib.get_close_matches(candidate, options, n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


def _unknown_key_hint(section: str | None, key: str) -> str:
    """Hint for an unknown key, first within its section, then anywhere."""
    if section is not None:
        close = difflib.get_close_matches(key, SECTION_KEYS[section], n=1, cutoff=0.6)
        if close:
            return f"; did you mean '{section}.{close[0]}'?"
    elsewhere = [
        dotted for dotted in ALL_KEYS if dotted.rsplit(".", 1)[-1] == key and dotted != key
    ]
    if elsewhere:
        return f"; did you mean '{elsewhere[0]}'?"
    dotted = key if section is None else f"{section}.{key}"
    return _hint(dotted, ALL_KEYS)


def check_keys(data: Mapping[str, Any]) -> None:
    for key, value in data.items():
        if key in TOP_LEVEL_KEYS or key in SECTIONS:
            continue
        if isinstance(value, Mapping):
            hint = _hint(str(key), tuple(SECTIONS))
            raise error(f"unknown scene section '{key}'{hint}")
        raise error(f"unknown scene key '{key}'{_unknown_key_hint(None, str(key))}")
    for section, keys in SECTION_KEYS.items():
        table = data.get(section, {})
        if not isinstance(table, Mapping):
            raise error(f"scene key '{section}' must be a table ([{section}]), got {shown(table)}")
        for key in table:
            if key not in keys:
                hint = _unknown_key_hint(section, str(key))
                raise error(f"unknown scene key '{section}.{key}'{hint}")


def sets_keys(data: Mapping[str, Any]) -> bool:
    """Whether a scene's data (as read from TOML) sets any key besides ``name`` and
    ``description``: an empty section table sets nothing."""
    for key, value in data.items():
        if key in TOP_LEVEL_KEYS:
            continue
        if not isinstance(value, Mapping) or sets_keys_in(value):
            return True
    return False


def sets_keys_in(table: Mapping[str, Any]) -> bool:
    """Whether a section table sets a key (an empty nested table sets none)."""
    return any(not isinstance(v, Mapping) or sets_keys_in(v) for v in table.values())
