"""The session file format, and its replay into a :class:`Session` model.

A session file is JSON Lines (UTF-8, one JSON object per line, ``\\n`` after every line). Line 1
is the header, every later line one event. Each line ends with two fields, in this order:

- ``"prev"``: the sha256 (hex) of the previous line's bytes, without its newline (``null`` on
  the header). Deleting, inserting or reordering lines breaks this chain.
- ``"hash"``: the sha256 (hex) of this line's own bytes up to, not including, the
  ``,"hash":"`` that introduces it. An edit of any line, the last one included, breaks it.

The *last hash* of a file is its last line's own ``hash`` field: it covers that line's ``prev``,
which covers the line before, and so on, so it anchors the whole file as well as a hash of the
whole line would, and it is a string a quality engineer finds in the file with ``grep``. It is
printed on every summary and report so that a filed report anchors its session file (a chain
alone cannot stop someone who rewrites every later line too).

Events carry ``seq`` (1, 2, 3 ... after the header), ``t`` (the wall-clock time the event was
written, ISO-8601 UTC with microseconds and a ``Z``) and ``type``; the fields of each type are
checked by :class:`~station.session.replay.Replay`, which both the writer (before it writes)
and the loader use, so a file the writer produced always loads.

Where each part lives: one line's encoding and check in :mod:`station.session.lines`, the
header and event checks in :mod:`station.session.replay`, the :class:`Session` model and the
loader (torn tails included) here, the writer in :mod:`station.session.journal`.
``sessions/README.md`` describes the format for people.

Nothing here loads numpy until a caller asks for arrays: the home screen lists sessions
without it.
"""

from __future__ import annotations

import errno
import fcntl
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

from station.errors import StationError
from station.inputfiles import open_input_file, read_input_bytes
from station.session.durable import fsync_folder, open_append_no_follow
from station.session.lines import (
    SessionFileError,
    decode_line,
    has_hash_suffix,
    looks_like_session,
    not_a_session_error,
)
from station.session.replay import Cycle, Replay, SampleBatch, Status, Trace

if TYPE_CHECKING:
    import numpy as np


@dataclass(frozen=True)
class TornTail:
    """A last line cut short by a crash (or damaged), found when the file was opened."""

    offset: int
    """Where the torn bytes began; the file is kept up to here."""
    length: int
    """How many bytes were torn."""
    moved_to: Path | None
    """The ``.torn`` file that now holds them, or None when the file was left as it is."""
    message: str


@dataclass(frozen=True)
class Session:
    """A session file replayed: header, events and what they add up to."""

    path: Path
    header: Mapping[str, Any]
    events: tuple[Mapping[str, Any], ...]
    cycles: Mapping[int, Cycle]
    """Every recorded cycle by number, rejected ones included (readings are never deleted)."""
    rejected: Mapping[int, str]
    """Rejected cycle number -> the reason given."""
    notes: tuple[Mapping[str, Any], ...]
    alarms: tuple[Mapping[str, Any], ...]
    inputs: Mapping[str, Mapping[str, Any]]
    """Step id -> the values the operator typed (the latest input event of that step)."""
    input_events: tuple[Mapping[str, Any], ...]
    """Every input event in order (a step inside a repeat block has one per placement)."""
    zeroes: tuple[Mapping[str, Any], ...]
    samples: tuple[SampleBatch, ...]
    confirmed_steps: tuple[str, ...]
    """Ids of the steps a ``step`` event marked ``confirmed``, in order, without repeats."""
    status: Status
    """``finished`` after a finish event; ``interrupted`` after a signal; else ``running``
    (which, for a file nobody is writing, means the writer stopped without a word: a crash)."""
    last_seq: int
    last_hash: str
    """The last line's own ``hash`` field: the anchor to print (it is in the file)."""
    lines: int
    torn: TornTail | None = None
    acks: tuple[Mapping[str, Any], ...] = ()
    """Every ``ack`` event in order: an alarm acknowledged with its cause."""
    traces: tuple[Trace, ...] = ()
    """Every ``trace`` event in order: a return's trace under the arrival trigger."""

    @classmethod
    def from_replay(cls, replay: Replay, path: Path, lines: int, torn: TornTail | None) -> Session:
        """The immutable model of what ``replay`` replayed from the ``lines`` lines of ``path``."""
        return cls(
            path=path,
            header=replay.header,
            events=tuple(replay.events),
            cycles=dict(replay.cycles),
            rejected=dict(replay.rejected),
            notes=tuple(replay.notes),
            alarms=tuple(replay.alarms),
            inputs=dict(replay.inputs),
            input_events=tuple(replay.input_events),
            zeroes=tuple(replay.zeroes),
            samples=tuple(replay.samples),
            confirmed_steps=tuple(replay.confirmed_steps),
            status=replay.status,
            last_seq=replay.last_seq,
            last_hash=replay.last_hash or "",
            lines=lines,
            torn=torn,
            acks=tuple(replay.acks),
            traces=tuple(replay.traces),
        )

    @property
    def session_id(self) -> str:
        """The session's uuid."""
        return str(self.header["session"])

    @property
    def robot(self) -> str:
        """The robot's name as the operator typed it."""
        return str(self.header["robot"])

    @property
    def operator(self) -> str:
        """The operator's name ('' when none was given)."""
        return str(self.header.get("operator") or "")

    @property
    def procedure_id(self) -> str:
        """The id of the procedure the session follows."""
        return str(self.header["procedure"]["id"])

    @property
    def created(self) -> str:
        """When the session was created, ISO-8601 UTC."""
        return str(self.header["created"])

    @property
    def channels(self) -> tuple[str, ...]:
        """The channels of the session, in order."""
        return tuple(self.header["channels"])

    @property
    def unit(self) -> str:
        """The session's unit (``in`` or ``mm``)."""
        return str(self.header["unit"])

    @property
    def limits(self) -> dict[str, dict[str, float]]:
        """Channel -> ``{"lsl", "usl", "nominal"}`` as recorded in the header (may be empty)."""
        limits = self.header.get("limits") or {}
        return {ch: dict(spec) for ch, spec in limits.items() if isinstance(spec, Mapping)}

    @property
    def cycles_target(self) -> int | None:
        """The cycle count the session aims for, when the header says."""
        value = self.header.get("cycles_target")
        return value if isinstance(value, int) else None

    @property
    def accepted_cycles(self) -> tuple[int, ...]:
        """Numbers of the recorded cycles that are not rejected, ascending."""
        return tuple(n for n in sorted(self.cycles) if n not in self.rejected)

    @property
    def excluded_cycles(self) -> tuple[int, ...]:
        """Numbers of the rejected cycles, ascending: what the analysis leaves out."""
        return tuple(sorted(self.rejected))

    @property
    def next_cycle(self) -> int:
        """The number the next cycle gets (numbering continues across resumes)."""
        return max(self.cycles, default=0) + 1

    @property
    def finished(self) -> bool:
        """True once a finish event is the session's last word."""
        return self.status == "finished"

    @property
    def recovered_torn_bytes(self) -> int:
        """How many torn bytes were found at the end of the file (0 when none)."""
        return self.torn.length if self.torn else 0

    def channel_values(self, include_rejected: bool = False) -> dict[str, np.ndarray]:
        """One array per channel, in cycle order, for the analysis.

        Rejected cycles are left out unless ``include_rejected``; :attr:`excluded_cycles` says
        which. A channel a cycle did not capture is left out of that channel's array.
        :meth:`channel_cycles` gives the cycle number of each value.
        """
        import numpy as np

        return {
            channel: np.asarray([value for _, value in column], dtype=float)
            for channel, column in self._columns(include_rejected).items()
        }

    def channel_cycles(self, include_rejected: bool = False) -> dict[str, np.ndarray]:
        """The cycle number of each value :meth:`channel_values` gives, channel by channel:
        pass both to :func:`station.analysis.summary.analyze` (``cycles=``) so the report and
        the alarms name cycles, not positions among the accepted readings."""
        import numpy as np

        return {
            channel: np.asarray([number for number, _ in column], dtype=int)
            for channel, column in self._columns(include_rejected).items()
        }

    def channel_times(self, include_rejected: bool = False) -> dict[str, np.ndarray]:
        """The time (seconds since the epoch) of each value :meth:`channel_values` gives: its
        cycle's event time ``t`` (one time per cycle, the one an export carries, so a table
        of the session dates its readings the same)."""
        import numpy as np

        numbers = sorted(self.cycles) if include_rejected else self.accepted_cycles
        times: dict[str, list[float]] = {channel: [] for channel in self.channels}
        for number in numbers:
            cycle = self.cycles[number]
            stamp = event_seconds(cycle.t)
            for channel in cycle.readings:
                times.setdefault(channel, []).append(stamp)
        return {channel: np.asarray(column, dtype=float) for channel, column in times.items()}

    def _columns(self, include_rejected: bool) -> dict[str, list[tuple[int, float]]]:
        numbers = sorted(self.cycles) if include_rejected else self.accepted_cycles
        columns: dict[str, list[tuple[int, float]]] = {channel: [] for channel in self.channels}
        for number in numbers:
            for channel, reading in self.cycles[number].readings.items():
                columns.setdefault(channel, []).append((number, reading.value))
        return columns


def event_seconds(stamp: str) -> float:
    """An event's ISO-8601 UTC time ``t`` as seconds since the epoch (NaN when unreadable)."""
    try:
        return datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()
    except ValueError:
        return math.nan


# --------------------------------------------------------------------------------------------
# Loading


@dataclass(frozen=True)
class _Split:
    """A file's bytes cut into complete lines and, maybe, a torn tail."""

    lines: list[bytes]
    kept: int
    """Bytes that are complete lines."""
    torn_reason: str | None


def _split(data: bytes) -> _Split:
    lines = data.split(b"\n")
    tail = lines.pop()  # bytes after the last newline: b"" when the file ends cleanly
    if tail:
        return _Split(lines, len(data) - len(tail), NO_NEWLINE)
    if lines and _unparsable(lines[-1]):
        last = lines.pop()
        return _Split(lines, len(data) - len(last) - 1, DOES_NOT_PARSE)
    return _Split(lines, len(data), None)


NO_NEWLINE = "the last line has no newline (cut short)"
DOES_NOT_PARSE = "the last line does not parse"


def _unparsable(last: bytes) -> bool:
    """True when a complete last line is torn: it does not decode and has no well-formed hash.
    A complete last line that does not decode is what a crash leaves when the file's length
    reached the disk before its data (zeros); an edited line that still decodes but fails its
    hash is not torn: decode_line tells the two apart."""
    try:
        decode_line(last)
    except ValueError:
        return not has_hash_suffix(last)
    return False


def _replay_line(replay: Replay, path: Path, number: int, line: bytes) -> dict[str, Any]:
    """Check line ``number`` against what came before and add it to ``replay``; its record.
    SessionFileError naming the line and the fault when it cannot come next (``replay`` is
    then as it was)."""
    try:
        record = decode_line(line)
        if record.get("prev") != replay.chain_hash:
            raise ValueError(
                "the hash chain is broken: 'prev' does not match the previous line "
                "(a line before it was changed, removed or inserted)"
            )
        replay.check(record)
    except ValueError as error:
        raise SessionFileError(path, number, str(error)) from None
    replay.apply(record, line)
    return record


def replay_bytes(data: bytes, path: Path, *, allow_torn: bool) -> tuple[Replay, int, _Split]:
    """Check and replay a file's bytes; SessionFileError naming the first bad line.

    Returns the replay, the number of lines replayed and the split (with the torn tail, when
    ``allow_torn``; otherwise a torn tail is itself the first bad line). Bytes that do not
    begin like a session file at all (:func:`looks_like_session`) are a plain StationError
    saying so, not a damaged session.
    """
    if not looks_like_session(data):
        raise not_a_session_error(path, empty=not data)
    split = _split(data)
    torn = None
    if split.torn_reason and not allow_torn:
        torn = SessionFileError(path, len(split.lines) + 1, f"torn: {split.torn_reason}")
    if not split.lines:
        raise torn or SessionFileError(
            path, 1, "no complete header line (cut while being created?)"
        )
    replay = Replay()
    for number, line in enumerate(split.lines, start=1):
        _replay_line(replay, path, number, line)
    # The torn tail is the first bad line only when every line before it holds: a newline
    # written into the last line leaves a bad complete line before the "torn" rest of it.
    if torn is not None:
        raise torn
    return replay, len(split.lines), split


def replay_stream(
    handle: BinaryIO, path: Path, replay: Replay
) -> Iterator[tuple[int, dict[str, Any]]]:
    """Check and replay a session file read from ``handle`` one line at a time into
    ``replay``, yielding each line's number and record once it holds: the checks and
    faults of :func:`replay_bytes` with ``allow_torn=False`` (a torn tail is the first bad
    line), in memory that does not grow with the file beyond what ``replay`` keeps (a replay
    that keeps only its checks holds runs of cycle numbers, not the cycles). SessionFileError
    names the first bad line; on it, ``replay`` holds every line before."""
    line = handle.readline()
    # A first line that ends in a newline says, as the whole file would, that more follows.
    if not looks_like_session(line):
        raise not_a_session_error(path, empty=not line)
    number = 0
    while line:
        following = handle.readline()
        number += 1
        if not line.endswith(b"\n"):
            raise SessionFileError(path, number, f"torn: {NO_NEWLINE}")
        line = line[:-1]
        if not following and _unparsable(line):
            raise SessionFileError(path, number, f"torn: {DOES_NOT_PARSE}")
        yield number, _replay_line(replay, path, number, line)
        line = following


def load_session(path: str | os.PathLike[str], *, recover: bool = True) -> Session:
    """Read a session file and replay it into a :class:`Session`.

    A torn last line (no trailing newline, or a last line that does not parse) is reported in
    ``session.torn``; with ``recover`` its bytes are moved to ``<file>.torn`` (appended when one
    exists) and the file is cut back to its last complete line, so the next writer continues a
    clean chain. Nothing else ever modifies the file; a read-only review passes
    ``recover=False``. A file another process is writing is never cut. Any other fault (a broken
    chain, a malformed line, a wrong format, seq out of order) is a :class:`SessionFileError`
    naming the line; nothing is silently dropped.
    """
    path = Path(path)
    data = read_session_bytes(path)
    replay, lines, split = replay_bytes(data, path, allow_torn=True)
    torn = None
    if split.torn_reason:
        torn = _handle_torn(path, data, split, recover)
    return Session.from_replay(replay, path, lines, torn)


SESSION_FILE_LIMIT = 1 << 30
"""The largest session file read (1 GiB, some 5 million readings): a bigger one is refused."""


def read_session_bytes(path: Path) -> bytes:
    """The file's bytes; StationError (exit 2) when it is missing, unreadable, not a regular
    file (a FIFO, a device, a folder) or larger than :data:`SESSION_FILE_LIMIT`."""
    if not os.path.lexists(path):
        raise StationError(f"session file {path} does not exist")
    return read_input_bytes(path, "session file", SESSION_FILE_LIMIT)


def open_session_file(path: Path) -> BinaryIO:
    """The file open to read a line at a time, with the faults of :func:`read_session_bytes`
    (a file past :data:`SESSION_FILE_LIMIT` fails when the read gets there)."""
    if not os.path.lexists(path):
        raise StationError(f"session file {path} does not exist")
    return open_input_file(path, "session file", SESSION_FILE_LIMIT)


def _handle_torn(path: Path, data: bytes, split: _Split, recover: bool) -> TornTail:
    torn_bytes = data[split.kept :]
    where = f"{len(torn_bytes)} byte(s) after line {len(split.lines)}"
    if not recover:
        return TornTail(
            split.kept,
            len(torn_bytes),
            None,
            f"{where} are torn ({split.torn_reason}); left in place (opened read-only)",
        )
    torn_path = path.with_name(path.name + ".torn")
    try:
        fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW)
    except OSError as error:
        return TornTail(
            split.kept,
            len(torn_bytes),
            None,
            f"{where} are torn ({split.torn_reason}); could not move them aside: {error.strerror}",
        )
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            if error.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            return TornTail(
                split.kept,
                len(torn_bytes),
                None,
                f"{where} are incomplete; another process is writing the session",
            )
        # Re-read under the lock: only cut what is still exactly the torn tail we saw.
        if os.fstat(fd).st_size != len(data) or os.pread(fd, len(torn_bytes), split.kept) != (
            torn_bytes
        ):
            return TornTail(
                split.kept, len(torn_bytes), None, f"{where} changed while being read; left as is"
            )
        # Save the torn bytes durably (data and the .torn file's name) before cutting them from
        # the session file.
        # Never through a link planted at <file>.torn (O_NOFOLLOW), only into a regular file.
        torn_fd = open_append_no_follow(torn_path)
        try:
            _write_all(torn_fd, torn_bytes)
            os.fsync(torn_fd)
        finally:
            os.close(torn_fd)
        fsync_folder(path.parent)
        os.ftruncate(fd, split.kept)
        os.fsync(fd)
    except OSError as error:
        return TornTail(
            split.kept,
            len(torn_bytes),
            None,
            f"{where} are torn ({split.torn_reason}); could not move them aside: {error.strerror}",
        )
    finally:
        os.close(fd)
    return TornTail(
        split.kept,
        len(torn_bytes),
        torn_path,
        f"recovered a torn last line: {where} moved to {torn_path.name}; "
        f"everything before it is kept",
    )


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        written = os.write(fd, view)
        view = view[written:]
