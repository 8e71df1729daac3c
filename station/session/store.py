"""The sessions folder: where session files live, and what is in it."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TypedDict

from station.errors import StationError
from station.session.durable import data_home, refuse_links_below
from station.session.model import Session, load_session
from station.session.replay import Status

SESSIONS_ENV = "STATION_SESSIONS"


def sessions_folder(
    explicit: str | os.PathLike[str] | None = None,
    *,
    environ: Mapping[str, str] | None = None,
    cwd: Path | None = None,
) -> tuple[Path, str]:
    """The sessions folder and a phrase saying why it is that one (for the screen and commands).

    In order: ``explicit`` (``--sessions DIR``), ``STATION_SESSIONS``, ``./sessions`` when the
    working directory has one, else ``$XDG_DATA_HOME/station/sessions`` (by default
    ``~/.local/share/station/sessions``; StationError when a level of it below
    ``$XDG_DATA_HOME`` is a symbolic link). The folder is not created here; the writer creates it.
    """
    environ = os.environ if environ is None else environ
    if explicit is not None and not str(explicit).strip():
        raise StationError("--sessions is empty; name the sessions folder (or leave it out)")
    if explicit:
        return Path(explicit), "from --sessions"
    if environ.get(SESSIONS_ENV):
        return Path(environ[SESSIONS_ENV]), f"from {SESSIONS_ENV}"
    local = (cwd or Path.cwd()) / "sessions"
    if local.is_dir():
        return local, "the working directory's sessions folder"
    home = data_home(environ)
    folder = refuse_links_below(home, home / "station" / "sessions", "the sessions folder")
    return folder, "the user's data folder"


@dataclass(frozen=True)
class SessionSummary:
    """One line of a sessions listing. ``error`` is set (and the rest mostly empty) for a file
    that does not load."""

    path: Path
    robot: str = ""
    procedure: str = ""
    created: str = ""
    status: Status | None = None
    cycles: int = 0
    """Accepted (not rejected) cycles."""
    rejected: int = 0
    cycles_target: int | None = None
    operator: str = ""
    last_hash: str = ""
    torn: bool = False
    error: str | None = None
    counted: str = "cycles"
    """What the session counts: ``cycles``, ``placements`` (a repeated block: fixture
    placements, joints, positions) or ``points`` (streamed along a bar, toward strokes)."""
    done: int = 0
    """How many of them the file holds (a placement counts once any of it is in)."""
    target: int | None = None
    """How many cycles, placements or strokes the set-up asked for (None: not said)."""

    @property
    def progress(self) -> str:
        """``12 of 30 cycles``, ``2 of 3 placements`` (or ``12 cycles``); a stroke session
        ``1420 points, 3 strokes asked``."""
        if self.counted == "points":
            return f"{self.done} points, {self.target} strokes asked"
        if self.target:
            return f"{self.done} of {self.target} {self.counted}"
        return f"{self.done} {self.counted}"

    @property
    def progress_brief(self) -> str:
        """:attr:`progress` for a narrow column: ``30/30 cycles``, ``2/3 placed``,
        ``1420 points``."""
        if self.counted == "points":
            return f"{self.done} points"
        word = "placed" if self.counted == "placements" else self.counted
        return f"{self.done}/{self.target} {word}" if self.target else f"{self.done} {word}"

    @property
    def resumable(self) -> bool:
        """True for an intact session that has not finished."""
        return self.error is None and self.status in ("running", "interrupted")


def summarise(path: Path) -> SessionSummary:
    """A summary of one session file, read-only; a file that does not load gives its error."""
    try:
        session = load_session(path, recover=False)
    except StationError as error:
        return SessionSummary(path=path, error=error.message)
    return SessionSummary(
        path=path,
        robot=session.robot,
        procedure=session.procedure_id,
        created=session.created,
        status=session.status,
        cycles=len(session.accepted_cycles),
        rejected=len(session.rejected),
        cycles_target=session.cycles_target,
        operator=session.operator,
        last_hash=session.last_hash,
        torn=session.torn is not None,
        **_progress(session),
    )


class _Progress(TypedDict):
    """The progress fields of a :class:`SessionSummary`."""

    counted: str
    done: int
    target: int | None


def _progress(session: Session) -> _Progress:
    """What ``session`` counts, how many are in and how many were asked for: points toward
    strokes for a stroke step (a linearity session streams points, not cycles), placements for a
    repeated block, else accepted cycles."""
    header = session.header
    strokes, placements = header.get("strokes_target"), header.get("placements_target")
    if isinstance(strokes, int):
        # Which stretches of the stream are whole strokes is the analysis's to say (a listing
        # loads no numpy): the points streamed are what the file plainly holds.
        points = sum(len(batch.values) for batch in session.samples)
        return {"counted": "points", "done": points, "target": strokes}
    if isinstance(placements, int):
        accepted = set(session.accepted_cycles)
        reached = {
            cycle.placement
            for number, cycle in session.cycles.items()
            if number in accepted and cycle.placement is not None
        }
        return {"counted": "placements", "done": len(reached), "target": placements}
    return {
        "counted": "cycles",
        "done": len(session.accepted_cycles),
        "target": session.cycles_target,
    }


def session_paths(folder: str | os.PathLike[str]) -> list[Path]:
    """The session files of ``folder``: every ``*.jsonl`` that is a file ([] when no folder)."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    return [path for path in folder.glob("*.jsonl") if path.is_file()]


def list_sessions(folder: str | os.PathLike[str]) -> list[SessionSummary]:
    """Every ``*.jsonl`` in ``folder``, sorted by robot then creation time; [] when no folder.

    Files that do not load are listed with their error (sorted last), never raised.
    """
    summaries = [summarise(path) for path in session_paths(folder)]
    return sorted(
        summaries,
        key=lambda s: (s.error is not None, s.robot.casefold(), s.created, s.path.name),
    )


def find_unfinished(folder: str | os.PathLike[str]) -> list[SessionSummary]:
    """The sessions that can be resumed (running or interrupted), newest first."""
    unfinished = [s for s in list_sessions(folder) if s.resumable]
    return sorted(unfinished, key=lambda s: s.created, reverse=True)


def writer_alive(path: Path) -> bool:
    """True when a live station process holds the session file open for writing (its writer's
    exclusive ``flock``); False when nobody does, or the file cannot be opened.

    The probe takes a shared lock for an instant and gives it back at once; a writer starting
    in that instant is refused with its "open in another process" sentence and can be retried.
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError as error:
        return error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES)
    else:
        with contextlib.suppress(OSError):
            fcntl.flock(fd, fcntl.LOCK_UN)
        return False
    finally:
        os.close(fd)


def status_words(summary: SessionSummary, *, alive: bool | None = None) -> str:
    """How a listing names a session's state. A file still marked ``running`` whose writer is
    gone (no live lock) stopped without writing ``interrupted`` or ``finish``: a crash, a
    power loss, a kill -9. ``alive`` is the writer probe's answer (asked when None)."""
    if summary.error:
        return "unreadable"
    if summary.status == "running":
        if alive is None:
            alive = writer_alive(summary.path)
        return "running now" if alive else "stopped without a word (crashed?)"
    return str(summary.status or "")
