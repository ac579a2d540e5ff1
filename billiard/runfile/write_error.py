"""The error of a streamed run that could not write its files (:class:`RunWriteError`),
worded with what is kept and how to continue."""

from __future__ import annotations

import errno
import os
import shlex
from pathlib import Path

__all__ = ["RunWriteError"]

#: the errors of a full disk or a quota: free some space, then continue
_DISK_FULL = frozenset({errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)})


class RunWriteError(OSError):
    """A streamed run could not write its files (the disk is full, a quota, an I/O
    error). The CSV file ends with the ``rows`` whole rows that reached it, and
    :func:`billiard.run.persist.resume` keeps them all (rows after the last checkpoint are
    recomputed and checked, not rewritten). ``strerror`` is the one-line message: what
    failed, how many impacts are kept, and how to continue.

    Attributes:
        rows: whole rows in the CSV file.
        checkpoint_rows: rows the checkpoint describes (a resume recomputes the rest).
        out_dir: the run directory.
    """

    def __init__(self, errno_: int, message: str, rows: int, checkpoint_rows: int, out: Path):
        super().__init__(errno_, message)
        self.rows = rows
        self.checkpoint_rows = checkpoint_rows
        self.out_dir = out

    @classmethod
    def after(
        cls, exc: OSError, out: Path, rows: int, checkpoint_rows: int, *, csv: Path,
        resumable: bool,
    ) -> RunWriteError:  # fmt: skip
        """The error after ``exc``, for the run in ``out`` whose CSV file ``csv`` holds
        ``rows`` whole rows; ``resumable``: a checkpoint was written."""
        code = exc.errno or errno.EIO
        if code in _DISK_FULL:
            what = f"the disk is full ({os.strerror(code)})"
        else:
            where = f" {exc.filename}" if exc.filename else ""
            what = f"a write failed{where} ({exc.strerror or exc})"
        if resumable:
            again = (
                f"free some space, then continue with "
                f"`billiard run --resume {shlex.quote(str(out))}`"
                if code in _DISK_FULL
                else f"continue with `billiard run --resume {shlex.quote(str(out))}`"
            )
        else:  # not even the first checkpoint was written: nothing to continue from
            again = "nothing to continue from: run it again"
        return cls(
            code,
            f"{what}: {rows} impacts kept in {csv}; {again}",
            rows,
            checkpoint_rows,
            out,
        )
