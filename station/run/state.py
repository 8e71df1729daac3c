"""What the front ends read from the engine: immutable snapshots, the operator's next action and
the progress of the current step.

Front ends switch on :class:`Action` (a small closed set: confirm, input, zero, capture, stream,
finish, done), never on a step kind or a procedure id: a procedure with a new step kind runs in
every front end as long as its handler answers with one of these actions.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from station.text import format_figure

if TYPE_CHECKING:
    from station.procedures import InputField, Step
    from station.session.alarms import RecordedAlarm

StepMark = Literal["done", "current", "pending"]

RunnerStatus = Literal["running", "paused", "finished", "interrupted", "failed"]
"""``running`` (steps or cycles to do), ``paused`` (captures refused until resumed),
``finished`` (a ``finish`` event is written), ``interrupted`` (an ``interrupted`` event is written;
the file stays resumable), ``failed`` (a write failed; the file holds everything acknowledged)."""

MessageLevel = Literal["info", "warning", "error"]

ActionKind = Literal["confirm", "input", "zero", "capture", "stream", "finish", "done"]
ACTION_KINDS: tuple[str, ...] = ("confirm", "input", "zero", "capture", "stream", "finish", "done")
"""The closed set of operator actions. Each maps to one engine call: ``confirm`` ->
:meth:`~station.run.engine.Runner.confirm`, ``input`` -> ``submit_input``, ``zero`` -> ``zero``,
``capture`` -> ``capture``, ``stream`` -> ``stream_strokes``, ``finish`` -> ``finish``; ``done``
asks nothing (the session is closed)."""


@dataclass(frozen=True)
class Action:
    """The next thing the operator must do, as a front end needs it.

    ``may_confirm``: for ``capture`` and ``stream``, the step already has its minimum and may be
    closed with ``confirm`` (the operator may also go on capturing up to the target).
    ``fields``: for ``input``, what to type. ``prompt``: the sentence to show.
    """

    kind: ActionKind
    prompt: str = ""
    fields: tuple[InputField, ...] = ()
    may_confirm: bool = False
    paced_by_devices: bool = False
    """For ``capture``: the sets come by themselves (the robot's arrival, a DATA press), so a
    front end says so instead of asking for a key per cycle."""
    part: int | None = None
    """For ``capture`` in a step that presents numbered parts (a ``parts`` step): the part the
    next reading set is of, else None."""

    def __post_init__(self) -> None:
        if self.kind not in ACTION_KINDS:
            raise ValueError(f"unknown action {self.kind!r}")


@dataclass(frozen=True)
class Progress:
    """How far the current step is: ``done`` of ``target`` (at least ``minimum``) ``noun``s,
    e.g. 7 of 30 cycles (min 25), 2 of 6 strokes."""

    done: int
    target: int
    minimum: int
    noun: str
    """``cycle``, ``stroke``, ``reading``..., singular."""
    under_way: int = 0
    """Points of the stroke under way (streamed steps), else 0."""

    @property
    def complete(self) -> bool:
        """True when the target is reached."""
        return self.done >= self.target

    @property
    def enough(self) -> bool:
        """True when the minimum is reached."""
        return self.done >= self.minimum

    def text(self) -> str:
        """``7 of 30 cycles``."""
        return f"{self.done} of {self.target} {self.noun}s"


@dataclass(frozen=True)
class StepView:
    """One step of the unrolled procedure as the operator sees it."""

    index: int
    step: Step
    """The procedure's step (``id``, ``kind``, ``title``, ``text`` and the kind's own fields)."""
    placement: int | None
    """1-based placement inside a ``repeat`` block, else ``None``."""
    mark: StepMark

    @property
    def id(self) -> str:
        """The step's id in the procedure."""
        return self.step.id

    @property
    def kind(self) -> str:
        """The step's kind (for listing only: front ends act on :class:`Action`)."""
        return self.step.kind


@dataclass(frozen=True)
class OperatorMessage:
    """A sentence for the operator (a refused capture, a warning, an acknowledgement)."""

    level: MessageLevel
    text: str


@dataclass(frozen=True)
class PortState:
    """What one port is doing: ``connecting``, ``connected`` or ``disconnected``, and how many
    frames it rejected."""

    url: str
    status: str
    rejected_frames: int
    detail: str = ""


@dataclass(frozen=True)
class CycleRecord:
    """One recorded reading set (its ``reading`` event is on disk)."""

    cycle: int
    values: Mapping[str, float]
    step_id: str
    placement: int | None
    rejected: str | None = None
    """The reason when the cycle was rejected afterwards."""
    resolution: float | None = None
    """The session's gauge resolution: :meth:`line` shows that many decimals."""
    times: Mapping[str, float] | None = None
    """Each channel's reading time (``t_wall``), for the drift's trend; None when unknown."""
    part: int | None = None
    """The part a ``parts`` step measured in this cycle, else None."""

    def line(self) -> str:
        """The one-line form ``cycle 7 x=+0.00120 y=-0.00032 z=+0.00010`` (``cycle 7 part 3
        x=...`` for a part): the values as the session file holds them (after the zero, which
        is a mean and so no whole gauge step), in the one number format
        (:func:`~station.text.format_figure`): what the operator is told was captured is what
        was saved and is judged."""
        part = "" if self.part is None else f"part {self.part} "
        return f"cycle {self.cycle} {part}" + " ".join(
            f"{channel}={format_figure(value, self.resolution)}"
            for channel, value in self.values.items()
        )


class CycleLog(Sequence[CycleRecord]):
    """The recorded cycles at one moment: the first ``length`` records of the engine's list,
    which only grows (a reject replaces the list, never a record in it). Taking one costs the
    same at the 10 000th cycle as at the first; it never changes once taken."""

    __slots__ = ("_length", "_records", "accepted")

    def __init__(self, records: list[CycleRecord], accepted: int) -> None:
        self._records = records
        self._length = len(records)
        self.accepted = accepted
        """How many of them are not rejected."""

    def __len__(self) -> int:
        return self._length

    def __getitem__(self, index):  # type: ignore[override]
        if isinstance(index, slice):
            return tuple(self._records[i] for i in range(*index.indices(self._length)))
        if index < 0:
            index += self._length
        if not 0 <= index < self._length:
            raise IndexError(index)
        return self._records[index]

    def __iter__(self) -> Iterator[CycleRecord]:
        return itertools.islice(self._records, self._length)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence):
            return tuple(self) == tuple(other)
        return NotImplemented

    def __repr__(self) -> str:
        return f"CycleLog({list(self)!r})"


@dataclass(frozen=True)
class CycleOutcome:
    """The result of one capture attempt: recorded (the event is on disk) or refused, with the
    operator's sentence either way."""

    recorded: bool
    message: str
    cycle: CycleRecord | None = None
    port_down: bool = False
    """Refused only because a port was down for the whole wait (the line is reconnecting):
    not the gauges refusing a set, so a caller counting refusals should not count it."""
    waited: bool = False
    """Nothing arrived within the wait while the devices set the pace (push, arrival): the
    operator or the robot has not given a set yet, which is not a refused set."""


@dataclass(frozen=True)
class StrokeOutcome:
    """The result of one stroke: how many points were recorded (in ``samples`` events, all on
    disk) and how many reading sets were skipped because a channel was missing or stale."""

    stroke: int
    points: int
    skipped: int
    message: str
    direction: str = ""
    """``A→B`` or ``B→A`` when the travel split the stroke."""
    count: int = 0
    """Whole strokes recorded in the step with this one (the k of "stroke k of N")."""
    profile: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    """The stroke's points per channel (streamed strokes only), for a per-stroke figure."""

    def line(self) -> str:
        """The one-line form ``stroke 7 A→B 412 points`` (the count, not the file's number)."""
        return f"stroke {self.count or self.stroke} {self.direction} {self.points} points".replace(
            "  ", " "
        )


@dataclass(frozen=True)
class RunnerState:
    """An immutable snapshot of the engine, safe to read from any thread."""

    path: Path
    status: RunnerStatus
    steps: tuple[StepView, ...]
    current: StepView | None
    """The step to do now; ``None`` once every step is done (the session can be finished)."""
    action: Action
    """What the operator must do next."""
    progress: Progress | None
    """How far the current step is (steps that count something), else ``None``."""
    placement: int | None
    """The current placement p of a ``repeat`` block (1-based), else ``None``."""
    placements: int | None
    """P: how many placements the current ``repeat`` block has, else ``None``."""
    cycles: Sequence[CycleRecord]
    """Every recorded cycle of the session, rejected ones included (with their reason): a
    :class:`CycleLog`, or any sequence."""
    instruments: tuple[PortState, ...]
    messages: tuple[OperatorMessage, ...]
    """The latest operator messages, oldest first."""
    last_hash: str
    alarms: int
    """How many ``alarm`` events are in the file."""
    alarm_list: tuple[RecordedAlarm, ...] = ()
    """Every ``alarm`` event in the file, oldest first, with its acknowledgements (the alarm
    list reads them here, never through the engine's lock)."""
    failure: str = ""
    """Why the session failed (status ``failed``: a write failed, e.g. the disk is full);
    empty otherwise."""
    zero: Mapping[str, Any] = field(default_factory=dict)
    """The zero in force per channel: its last ``zero`` event's entry (method, offset, n,
    mean, spread...)."""
    next_cycle: int = 1
    """The number the next recorded cycle gets (numbering runs over the whole session and
    skips nothing: a rejected cycle keeps its number)."""

    @property
    def accepted(self) -> int:
        """Cycles recorded and not rejected, over the whole session."""
        if isinstance(self.cycles, CycleLog):
            return self.cycles.accepted
        return sum(1 for record in self.cycles if record.rejected is None)

    @property
    def last_cycle(self) -> CycleRecord | None:
        """The most recent recorded cycle, or ``None``."""
        return self.cycles[-1] if self.cycles else None

    @property
    def can_capture(self) -> bool:
        """True when a capture would be recorded (the action is ``capture``)."""
        return self.status == "running" and self.action.kind == "capture"

    @property
    def complete(self) -> bool:
        """True when every step is done."""
        return self.current is None


@dataclass(frozen=True)
class RunnerNotice:
    """What the listener receives: the event just written (``None`` for a change that is not
    in the file: instrument status, a refused capture), the state after it and, when the
    analysis changed, the live analysis after it (so a display never asks the engine)."""

    event: Mapping[str, Any] | None
    state: RunnerState
    message: OperatorMessage | None = None
    analysis: Any = None
    """The live analysis (the kind's snapshot) when this notice changed it, else ``None``."""
    result: Any = None
    """With ``analysis``: the kind's own live result (per-stroke straightness...), or None."""


Listener = Callable[[RunnerNotice], None]
