"""The session index: what ``station history`` needs of each session file, kept in SQLite.

Reading a session for a history costs its chain check and its analysis (some 30 ms of CPU);
a plant's folder of thousands of sessions took minutes. The index keeps, per file, the
:class:`~station.record.history.SessionFigures` it gave (whose session it is, when, its
verdict and figures, or why it could not be read) with the file's size, modification and
change times and inode. A file is read again only when one of those changed, a file gone
from the folder is dropped, and a new one is read: **the files stay the truth**, the index is
a cache of what reading them gives.

It lives in the station's data folder (``$XDG_DATA_HOME/station/session-index.sqlite3``),
one per station (per user), whichever sessions folder it indexes: several stations sharing one
sessions folder each keep their own index of it, so none writes to another's. Two commands of
one station that use it at once take turns (SQLite's file locks; a command writes its
new rows in short transactions and waits up to :data:`BUSY_SECONDS` for the other's).

Whatever goes wrong with the index never stops a history: a damaged index file is removed
and built again from the files, with a warning; an index that cannot be opened or written
(a read-only data folder, a lock held too long) is done without, with a warning, and the
history reads the files. A new station version rebuilds it (the figures it computes may have
changed).
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from station import __version__
from station.errors import StationError
from station.record.history import ChannelFigures, HistoryEntry, SessionFigures, session_figures
from station.record.text import plain
from station.session.durable import data_home, make_folders, refuse_links_below
from station.session.store import session_paths

INDEX_NAME = "session-index.sqlite3"
FORMAT = f"station-session-index/1 station {__version__}"
"""What the index was built by: another value (a new station version) rebuilds it."""
BUSY_SECONDS = 10.0
"""How long a command waits for another that is writing the index."""
_BATCH = 200
"""Rows written per transaction: a long first build keeps what it did if it is stopped."""

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS files (
    folder TEXT NOT NULL,
    name TEXT NOT NULL,
    size INTEGER NOT NULL,
    mtime_ns INTEGER NOT NULL,
    ctime_ns INTEGER NOT NULL,
    inode INTEGER NOT NULL,
    robot TEXT,
    created TEXT NOT NULL,
    session TEXT NOT NULL,
    entry TEXT,
    error TEXT,
    PRIMARY KEY (folder, name)
);
"""

_Stamp = tuple[int, int, int, int]
"""A file's size, modification time, change time and inode: any change reads it again."""


def index_path(environ: Mapping[str, str] | None = None) -> Path:
    """The index file: ``$XDG_DATA_HOME/station/session-index.sqlite3``; StationError when a
    level of it below ``$XDG_DATA_HOME`` is a symbolic link."""
    home = data_home(environ)
    return refuse_links_below(home, home / "station" / INDEX_NAME, "the session index")


class SessionIndex:
    """The index of the session files of any folder, in one SQLite file.

    Build it with :meth:`open`; :meth:`figures` gives a folder's files' figures. Nothing it
    does raises for a fault of the index itself: :attr:`warnings` says what went wrong and
    what was done instead (a command prints them on standard error).
    """

    def __init__(self, path: Path | None) -> None:
        self.path = path
        """The index file; None when this run does without one."""
        self.warnings: list[str] = []
        self._db: sqlite3.Connection | None = None

    @classmethod
    def open(cls, path: Path | None = None) -> SessionIndex:
        """The station's index (:func:`index_path`, or ``path``); an index that cannot be
        used is a SessionIndex without one, its warning saying why."""
        try:
            path = index_path() if path is None else path
        except StationError as error:
            index = cls(None)
            index._do_without(error.message)
            return index
        return cls(path)

    # -- reading a folder -----------------------------------------------------------------------

    def figures(self, folder: Path, *, robot: str | None = None) -> list[SessionFigures]:
        """The figures of every session file of ``folder``, from the index where the file has
        not changed since it was read, from the file otherwise (the index then keeps them).
        With ``robot``, only that robot's sessions are analysed: the others are loaded (their
        robot and date, or why they cannot be read, are kept) and analysed when asked for."""
        paths = session_paths(folder)
        if self.path is not None:
            try:
                return self._figures(folder, paths, robot)
            except OSError as error:  # its folder cannot be made (a read-only data folder)
                self._close()
                self._do_without(f"it cannot be made ({error.strerror})")
            except sqlite3.DatabaseError as error:
                self._close()
                if not _damaged(error):
                    self._do_without(f"it cannot be used ({error})")
                else:
                    self._rebuild(error)
                    if self.path is not None:
                        try:
                            return self._figures(folder, paths, robot)
                        except sqlite3.DatabaseError as again:
                            self._close()
                            self._do_without(f"it cannot be used ({again})")
        return [session_figures(path, robot=robot) for path in paths]

    def _figures(
        self, folder: Path, paths: Sequence[Path], robot: str | None
    ) -> list[SessionFigures]:
        db = self._connect()
        key = str(folder.resolve())
        known = {
            row[0]: row
            for row in db.execute(
                "SELECT name, size, mtime_ns, ctime_ns, inode, robot, created, session, entry, "
                "error FROM files WHERE folder = ?",
                (key,),
            )
        }
        found: list[SessionFigures] = []
        fresh: list[tuple[Any, ...]] = []
        for path in paths:
            stamp = _stamp(path)
            row = known.get(path.name)
            if stamp is not None and row is not None and tuple(row[1:5]) == stamp:
                kept = _from_row(path, row[5:])
                if kept is not None and not _wanted_unanalysed(kept, robot):
                    found.append(kept)
                    continue
            figures = session_figures(path, robot=robot)
            found.append(figures)
            if stamp is not None:
                fresh.append((key, path.name, *stamp, *_to_row(figures)))
            if len(fresh) >= _BATCH:
                self._write(db, key, fresh, ())
                fresh = []
        gone = set(known) - {path.name for path in paths}
        if fresh or gone:
            self._write(db, key, fresh, gone)
        return found

    @staticmethod
    def _write(
        db: sqlite3.Connection, folder: str, rows: Sequence[tuple[Any, ...]], gone: Any
    ) -> None:
        with db:
            db.executemany("INSERT OR REPLACE INTO files VALUES (?,?,?,?,?,?,?,?,?,?,?)", rows)
            db.executemany(
                "DELETE FROM files WHERE folder = ? AND name = ?", [(folder, n) for n in gone]
            )

    # -- the file -------------------------------------------------------------------------------

    def _connect(self) -> sqlite3.Connection:
        if self._db is not None:
            return self._db
        assert self.path is not None
        make_folders(self.path.parent)
        db = sqlite3.connect(self.path, timeout=BUSY_SECONDS)
        try:
            # A cache: a power loss may cost its last rows (they are read again), never the
            # session files. A damaged file is found and built again (see figures).
            db.execute("PRAGMA synchronous = NORMAL")
            db.executescript(_SCHEMA)
            row = db.execute("SELECT value FROM meta WHERE key = 'format'").fetchone()
            if row is None or row[0] != FORMAT:
                with db:
                    db.execute("DELETE FROM files")
                    db.execute("INSERT OR REPLACE INTO meta VALUES ('format', ?)", (FORMAT,))
        except BaseException:
            db.close()
            raise
        self._db = db
        return db

    def _rebuild(self, error: sqlite3.DatabaseError) -> None:
        """Remove a damaged index file (and SQLite's files beside it) to build it again."""
        assert self.path is not None
        try:
            for suffix in ("", "-journal", "-wal", "-shm"):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(f"{self.path}{suffix}")
        except OSError as removal:
            self._do_without(f"it is damaged ({error}) and cannot be removed: {removal.strerror}")
            return
        self.warnings.append(
            f"the session index {plain(self.path)} was damaged ({error}); it is built again "
            "from the session files"
        )

    def _do_without(self, why: str) -> None:
        where = "" if self.path is None else f" {plain(self.path)}"
        self.warnings.append(
            f"the session index{where} is not used: {why}; the session files are read instead"
        )
        self.path = None

    def _close(self) -> None:
        if self._db is not None:
            with contextlib.suppress(sqlite3.Error):
                self._db.close()
            self._db = None

    def close(self) -> None:
        """Close the index file (the index can be used again: it reopens)."""
        self._close()

    def __enter__(self) -> SessionIndex:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _damaged(error: sqlite3.DatabaseError) -> bool:
    """True for an index file that is not a database or a damaged one (built again); False
    for one that is busy, read-only or on a full disk (done without this time)."""
    if isinstance(error, sqlite3.OperationalError):
        text = str(error).lower()
        return "malformed" in text or "not a database" in text
    return True


def _wanted_unanalysed(figures: SessionFigures, robot: str | None) -> bool:
    """True for a kept session that was loaded but not analysed (another robot's, read for
    one robot's history) when ``robot``'s (or every robot's, None) figures are wanted."""
    unanalysed = figures.robot is not None and figures.entry is None and figures.error is None
    return unanalysed and robot in (None, figures.robot)


def _stamp(path: Path) -> _Stamp | None:
    try:
        info = os.stat(path)
    except OSError:
        return None  # read it (its error is the history's), keep nothing
    return info.st_size, info.st_mtime_ns, info.st_ctime_ns, info.st_ino


def _to_row(figures: SessionFigures) -> tuple[Any, ...]:
    entry = None
    if figures.entry is not None:
        fields = asdict(figures.entry)
        del fields["path"], fields["baseline"]  # the folder's path and the baseline: on reading
        entry = json.dumps(fields)
    return figures.robot, figures.created, figures.session_id, entry, figures.error


def _from_row(path: Path, row: Sequence[Any]) -> SessionFigures | None:
    """The figures a row kept; None when the row cannot be read back (the file is read again)."""
    robot, created, session_id, entry, error = row
    try:
        return SessionFigures(
            path=path,
            robot=robot,
            created=created,
            session_id=session_id,
            entry=None if entry is None else _entry_from_json(path, entry),
            error=error,
        )
    except (ValueError, TypeError, KeyError, AttributeError):
        return None


def _entry_from_json(path: Path, text: str) -> HistoryEntry:
    fields = json.loads(text)
    channels = {name: ChannelFigures(**figures) for name, figures in fields.pop("channels").items()}
    return HistoryEntry(path=path, channels=channels, **fields)
