"""Writing ``collisions.csv`` rows: microseconds per row of
:func:`billiard.runfile.rows.format_rows`, ``repr`` against the compiled formatter
(:mod:`billiard.kernels.float_text`), on the rows of a real run.

    python -m bench.rows [--scene wedge-6.6hz] [--rows 20000] [--repeats 5]

Each figure is the median of ``--repeats`` timings (``time.perf_counter``) of formatting
all rows at once, in this process, after one untimed call (the compiled formatter loads
from numba's cache or compiles). The two texts are checked equal. Not a timed test: the
machine's load moves every number here.
"""

from __future__ import annotations

import argparse
import statistics
import time


def _block(scene_name: str, rows: int):
    """The rows of a ``rows``-impact run kept in memory, as one float64 block."""
    import numpy as np

    from billiard.run.simulate import simulate
    from billiard.runfile import rows as _rows
    from billiard.scene.scene import load_scene

    result = simulate(load_scene(scene_name), collisions=rows)
    columns = result.columns
    names = list(columns)
    return np.array(
        [_rows.row_of([columns[name][i] for name in names]) for i in range(len(result))],
        dtype=np.float64,
    )


def _median_us_per_row(fn, block, repeats: int) -> float:
    fn(block, "\n")
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn(block, "\n")
        times.append(time.perf_counter() - start)
    return statistics.median(times) / len(block) * 1e6


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="wedge-6.6hz")
    parser.add_argument("--rows", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    from billiard import jit
    from billiard.runfile import rows as _rows

    block = _block(args.scene, args.rows)
    print(f"{len(block)} rows of {args.scene}, median of {args.repeats}")
    slow = _median_us_per_row(_rows._format_rows_repr, block, args.repeats)
    print(f"repr:     {slow:6.2f} us/row")
    if not jit.ENABLED:
        print(f"compiled: unavailable ({jit.numba_problem()})")
        return
    assert _rows._format_rows_compiled(block, "\n") == _rows._format_rows_repr(block, "\n")
    fast = _median_us_per_row(_rows._format_rows_compiled, block, args.repeats)
    print(f"compiled: {fast:6.2f} us/row ({slow / fast:.1f} times faster)")


if __name__ == "__main__":
    main()
