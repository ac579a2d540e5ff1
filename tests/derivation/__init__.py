"""What the derivation's tests share: the mark of a byte-for-byte check of generated/."""

import pytest
from billiard.derivation.build import sympy_mismatch

_MISMATCH = sympy_mismatch()
#: A byte-for-byte check of generated/ needs the sympy release that wrote it (the test
#: extra pins it; tests/api/test_packaging.py checks the pin): under another, skipped with
#: the line that names the release needed.
needs_generating_sympy = pytest.mark.skipif(_MISMATCH is not None, reason=str(_MISMATCH))
