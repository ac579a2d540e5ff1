"""What every command shares: the one-line user error and small helpers."""

from __future__ import annotations

import sys


class UserError(Exception):
    """An error to report in one line, without a traceback."""


def _note(line: str) -> None:
    print(f"billiard: note: {line}", file=sys.stderr)
