"""Where a streamed run keeps its rows: CSV text (``collisions.csv``, the default, which
any tool reads) or typed binary rows (``collisions.npy``, :mod:`billiard.runfile.npyfile`:
less than half the bytes, read back in a fraction of the time).

``billiard run --store auto`` (the command's default) keeps CSV unless the run's CSV
files would be large: over :data:`AUTO_BINARY_BYTES`, estimated before the run from the
impacts asked for (:data:`CSV_IMPACT_BYTES` each) and the trajectory samples
(:mod:`billiard.run.output_size`), it writes the binary files and says so in one line.
The paper's scenes at their default impact counts stay far below it.
"""

from __future__ import annotations

import math

from billiard.run.output_size import SampleEstimate
from billiard.runfile.npyfile import COLLISIONS

__all__ = ["AUTO_BINARY_BYTES", "CSV_IMPACT_BYTES", "STORES", "choose_store"]

#: The stores a run can write: ``auto`` picks one of the other two.
STORES = ("auto", "csv", "npy")
#: Bytes of one row of collisions.csv (measured: 321 on average over 10^6 impacts of
#: the wedge, 300-330 over the paper's scenes).
CSV_IMPACT_BYTES = 321
#: Estimated CSV bytes of a run beyond which ``auto`` writes binary files: 100 MB, some
#: 310,000 impacts (a million impacts make 321 MB of CSV, 137 MB of binary rows).
AUTO_BINARY_BYTES = 10**8


def choose_store(
    store: str, impacts: int, samples: SampleEstimate | None = None
) -> tuple[str, str | None]:
    """The store (``csv`` or ``npy``) of a run of ``impacts`` impacts sampled as
    ``samples`` estimates, and for ``auto`` a one-line reason (None otherwise).

    Raises:
        ValueError: ``store`` is not one of :data:`STORES`.
    """
    if store not in STORES:
        raise ValueError(f"store must be one of {', '.join(STORES)}, got {store!r}")
    if store != "auto":
        return store, None
    size = impacts * CSV_IMPACT_BYTES + (samples.bytes if samples is not None else 0.0)
    if size <= AUTO_BINARY_BYTES:
        return "csv", None
    amount = f"about {size / 1e6:,.0f} MB" if math.isfinite(size) else "an unbounded size"
    return "npy", (
        f"the run's CSV files would take {amount} (over "
        f"{AUTO_BINARY_BYTES / 1e6:,.0f} MB): writing binary files (collisions.npy, "
        f"{100 * COLLISIONS.dtype.itemsize / CSV_IMPACT_BYTES:.0f} % of the bytes; "
        f"`billiard export DIR --csv` writes the CSV files from them, --store csv writes "
        f"CSV instead)"
    )
