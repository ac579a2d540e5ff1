"""``billiard --help`` and the help of every command: each option's default is shown,
each quantity names its unit; ``billiard --version``."""

from __future__ import annotations

import argparse
import importlib.metadata
import re
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest

import billiard
from billiard.cli import build_parser, main, shows_default, version_text

ROOT = Path(__file__).resolve().parents[2]

#: metavars that stand for a quantity whatever the option's type (text parsed later)
QUANTITY_METAVARS = {"S", "DT", "H"}
#: a unit in the help: in parentheses or after ';' or ',', or spelled out
UNIT = re.compile(
    r"[(;,]\s*(m|s|Hz|kg|rad|m/s|rad/s|J|N s)\s*[);,]|\(\s*(m|s)\b|\b(seconds|metres|units?)\b"
)

#: Options of commands defined in files another change owns (billiard/cli/study.py),
#: whose help lacks a unit; the wording to give them is in the reason.


def commands(
    parser: argparse.ArgumentParser, name: str = "billiard"
) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    yield name, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for command, sub in action.choices.items():
                yield from commands(sub, command)


def options() -> list[tuple[str, argparse.ArgumentParser, argparse.Action]]:
    return [
        (name, parser, action)
        for name, parser in commands(build_parser())
        for action in parser._actions
        if action.option_strings
    ]


def expanded_help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The option's help as printed, before it is wrapped into lines."""
    return parser._get_formatter()._expand_help(action)


def option_id(case: tuple) -> str:
    return f"{case[0]} {case[2].option_strings[-1]}"


def test_every_command_is_walked():
    names = [name for name, _ in commands(build_parser())]
    assert names == [
        "billiard",
        "derive",
        "scenes",
        "run",
        "export",
        "calibrate",
        "plot",
        "lyapunov",
        "bench",
        "reproduce",
        "sweep",
        "hysteresis",
        "uncertainty",
        "orbits",
        "view",
    ]
    for _, parser in commands(build_parser()):
        assert parser.format_help()  # every help prints


@pytest.mark.parametrize("case", [c for c in options() if shows_default(c[2])], ids=option_id)
def test_every_default_is_shown(case):
    name, parser, action = case
    text = expanded_help(parser, action)
    assert "default" in text and str(action.default) in text, (
        f"`billiard {name} --help`: {action.option_strings[-1]} does not show its default "
        f"{action.default!r}: {text!r}"
    )


def test_lyapunov_shows_its_defaults():
    parser = dict(commands(build_parser()))["lyapunov"]
    text = " ".join(parser.format_help().split())
    for shown in ("(default: 5000)", "(default: 0)", "(default: 1e-09)"):
        assert shown in text


def _quantity_cases() -> list:
    cases = []
    for case in options():
        name, _, action = case
        if action.type is not float and action.metavar not in QUANTITY_METAVARS:
            continue
        cases.append(pytest.param(case, id=option_id(case)))
    return cases


@pytest.mark.parametrize("case", _quantity_cases())
def test_every_quantity_names_its_unit(case):
    name, parser, action = case
    text = expanded_help(parser, action)
    assert UNIT.search(text), (
        f"`billiard {name} --help`: {action.option_strings[-1]} is a quantity but its help "
        f"names no unit: {text!r}"
    )


def test_quantities_are_found():
    found = {(c.values[0][0], c.values[0][2].option_strings[-1]) for c in _quantity_cases()}
    assert {("run", "--duration"), ("lyapunov", "--d0"), ("sweep", "--duration")} <= found


def _pyproject_version() -> str:
    with open(ROOT / "pyproject.toml", "rb") as handle:
        return tomllib.load(handle)["project"]["version"]


def test_version_names_the_distribution_its_version_and_the_package(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    folder = Path(billiard.__file__).resolve().parent
    expected = importlib.metadata.version("realworld-billiard")
    assert capsys.readouterr().out == f"realworld-billiard {expected} (package at {folder})\n"


def test_version_of_a_checkout_that_is_not_installed(monkeypatch):
    def not_installed(name: str) -> str:
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", not_installed)
    folder = Path(billiard.__file__).resolve().parent
    assert version_text() == (
        f"realworld-billiard {_pyproject_version()} (not installed; package at {folder})"
    )


def test_the_package_version_is_pyprojects():
    assert billiard.__version__ == _pyproject_version()
