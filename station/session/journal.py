"""The append-only session journal: every event on disk (written and fsynced) before it counts.

:class:`SessionWriter` creates a session file in the sessions folder (mode 0640, ``O_EXCL``, a
sanitised name that cannot leave the folder), appends one JSON line per event with ``seq``,
``t``, ``type``, ``prev`` and the line's own ``hash`` (the format is in
:mod:`station.session.model` and ``sessions/README.md``) and returns only once ``os.fsync`` has
returned. Each event is checked by the same :class:`~station.session.replay.Replay` the loader
uses before it is written, so a file the writer produced always loads.

While a writer is open it holds an exclusive ``flock`` on the file: a second writer (another
``station capture --resume`` or the TUI) is refused, and the loader never cuts a torn tail of a
file that is being written.

A write that fails (a full disk ``ENOSPC``, a quota ``EDQUOT``, the file-size limit ``EFBIG``
under ``ulimit -f``, an ``EIO``) raises a :class:`~station.errors.StationError` that says what
is on disk and how to resume; the writer cuts the partial line it may have left (or, if even
that fails, the next open moves it aside as a torn tail), so nothing acknowledged is ever
affected. The writer is unusable afterwards.

``SIGXFSZ``: when a process exceeds ``RLIMIT_FSIZE`` the kernel sends it SIGXFSZ, whose default
action kills the process without a word. CPython already ignores SIGXFSZ at start-up (so the
write fails with ``EFBIG`` instead); :meth:`SessionWriter.create` and :meth:`resume` set it to
``SIG_IGN`` again when called on the main thread, in case an embedding program restored the
default.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import re
import signal
import socket
import stat
import threading
import unicodedata
import uuid
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, NoReturn

from station.errors import StationError
from station.inputfiles import check_regular_file
from station.session.durable import fsync_folder, make_folders
from station.session.lines import FORMAT, decode_line, encode_line
from station.session.model import Session, load_session, read_session_bytes, replay_bytes
from station.session.replay import HEADER_REQUIRED, RESERVED_FIELDS, Replay
from station.session.signing import finish_message, station_key

_NAME_LIMIT = 40
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def sanitise_name(name: str, fallback: str = "unnamed") -> str:
    """``name`` reduced to ``[A-Za-z0-9._-]`` for a file name: never a path, never empty.

    Accents are dropped to their base letters, other characters become ``_``, and leading dots
    are removed, so ``../../etc/x`` becomes ``etc_x`` and cannot leave the folder.
    """
    ascii_name = unicodedata.normalize("NFKD", name).encode("ascii", "ignore").decode("ascii")
    cleaned = _UNSAFE.sub("_", ascii_name).strip("._-")
    cleaned = re.sub(r"[._-]{2,}", lambda m: m.group(0)[0], cleaned)[:_NAME_LIMIT].strip("._-")
    return cleaned or fallback


def utc_now_iso(moment: datetime | None = None) -> str:
    """An event time: ISO-8601 UTC with microseconds and ``Z``.

    For example ``2026-11-23T17:31:30.123456Z``.
    """
    moment = moment or datetime.now(UTC)
    return moment.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def _ignore_sigxfsz() -> None:
    if hasattr(signal, "SIGXFSZ") and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


def _lock(fd: int, path: Path) -> None:
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        os.close(fd)
        if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            raise StationError(
                f"session file {path} is open for writing in another station process; "
                "close that one first"
            ) from None
        raise StationError(f"cannot lock session file {path}: {error.strerror}") from None


class SessionWriter:
    """Appends events to one session file; build it with :meth:`create` or :meth:`resume`.

    ``append`` is thread-safe (the gauge reader thread and the UI may both record events).
    """

    def __init__(self, path: Path, fd: int, replay: Replay, size: int) -> None:
        self.path = path
        self._fd: int | None = fd
        # The writer checks each event before it writes it; it keeps only what that needs (a
        # session of hours stays small in memory; the file holds everything).
        replay.keep_checks_only()
        self._replay = replay
        self._size = size
        self._lock = threading.Lock()

    # -- construction -------------------------------------------------------------------------

    @classmethod
    def create(
        cls,
        folder: str | os.PathLike[str],
        header_fields: Mapping[str, Any],
        *,
        now: datetime | None = None,
    ) -> SessionWriter:
        """Create a new session file in ``folder`` and write its header (fsynced).

        ``header_fields`` must hold ``robot``, ``procedure`` (``id``, ``version``, ``sha256``),
        ``channels`` and ``unit`` (``station.run.SessionSetup.header_fields`` builds them);
        ``format``, ``session``,
        ``created``, ``host`` and ``prev`` are filled in. The file is
        ``<date>T<time>Z_<robot>_<procedure>.jsonl`` (UTC; names sanitised), with ``-2``,
        ``-3`` ... before ``.jsonl`` when that name is taken.
        """
        missing = [key for key in HEADER_REQUIRED if key not in header_fields]
        if missing:
            raise StationError(f"a session header needs {', '.join(missing)}")
        moment = now or datetime.now(UTC)
        signer = {} if "signer" in header_fields else {"signer": station_key().header_field()}
        header = {
            "format": FORMAT,
            "session": str(uuid.uuid4()),
            "created": utc_now_iso(moment),
            "host": socket.gethostname(),
            **signer,
            **{k: v for k, v in header_fields.items() if k not in ("format", "prev", "hash")},
        }
        line = encode_line(header, None)
        replay = Replay()
        try:
            replay.check(decode_line(line))
        except ValueError as error:
            raise StationError(f"cannot start the session: {error}") from None

        folder = Path(folder)
        try:
            make_folders(folder)
        except OSError as error:
            raise StationError(
                f"cannot create the sessions folder {folder}: {error.strerror}"
            ) from None
        procedure = header["procedure"]
        stem = "_".join(
            (
                moment.astimezone(UTC).strftime("%Y-%m-%dT%H%M%SZ"),
                sanitise_name(str(header["robot"]), "robot"),
                sanitise_name(str(procedure.get("id", "")), "procedure"),
            )
        )
        _ignore_sigxfsz()
        for attempt in range(1, 1000):
            name = f"{stem}.jsonl" if attempt == 1 else f"{stem}-{attempt}.jsonl"
            path = folder / name
            try:
                fd = os.open(
                    path,
                    os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND | os.O_NOFOLLOW,
                    0o640,
                )
                break
            except FileExistsError:
                continue
            except OSError as error:
                raise StationError(
                    f"cannot create a session file in {folder}: {error.strerror}"
                ) from None
        else:
            raise StationError(f"too many sessions named {stem} in {folder}")
        with contextlib.suppress(OSError):
            os.fchmod(fd, 0o640)  # exactly 0640, whatever the umask
        _lock(fd, path)
        writer = cls(path, fd, replay, 0)
        writer._write_line(line, decode_line(line))
        # A new file's name is durable only once its folder is synced.
        fsync_folder(folder)
        return writer

    @classmethod
    def resume(cls, path: str | os.PathLike[str], **fields: Any) -> tuple[SessionWriter, Session]:
        """Continue an unfinished session: recover a torn tail, then append a ``resume`` event.

        Returns the writer and the session as it was before the resume event (its
        ``next_cycle`` is the number the next cycle gets). ``fields`` go into the resume event
        (for instance ``by="station capture"``). A finished session is a StationError.
        """
        path = Path(path)
        _ignore_sigxfsz()
        check_regular_file(path, "session file")
        try:
            fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_NOFOLLOW | os.O_NONBLOCK)
        except FileNotFoundError:
            raise StationError(f"session file {path} does not exist") from None
        except OSError as error:
            if error.errno == errno.ELOOP:
                raise StationError(
                    f"session file {path} is a symbolic link; resume the file it points to"
                ) from None
            raise StationError(f"cannot open session file {path}: {error.strerror}") from None
        _require_regular(fd, path)
        os.set_blocking(fd, True)
        _lock(fd, path)
        try:
            # The loader cannot take the lock we hold, so it would leave a torn tail in place:
            # release it for the moment of recovery, then take it again and replay what is there.
            fcntl.flock(fd, fcntl.LOCK_UN)
            recovered = load_session(path, recover=True)
            if recovered.torn is not None and recovered.torn.moved_to is None:
                raise StationError(f"cannot resume {path}: {recovered.torn.message}")
            _lock_again(fd, path)
            data = read_session_bytes(path)
            replay, lines, _ = replay_bytes(data, path, allow_torn=False)
        except BaseException:
            _close_quietly(fd)
            raise
        session = Session.from_replay(replay, path, lines, recovered.torn)
        if session.finished:
            _close_quietly(fd)
            raise StationError(
                f"session {path} is finished; start a new session instead of resuming it"
            )
        writer = cls(path, fd, replay, len(data))
        writer.append("resume", previous_status=session.status, **fields)
        return writer, session

    # -- writing ------------------------------------------------------------------------------

    @property
    def seq(self) -> int:
        """The seq of the last event on disk (0 when only the header is)."""
        return self._replay.last_seq

    @property
    def last_hash(self) -> str:
        """The last line's own ``hash`` field: print it on summaries to anchor the file (it is
        in the file, so ``grep`` finds it)."""
        return self._replay.last_hash or ""

    @property
    def next_cycle(self) -> int:
        """The number the next cycle gets."""
        return self._replay.cycle_seqs.highest + 1

    @property
    def closed(self) -> bool:
        """True after :meth:`close` or a failed write."""
        return self._fd is None

    def snapshot(self) -> Session:
        """The session as written so far (no file access)."""
        with self._lock:
            return Session.from_replay(self._replay, self.path, self._replay.last_seq + 1, None)

    def append(self, type: str, **fields: Any) -> dict[str, Any]:
        """Write one event and fsync it; return the event as stored (with seq, t, prev, hash).

        A field the journal sets itself (seq, t, type, prev, hash) is refused; an event that
        would not replay (a reading without values, a reject of an unknown cycle ...) is a
        StationError and nothing is written. Do not call it from a signal handler (the handler
        could run inside an append holding the lock): set a flag and append from the loop.
        """
        reserved = RESERVED_FIELDS.intersection(fields)
        if reserved:
            raise StationError(f"an event cannot set {', '.join(sorted(reserved))} itself")
        with self._lock:
            if self._fd is None:
                raise StationError(f"session file {self.path} is closed; resume it to continue")
            self._check_still_there()
            record = {"seq": self._replay.last_seq + 1, "t": utc_now_iso(), "type": type, **fields}
            if type == "finish" and "signer" in self._replay.header:
                record["signature"] = self._sign_finish(record["seq"])
            line = encode_line(record, self._replay.chain_hash)
            stored = decode_line(line)
            try:
                self._replay.check(stored)
            except ValueError as error:
                raise StationError(f"cannot record the {type} event: {error}") from None
            self._write_line(line, stored)
            return stored

    def _sign_finish(self, seq: int) -> str:
        key = station_key()
        assert key is not None
        signer = self._replay.header["signer"]
        if not isinstance(signer, Mapping) or signer.get("key") != key.id:
            raise StationError(
                f"session {self.path} was started with station key {signer.get('key')}, not "
                f"this station's key {key.id}: finish it on the station that started it"
            )
        message = finish_message(
            str(self._replay.header["session"]), self._replay.chain_hash or "", seq
        )
        return key.sign(message)

    def _check_still_there(self) -> None:
        """StationError when the session file was deleted, renamed away or replaced since it
        was opened: appending to an unlinked file would acknowledge readings nobody can read."""
        assert self._fd is not None
        try:
            opened = os.fstat(self._fd)
            named = os.stat(self.path)
        except FileNotFoundError:
            named = None
        except OSError:
            return
        if (
            named is None
            or opened.st_nlink == 0
            or (named.st_dev, named.st_ino) != (opened.st_dev, opened.st_ino)
        ):
            fd, self._fd = self._fd, None
            _close_quietly(fd)
            replaced = named is not None and (named.st_dev, named.st_ino) != (
                opened.st_dev,
                opened.st_ino,
            )
            what = "replaced" if replaced else "deleted"
            raise StationError(
                f"the session file {self.path} was {what} while the session was running; "
                "capture stopped (nothing more is acknowledged). Restore the file from a backup "
                "and resume it, or start a new session"
            )

    def _write_line(self, line: bytes, stored: dict[str, Any]) -> None:
        assert self._fd is not None
        data = line + b"\n"
        view = memoryview(data)
        try:
            while view:
                view = view[os.write(self._fd, view) :]
            os.fsync(self._fd)
        except OSError as error:
            self._fail(error)
        self._size += len(data)
        self._replay.apply(stored, line)

    def _fail(self, error: OSError) -> NoReturn:
        fd, self._fd = self._fd, None
        assert fd is not None
        try:
            # Cut a partial line now; if that fails too, the next open moves it aside.
            os.ftruncate(fd, self._size)
            os.fsync(fd)
        except OSError:
            pass
        _close_quietly(fd)
        cause = {
            errno.ENOSPC: ("the disk is full", "free some space"),
            errno.EDQUOT: ("the disk quota is used up", "free some space"),
            errno.EFBIG: (
                "the file-size limit was reached (ulimit -f)",
                "raise the limit",
            ),
            errno.EIO: ("the disk reported an input/output error", "check the disk"),
        }.get(error.errno or 0, (f"writing failed ({error.strerror})", "fix the cause"))
        cycles = self._replay.cycle_seqs
        kept = f"cycle {cycles.highest}" if cycles else f"event {self._replay.last_seq}"
        if not self._replay.header:
            with contextlib.suppress(OSError):
                self.path.unlink()
            raise StationError(
                f"{cause[0]}: the session file {self.path} could not be created; {cause[1]} "
                "and start again"
            ) from None
        raise StationError(
            f"{cause[0]}: nothing was lost up to {kept} in {self.path}; {cause[1]}",
            remedy="resume_session",
            subject=str(self.path),
        ) from None

    def close(self) -> None:
        """Close the file (idempotent). Everything appended is already on disk."""
        with self._lock:
            fd, self._fd = self._fd, None
        if fd is not None:
            _close_quietly(fd)

    def __enter__(self) -> SessionWriter:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _lock_again(fd: int, path: Path) -> None:
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        raise StationError(
            f"session file {path} is open for writing in another station process; "
            "close that one first"
        ) from None


def _require_regular(fd: int, path: Path) -> None:
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        _close_quietly(fd)
        raise StationError(f"{path} is not a regular file; give a session file (.jsonl)")


def _close_quietly(fd: int) -> None:
    with contextlib.suppress(OSError):
        os.close(fd)
