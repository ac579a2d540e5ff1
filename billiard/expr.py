"""Curve expressions: the whitelist parser lives in :mod:`billiard.derivation.expr`.

This module re-exports it for code that imports ``billiard.expr``.
"""

from billiard.derivation.expr import *  # noqa: F403
from billiard.derivation.expr import __all__  # noqa: F401
