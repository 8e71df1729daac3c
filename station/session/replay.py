"""Replay: the one place that knows what a valid header and a valid event are.

:class:`Replay` checks each record of a session file in order and accumulates what they add up
to: the cycles and their readings, rejects, notes, alarms, inputs, streamed points and the
session's status. The writer checks every event with it before writing, and the loader replays
a file with it, so a file the writer produced always loads. The table :data:`_EVENT_CHECKS`
holds one check per event type. Like the model, it loads numpy only when arrays are asked for
(:meth:`SampleBatch.as_arrays`).
"""

from __future__ import annotations

import math
from array import array
from bisect import bisect_right
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from station.session.lines import FORMAT, line_hash

if TYPE_CHECKING:
    import numpy as np

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
    "trace",
    "resume",
    "interrupted",
    "finish",
)
RESERVED_FIELDS: frozenset[str] = frozenset({"seq", "t", "type", "prev", "hash"})
"""Fields the journal sets itself; an event cannot carry them."""
HEADER_REQUIRED: tuple[str, ...] = ("robot", "procedure", "channels", "unit")
"""Header fields the caller of ``SessionWriter.create`` must give."""

Status = Literal["running", "interrupted", "finished"]


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
    part: int | None = None
    """The part a ``parts`` step measured in this cycle (1, 2 ...), when any."""


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
class Trace:
    """One ``trace`` event: the gauges' trace of one return under the arrival trigger (the
    approach, the settling, the rest), recorded after the cycle it ended in. ``t`` is each
    row's seconds after ``t0`` (the event's ``times``; ``t0`` the first arrival, on the reading
    clock), ``every`` how many rows came per row kept (the trace is bounded: a long one is
    decimated)."""

    seq: int
    cycle: int
    step: str
    channels: tuple[str, ...]
    t: tuple[float, ...]
    values: tuple[tuple[float, ...], ...]
    every: int = 1
    t0: float | None = None

    def as_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The times and the rows (one column per channel) as arrays."""
        import numpy as np

        rows = np.asarray(self.values, dtype=float).reshape(len(self.values), len(self.channels))
        return np.asarray(self.t, dtype=float), rows


def _is_number(value: Any) -> bool:
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        return False


READING_LIMIT = 1e150
"""The largest magnitude a recorded value or limit may have, in a session file or a CSV table:
squares and sums of ten million of them stay finite floats (a 1e308 would overflow the mean and
sigma into nonsense)."""
CYCLE_LIMIT = 2**53
"""Cycle numbers stay exact as floats and fit every integer array."""
COUNT_LIMIT = 1_000_000
"""The largest cycle, placement or stroke target a header may ask for."""


def _is_reading(value: Any) -> bool:
    return _is_number(value) and abs(value) <= READING_LIMIT


def _optional_number(value: Any) -> float | None:
    return float(value) if _is_number(value) else None


class CycleSeqs(Mapping[int, int]):
    """The recorded cycle numbers, each with the seq of its reading event: what checking a
    later reading or reject needs (a second reading of a cycle names the first one's seq).

    Held as runs while the numbers ascend (the engine numbers cycles so, a resumed session
    included): a run is cycles ``first``, ``first + 1`` ... whose seqs step by the same stride,
    four 8-byte integers however long it is. A session's cycles make one run between two other
    events (a reject, an alarm, a note), so ``station verify`` and a writer hold a session of
    millions of readings in a few kilobytes. Only a number that comes out of order turns the
    runs into a dict, a hundred bytes a cycle.
    """

    def __init__(self) -> None:
        self._first = array("q")
        self._seq = array("q")
        self._stride = array("q")
        self._count = array("q")
        self._total = 0
        self._unordered: dict[int, int] | None = None
        self.highest = 0
        """The largest cycle number recorded (0 before any)."""

    def add(self, cycle: int, seq: int) -> None:
        """Record that ``cycle``'s reading is event ``seq`` (a cycle not recorded yet)."""
        self._total += 1
        if self._unordered is not None:
            self._unordered[cycle] = seq
        elif not self._first or cycle > self.highest:
            self._extend(cycle, seq)
        else:
            self._unordered = dict(self._pairs())
            self._unordered[cycle] = seq
            for column in (self._first, self._seq, self._stride, self._count):
                del column[:]
        self.highest = max(self.highest, cycle)

    def _extend(self, cycle: int, seq: int) -> None:
        if self._first:
            first, start, count = self._first[-1], self._seq[-1], self._count[-1]
            stride = seq - start if count == 1 else self._stride[-1]
            if cycle == first + count and seq == start + count * stride:
                self._stride[-1] = stride
                self._count[-1] = count + 1
                return
        self._first.append(cycle)
        self._seq.append(seq)
        self._stride.append(0)
        self._count.append(1)

    def _pairs(self) -> Iterator[tuple[int, int]]:
        for first, seq, stride, count in zip(
            self._first, self._seq, self._stride, self._count, strict=True
        ):
            for step in range(count):
                yield first + step, seq + step * stride

    def _run(self, cycle: object) -> int | None:
        if not isinstance(cycle, int) or not self._first or cycle > self.highest:
            return None
        at = bisect_right(self._first, cycle) - 1
        return at if at >= 0 and cycle < self._first[at] + self._count[at] else None

    def __getitem__(self, cycle: int) -> int:
        if self._unordered is not None:
            return self._unordered[cycle]
        at = self._run(cycle)
        if at is None:
            raise KeyError(cycle)
        return self._seq[at] + (cycle - self._first[at]) * self._stride[at]

    def __contains__(self, cycle: object) -> bool:
        if self._unordered is not None:
            return cycle in self._unordered
        return self._run(cycle) is not None

    def __iter__(self) -> Iterator[int]:
        if self._unordered is not None:
            return iter(self._unordered)
        return (cycle for cycle, _ in self._pairs())

    def __len__(self) -> int:
        return self._total


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
    traces: list[Trace] = field(default_factory=list)
    confirmed_steps: list[str] = field(default_factory=list)
    status: Status = "running"
    last_seq: int = 0
    last_hash: str | None = None
    """The last line's own ``hash`` field: the anchor printed on summaries and reports."""
    chain_hash: str | None = None
    """The sha256 of the last line's bytes: the next line's ``prev``."""
    cycle_seqs: CycleSeqs = field(default_factory=CycleSeqs)
    """The seq of each recorded cycle's reading, by cycle number: what checking a later reading
    or reject needs (kept in every mode; :attr:`cycles` holds the cycles themselves)."""
    alarm_seqs: set[int] = field(default_factory=set)
    """The seqs of the alarm events: what checking an acknowledgement needs."""
    checks_only: bool = False
    """A writer's (or ``station verify``'s) replay: keep what checking the next event needs
    (the header, the cycle numbers, rejects, alarm seqs, inputs), not every event's record, its
    cycles and readings, alarms or streamed points, so a long session's memory stays small (the
    file keeps everything)."""

    def keep_checks_only(self) -> None:
        """Drop what only a reader of the whole session needs (see :attr:`checks_only`)."""
        self.checks_only = True
        self.events.clear()
        self.cycles.clear()
        self.alarms.clear()
        self.samples.clear()
        self.traces.clear()
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
        if kind == "reading":
            # Checking later events needs the cycle's number (and seq), not its values.
            self.cycle_seqs.add(record["cycle"], record["seq"])
        elif kind == "alarm":
            self.alarm_seqs.add(record["seq"])
        if kind == "reading" and not self.checks_only:
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
                part=record.get("part"),
            )
        elif kind == "reject":
            self.rejected[record["cycle"]] = record["reason"]
        elif kind == "note" and not self.checks_only:
            self.notes.append(record)
        elif kind == "alarm" and not self.checks_only:
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
        elif kind == "trace" and not self.checks_only:
            t0 = record.get("t0")
            self.traces.append(
                Trace(
                    seq=record["seq"],
                    cycle=record["cycle"],
                    step=record["step"],
                    channels=tuple(record["channels"]),
                    t=tuple(float(v) for v in record["times"]),
                    values=tuple(tuple(float(v) for v in row) for row in record["values"]),
                    every=int(record.get("every", 1)),
                    t0=_optional_number(t0),
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
    if cycle in replay.cycle_seqs:
        raise ValueError(f"cycle {cycle} is recorded twice (seq {replay.cycle_seqs[cycle]})")
    part = record.get("part")
    if part is not None and not (
        isinstance(part, int) and not isinstance(part, bool) and 1 <= part <= COUNT_LIMIT
    ):
        raise ValueError(f"a reading's 'part' must be a whole number from 1 to {COUNT_LIMIT}")
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
    if cycle not in replay.cycle_seqs:
        raise ValueError(f"a reject names cycle {cycle}, which was never recorded")
    _need_text(record, "reason")


def _check_note(replay: Replay, record: Mapping[str, Any]) -> None:
    _need_text(record, "text")


def _check_rows(replay: Replay, record: Mapping[str, Any], kind: str) -> list[Any]:
    """A ``samples`` or ``trace`` event's ``step``, ``channels`` and ``values``; the rows."""
    _need_text(record, "step")
    channels = record.get("channels")
    if (
        not isinstance(channels, list)
        or not channels
        or not all(isinstance(c, str) and c in replay.header["channels"] for c in channels)
    ):
        raise ValueError(f"a {kind} event needs 'channels', a list of the session's channels")
    values = record.get("values")
    if not isinstance(values, list) or not all(
        isinstance(row, list) and len(row) == len(channels) and all(map(_is_reading, row))
        for row in values
    ):
        raise ValueError(f"a {kind} event needs 'values', rows of one number per channel")
    return values


def _check_trace(replay: Replay, record: Mapping[str, Any]) -> None:
    """A return's trace: ``cycle`` (a recorded cycle), ``step``, ``channels``, ``values`` (rows),
    ``times`` (one per row, s after ``t0``, never going back), ``every`` (rows per row kept)."""
    cycle = _need_cycle(record)
    if cycle not in replay.cycle_seqs:
        raise ValueError(f"a trace event names cycle {cycle}, which is not a recorded cycle")
    values = _check_rows(replay, record, "trace")
    times = record.get("times")
    if (
        not isinstance(times, list)
        or len(times) != len(values)
        or not all(map(_is_number, times))
        or any(b < a for a, b in zip(times, times[1:], strict=False))
    ):
        raise ValueError("a trace event's 'times' must hold one time per row, never going back")
    every = record.get("every", 1)
    if not isinstance(every, int) or isinstance(every, bool) or every < 1:
        raise ValueError("a trace event's 'every' must be a whole number, 1 or more")
    if "t0" in record and not _is_number(record["t0"]):
        raise ValueError("a trace event's 't0' must be a number")


def _check_samples(replay: Replay, record: Mapping[str, Any]) -> None:
    values = _check_rows(replay, record, "samples")
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
    if alarm not in replay.alarm_seqs:
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
    "trace": _check_trace,
    "resume": _check_free,
    "interrupted": _check_free,
    "finish": _check_free,
}
