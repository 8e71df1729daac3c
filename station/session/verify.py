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

import base64
import os
import textwrap
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from station.plain import plain
from station.session.lines import SessionFileError
from station.session.model import open_session_file, replay_stream
from station.session.replay import Replay
from station.session.signing import check_finish_signature, key_id, predates_signing
from station.session.trust import find_trusted

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
    key: str = ""
    """The id of the station key the header names ('' for an unsigned session)."""
    signed_by: str = ""
    """The key whose signature on the finish holds and how it is trusted ('' when no finish
    is signed: an unsigned or unfinished session)."""
    remarks: tuple[str, ...] = ()
    """What the verdict does and does not show (the anchor, the signature, this station)."""
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
        for remark in self.remarks:
            lines += textwrap.wrap(
                remark, width=_WIDTH, initial_indent="  ", subsequent_indent="  "
            )
        if self.signed_by:
            lines.append(f"signed by station key: {self.signed_by}")
        if self.ok:
            lines.append(f"last hash: {self.last_hash}")
        return "\n".join(lines)


def verify_session(
    path: str | os.PathLike[str],
    anchor: str | None = None,
    *,
    allow_unsigned: bool = False,
    trust_any: bool = False,
) -> VerifyResult:
    """Check a session file without changing it.

    A missing or unreadable file is a StationError (exit 2); a damaged one is a result with
    ``ok`` False naming the first bad line. With ``anchor`` (the last hash a filed report
    quotes) the file holds only when that is its last line's hash: a file cut short or extended
    since the report fails. A finished session's ``finish`` must carry a valid signature by the
    key its header names, and that key must be in the trust store (:mod:`station.session.trust`)
    unless ``trust_any``. A header without ``signer`` fails unless it is dated before stations
    signed (:func:`predates_signing`) or ``allow_unsigned``; the remarks say which allowance
    let the file pass.
    """
    path = Path(path)
    wanted = None if anchor is None else anchor.strip().lower()
    # Only what checking the next line needs is kept (runs of cycle numbers, not the cycles),
    # and the file is read once, a line at a time: a session of hours verifies in a few
    # megabytes. The anchor is looked for during the same pass.
    replay = Replay()
    replay.keep_checks_only()
    lines, last, anchored_at = 0, None, None
    with open_session_file(path) as handle:
        try:
            for lines, record in replay_stream(handle, path, replay):
                last = record  # the finish, when it is the last line, carries the signature
                # The line's own hash field, or the hash of its bytes (the next line's prev).
                if anchored_at is None and wanted in (replay.last_hash, replay.chain_hash):
                    anchored_at = lines
        except SessionFileError as error:
            # The counts and last hash are those of the intact lines before the bad one.
            return _counts(
                replay,
                path,
                ok=False,
                lines=error.line - 1,
                first_bad_line=error.line,
                message=f"NOT intact: line {error.line}: {error.fault}",
            )
    rejected = f", {len(replay.rejected)} rejected" if replay.rejected else ""
    result = _counts(
        replay,
        path,
        ok=True,
        lines=lines,
        first_bad_line=None,
        message=(
            f"intact: {lines} lines, {replay.last_seq} events, "
            f"{len(replay.cycle_seqs)} cycles{rejected}, {replay.status}"
        ),
    )
    assert last is not None  # a file without a complete line is a SessionFileError
    return _verify_end(result, replay.header, last, wanted, anchored_at, allow_unsigned, trust_any)


def _counts(replay: Replay, path: Path, **verdict: Any) -> VerifyResult:
    """The result with the counts of the lines that hold (``replay``: the events are numbered
    from 1 without a gap, so the last seq is their count)."""
    return VerifyResult(
        path=path,
        events=replay.last_seq,
        cycles=len(replay.cycle_seqs),
        last_hash=replay.last_hash or "",
        **verdict,
    )


def _verify_end(
    result: VerifyResult,
    header: dict[str, Any],
    last: dict[str, Any],
    anchor: str | None,
    anchored_at: int | None,
    allow_unsigned: bool,
    trust_any: bool,
) -> VerifyResult:
    """The signature of a finished session, the trust in its key, the anchor (found at line
    ``anchored_at``, as its own hash or the hash of its bytes), and what the verdict cannot
    show."""
    lines = result.lines
    finished = last.get("type") == "finish"
    signed = _signature(header, last if finished else None, allow_unsigned, trust_any)
    if isinstance(signed, _Refusal):
        return replace(result, ok=False, first_bad_line=signed.line, message=signed.message)
    key, signed_by, remarks = signed
    if anchor is not None:
        if anchor != result.last_hash:
            where = anchored_at
            fault = (
                f"the anchor is line {where}'s hash, not the last line's: "
                f"{lines - where} line(s) were added after the report"
                if where is not None
                else "the anchor is not in the file: it was cut short or rewritten since the report"
            )
            return replace(
                result,
                ok=False,
                first_bad_line=(where + 1) if where is not None else lines,
                message=f"NOT intact: {fault}",
                key=key,
                signed_by=signed_by,
            )
        remarks.append("The last line is the anchor: nothing was cut or added since the report.")
    elif result.message.endswith(("running", "interrupted")):
        remarks.append(
            "The chain cannot show lines cut from the end (a finished session cut short looks "
            "unfinished): check with --anchor HASH, the last hash on the filed report."
        )
    return replace(result, key=key, signed_by=signed_by, remarks=tuple(remarks))


@dataclass(frozen=True)
class _Refusal:
    message: str
    line: int | None
    """The line at fault (None when the file is well formed but no trusted key vouches)."""


def _signature(
    header: dict, finish: dict | None, allow_unsigned: bool, trust_any: bool
) -> tuple[str, str, list[str]] | _Refusal:
    """Who vouches for the file: the key id the header names, what the ``signed by`` line says
    ('' unless a finish is signed) and the remarks; or the verdict when nothing does.

    Exit 0 needs a finish signed by a trusted key, or an unsigned header dated before stations
    signed (:func:`predates_signing`). An unfinished session has nothing signed yet: its
    header's key must still be trusted, and the verdict never says it is signed."""
    signer = header.get("signer")
    if signer is None:
        created = plain(header.get("created"), limit=40)
        if predates_signing(header):
            return "", "", [_UNSIGNED_OLD.format(created=created)]
        if allow_unsigned:
            return "", "", [_UNSIGNED_ALLOWED.format(created=created)]
        return _Refusal(_UNSIGNED_FORGED.format(created=created), None)
    if finish is not None:
        check = check_finish_signature(header, finish)
        if not check.ok:
            line = finish["seq"] + 1
            return _Refusal(f"NOT intact: line {line}: {check.message}", line)
    try:
        raw = base64.b64decode(str(signer.get("public_key")), validate=True)
    except ValueError:
        return _Refusal("NOT intact: line 1: the header's signer is not an Ed25519 public key", 1)
    # The id of the key itself, not the id the header claims for it.
    key = key_id(raw)
    remarks: list[str] = []
    trusted = find_trusted(raw)
    if trusted is not None:
        trust = f"trusted: {trusted.name}" if trusted.name else "trusted"
    elif trust_any:
        trust = "not in the trust store"
        remarks.append(_UNTRUSTED_ALLOWED.format(key=key))
    else:
        return _Refusal(_UNTRUSTED.format(key=key, signs="signed" if finish else "recorded"), None)
    if finish is None:
        remarks.append(
            f"The session is unfinished, so nothing in it is signed yet; its header names "
            f"station key {key} ({trust})."
        )
        return key, "", remarks
    return key, f"{key} ({trust})", remarks


_UNSIGNED_OLD = (
    "The session is unsigned: its header dates it {created}, before stations signed their "
    "sessions. Nothing shows who wrote it: only the anchor on its filed report vouches for it."
)
_UNSIGNED_ALLOWED = (
    "--allow-unsigned: the session is unsigned, though its header dates it {created}, when "
    "stations sign every session. Nothing shows who wrote it."
)
_UNSIGNED_FORGED = (
    "NOT trusted: the session is unsigned, though its header dates it {created}, when stations "
    "sign every session: its signature was removed. Only for a file known to be unsigned, "
    "check the chain with --allow-unsigned."
)
_UNTRUSTED_ALLOWED = (
    "--trust-any: station key {key} is not in this station's trust store; the signature shows "
    "only that whoever holds that key wrote the file."
)
_UNTRUSTED = (
    "NOT trusted: the session is {signs} with station key {key}, which is not in this "
    "station's trust store. If it is the key of the station that recorded the session, add it "
    "with `station keys trust FILE.pub` (FILE.pub: what `station keys show` prints there)."
)
