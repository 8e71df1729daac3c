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
checked by :class:`Replay`, which both the writer (before it writes) and the loader use, so a
file the writer produced always loads.

The writer lives in :mod:`station.session.journal`; ``sessions/README.md`` describes the format
for people.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from station.errors import StationError
from station.session.durable import fsync_folder, open_append_no_follow

if TYPE_CHECKING:
    import numpy as np

FORMAT = "station-session/1"
EVENT_TYPES: tuple[str, ...] = (
    "step",
    "input",
    "zero",
    "reading",
    "reject",
    "note",
    "alarm",
    "ack",
    "instrument",
    "samples",
    "resume",
    "interrupted",
    "finish",
)
RESERVED_FIELDS: frozenset[str] = frozenset({"seq", "t", "type", "prev", "hash"})
"""Fields the journal sets itself; an event cannot carry them."""
HEADER_REQUIRED: tuple[str, ...] = ("robot", "procedure", "channels", "unit")
"""Header fields the caller of ``SessionWriter.create`` must give."""

Status = Literal["running", "interrupted", "finished"]

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


# --------------------------------------------------------------------------------------------
# Lines


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
        record = json.loads(line.decode("utf-8"), parse_constant=_reject_constant)
    except UnicodeDecodeError:
        raise ValueError("the line is not UTF-8 text") from None
    except RecursionError:
        raise ValueError("the line nests too deeply") from None
    except ValueError as error:
        raise ValueError(f"the line is not valid JSON ({error})") from None
    if not isinstance(record, dict):
        raise ValueError("the line is not a JSON object")
    return record


# --------------------------------------------------------------------------------------------
# The model


@dataclass(frozen=True)
class ChannelReading:
    """One channel of one cycle: the zeroed value and how it was obtained."""

    value: float
    """The value the analysis uses: the device value minus the zero offset."""
    unit: str
    raw_value: float | None = None
    """The value the device sent (before the software zero offset)."""
    zero: float | None = None
    """The software zero offset subtracted, or None when the device was zeroed by command."""
    raw: str = ""
    """The frame text as received."""
    t_wall: float | None = None
    t_mono: float | None = None


@dataclass(frozen=True)
class Cycle:
    """One recorded cycle: a reading set, one value per channel the step captures."""

    number: int
    seq: int
    t: str
    step: str
    readings: Mapping[str, ChannelReading]
    placement: int | None = None
    """The repeat-block iteration (fixture placement) the cycle belongs to, when any."""


@dataclass(frozen=True)
class SampleBatch:
    """One ``samples`` event: streamed points of one stroke, one row per point."""

    seq: int
    step: str
    stroke: int | None
    channels: tuple[str, ...]
    values: tuple[tuple[float, ...], ...]
    t_mono: tuple[float, ...] = ()

    def as_arrays(self) -> dict[str, np.ndarray]:
        """The points as one array per channel."""
        import numpy as np

        table = np.asarray(self.values, dtype=float).reshape(len(self.values), len(self.channels))
        return {channel: table[:, index] for index, channel in enumerate(self.channels)}


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


# --------------------------------------------------------------------------------------------
# Replay: the one place that knows what a valid header and a valid event are


def event_seconds(stamp: str) -> float:
    """An event's ISO-8601 UTC time ``t`` as seconds since the epoch (NaN when unreadable)."""
    from datetime import datetime

    try:
        return datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()
    except ValueError:
        return math.nan


def _is_number(value: Any) -> bool:
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        return False


READING_LIMIT = 1e150
"""The largest magnitude a recorded value or limit may have (as for CSV tables): the squares
and sums the analysis takes stay finite."""
CYCLE_LIMIT = 2**53
"""Cycle numbers stay exact as floats and fit every integer array."""
COUNT_LIMIT = 1_000_000
"""The largest cycle, placement or stroke target a header may ask for."""


def _is_reading(value: Any) -> bool:
    return _is_number(value) and abs(value) <= READING_LIMIT


def _optional_number(value: Any) -> float | None:
    return float(value) if _is_number(value) else None


@dataclass
class Replay:
    """Accumulates a session's header and events, checking each one.

    :meth:`check` raises ``ValueError`` with the fault (the caller adds file and line);
    :meth:`apply` adds a checked record. The writer checks an event before writing it, so what
    it writes always replays.
    """

    header: dict[str, Any] = field(default_factory=dict)
    events: list[dict[str, Any]] = field(default_factory=list)
    cycles: dict[int, Cycle] = field(default_factory=dict)
    rejected: dict[int, str] = field(default_factory=dict)
    notes: list[dict[str, Any]] = field(default_factory=list)
    alarms: list[dict[str, Any]] = field(default_factory=list)
    acks: list[dict[str, Any]] = field(default_factory=list)
    inputs: dict[str, dict[str, Any]] = field(default_factory=dict)
    input_events: list[dict[str, Any]] = field(default_factory=list)
    zeroes: list[dict[str, Any]] = field(default_factory=list)
    samples: list[SampleBatch] = field(default_factory=list)
    confirmed_steps: list[str] = field(default_factory=list)
    status: Status = "running"
    last_seq: int = 0
    last_hash: str | None = None
    """The last line's own ``hash`` field: the anchor printed on summaries and reports."""
    chain_hash: str | None = None
    """The sha256 of the last line's bytes: the next line's ``prev``."""
    checks_only: bool = False
    """A writer's replay: keep what checking the next event needs (the header, the cycle numbers,
    rejects, alarms, inputs), not every event's record, its readings or its streamed points, so
    a long session's memory stays small (the file keeps everything)."""

    def keep_checks_only(self) -> None:
        """Drop what only a reader of the whole session needs (see :attr:`checks_only`)."""
        self.checks_only = True
        self.events.clear()
        self.samples.clear()
        self.notes.clear()
        self.input_events.clear()

    def check(self, record: Mapping[str, Any]) -> None:
        """Raise ValueError naming the fault when ``record`` cannot come next."""
        if not self.header:
            _check_header(record)
            return
        if "format" in record:
            raise ValueError("a second header in the middle of the file")
        if self.status == "finished":
            raise ValueError(
                "an event after the session's finish (a finished session holds nothing more; "
                "the line was added later)"
            )
        seq = record.get("seq")
        if not isinstance(seq, int) or isinstance(seq, bool):
            raise ValueError("the event has no integer 'seq'")
        if seq != self.last_seq + 1:
            raise ValueError(f"seq {seq} out of order (expected {self.last_seq + 1})")
        if not isinstance(record.get("t"), str):
            raise ValueError("the event has no time 't'")
        kind = record.get("type")
        if kind not in EVENT_TYPES:
            raise ValueError(f"unknown event type {kind!r}")
        _EVENT_CHECKS[kind](self, record)

    def apply(self, record: dict[str, Any], line: bytes) -> None:
        """Add a checked record; ``line`` is its bytes on disk (for the chain)."""
        self.chain_hash = line_hash(line)
        self.last_hash = str(record["hash"])
        if not self.header:
            self.header = record
            return
        if not self.checks_only:
            self.events.append(record)
        self.last_seq = record["seq"]
        kind = record["type"]
        if kind == "reading" and self.checks_only:
            # Checking later events needs the cycle's number, not its values.
            self.cycles[record["cycle"]] = Cycle(
                number=record["cycle"], seq=record["seq"], t=record["t"], step="", readings={}
            )
        elif kind == "reading":
            readings = {
                channel: ChannelReading(
                    value=float(spec["value"]),
                    unit=str(spec.get("unit") or self.header["unit"]),
                    raw_value=_optional_number(spec.get("raw_value")),
                    zero=_optional_number(spec.get("zero")),
                    raw=str(spec.get("raw", "")),
                    t_wall=_optional_number(spec.get("t_wall")),
                    t_mono=_optional_number(spec.get("t_mono")),
                )
                for channel, spec in record["channels"].items()
            }
            placement = record.get("placement")
            self.cycles[record["cycle"]] = Cycle(
                number=record["cycle"],
                seq=record["seq"],
                t=record["t"],
                step=str(record.get("step", "")),
                readings=readings,
                placement=placement if isinstance(placement, int) else None,
            )
        elif kind == "reject":
            self.rejected[record["cycle"]] = record["reason"]
        elif kind == "note" and not self.checks_only:
            self.notes.append(record)
        elif kind == "alarm":
            self.alarms.append(record)
        elif kind == "ack":
            self.acks.append(record)
        elif kind == "input":
            self.inputs[record["step"]] = record["values"]
            if not self.checks_only:
                self.input_events.append(record)
        elif kind == "zero":
            self.zeroes.append(record)
        elif kind == "samples" and not self.checks_only:
            stroke = record.get("stroke")
            self.samples.append(
                SampleBatch(
                    seq=record["seq"],
                    step=record["step"],
                    stroke=stroke if isinstance(stroke, int) else None,
                    channels=tuple(record["channels"]),
                    values=tuple(tuple(float(v) for v in row) for row in record["values"]),
                    t_mono=tuple(float(v) for v in record.get("t_mono") or ()),
                )
            )
        elif kind == "step":
            if record["action"] == "confirmed" and record["step"] not in self.confirmed_steps:
                self.confirmed_steps.append(record["step"])
        elif kind == "finish":
            self.status = "finished"
        elif kind == "interrupted":
            self.status = "interrupted"
        elif kind == "resume":
            self.status = "running"

    def freeze(self, path: Path, lines: int, torn: TornTail | None) -> Session:
        """The immutable model of what was replayed."""
        return Session(
            path=path,
            header=self.header,
            events=tuple(self.events),
            cycles=dict(self.cycles),
            rejected=dict(self.rejected),
            notes=tuple(self.notes),
            alarms=tuple(self.alarms),
            inputs=dict(self.inputs),
            input_events=tuple(self.input_events),
            zeroes=tuple(self.zeroes),
            samples=tuple(self.samples),
            confirmed_steps=tuple(self.confirmed_steps),
            status=self.status,
            last_seq=self.last_seq,
            last_hash=self.last_hash or "",
            lines=lines,
            torn=torn,
            acks=tuple(self.acks),
        )


def _check_header(record: Mapping[str, Any]) -> None:
    if record.get("format") != FORMAT:
        raise ValueError(f"not a station session header (format {record.get('format')!r})")
    for key in ("session", "created", "robot", "unit"):
        if not isinstance(record.get(key), str):
            raise ValueError(f"the header has no text {key!r}")
    procedure = record.get("procedure")
    if not isinstance(procedure, dict) or not all(
        isinstance(procedure.get(key), str) for key in ("id", "version", "sha256")
    ):
        raise ValueError("the header's 'procedure' needs text 'id', 'version' and 'sha256'")
    channels = record.get("channels")
    if (
        not isinstance(channels, list)
        or not channels
        or not all(isinstance(c, str) and c for c in channels)
        or len(set(channels)) != len(channels)
    ):
        raise ValueError("the header's 'channels' must be a list of distinct names")
    limits = record.get("limits", {})
    if limits is not None and not isinstance(limits, dict):
        raise ValueError("the header's 'limits' must be a table")
    for channel, spec in (limits or {}).items():
        if not isinstance(spec, dict):
            raise ValueError(f"the header's limits of {channel!r} must be a table")
        for key in ("lsl", "usl", "nominal"):
            if spec.get(key) is not None and not _is_reading(spec[key]):
                raise ValueError(
                    f"the header's {key} of {channel!r} must be a finite number within "
                    f"±{READING_LIMIT:g}"
                )
    for key in ("resolution", "threshold"):
        value = record.get(key)
        if value is not None and not (_is_reading(value) and value > 0):
            raise ValueError(f"the header's {key!r} must be a number above 0")
    for key in ("cycles_target", "placements_target", "strokes_target"):
        value = record.get(key)
        if value is not None and not (
            isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= COUNT_LIMIT
        ):
            raise ValueError(f"the header's {key!r} must be a whole number from 1 to {COUNT_LIMIT}")
    if record.get("rules") is not None and not isinstance(record.get("rules"), str):
        raise ValueError("the header's 'rules' must be text")
    signer = record.get("signer")
    if signer is not None and not (
        isinstance(signer, dict)
        and isinstance(signer.get("key"), str)
        and isinstance(signer.get("public_key"), str)
    ):
        raise ValueError("the header's 'signer' needs text 'key' and 'public_key'")
    if record.get("prev", "missing") is not None:
        raise ValueError("the header's 'prev' must be null")


def _need_text(record: Mapping[str, Any], key: str) -> str:
    value = record.get(key)
    if not isinstance(value, str) or not value:
        raise ValueError(f"a {record['type']} event needs text {key!r}")
    return value


def _need_cycle(record: Mapping[str, Any]) -> int:
    cycle = record.get("cycle")
    if not isinstance(cycle, int) or isinstance(cycle, bool) or not 1 <= cycle <= CYCLE_LIMIT:
        raise ValueError(f"a {record['type']} event needs a cycle number from 1 to {CYCLE_LIMIT}")
    return cycle


def _check_step(replay: Replay, record: Mapping[str, Any]) -> None:
    _need_text(record, "step")
    _need_text(record, "action")


def _check_input(replay: Replay, record: Mapping[str, Any]) -> None:
    _need_text(record, "step")
    if not isinstance(record.get("values"), dict):
        raise ValueError("an input event needs a table 'values'")


def _check_zero(replay: Replay, record: Mapping[str, Any]) -> None:
    channels = record.get("channels")
    if not isinstance(channels, dict) or not channels:
        raise ValueError("a zero event needs a table 'channels'")
    for channel, spec in channels.items():
        if channel not in replay.header["channels"]:
            raise ValueError(f"a zero event names channel {channel!r}, not in the session")
        if not isinstance(spec, dict):
            raise ValueError(f"a zero event's channel {channel!r} must be a table")


def _check_reading(replay: Replay, record: Mapping[str, Any]) -> None:
    cycle = _need_cycle(record)
    if cycle in replay.cycles:
        raise ValueError(f"cycle {cycle} is recorded twice (seq {replay.cycles[cycle].seq})")
    channels = record.get("channels")
    if not isinstance(channels, dict) or not channels:
        raise ValueError("a reading event needs a table 'channels'")
    for channel, spec in channels.items():
        if channel not in replay.header["channels"]:
            raise ValueError(f"a reading names channel {channel!r}, not in the session")
        if not isinstance(spec, dict) or not _is_reading(spec.get("value")):
            raise ValueError(
                f"a reading's channel {channel!r} needs a number 'value' within ±{READING_LIMIT:g}"
            )


def _check_reject(replay: Replay, record: Mapping[str, Any]) -> None:
    cycle = _need_cycle(record)
    if cycle not in replay.cycles:
        raise ValueError(f"a reject names cycle {cycle}, which was never recorded")
    _need_text(record, "reason")


def _check_note(replay: Replay, record: Mapping[str, Any]) -> None:
    _need_text(record, "text")


def _check_samples(replay: Replay, record: Mapping[str, Any]) -> None:
    _need_text(record, "step")
    channels = record.get("channels")
    if (
        not isinstance(channels, list)
        or not channels
        or not all(isinstance(c, str) and c in replay.header["channels"] for c in channels)
    ):
        raise ValueError("a samples event needs 'channels', a list of the session's channels")
    values = record.get("values")
    if not isinstance(values, list) or not all(
        isinstance(row, list) and len(row) == len(channels) and all(map(_is_reading, row))
        for row in values
    ):
        raise ValueError("a samples event needs 'values', rows of one number per channel")
    t_mono = record.get("t_mono")
    if t_mono is not None and (
        not isinstance(t_mono, list)
        or len(t_mono) != len(values)
        or not all(map(_is_number, t_mono))
    ):
        raise ValueError("a samples event's 't_mono' must hold one number per row")


def _check_ack(replay: Replay, record: Mapping[str, Any]) -> None:
    """An acknowledgement: ``alarm`` (the seq of a recorded alarm event), ``cause`` (one of the
    procedure's causes), ``text`` (required when the cause is "other"), ``action`` (optional
    corrective action)."""
    alarm = record.get("alarm")
    if not isinstance(alarm, int) or isinstance(alarm, bool):
        raise ValueError("an ack event needs 'alarm', the seq of the alarm it acknowledges")
    if not any(event["seq"] == alarm for event in replay.alarms):
        raise ValueError(f"an ack names alarm {alarm}, which is not a recorded alarm event")
    cause = _need_text(record, "cause")
    for key in ("text", "action", "by"):
        if key in record and not isinstance(record[key], str):
            raise ValueError(f"an ack event's {key!r} must be text")
    if cause == "other" and not str(record.get("text") or "").strip():
        raise ValueError("an ack with the cause 'other' needs a 'text' saying what it was")


def _check_free(replay: Replay, record: Mapping[str, Any]) -> None:
    """Events whose fields are free-form (alarm, instrument, resume, interrupted, finish)."""


_EVENT_CHECKS = {
    "step": _check_step,
    "input": _check_input,
    "zero": _check_zero,
    "reading": _check_reading,
    "reject": _check_reject,
    "note": _check_note,
    "alarm": _check_free,
    "ack": _check_ack,
    "instrument": _check_free,
    "samples": _check_samples,
    "resume": _check_free,
    "interrupted": _check_free,
    "finish": _check_free,
}


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
        return _Split(lines, len(data) - len(tail), "the last line has no newline (cut short)")
    if lines:
        try:
            decode_line(lines[-1])
        except ValueError:
            # A complete last line that does not decode is what a crash leaves when the file's
            # length reached the disk before its data (zeros); an edited line that still decodes
            # but fails its hash is not torn: decode_line tells the two apart.
            last = lines[-1]
            if not _has_hash_suffix(last):
                lines.pop()
                return _Split(lines, len(data) - len(last) - 1, "the last line does not parse")
    return _Split(lines, len(data), None)


def _has_hash_suffix(line: bytes) -> bool:
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
    return first.startswith(_HEADER_START) or (len(data) > len(first) and _has_hash_suffix(first))


def not_a_session_error(path: Path | str, empty: bool = False) -> StationError:
    """The one sentence for a file that is not a session file at all (exit 2)."""
    what = "is empty:" if empty else "is"
    return StationError(
        f"{path} {what} not a station session file (its first line is not a {FORMAT} header)"
    )


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
    if split.torn_reason and not allow_torn:
        raise SessionFileError(path, len(split.lines) + 1, f"torn: {split.torn_reason}")
    if not split.lines:
        raise SessionFileError(path, 1, "no complete header line (cut while being created?)")
    replay = Replay()
    for number, line in enumerate(split.lines, start=1):
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
    return replay, len(split.lines), split


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
    return replay.freeze(path, lines, torn)


SESSION_FILE_LIMIT = 1 << 30
"""The largest session file read (1 GiB, some 5 million readings): a bigger one is refused."""


def read_session_bytes(path: Path) -> bytes:
    """The file's bytes; StationError (exit 2) when it is missing, unreadable, not a regular
    file (a FIFO, a device, a folder) or larger than :data:`SESSION_FILE_LIMIT`."""
    from station.inputfiles import read_input_bytes

    if not os.path.lexists(path):
        raise StationError(f"session file {path} does not exist")
    return read_input_bytes(path, "session file", SESSION_FILE_LIMIT)


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
