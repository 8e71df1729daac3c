"""Making files and folders survive a power loss: fsync the data, then the folder entries.

A file's data is durable once ``os.fsync`` on the file returns; its *name* is durable only once
the folder holding it is synced too, and a folder just created is itself a name in its parent.
These helpers are the one place the session code does that.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TextIO, TypeVar

from station.errors import StationError

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


def data_home(environ: Mapping[str, str] | None = None) -> Path:
    """``$XDG_DATA_HOME`` (``~/.local/share`` when unset): the user's folder, which holds the
    station's own ``station/`` data folder (sessions, baselines, the gauge register)."""
    environ = os.environ if environ is None else environ
    return Path(environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share"))


def refuse_links_below(base: Path, path: Path, what: str) -> Path:
    """``path`` when no level of it below ``base`` is a symbolic link; else a StationError
    naming the link and ``what`` it leads to.

    ``base`` is the user's own folder (``$XDG_DATA_HOME``, ``$XDG_CONFIG_HOME``); the levels
    below it are the station's, which it creates itself and never reads or writes through a link
    (a link there would send a baseline, the gauge register or a session somewhere else, or make
    a register in an empty folder read as "no gauges recorded yet"). Levels that do not exist
    yet are no link.
    """
    try:
        below = Path(path).relative_to(base)
    except ValueError:
        return path
    level = Path(base)
    for part in below.parts:
        level = level / part
        try:
            info = os.lstat(level)
        except FileNotFoundError:
            break
        except OSError as error:
            raise StationError(f"cannot read {level}: {error.strerror}") from None
        if stat.S_ISLNK(info.st_mode):
            raise StationError(
                f"{level} is a symbolic link, refused for {what}: station does not read or "
                "write its data through links; replace the link with a folder (or the file) "
                "itself"
            )
    return path


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


def replace_durably(
    path: Path,
    write: Callable[[TextIO], T],
    *,
    overwrite: bool = True,
    not_over: Path | None = None,
    mode: int = 0o640,
) -> T:
    """Write a text file in full, or not at all, without following a planted link.

    ``write(handle)`` fills a private temporary file created beside ``path`` (``O_EXCL`` with an
    unpredictable name, ``mode`` 0640 unless given, never through a symlink), which is synced,
    renamed over ``path`` (a rename replaces a link at ``path`` itself, never its target), and
    the folder synced. Returns what ``write`` returned.

    Refused with a StationError, before anything is written: ``path`` is a symbolic link or not
    a regular file, ``path`` exists and ``overwrite`` is False, or ``path`` is the same file as
    ``not_over`` (the input being exported). OSError when writing fails (the temporary file is
    removed).
    """
    path = Path(path)
    check_output_path(path, overwrite=overwrite, not_over=not_over)
    fd, partial = _private_temporary(path, mode)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            result = write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        # A link or another file planted at ``path`` since the check is replaced, not followed.
        check_output_path(path, overwrite=overwrite, not_over=not_over)
        os.replace(partial, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(partial)
        raise
    fsync_folder(path.parent)
    return result


def write_text_durably(
    path: Path,
    text: str,
    *,
    overwrite: bool = True,
    not_over: Path | None = None,
    mode: int = 0o640,
) -> None:
    """:func:`replace_durably` for a whole string."""
    replace_durably(
        path, lambda handle: handle.write(text), overwrite=overwrite, not_over=not_over, mode=mode
    )


def check_output_path(path: Path, *, overwrite: bool = True, not_over: Path | None = None) -> None:
    """StationError when ``path`` may not be written: a symbolic link, not a regular file, an
    existing file without ``overwrite``, or the same file as ``not_over``. OSError when its
    name cannot even be looked up (too long, a file where a folder should be, no permission),
    for the caller to word as it words a failed write."""
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    if stat.S_ISLNK(info.st_mode):
        raise StationError(
            f"{path} is a symbolic link; station does not write through links: remove it or "
            "choose another name"
        )
    if not stat.S_ISREG(info.st_mode):
        raise StationError(f"{path} is not a regular file; choose another name")
    if not_over is not None:
        with contextlib.suppress(OSError):
            source = os.stat(not_over)
            if (source.st_dev, source.st_ino) == (info.st_dev, info.st_ino):
                raise StationError(
                    f"{path} is the input file itself; write the output to another name"
                )
    if not overwrite:
        raise StationError(f"{path} exists; pass --force to overwrite it or choose another name")


def _private_temporary(path: Path, mode: int) -> tuple[int, str]:
    """A new file beside ``path`` with an unpredictable name: ``O_EXCL | O_NOFOLLOW``."""
    for _ in range(100):
        name = path.with_name(f".{path.name[:200]}.{secrets.token_hex(8)}.partial")
        try:
            fd = os.open(name, _NEW_FILE_FLAGS, mode)
        except FileExistsError:
            continue
        return fd, str(name)
    raise FileExistsError(f"no free temporary name beside {path}")


_NEW_FILE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)


def open_append_no_follow(path: Path, mode: int = 0o640) -> int:
    """A file descriptor appending to ``path`` (created when missing), never through a link:
    ``O_NOFOLLOW`` refuses a symlink at ``path`` (OSError ``ELOOP``) and a non-regular file is
    refused (OSError ``EINVAL``)."""
    fd = os.open(
        path,
        os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0),
        mode,
    )
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise OSError(errno.EINVAL, "not a regular file", str(path))
    return fd
