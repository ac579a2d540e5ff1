"""Writing TOML (``billiard/scene/toml_text.py``): what is written reads back with
:mod:`tomllib` as the same value, floats bit for bit; non-finite numbers and values that
are not TOML scalars are refused with the documented messages."""

from __future__ import annotations

import math
import re
import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from billiard.scene.toml_text import toml_key, toml_string, toml_value

AWKWARD = [
    "",
    '"',
    '""""',
    "'''",
    "\\",
    "\\\\",
    '\\"',
    "\\u0041",  # a backslash and 'u': text, not an escape
    "C:\\temp\\new",
    "tab\tnew\nline\r\nfeed\fbell\bend",
    "\x00\x01\x1f\x7f",
    "\u0085\u2028\u2029",  # other line breaks: not control characters for TOML
    "é ü ß ∞ 𝄞 😀",
    "# not a comment",
    "a = 1\n[table]",
]


def _read(key_text: str, value_text: str) -> dict:
    return tomllib.loads(f"{key_text} = {value_text}\n")


@pytest.mark.parametrize("text", AWKWARD)
def test_awkward_strings_read_back(text):
    written = toml_string(text)
    assert "\n" not in written and "\r" not in written  # one line of a TOML file
    assert _read("k", written) == {"k": text}


@given(st.text())
@settings(max_examples=150, deadline=None, derandomize=True)
def test_any_string_reads_back(text):
    assert _read("k", toml_string(text)) == {"k": text}


@pytest.mark.parametrize("code", [*range(0x20), 0x7F])
def test_control_characters_are_escaped(code):
    # TOML forbids them raw in a basic string
    written = toml_string(chr(code))
    assert not any(ord(ch) < 0x20 or ord(ch) == 0x7F for ch in written)
    assert _read("k", written) == {"k": chr(code)}


@pytest.mark.parametrize(
    "key", ["", "a.b", "a b", "a=b", "[x]", '"', "\\", "é", "\n", "#", "true", "1.5", "-"]
)
def test_awkward_keys_read_back_as_one_key(key):
    # a dotted or quoted key must come back as the one key, not a nested table
    assert _read(toml_key(key), "1") == {key: 1}


@given(st.text())
@settings(max_examples=150, deadline=None, derandomize=True)
def test_any_key_reads_back(key):
    assert _read(toml_key(key), "true") == {key: True}


@given(st.from_regex(r"[A-Za-z0-9_-]+", fullmatch=True))
@settings(max_examples=100, deadline=None, derandomize=True)
def test_bare_keys_are_written_bare(key):
    # the TOML spec's bare keys: ASCII letters, digits, '_' and '-'
    assert toml_key(key) == key
    assert _read(key, "0") == {key: 0}


def _same_float(x: float, y: float) -> bool:
    return type(y) is float and x.hex() == y.hex()  # bit for bit, signed zeros included


@pytest.mark.parametrize(
    "x",
    [
        0.0,
        -0.0,
        0.1,
        -2.5e-3,
        1e16,  # repr writes 1e+16
        1.0e-5,  # repr writes 1e-05
        5e-324,  # the smallest subnormal
        2.2250738585072014e-308,
        1.7976931348623157e308,
        1 / 3,
        9.81,
        1.3028e-4,
    ],
)
def test_floats_read_back_bit_for_bit(x):
    value = _read("v", toml_value(x))["v"]
    assert _same_float(x, value), (x, toml_value(x), value)


@given(st.floats(allow_nan=False, allow_infinity=False))
@settings(max_examples=500, deadline=None, derandomize=True)
def test_any_finite_float_reads_back_bit_for_bit(x):
    written = toml_value(x)
    assert written == repr(x)
    assert _same_float(x, _read("v", written)["v"])


@pytest.mark.parametrize("x", [math.inf, -math.inf, math.nan])
def test_non_finite_numbers_are_refused(x):
    with pytest.raises(ValueError, match=re.escape(f"cannot write the non-finite number {x!r}")):
        toml_value(x)


@given(st.integers(min_value=-(2**63), max_value=2**63 - 1))
@settings(max_examples=200, deadline=None, derandomize=True)
def test_integers_read_back(n):
    value = _read("v", toml_value(n))["v"]
    assert type(value) is int and value == n


@pytest.mark.parametrize("flag", [True, False])
def test_booleans_read_back_as_booleans(flag):
    # bool is an int in Python; TOML writes it as true/false, not 1/0
    value = _read("v", toml_value(flag))["v"]
    assert value is flag


@given(st.text())
@settings(max_examples=100, deadline=None, derandomize=True)
def test_string_values_read_back(text):
    assert _read("v", toml_value(text)) == {"v": text}


@pytest.mark.parametrize(
    ("value", "name"),
    [(None, "NoneType"), ([1.0], "list"), ({"a": 1}, "dict"), (b"x", "bytes"), (1j, "complex")],
)
def test_other_values_are_refused(value, name):
    with pytest.raises(TypeError, match=re.escape(f"cannot write {name} as a TOML value")):
        toml_value(value)
