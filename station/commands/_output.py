"""The one way a command writes its ``-o OUT`` file (``report``, ``export``, ``gains fit --c``).

OUT comes from the command line, so anything the file system refuses (a name over 255 bytes, a
missing folder, a read-only place) is a one-line sentence that says what to do, never a
traceback, and every command words it the same. The file is written durably, in full or not at
all, never through a symlink and never over the command's own input
(:func:`station.session.durable.replace_durably`).
"""

from __future__ import annotations

import errno
from collections.abc import Callable
from pathlib import Path
from typing import TextIO, TypeVar

from station.errors import StationError
from station.plain import plain
from station.session.durable import check_output_path, replace_durably

T = TypeVar("T")

_SHOWN_NAME = 120
"""Characters of OUT shown in an error: a name too long for the file system is itself the
error, and the sentence stays on one line."""


def write_output_file(
    out: str | Path,
    write: Callable[[TextIO], T],
    *,
    force: bool,
    source: Path | None = None,
    mode: int = 0o640,
) -> T:
    """Write OUT with ``write(handle)`` and return what it returned.

    Refused with a StationError before anything is written when OUT exists and ``force`` is
    False, is a symbolic link or not a regular file, or is ``source`` itself; a file system
    error (a name too long, a missing folder, no permission, a full disk) is a StationError
    naming OUT and what to do.
    """
    out = Path(out)
    try:
        return replace_durably(out, write, overwrite=force, not_over=source, mode=mode)
    except OSError as error:
        raise StationError(output_error(out, error)) from None


def check_output_file(out: str | Path, *, force: bool, source: Path | None = None) -> None:
    """Refuse OUT as :func:`write_output_file` would, before any work is spent on its content."""
    out = Path(out)
    try:
        check_output_path(out, overwrite=force, not_over=source)
    except OSError as error:
        raise StationError(output_error(out, error)) from None


def output_error(out: Path, error: OSError) -> str:
    """The sentence for an OSError met writing OUT: what went wrong and what to do."""
    shown = plain(str(out), limit=_SHOWN_NAME)
    if error.errno == errno.ENAMETOOLONG:
        return (
            f"cannot write {shown}: the name is longer than the file system allows "
            "(255 bytes a name); choose a shorter name."
        )
    if error.errno in (errno.ENOENT, errno.ENOTDIR):
        folder = plain(str(out.parent), limit=_SHOWN_NAME)
        return f"cannot write {shown}: the folder {folder} does not exist; create it first."
    if error.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f"cannot write {shown}: {error.strerror}; choose a folder you may write in."
    if error.errno in (errno.ENOSPC, errno.EDQUOT):
        return f"cannot write {shown}: {error.strerror}; free some space or write elsewhere."
    return f"cannot write {shown}: {error.strerror or error}."
