"""Making files and folders survive a power loss: fsync the data, then the folder entries.

A file's data is durable once ``os.fsync`` on the file returns; its *name* is durable only once
the folder holding it is synced too, and a folder just created is itself a name in its parent.
These helpers are the one place the session code does that.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import TextIO, TypeVar

T = TypeVar("T")


def fsync_folder(folder: Path) -> None:
    """Sync ``folder`` so the names created or renamed in it survive a power loss.

    Best effort: a file system that cannot sync a folder (some network mounts) is left as is.
    """
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):
            os.fsync(fd)
    finally:
        os.close(fd)


def make_folders(folder: Path) -> None:
    """Create ``folder`` and any missing parents, syncing each new one's parent so the whole
    path survives a power loss (``mkdir -p`` alone leaves the new names in the page cache).

    OSError when a folder cannot be created.
    """
    missing: list[Path] = []
    current = folder
    while not current.exists():
        missing.append(current)
        if current.parent == current:
            break
        current = current.parent
    folder.mkdir(parents=True, exist_ok=True)
    for created in reversed(missing):
        fsync_folder(created.parent)


def replace_durably(path: Path, write: Callable[[TextIO], T]) -> T:
    """Write a text file in full, or not at all: ``write(handle)`` fills a hidden ``.partial``
    beside ``path``, which is synced, renamed over ``path``, and the folder synced. Returns what
    ``write`` returned.

    OSError when writing fails (the partial file is removed).
    """
    partial = path.with_name(f".{path.name}.partial")
    try:
        with open(partial, "w", encoding="utf-8", newline="") as handle:
            result = write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    fsync_folder(path.parent)
    return result
