"""``station verify``: is a session file intact? The same checks the loader makes, read-only.

A file is intact when every line decodes, every line's own ``hash`` matches its bytes, the
``prev`` chain is unbroken, ``seq`` counts up from 1, every event is well formed, and the file
ends with a newline (a torn tail is reported as the first bad line: loading or resuming the
session moves it aside, after which the file verifies). The summary carries the last line's
own ``hash`` field, which anchors the file: a filed report that quotes it shows whether the file
changed, and ``grep`` finds it in the file. A file that is not a session file at all (a CSV
table, an empty file) is a StationError saying so (exit 2), not a damaged session.
"""

from __future__ import annotations

import os
import textwrap
from dataclasses import dataclass
from pathlib import Path

from station.session.model import SessionFileError, read_session_bytes, replay_bytes

_WIDTH = 79


@dataclass(frozen=True)
class VerifyResult:
    """The verdict on one session file."""

    ok: bool
    path: Path
    lines: int
    """Intact lines (all of them when ``ok``; the lines before the first bad one otherwise)."""
    events: int
    cycles: int
    last_hash: str
    """The last intact line's own ``hash`` field ('' when not even the header is intact)."""
    first_bad_line: int | None
    message: str
    """The verdict after the file's name: ``intact: 6 lines, ...`` or ``NOT intact: line 3:
    <fault>``."""

    @property
    def report(self) -> str:
        """What ``station verify`` prints, for an 80-column terminal: ``<file>: intact`` (or
        ``NOT intact``), the details wrapped below, and, when intact, ``last hash: <hash>`` on
        a line of its own (only a very long file name makes a line longer)."""
        verdict, _, details = self.message.partition(": ")
        lines = [f"{self.path}: {verdict}"]
        lines += textwrap.wrap(details, width=_WIDTH, subsequent_indent="  ")
        if self.ok:
            lines.append(f"last hash: {self.last_hash}")
        return "\n".join(lines)


def verify_session(path: str | os.PathLike[str]) -> VerifyResult:
    """Check a session file without changing it.

    A missing or unreadable file is a StationError (exit 2); a damaged one is a result with
    ``ok`` False naming the first bad line.
    """
    path = Path(path)
    data = read_session_bytes(path)
    try:
        replay, lines, _ = replay_bytes(data, path, allow_torn=False)
    except SessionFileError as error:
        # Replay the intact lines before the bad one, for the counts and their last hash.
        good = b"".join(line + b"\n" for line in data.split(b"\n")[: error.line - 1])
        try:
            replay, lines, _ = (
                replay_bytes(good, path, allow_torn=False) if good else (None, 0, None)
            )
        except SessionFileError:
            replay, lines = None, 0
        return VerifyResult(
            ok=False,
            path=path,
            lines=lines,
            events=len(replay.events) if replay else 0,
            cycles=len(replay.cycles) if replay else 0,
            last_hash=(replay.last_hash or "") if replay else "",
            first_bad_line=error.line,
            message=f"NOT intact: line {error.line}: {error.fault}",
        )
    rejected = f", {len(replay.rejected)} rejected" if replay.rejected else ""
    return VerifyResult(
        ok=True,
        path=path,
        lines=lines,
        events=len(replay.events),
        cycles=len(replay.cycles),
        last_hash=replay.last_hash or "",
        first_bad_line=None,
        message=(
            f"intact: {lines} lines, {len(replay.events)} events, "
            f"{len(replay.cycles)} cycles{rejected}, {replay.status}"
        ),
    )
