"""The pinned sha256 of collisions.csv of 20,000 impacts of every paper scene, drag on
and off (``tests/data/collisions_sha256.json``, written by the engine before it ran on
the kernels), the test cases over them (all eight run by default), and the platform on
which every sha256 pin of the tests holds.

What a pin freezes: the records' float64 values (the CSV is their ``repr``, so equal
values are equal bytes everywhere). They are IEEE arithmetic, the same on every
platform, plus the results of libm's ``sin``, ``cos``, ``atan`` and ``pow``, which
glibc rounds to within one ulp but not always to nearest. Another libm, another glibc
release, or glibc's routines for a CPU without FMA and AVX2 (glibc picks them at
start-up) give another last bit for a few arguments in 10,000, and a chaotic scene
carries that into every later record: with glibc 2.36's routines for a CPU without FMA
(``GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA``) three of the four paper scenes leave
their pin within 2,000 impacts, while the compiled and the interpreted runs still write
equal bytes. So a pin is checked only where it was made (:data:`PINNED_ON`) and skipped,
with the reason, elsewhere; the comparisons that hold on every platform (compiled
against interpreted, kernels against the classes, validations against closed forms)
run everywhere. ``BILLIARD_CHECK_PINS=1`` checks the pins on any platform: the way to
confirm a new one before adding it to :data:`PINNED_ON`.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import platform
import struct
from pathlib import Path

import pytest

PINS = json.loads((Path(__file__).parent / "data" / "collisions_sha256.json").read_text())

#: arguments per function of :func:`libm_fingerprint`: enough that glibc's routines for
#: CPUs with and without FMA differ on a dozen of them per function
_PROBES = 20_000

#: the platforms on which every sha256 pin of the tests was computed or checked: the
#: machine, the C library, and the libm fingerprint (here glibc's FMA and AVX2 routines)
PINNED_ON: tuple[dict[str, str], ...] = (
    {"machine": "x86_64", "libc": "glibc 2.36", "libm": "7b3ecd3adcc7f1b9"},
)


def libm_fingerprint() -> str:
    """sha256 (16 hex digits) of the bits of ``sin``, ``cos``, ``atan`` and ``pow`` on
    evenly spaced arguments of the ranges the scenes use: the libm routines the process
    runs, whichever code path the C library chose for this CPU."""
    digest = hashlib.sha256()
    functions = (
        (math.sin, -50.0, 50.0),
        (math.cos, -50.0, 50.0),
        (math.atan, -20.0, 20.0),
        (lambda x: math.pow(x, -0.2), 1e-9, 10.0),  # the step-size factor err**-0.2
    )
    for function, lo, hi in functions:
        step = (hi - lo) / _PROBES
        values = [function(lo + (k + 0.5) * step) for k in range(_PROBES)]
        digest.update(struct.pack(f"<{_PROBES}d", *values))
    return digest.hexdigest()[:16]


@functools.cache
def this_platform() -> dict[str, str]:
    """This process's platform, in the terms of :data:`PINNED_ON`."""
    name, version = platform.libc_ver()
    return {
        "machine": platform.machine(),
        "libc": f"{name} {version}" if name else "an unknown C library",
        "libm": libm_fingerprint(),
    }


def _describe(where: dict[str, str]) -> str:
    return f"{where['machine']} {where['libc']} (libm fingerprint {where['libm']})"


def require_pinned_platform() -> None:
    """Skip the calling test unless this platform is one of :data:`PINNED_ON` (or
    ``BILLIARD_CHECK_PINS=1``), saying what the pins freeze and what runs instead."""
    if os.environ.get("BILLIARD_CHECK_PINS") == "1":
        return
    here = this_platform()
    if here in PINNED_ON:
        return
    made = "; ".join(_describe(where) for where in PINNED_ON)
    pytest.skip(
        f"the sha256 pins freeze values computed with the libm of {made}; this is "
        f"{_describe(here)}, whose sin/cos/atan/pow may differ in the last bit. The "
        "compiled runs are still compared with the interpreted ones and the validations "
        "with their references; BILLIARD_CHECK_PINS=1 checks the pins anyway"
    )


def pinned_cases() -> list:
    """One pytest parameter (scene name, drag) per pinned file."""
    return [pytest.param(*key.split(), id=key.replace(" ", "-")) for key in PINS["sha256"]]
