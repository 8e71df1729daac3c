"""Reading files given from outside: regular files only, and never more than a bound.

A FIFO named like a session or a procedure would hang a command forever, ``/dev/zero`` would
grow its memory without end and a folder gives a confusing error: every input file the station
reads (session files, CSV tables, procedure files, ``--inputs``) goes through here, and each of
those is refused with one sentence before a byte is read.
"""

from __future__ import annotations

import errno
import io
import os
import stat
from pathlib import Path
from typing import Any, BinaryIO

from station.errors import StationError
from station.plain import plain

MEBIBYTE = 1 << 20


def check_regular_file(path: str | os.PathLike[str], what: str = "file") -> os.stat_result:
    """The ``stat`` of ``path`` when it is a regular file (a link to one is fine); otherwise a
    StationError naming ``what`` it should be: missing, a folder, a FIFO, a device, a socket,
    or a name too long for the file system."""
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise StationError(f"{_shown(path)}: no such file; check the path.") from None
    except OSError as error:
        raise StationError(f"cannot open {what} {_shown(path)}: {error.strerror}") from None
    if stat.S_ISDIR(info.st_mode):
        raise StationError(f"{_shown(path)} is a folder; give the {what} itself.")
    if not stat.S_ISREG(info.st_mode):
        kind = (
            "a FIFO (named pipe)"
            if stat.S_ISFIFO(info.st_mode)
            else "a device"
            if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode)
            else "not a regular file"
        )
        raise StationError(f"{_shown(path)} is {kind}; give a regular {what}.")
    return info


def read_input_bytes(path: str | os.PathLike[str], what: str, limit: int) -> bytes:
    """The bytes of the regular file ``path`` (see :func:`check_regular_file`), at most
    ``limit`` of them: a larger file is a StationError saying so. Opened without blocking, so a
    FIFO put in place after the check cannot hang the read."""
    with open_input_file(path, what, limit) as handle:
        return b"".join(iter(lambda: handle.read(MEBIBYTE), b""))


def open_input_file(path: str | os.PathLike[str], what: str, limit: int) -> BinaryIO:
    """The regular file ``path`` (see :func:`check_regular_file`) open to read its bytes,
    which stop with a StationError saying so past ``limit`` of them. Opened without blocking,
    so a FIFO put in place after the check cannot hang the read; a reader that streams the
    file (``station verify``) holds a line at a time, not the file."""
    path = Path(path)
    check_regular_file(path, what)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:
        if error.errno == errno.ENOENT:
            raise StationError(f"{_shown(path)}: no such file; check the path.") from None
        raise StationError(f"cannot open {what} {_shown(path)}: {error.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise StationError(f"{_shown(path)} is not a regular file; give a regular {what}.")
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return io.BufferedReader(_BoundedFile(fd, path, what, limit), buffer_size=MEBIBYTE)


class _BoundedFile(io.RawIOBase):
    """A file descriptor read up to a bound: reading past ``limit`` bytes is a StationError
    saying the file is too large, and a failed read one naming the file."""

    def __init__(self, fd: int, path: Path, what: str, limit: int) -> None:
        super().__init__()
        self._fd, self._path, self._what, self._limit = fd, path, what, limit
        self._total = 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        try:
            count = os.readv(self._fd, [buffer])
        except OSError as error:
            raise StationError(
                f"cannot read {self._what} {_shown(self._path)}: {error.strerror}"
            ) from None
        self._total += count
        if self._total > self._limit:
            raise StationError(
                f"{_shown(self._path)} is larger than {self._limit // MEBIBYTE} MiB, more than a "
                f"{self._what} can be; check that it is the right file."
            )
        return count

    def close(self) -> None:
        if not self.closed:
            os.close(self._fd)
        super().close()


def _shown(path: Path) -> str:
    # A file name over the system's limit is itself the error; keep the sentence one line.
    return plain(str(path), limit=300)
