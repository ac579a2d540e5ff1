"""What every command shares: the one-line user error and small helpers."""

from __future__ import annotations

import argparse
import sys


class UserError(Exception):
    """An error to report in one line, without a traceback."""


def _note(line: str) -> None:
    print(f"billiard: note: {line}", file=sys.stderr)


def add_set_argument(parser: argparse.ArgumentParser, help: str) -> None:
    """The repeatable ``--set KEY=VALUE`` scene override every scene command takes."""
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help=help)
