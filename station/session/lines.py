"""One line of a session file: its encoding with ``prev`` and ``hash``, its check, and how a
file's first bytes are recognised as a session file at all.

The format as a whole (what the two hash fields cover, what the last hash anchors) is described
in :mod:`station.session.model`; the fields of the header and of each event are checked in
:mod:`station.session.replay`.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from station.errors import StationError

FORMAT = "station-session/1"

_HASH_PREFIX = b',"hash":"'
_HASH_SUFFIX_LENGTH = len(_HASH_PREFIX) + 64 + 2  # ,"hash":"<64 hex>"}
_HEX64 = re.compile(rb"^[0-9a-f]{64}$")


class SessionFileError(StationError):
    """A session file that is not intact; ``line`` is the 1-based number of the first bad line."""

    def __init__(self, path: Path | str, line: int, fault: str) -> None:
        super().__init__(f"session file {path}: line {line}: {fault}")
        self.path = Path(path)
        self.line = line
        self.fault = fault


def line_hash(line: bytes) -> str:
    """The sha256 hex of one line's bytes (without its newline): the next line's ``prev``."""
    return hashlib.sha256(line).hexdigest()


def _json_default(value: Any) -> Any:
    # numpy scalars and arrays reach the journal from the analysis and the reader.
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, tuple | set | frozenset):
        return list(value)
    raise TypeError(f"cannot store {type(value).__name__} in a session file")


def encode_line(record: Mapping[str, Any], prev: str | None) -> bytes:
    """One line (without the newline): ``record`` plus ``prev`` and the line's own ``hash``."""
    try:
        body = json.dumps(
            {**record, "prev": prev},
            ensure_ascii=False,
            separators=(",", ":"),
            allow_nan=False,
            default=_json_default,
        ).encode("utf-8")
    except ValueError as error:
        # allow_nan=False: a NaN or infinity is never a measurement.
        raise StationError(f"cannot record a value that is not a finite number ({error})") from None
    body = body[:-1]  # reopen the object to append the hash of everything before it
    return body + _HASH_PREFIX + line_hash(body).encode("ascii") + b'"}'


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number")


# One decoder for every line: json.loads(text, parse_constant=...) builds a new one per call,
# a tenth of the time of reading a long session.
_DECODER = json.JSONDecoder(parse_constant=_reject_constant)


def decode_line(line: bytes) -> dict[str, Any]:
    """The object on one line; ValueError saying why when the line is damaged."""
    if len(line) <= _HASH_SUFFIX_LENGTH or not line.endswith(b'"}'):
        raise ValueError("the line does not end with its hash")
    split = len(line) - _HASH_SUFFIX_LENGTH
    body, suffix = line[:split], line[split:]
    digest = suffix[len(_HASH_PREFIX) : -2]
    if not suffix.startswith(_HASH_PREFIX) or not _HEX64.match(digest):
        raise ValueError("the line does not end with its hash")
    if line_hash(body) != digest.decode("ascii"):
        raise ValueError("the line's content does not match its hash (the line was edited)")
    try:
        record = _DECODER.decode(line.decode("utf-8"))
    except UnicodeDecodeError:
        raise ValueError("the line is not UTF-8 text") from None
    except RecursionError:
        raise ValueError("the line nests too deeply") from None
    except ValueError as error:
        raise ValueError(f"the line is not valid JSON ({error})") from None
    if not isinstance(record, dict):
        raise ValueError("the line is not a JSON object")
    return record


def has_hash_suffix(line: bytes) -> bool:
    """True when a line ends in ``,"hash":"<64 hex>"}``, whether or not the hash matches."""
    if len(line) <= _HASH_SUFFIX_LENGTH:
        return False
    suffix = line[len(line) - _HASH_SUFFIX_LENGTH :]
    return suffix.startswith(_HASH_PREFIX) and bool(_HEX64.match(suffix[len(_HASH_PREFIX) : -2]))


_HEADER_START = b'{"format":"' + FORMAT.encode("ascii") + b'"'


def looks_like_session(data: bytes) -> bool:
    """True when ``data`` (a file's first bytes, at least its first line) begins like a session
    file: the header's opening ``{"format":"station-session/1"`` (the writer puts it first, so
    even a header cut short while being created has it), or a first line that ends in a
    well-formed hash (a session whose header was edited is damaged, not foreign)."""
    first = data.split(b"\n", 1)[0]
    return first.startswith(_HEADER_START) or (len(data) > len(first) and has_hash_suffix(first))


def not_a_session_error(path: Path | str, empty: bool = False) -> StationError:
    """The one sentence for a file that is not a session file at all (exit 2)."""
    what = "is empty:" if empty else "is"
    return StationError(
        f"{path} {what} not a station session file (its first line is not a {FORMAT} header)"
    )
