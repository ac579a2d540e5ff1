"""Reading a file a user names (a scene file, a run's scene.toml or checkpoint): only a
regular file, and only up to a size limit, so that ``billiard run /dev/zero``, a named
pipe or a runaway file fails in one line instead of reading without end."""

from __future__ import annotations

import os
import stat
from pathlib import Path

__all__ = ["MAX_SCENE_BYTES", "FileRefused", "check_regular", "open_regular", "read_limited"]

#: Largest scene file read (bytes): a scene file is a few kilobytes of TOML.
MAX_SCENE_BYTES = 1 << 20

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a named pipe"),
    (stat.S_ISSOCK, "a socket"),
)


class FileRefused(OSError):
    """The file is not a regular file, or is larger than the limit; ``reason`` is the
    one-line explanation (without the file's name)."""

    def __init__(self, path: Path, reason: str):
        super().__init__(reason)
        self.path = path
        self.reason = reason


def _size(size: int) -> str:
    mib, rest = divmod(size, 1 << 20)
    return f"{mib} MiB" if mib and not rest else f"{size:,} bytes"


def _refuse_irregular(path: Path, mode: int) -> None:
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "not a file")
        raise FileRefused(path, f"is not a regular file ({kind})")


def check_regular(path: str | os.PathLike[str]) -> None:
    """Refuse a path that is not a regular file (a device, a pipe, a folder) before a
    reader that takes any size (a run's CSV files) opens it.

    Raises:
        FileRefused: not a regular file.
        OSError: it cannot be looked at (missing, no permission).
    """
    _refuse_irregular(Path(path), os.stat(path).st_mode)


def open_regular(path: str | os.PathLike[str]) -> int:
    """A file descriptor of ``path`` opened for reading, refused unless it is a regular
    file. It is opened without blocking (a named pipe with no writer does not hang the
    open) and checked on the descriptor; the caller closes it.

    Raises:
        FileRefused: not a regular file (a device, a pipe, a folder).
        OSError: the file cannot be opened (missing, no permission).
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    fd = os.open(path, flags)
    try:
        _refuse_irregular(Path(path), os.fstat(fd).st_mode)
    except BaseException:
        os.close(fd)
        raise
    return fd


def read_limited(path: str | os.PathLike[str], limit: int | None) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes (None: any size).

    The file is opened by :func:`open_regular` and checked before anything is read; at
    most ``limit`` + 1 bytes are read, so a file that grows meanwhile is refused too.

    Raises:
        FileRefused: not a regular file (a device, a pipe, a folder), or over the limit.
        OSError: the file cannot be opened or read (missing, no permission).
    """
    path = Path(path)
    fd = open_regular(path)
    try:
        info = os.fstat(fd)
        if limit is not None and info.st_size > limit:
            raise FileRefused(path, f"is {_size(info.st_size)}, over the limit of {_size(limit)}")
        chunks: list[bytes] = []
        total = 0
        cap = info.st_size + 1 if limit is None else limit + 1
        while True:
            chunk = os.read(fd, max(1 << 16, cap - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if limit is not None and total > limit:
                raise FileRefused(path, f"grew past the limit of {_size(limit)} while being read")
    finally:
        os.close(fd)
    return b"".join(chunks)
