"""The procedure runner: one state machine that turns a procedure's steps, the operator's actions
and the instruments' readings into session events.

The TUI and ``station capture`` both drive a :class:`Runner`; nothing about how a step behaves
lives anywhere else. The runner never imports a UI. Its rules:

* A step is *done* when its ``step`` event is on disk. ``check`` steps are done by
  :meth:`Runner.confirm`; ``input`` steps by :meth:`Runner.submit_input` (an ``input`` event, then
  the ``step`` event); ``zero`` steps by :meth:`Runner.zero`; a ``capture`` step by one recorded
  reading set; a ``cycles`` step by :meth:`Runner.confirm` once at least the procedure's minimum
  of accepted cycles is recorded (``station capture`` confirms when the target is reached); a
  ``stroke`` step by :meth:`Runner.confirm` once its minimum of strokes is streamed
  (:meth:`Runner.stroke` until :meth:`Runner.end_stroke`, points in ``samples`` events). A
  ``repeat`` block is unrolled into its steps once per placement.
* A cycle is recorded only when every channel the step needs has a fresh reading from this
  trigger. A missing, stale or duplicated channel is an operator message and nothing is written.
* *Acknowledged* means: the ``reading`` event is fsynced (the journal's ``append`` returns only
  then). :meth:`Runner.capture` returns, and the listener is called, after that.
* Cycles are numbered 1, 2, ... over the whole session; a rejected cycle keeps its number (readings
  are never deleted), a resumed session continues the numbering.
* Alarms of the live analysis are written as ``alarm`` events when they first appear.

Threads: every public method may be called from any thread. A lock serialises journal writes
and state changes; blocking waits on the instruments happen outside it, so :meth:`interrupt`
(from a signal handler's thread) never waits for a capture timeout. Whatever arrives on a
reader's thread (a completed ``push`` set, a port's state change) is queued, without the lock,
to the runner's own intake thread, which writes it (so the reader keeps draining the line while
the disk syncs). A push set becomes a cycle while the ``cycles`` or ``capture`` step that was
current when it arrived still is, the runner is not paused, and the step does not have its count
yet. A capture, zero or stroke records only into the step it was started in: confirming a
``cycles`` step waits until the capture under way ends.

A resumed session puts the recorded zero back on the gauges (each channel's last ``zero``
event), so cycles after the resume are zeroed like those before it. A failed write (a full
disk) makes the runner ``failed``; every later action raises the journal's own sentence
(:attr:`Runner.failure`).

The listener receives a :class:`RunnerNotice` after every event is on disk (and for messages
that are not in the file), on whichever thread produced it; it must not block. Alarms: the live
update's alarms are written as each cycle arrives; the full analysis' alarms (which can flag
an earlier pattern once the limits have moved) at the end of every capture/cycles step and
before the finish. An alarm is new unless it flags a cycle an alarm of the same rule and
channel already flagged (a run growing by a point is one alarm).
"""

from __future__ import annotations

import contextlib
import math
import queue
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from station.errors import StationError
from station.instruments.base import SerialSettings
from station.instruments.gauge import TRIGGERS, Trigger, unit_mismatch

if TYPE_CHECKING:
    from station.analysis.summary import Analysis
    from station.procedures import Procedure, Step

StepMark = Literal["done", "current", "pending"]

RunnerStatus = Literal["running", "paused", "finished", "interrupted", "failed"]
"""``running`` (steps or cycles to do), ``paused`` (captures refused until resumed),
``finished`` (a ``finish`` event is written), ``interrupted`` (an ``interrupted`` event is written;
the file stays resumable), ``failed`` (a write failed; the file holds everything acknowledged)."""

MessageLevel = Literal["info", "warning", "error"]

CAPTURE_BY = "station capture"
"""The ``by`` recorded when the headless command confirms a step itself."""

_MESSAGES_KEPT = 20


def value_decimals(resolution: float | None) -> int:
    """How many decimals a gauge of ``resolution`` shows (0.0001 -> 4, 0.0005 -> 4, 0.002 -> 3,
    1e-05 -> 5); 5 when the resolution is unknown."""
    if resolution is None or not math.isfinite(resolution) or resolution <= 0:
        return 5
    from decimal import Decimal

    exponent = Decimal(repr(float(resolution))).normalize().as_tuple().exponent
    return max(0, -int(exponent))


def format_value(value: float, resolution: float | None) -> str:
    """A reading as the gauge shows it: signed, at its resolution's decimals (``+0.0012``).

    Rounding to the display is what the operator reads; the file keeps the full value."""
    text = f"{value:+.{value_decimals(resolution)}f}"
    # -0.00004 at four decimals would read "-0.0000": a zero has no sign worth showing.
    return "+" + text[1:] if text.startswith("-") and not text.strip("-0.") else text


@dataclass(frozen=True)
class PortSetup:
    """One serial line: where it is, what it speaks, and which station channel each device
    channel feeds (``{"1": "x", "2": "y", "3": "z"}``). ``settings`` ``None`` means the
    protocol's own line settings."""

    url: str
    protocol: str
    channel_map: Mapping[str, str]
    settings: SerialSettings | None = None

    def resolved_settings(self) -> SerialSettings:
        """The line settings in force: the given ones, else the protocol's."""
        from station.instruments.protocols import get_protocol

        return self.settings or get_protocol(self.protocol).settings

    def header(self) -> dict[str, Any]:
        """The port as it is recorded in the session header's ``instruments``."""
        return {
            "url": self.url,
            "protocol": self.protocol,
            "map": dict(self.channel_map),
            "settings": self.resolved_settings().as_kwargs(),
        }

    @classmethod
    def from_header(cls, recorded: Mapping[str, Any]) -> PortSetup:
        """The port a session header recorded (for resuming on the same line)."""
        settings = recorded.get("settings")
        return cls(
            url=str(recorded["url"]),
            protocol=str(recorded["protocol"]),
            channel_map={str(k): str(v) for k, v in dict(recorded.get("map") or {}).items()},
            settings=SerialSettings(**settings) if settings else None,
        )


@dataclass(frozen=True)
class SessionSetup:
    """What the set-up screen or the ``station capture`` flags collect before a session starts.

    ``None`` for ``unit``, ``resolution``, ``limits`` or ``cycles`` means the procedure's own
    value. Construction validates and raises :class:`StationError` with a sentence naming the
    field, so a set-up screen can show it next to the field.
    """

    procedure: Procedure
    robot: str
    operator: str
    ports: tuple[PortSetup, ...]
    trigger: Trigger = "poll"
    unit: str | None = None
    resolution: float | None = None
    limits: Mapping[str, Any] | None = None
    """Per channel a :class:`station.analysis.capability.SpecLimits` (or anything with ``lsl``,
    ``usl`` and ``nominal``)."""
    cycles: int | None = None
    rule_set: str = "report"
    threshold: float = 1.0
    placements: int | None = None
    """How many times each ``repeat`` block runs (fixture placements); ``None``: its target."""
    strokes: int | None = None
    """How many whole strokes each ``stroke`` step asks for; ``None``: its target."""

    def __post_init__(self) -> None:
        if not self.robot.strip():
            raise StationError("the robot name is empty: name the robot under test")
        if self.trigger not in TRIGGERS:
            raise StationError(
                f"unknown trigger {self.trigger!r}: use one of {', '.join(TRIGGERS)}"
            )
        if self.cycles is not None and self.cycles < 1:
            raise StationError(f"cycles must be at least 1, not {self.cycles}")
        if self.placements is not None and self.placements < 1:
            raise StationError(f"placements must be at least 1, not {self.placements}")
        if self.strokes is not None and self.strokes < 1:
            raise StationError(f"strokes must be at least 1, not {self.strokes}")
        if self.resolution is not None and not (
            math.isfinite(self.resolution) and self.resolution > 0
        ):
            raise StationError(f"the gauge resolution must be positive, not {self.resolution}")
        if not math.isfinite(self.threshold) or self.threshold <= 0:
            raise StationError(f"the capability threshold must be positive, not {self.threshold}")
        unknown = sorted(set(self.limits or {}) - set(self.channels))
        if unknown:
            raise StationError(
                f"limits given for {', '.join(unknown)}, which procedure "
                f"{self.procedure.id!r} does not measure (its channels: "
                f"{', '.join(self.channels)})"
            )
        if not self.ports:
            raise StationError("no port given: name the serial port of the indicators")
        mapped = {ch for port in self.ports for ch in port.channel_map.values()}
        missing = [ch for ch in self.channels if ch not in mapped]
        if missing:
            raise StationError(
                f"no device channel feeds {', '.join(missing)}: map one with --map, "
                f"e.g. 1=x,2=y,3=z"
            )

    @property
    def channels(self) -> tuple[str, ...]:
        """The station channels the procedure measures, in its order."""
        return tuple(self.procedure.channels)

    @property
    def resolved_unit(self) -> str:
        """The session's unit: the set-up's, else the procedure's."""
        return self.unit or self.procedure.unit

    @property
    def resolved_resolution(self) -> float:
        """The gauge resolution: the set-up's, else the procedure's."""
        return float(self.resolution if self.resolution is not None else self.procedure.resolution)

    @property
    def resolved_cycles(self) -> int:
        """The number of cycles a ``cycles`` step asks for: the set-up's, else the procedure's
        target."""
        return int(self.cycles if self.cycles is not None else self.procedure.cycles_target)

    def resolved_limits(self) -> dict[str, Any]:
        """Spec limits per channel: the procedure's defaults overridden by the set-up's."""
        return _procedure_limits(self.procedure) | dict(self.limits or {})

    def header_fields(self) -> dict[str, Any]:
        """The session header's fields (the journal adds format, session id, created, prev)."""
        return {
            "procedure": {
                "id": self.procedure.id,
                "version": self.procedure.version,
                "sha256": self.procedure.sha256,
                "analysis": self.procedure.analysis,
            },
            "robot": self.robot,
            "operator": self.operator,
            "host": socket.gethostname(),
            "unit": self.resolved_unit,
            "resolution": self.resolved_resolution,
            "limits": {
                channel: {"lsl": limits.lsl, "usl": limits.usl, "nominal": limits.nominal}
                for channel, limits in self.resolved_limits().items()
            },
            "channels": list(self.channels),
            "instruments": {
                "trigger": self.trigger,
                "ports": [port.header() for port in self.ports],
            },
            "cycles_target": self.resolved_cycles,
            # The count below which a verdict is provisional, and when the live limits freeze.
            "cycles_min": self.procedure.cycles_min,
            "freeze_after": self.procedure.cycles_min,
            **({"placements_target": self.placements} if self.placements else {}),
            **({"strokes_target": self.strokes} if self.strokes else {}),
            "rules": self.rule_set,
            "threshold": self.threshold,
        }


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
        """``check``, ``input``, ``zero``, ``capture``, ``cycles`` or ``stroke``."""
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

    def line(self) -> str:
        """The one-line form ``cycle 7 x=+0.0012 y=-0.0003 z=+0.0001`` (values at the
        resolution's decimals, :func:`format_value`)."""
        return f"cycle {self.cycle} " + " ".join(
            f"{channel}={format_value(value, self.resolution)}"
            for channel, value in self.values.items()
        )


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


@dataclass(frozen=True)
class StrokeOutcome:
    """The result of one stroke: how many points were recorded (in ``samples`` events, all on
    disk) and how many reading sets were skipped because a channel was missing or stale."""

    stroke: int
    points: int
    skipped: int
    message: str
    direction: str = ""
    """``A→B`` or ``B→A`` when the travel split the stroke (:meth:`Runner.stream_strokes`)."""
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
    """An immutable snapshot of the runner, safe to read from any thread."""

    path: Path
    status: RunnerStatus
    steps: tuple[StepView, ...]
    current: StepView | None
    """The step to do now; ``None`` once every step is done (the session can be finished)."""
    cycle: int
    """Accepted cycles in the current ``cycles`` step (the k of "cycle k of N")."""
    cycles_target: int
    """N: the cycles the current (or last) ``cycles`` step asks for."""
    cycles_min: int
    placement: int | None
    """The current placement p of a ``repeat`` block (1-based), else ``None``."""
    placements: int | None
    """P: how many placements the current ``repeat`` block has, else ``None``."""
    cycles: tuple[CycleRecord, ...]
    """Every recorded cycle of the session, rejected ones included (with their reason)."""
    instruments: tuple[PortState, ...]
    messages: tuple[OperatorMessage, ...]
    """The latest operator messages, oldest first."""
    last_hash: str
    alarms: int
    """How many ``alarm`` events are in the file."""
    strokes: int = 0
    """Strokes recorded in the current ``stroke`` step."""
    strokes_target: int = 0
    """How many strokes the current ``stroke`` step asks for (0 outside one)."""
    stroke_points: int = 0
    """Points streamed so far in the stroke under way (0 when none is)."""
    failure: str = ""
    """Why the session failed (status ``failed``: a write failed, e.g. the disk is full);
    empty otherwise."""

    @property
    def accepted(self) -> int:
        """Cycles recorded and not rejected, over the whole session."""
        return sum(1 for record in self.cycles if record.rejected is None)

    @property
    def last_cycle(self) -> CycleRecord | None:
        """The most recent recorded cycle, or ``None``."""
        return self.cycles[-1] if self.cycles else None

    @property
    def can_capture(self) -> bool:
        """True when a capture would be recorded (a capture step is current, not paused)."""
        return (
            self.status == "running"
            and self.current is not None
            and self.current.kind in ("capture", "cycles")
        )

    @property
    def complete(self) -> bool:
        """True when every step is done."""
        return self.current is None


Listener = Callable[["RunnerNotice"], None]


@dataclass(frozen=True)
class RunnerNotice:
    """What the listener receives: the event just written (``None`` for a change that is not
    in the file: instrument status, a refused capture), and the state after it."""

    event: Mapping[str, Any] | None
    state: RunnerState
    message: OperatorMessage | None = None


# --------------------------------------------------------------------------------------------
# Set-up helpers shared by the TUI and `station capture`


def _procedure_limits(procedure: Procedure) -> dict[str, Any]:
    from station.analysis.capability import SpecLimits

    return {
        channel: SpecLimits(lsl=limit.lsl, usl=limit.usl, nominal=limit.nominal)
        for channel, limit in procedure.limits.items()
    }


def header_limits(header: Mapping[str, Any]) -> dict[str, Any]:
    """The spec limits a session header records, as a
    :class:`~station.analysis.capability.SpecLimits` per channel it measures; a channel with
    neither an LSL nor a USL has none."""
    from station.analysis.capability import SpecLimits

    channels = header.get("channels")
    return {
        str(channel): SpecLimits(
            lsl=spec.get("lsl"), usl=spec.get("usl"), nominal=spec.get("nominal")
        )
        for channel, spec in dict(header.get("limits") or {}).items()
        if (channels is None or channel in channels)
        and isinstance(spec, Mapping)
        and (spec.get("lsl") is not None or spec.get("usl") is not None)
    }


def _reading_times(readings: Mapping[str, Any]) -> dict[str, float] | None:
    """Each channel's ``t_wall`` (the drift's trend runs on reading times), or None when a
    reading has none (the trend then runs on cycle order, as the session file's analysis)."""
    times = {channel: getattr(r, "t_wall", None) for channel, r in readings.items()}
    if any(t is None for t in times.values()):
        return None
    return {channel: float(t) for channel, t in times.items()}


def analysis_config(header: Mapping[str, Any]) -> Any:
    """The :class:`~station.analysis.summary.AnalysisConfig` a session header implies: its
    limits, resolution, unit, rule set and threshold (single readings, subgroup 1).

    The live analysis of a running session and the batch analysis of its file are both built
    from this, so the two agree.
    """
    from station.analysis.phases import DEFAULT_FREEZE_AFTER, baseline_from_json
    from station.analysis.summary import AnalysisConfig
    from station.analysis.verdict import DEFAULT_MIN_N

    resolution = header.get("resolution")
    minimum, freeze = header.get("cycles_min"), header.get("freeze_after")
    return AnalysisConfig(
        limits=header_limits(header),
        resolution=float(resolution) if isinstance(resolution, int | float) else None,
        unit=str(header.get("unit") or ""),
        rule_set=str(header.get("rules") or "report"),
        threshold=float(header.get("threshold") or 1.0),
        min_n=minimum if isinstance(minimum, int) and minimum >= 0 else DEFAULT_MIN_N,
        freeze_after=freeze if isinstance(freeze, int) and freeze >= 2 else DEFAULT_FREEZE_AFTER,
        baseline=baseline_from_json(header.get("baseline")),
    )


def setup_from_header(
    header: Mapping[str, Any],
    procedure: Procedure,
    *,
    ports: Sequence[PortSetup] | None = None,
) -> SessionSetup:
    """The set-up a session header records, to resume it. ``ports`` replaces the recorded
    ports (a USB adapter that came back under another name)."""
    instruments = dict(header.get("instruments") or {})
    recorded_ports = tuple(PortSetup.from_header(p) for p in instruments.get("ports") or ())
    cycles = header.get("cycles_target")
    placements, strokes = header.get("placements_target"), header.get("strokes_target")
    return SessionSetup(
        procedure=procedure,
        robot=str(header["robot"]),
        operator=str(header.get("operator") or ""),
        ports=tuple(ports) if ports else recorded_ports,
        trigger=instruments.get("trigger", "poll"),
        unit=str(header["unit"]),
        resolution=float(header["resolution"]) if header.get("resolution") else None,
        limits=header_limits(header),
        cycles=int(cycles) if isinstance(cycles, int) else None,
        rule_set=str(header.get("rules") or "report"),
        threshold=float(header.get("threshold") or 1.0),
        placements=placements if isinstance(placements, int) else None,
        strokes=strokes if isinstance(strokes, int) else None,
    )


def open_gauges(
    setup: SessionSetup,
    *,
    backoff: tuple[float, float] | None = None,
    on_reading: Callable[[Any], object] | None = None,
    poll_interval: float = 0.1,
) -> Any:
    """Build and start the :class:`~station.instruments.gauge.GaugeSet` the set-up describes.

    The runner attaches its own set and status callbacks; ``on_reading`` (every accepted
    frame, on a reader thread) is for a live display. The caller stops the set when done.
    """
    from station.instruments.gauge import DEFAULT_BACKOFF, GaugeSet, PortSpec
    from station.instruments.protocols import get_protocol

    specs = [
        PortSpec(
            url=port.url,
            protocol=get_protocol(port.protocol),
            channel_map=dict(port.channel_map),
            settings=port.settings,
        )
        for port in setup.ports
    ]
    gauges = GaugeSet(
        specs,
        trigger=setup.trigger,
        unit=setup.resolved_unit,
        resolution=setup.resolved_resolution,
        poll_interval=poll_interval,
        on_reading=on_reading,
        backoff=backoff or DEFAULT_BACKOFF,
    )
    gauges.start()
    return gauges


# --------------------------------------------------------------------------------------------
# The runner


@dataclass(frozen=True)
class _PlanItem:
    """One step of the unrolled procedure (a repeat block's steps appear once per placement)."""

    step: Step
    placement: int | None
    placements: int | None

    @property
    def key(self) -> tuple[str, int | None]:
        return (self.step.id, self.placement)


def _unroll(procedure: Procedure, placements: int | None = None) -> tuple[_PlanItem, ...]:
    items: list[_PlanItem] = []
    for step in procedure.steps:
        if step.kind == "repeat":
            count = int(placements or step.count_target or 1)
            for placement in range(1, count + 1):
                items.extend(_PlanItem(inner, placement, count) for inner in step.steps)
        else:
            items.append(_PlanItem(step, None, None))
    return tuple(items)


class Runner:
    """The state machine of one session; build it with :meth:`start` or :meth:`resume`.

    ``gauges`` is a started :class:`~station.instruments.gauge.GaugeSet` (see
    :func:`open_gauges`); the runner sets its push-set callback and listens to its ports'
    status, and the caller stops it after :meth:`finish` or :meth:`interrupt`.
    """

    def __init__(
        self,
        setup: SessionSetup,
        gauges: Any,
        writer: Any,
        *,
        listener: Listener | None = None,
    ) -> None:
        self.setup = setup
        self.gauges = gauges
        self._writer = writer
        self._listener = listener
        self._lock = threading.RLock()
        self._outcome_ready = threading.Condition(self._lock)
        self._outcomes = 0
        self._last_outcome: CycleOutcome | None = None
        self._plan = _unroll(setup.procedure, setup.placements)
        self._position = 0
        self._status: RunnerStatus = "running"
        self._busy = False
        self._cycles: list[CycleRecord] = []
        # Accepted cycles per (step id, placement) and in all: kept as counts so that a state
        # snapshot costs the same at the 10 000th cycle as at the first.
        self._accepted_by_step: dict[tuple[str, int | None], int] = {}
        self._accepted_count = 0
        self._next_cycle = 1
        # Strokes recorded per (step id, placement); the stroke under way and its stop signal.
        self._strokes: dict[tuple[str, int | None], int] = {}
        # The last stroke number written per step: partial segments (a lead-in, a stroke cut
        # by an interruption) keep their own numbers, so numbers never repeat.
        self._stroke_numbers: dict[tuple[str, int | None], int] = {}
        self._stream_queue: queue.SimpleQueue[Any] | None = None
        # Hands the stream queue over between a streamed stroke and the reader thread, so a
        # push set never waits for the runner's lock (the step position and the busy flag are
        # read there as single attributes).
        self._intake_lock = threading.Lock()
        self._claimed_position = -1
        # The last zero event's entry per channel ({"method", "offset"}), kept on resume.
        self._recorded_zero: dict[str, dict[str, Any]] = {}
        self._failure: str | None = None
        self._intake: queue.SimpleQueue[tuple[Any, ...] | None] | None = None
        self._hooked: list[tuple[Any, Any, Any]] = []
        self._warned_position = -1
        self._stroke_points = 0
        self._stroke_stop = threading.Event()
        self._messages: deque[OperatorMessage] = deque(maxlen=_MESSAGES_KEPT)
        self._alarm_count = 0
        # (channel, rule) -> the cycles recorded alarms flagged: an alarm sharing one of them is
        # the same pattern continuing (a run growing by a point), not a new one.
        self._alarm_flagged: dict[tuple[str, str], set[int]] = {}
        self._port_states: dict[str, str] = {}
        self.config = analysis_config(writer.snapshot().header)
        self._live = self._new_live()
        self._views: tuple[StepView, ...] = ()
        self._views_position = -1
        self._last_event: dict[str, Any] | None = None

    # -- construction -------------------------------------------------------------------------

    @classmethod
    def start(
        cls,
        setup: SessionSetup,
        gauges: Any,
        sessions_dir: str | Path,
        *,
        listener: Listener | None = None,
    ) -> Runner:
        """Create the session file (its header is on disk when this returns) and begin at the
        procedure's first step."""
        from station.session.journal import SessionWriter

        writer = SessionWriter.create(sessions_dir, setup.header_fields())
        runner = cls(setup, gauges, writer, listener=listener)
        runner._attach("when the session started")
        runner._say("info", f"Session file {writer.path}.")
        return runner

    @classmethod
    def resume(
        cls,
        path: str | Path,
        gauges: Any,
        *,
        setup: SessionSetup | None = None,
        procedures_dirs: Sequence[str | Path] = (),
        listener: Listener | None = None,
        by: str = "operator",
    ) -> Runner:
        """Continue an unfinished session: a torn tail is moved aside, a ``resume`` event is
        written, the steps already done stay done and cycle numbering continues.

        ``setup`` defaults to :func:`resume_setup` of the file (the recorded ports).
        """
        from station.session.journal import SessionWriter

        setup = setup or resume_setup(path, procedures_dirs=procedures_dirs)
        # The resume event records the line in use now: a USB adapter may have come back under
        # another name, and the header keeps the one the session began on.
        instruments = setup.header_fields()["instruments"]
        writer, session = SessionWriter.resume(path, by=by, instruments=instruments)
        try:
            runner = cls(setup, gauges, writer, listener=listener)
            runner._replay(session)
            device_zeroed = runner._restore_zero()
        except BaseException:
            writer.close()  # release the file's lock: the session stays resumable
            raise
        # Only now may readings and port changes reach the runner: its state is the file's.
        runner._attach("when the session resumed")
        if session.torn is not None:
            runner._say("warning", session.torn.message)
        if device_zeroed:
            runner._say(
                "warning",
                f"{', '.join(device_zeroed)} {'was' if len(device_zeroed) == 1 else 'were'} "
                "zeroed by the gauges' own command: if they were switched off since, they no "
                "longer are. Check that they read zero at the zero position before going on.",
            )
        if setup.procedure.sha256 != session.header["procedure"]["sha256"]:
            runner._say(
                "warning",
                f"The procedure file {setup.procedure.path} changed since this session began; "
                "its steps are followed as they are now.",
            )
        runner._say(
            "info",
            f"Resumed {writer.path}: {runner._accepted_total()} cycles so far; "
            f"the next cycle is {runner._next_cycle}.",
        )
        runner._notify(None)
        return runner

    def _replay(self, session: Any) -> None:
        """Rebuild the state from a session's events (resume)."""
        with self._lock:
            for event in session.events:
                kind = event["type"]
                if kind == "step" and self._position < len(self._plan):
                    item = self._plan[self._position]
                    if item.key == (event["step"], event.get("placement")):
                        self._position += 1
                elif kind == "zero":
                    for channel, zeroed in dict(event.get("channels") or {}).items():
                        self._recorded_zero[str(channel)] = dict(zeroed)
                elif kind == "alarm":
                    self._alarm_count += 1
                    key = (str(event.get("channel")), str(event.get("rule")))
                    self._alarm_flagged.setdefault(key, set()).update(event.get("cycles") or ())
            for number in sorted(session.cycles):
                cycle = session.cycles[number]
                self._cycles.append(
                    CycleRecord(
                        cycle=number,
                        values={ch: r.value for ch, r in cycle.readings.items()},
                        step_id=cycle.step,
                        placement=cycle.placement,
                        rejected=session.rejected.get(number),
                        resolution=self.setup.resolved_resolution,
                        times=_reading_times(cycle.readings),
                    )
                )
            self._next_cycle = session.next_cycle
            by_seq = {event["seq"]: event for event in session.events}
            marked = any(by_seq[batch.seq].get("end") for batch in session.samples)
            for batch in session.samples:
                event = by_seq[batch.seq]
                key = (batch.step, event.get("placement"))
                number = batch.stroke or 0
                self._stroke_numbers[key] = max(self._stroke_numbers.get(key, 0), number)
                if not marked:  # a file from before the end marks: every number is a stroke
                    self._strokes[key] = max(self._strokes.get(key, 0), number)
                elif event.get("end"):
                    self._strokes[key] = self._strokes.get(key, 0) + 1
            self._rebuild_live()
            self._views = ()

    def _restore_zero(self) -> list[str]:
        """Put the recorded zero back on the gauges (a resumed session may run on a fresh
        gauge set, whose readers know no offset): each channel's software offset from its last
        ``zero`` event, 0.0 for a device zero. Returns the channels the device zeroed (their
        zero lives in the gauge, which may have been power-cycled)."""
        offsets = {
            channel: float(zeroed.get("offset") or 0.0)
            if zeroed.get("method") == "software"
            else 0.0
            for channel, zeroed in self._recorded_zero.items()
            if channel in getattr(self.gauges, "channels", ())
        }
        if offsets:
            self.gauges.set_zero_offsets(offsets)
        return [c for c, zeroed in self._recorded_zero.items() if zeroed.get("method") == "device"]

    # -- callbacks from the instruments ---------------------------------------------------------

    def _attach(self, moment: str) -> None:
        """Start the intake thread, hook the gauges' set and status callbacks (undone by
        :meth:`_close`) and record how each line stands now. On failure everything is undone
        and the file closed."""
        self._intake: queue.SimpleQueue[tuple[Any, ...] | None] = queue.SimpleQueue()
        self._intake_thread = threading.Thread(
            target=self._take_in, name="runner intake", daemon=True
        )
        self._intake_thread.start()
        self._hooked: list[tuple[Any, Any, Any]] = []
        try:
            if getattr(self.gauges, "trigger", None) == "push":
                self.gauges.on_set = self._on_push_set
            for reader in getattr(self.gauges, "readers", ()):
                previous = reader.on_status
                self._port_states[reader.url] = reader.state

                def chained(status: Any, previous: Any = previous) -> None:
                    if previous is not None:
                        previous(status)
                    self._on_port_status(status)

                reader.on_status = chained
                self._hooked.append((reader, previous, chained))
            with self._lock:
                # The file says how each line stood when the session (re)started; changes
                # follow.
                for url, state in self._port_states.items():
                    self._append("instrument", port=url, state=state, message=moment)
        except BaseException:
            with self._lock:
                self._close()
            raise

    def _on_port_status(self, status: Any) -> None:
        """A port's state changed, on its reader's thread: handed to the intake thread, which
        writes the ``instrument`` event (the reader never waits for the disk)."""
        self._intake.put(("status", status))

    def _record_port_status(self, status: Any) -> None:
        """The intake side of :meth:`_on_port_status`. Lock held."""
        if status.state == self._port_states.get(status.port):
            return
        self._port_states[status.port] = status.state
        if self._status in ("running", "paused") and status.state in (
            "connected",
            "disconnected",
        ):
            self._append("instrument", port=status.port, state=status.state, message=status.message)
            level: MessageLevel = "info" if status.state == "connected" else "warning"
            self._say(level, f"{status.port}: {status.state} ({status.message})")

    def _on_push_set(self, result: Any) -> None:
        """A completed push set, on the reader's thread: note which step was current and hand
        it over, without the runner's lock.

        Recording (an fsync, the live figures, the alarms) happens on the intake thread, so
        the reader keeps draining the line while the disk works and never waits for a
        capture, a zero or a write under way."""
        with self._intake_lock:
            stream = self._stream_queue
            position, busy = self._position, self._busy
        if stream is not None:
            stream.put(result)  # a streamed stroke takes every set, in order
            return
        self._intake.put(("set", position, busy, result))

    def _take_in(self) -> None:
        """The intake thread: records queued push sets and port changes, in order, until the
        runner closes."""
        while True:
            queued = self._intake.get()
            if queued is None:
                return
            with self._lock:
                if self._writer.closed:
                    continue  # closed while this waited: the file takes nothing more
                # A failed write is already the operator's message and the runner's failure.
                with contextlib.suppress(StationError):
                    if queued[0] == "status":
                        self._record_port_status(queued[1])
                    else:
                        self._record_push_set(*queued[1:])

    def _record_push_set(self, position: int, busy: bool, result: Any) -> None:
        """Record a push set as a cycle if the step current when it arrived still is. Lock
        held."""
        if busy or self._status != "running" or position != self._position:
            # A software zero took this set, the session is not running, or the step moved on
            # since the set arrived.
            return
        if not self._capture_step():
            # Said once per step: a streaming device sends many sets a second.
            if self._warned_position != self._position:
                self._warned_position = self._position
                # A streaming device (a scale counter, a data logger) sends all the time: that
                # is normal, not a fault, so it is said calmly.
                self._say(
                    "info",
                    "The gauges are sending readings; none is recorded while no capture step "
                    "is current.",
                )
            return
        self._record(result, by="operator", position=position)

    # -- operator actions -----------------------------------------------------------------------

    def confirm(self, by: str = "operator") -> None:
        """Complete the current step: a ``check``; a ``cycles`` step once its minimum of
        accepted cycles is recorded; a ``zero`` step zeroes first. StationError otherwise."""
        with self._lock:
            item = self._current_item()
            kind = item.step.kind
            if kind == "zero":
                pass  # zero() takes the lock itself, outside this block
            elif kind == "check":
                self._complete_step(item, by)
                return
            elif kind == "cycles":
                if self._busy:
                    # The set being taken belongs to this step: going on now would file it
                    # under the next one.
                    raise StationError("a capture is under way: wait for it to end")
                done = self._step_accepted(item)
                target, minimum = self._cycle_counts(item)
                if done < minimum:
                    raise StationError(
                        f"only {done} of {target} cycles are recorded; capture at least "
                        f"{minimum - done} more before going on"
                    )
                if done < target:
                    self._say(
                        "warning",
                        f"Going on with {done} cycles, fewer than the {target} asked for.",
                    )
                self._complete_step(item, by)
                return
            elif kind == "input":
                raise StationError(
                    f"step {item.step.title!r} needs values: type "
                    + ", ".join(f.label for f in item.step.fields)
                )
            elif kind == "capture":
                raise StationError("this step records one reading set: capture it")
            elif kind == "stroke":
                done = self._strokes.get(item.key, 0)
                target, minimum = self._stroke_counts(item)
                if self._busy:
                    raise StationError("a stroke is under way: end it first")
                if done < minimum:
                    raise StationError(
                        f"only {done} of {target} strokes are recorded; record at least "
                        f"{minimum - done} more before going on"
                    )
                self._complete_step(item, by)
                return
            else:
                raise StationError(f"{kind} steps cannot be confirmed (step {item.step.title!r})")
        self.zero(by=by)

    def submit_input(self, values: Mapping[str, str], by: str = "operator") -> None:
        """Record the current ``input`` step's values and complete it.

        Each field is checked: a required one must not be empty, a number must parse as a
        finite number; an unknown name is refused. Nothing is written when one is wrong.
        """
        with self._lock:
            item = self._current_item()
            if item.step.kind != "input":
                raise StationError(f"step {item.step.title!r} does not take typed values")
            fields = {f.name: f for f in item.step.fields}
            unknown = sorted(set(values) - set(fields))
            if unknown:
                raise StationError(
                    f"step {item.step.title!r} has no field {', '.join(unknown)}; its fields: "
                    + ", ".join(fields)
                )
            recorded: dict[str, Any] = {}
            for name, spec in fields.items():
                text = str(values.get(name, "")).strip()
                if not text:
                    if spec.required:
                        raise StationError(f"{spec.label} is required: type a value")
                    continue
                if spec.type == "number":
                    try:
                        number = float(text)
                    except ValueError:
                        number = math.nan
                    if not math.isfinite(number):
                        unit = f" in {spec.unit}" if spec.unit else ""
                        raise StationError(f"{spec.label} must be a number{unit}, not {text!r}")
                    recorded[name] = number
                else:
                    recorded[name] = text
            self._append(
                "input", step=item.step.id, placement=item.placement, values=recorded, by=by
            )
            self._complete_step(item, by)

    def zero(self, by: str = "operator", timeout: float = 5.0) -> None:
        """Zero the current ``zero`` step's channels (the device's command, else a software
        offset from a fresh reading set), record a ``zero`` event and complete the step.

        A port that is down is waited for until ``timeout``; a gauge reading in another unit
        than the session's is refused (nothing zeroed)."""
        with self._lock:
            item = self._current_item()
            if item.step.kind != "zero":
                raise StationError(f"step {item.step.title!r} is not a zero step")
            self._claim()
        try:
            results = self.gauges.zero(
                list(item.step.channels), timeout, unit=self.setup.resolved_unit
            )
        except StationError as error:
            with self._lock:
                self._busy = False
                self._say("error", error.message)
            raise
        except BaseException:
            with self._lock:
                self._busy = False
            raise
        with self._lock:
            self._busy = False
            self._ensure_open()
            self._append(
                "zero",
                step=item.step.id,
                placement=item.placement,
                channels={
                    result.channel: {"method": result.method, "offset": result.offset}
                    for result in results
                },
                by=by,
            )
            self._complete_step(item, by)

    def capture(self, timeout: float = 5.0, by: str = "operator") -> CycleOutcome:
        """Take one reading set and record it as the next cycle (blocking: up to ``timeout``).

        With the ``push`` trigger this waits for the device's next set (which the runner
        records by itself). Returns the outcome; a refused set (a channel missing, stale or
        duplicated) records nothing and says why. A failed write raises StationError (the
        file keeps everything acknowledged).
        """
        with self._lock:
            item = self._current_item()
            if self._status == "paused":
                raise StationError("capture is paused: resume it first")
            if item.step.kind not in ("capture", "cycles"):
                raise StationError(f"step {item.step.title!r} does not capture readings")
            if self.setup.trigger == "push":
                seen = self._outcomes
                if not self._outcome_ready.wait_for(
                    lambda: self._outcomes != seen or self._status != "running", timeout
                ):
                    return self._refuse(
                        f"No reading set arrived within {timeout:g} s: press DATA on the "
                        "gauges (or check the cable)."
                    )
                if self._status == "failed":
                    self._ensure_open()  # raises the failure's own sentence
                if self._status != "running" or self._last_outcome is None:
                    return self._refuse(f"The session is {self._status}; nothing recorded.")
                return self._last_outcome
            self._claim()
        try:
            result = self.gauges.capture(timeout)
        except BaseException:
            with self._lock:
                self._busy = False
            raise
        with self._lock:
            self._busy = False
            return self._record(result, by=by, position=self._claimed_position)

    def stroke(
        self,
        timeout: float = 1.0,
        *,
        batch_seconds: float = 0.25,
        batch_points: int = 200,
        by: str = "operator",
    ) -> StrokeOutcome:
        """Stream reading sets as points of one stroke until :meth:`end_stroke` (blocking: call
        it from a worker thread while the robot moves along the bar).

        Each complete set of the step's channels is one point; points are written in ``samples``
        events (one per ``batch_seconds`` or ``batch_points``, so the fsync cost stays bounded)
        numbered by stroke. A set with a channel missing or stale is skipped and counted, never
        filled in. A stroke with no point is not counted.
        """
        with self._lock:
            item = self._current_item()
            if self._status == "paused":
                raise StationError("capture is paused: resume it first")
            if item.step.kind != "stroke":
                raise StationError(f"step {item.step.title!r} is not a stroke")
            self._claim()
            self._stroke_stop.clear()
            self._stroke_points = 0
            number = self._stroke_numbers.get(item.key, 0) + 1
            self._stroke_numbers[item.key] = number
        channels = list(item.step.channels)
        rows: list[list[float]] = []
        stamps: list[float] = []
        points = skipped = 0
        flushed_at = time.monotonic()

        def flush(end: bool = False) -> None:
            nonlocal rows, stamps, flushed_at
            if rows:
                self._write_samples(item, number, channels, rows, stamps, by, end=end)
            rows, stamps, flushed_at = [], [], time.monotonic()

        try:
            while not self._stroke_stop.is_set() and self._status == "running":
                result = self.gauges.capture(timeout)
                if _set_problem(result, channels, self.setup.resolved_unit):
                    skipped += 1
                    continue
                rows.append([float(result.readings[ch].value) for ch in channels])
                stamps.append(max(result.readings[ch].t_mono for ch in channels))
                points += 1
                self._stroke_points = points
                if len(rows) >= batch_points or time.monotonic() - flushed_at >= batch_seconds:
                    flush()
            flush(end=True)  # the operator ended it: a whole stroke by their word
        finally:
            with self._lock:
                self._busy = False
                self._stroke_points = 0
        with self._lock:
            if points:
                self._strokes[item.key] = self._strokes.get(item.key, 0) + 1
                message = f"Stroke {number}: {points} points recorded"
            else:
                message = f"Stroke {number}: no complete reading set; nothing recorded"
            if skipped:
                message += f", {skipped} incomplete sets skipped"
            self._say("info" if points else "warning", message + ".")
            return StrokeOutcome(number if points else 0, points, skipped, message + ".")

    def stream_strokes(
        self,
        timeout: float = 1.0,
        *,
        deadband: float | None = None,
        still_seconds: float = 2.0,
        batch_seconds: float = 0.25,
        batch_points: int = 200,
        on_stroke: Callable[[StrokeOutcome], object] | None = None,
        by: str = "operator",
    ) -> int:
        """Stream the current ``stroke`` step's channels and split the strokes by the travel
        of its direction channel (the scale) as they happen, until the step has its target of
        whole strokes, :meth:`end_stroke`, or the session stops (blocking: call it from a
        worker thread). Returns the whole strokes recorded in the step so far.

        Every complete set is a point and every point is written, in ``samples`` events
        numbered by stroke (one per ``batch_seconds`` or ``batch_points``, so the fsync cost
        stays bounded); the last event of a whole stroke carries ``end: true``. A whole stroke
        runs from rest or a reversal to a reversal or rest
        (:class:`~station.analysis.linearity.TravelTracker`, ``deadband`` default 100 gauge
        resolutions, ``still_seconds`` at rest to end one); a lead-in (the robot was moving
        when streaming began) or a stroke cut short keeps its own number without the mark, and
        the analysis leaves it out. ``on_stroke`` hears of each whole stroke once its points
        are on disk. With the ``push`` trigger every set the devices send is taken (queued
        from the reader's thread, none dropped); otherwise the gauges are polled back to back.
        """
        from station.analysis.linearity import TravelTracker

        with self._lock:
            item = self._current_item()
            if self._status == "paused":
                raise StationError("capture is paused: resume it first")
            if item.step.kind != "stroke":
                raise StationError(f"step {item.step.title!r} is not a stroke")
            if not item.step.direction_channel:
                raise StationError(f"step {item.step.title!r} names no direction channel")
            self._claim()
            self._stroke_stop.clear()
            pushed = self.setup.trigger == "push"
            if pushed:
                with self._intake_lock:
                    self._stream_queue = queue.SimpleQueue()
        channels = list(item.step.channels)
        scale = channels.index(item.step.direction_channel)
        target, _ = self._stroke_counts(item)
        resolution = self.setup.resolved_resolution
        tracker = TravelTracker(
            deadband if deadband is not None else 100 * resolution, still_seconds=still_seconds
        )
        # Points of the segment under way: written in batches, the whole segment kept until it
        # closes (one stroke's worth) for the listener's per-stroke figure.
        segment: list[tuple[list[float], float]] = []
        written = 0
        number = 0
        skipped = 0
        flushed_at = time.monotonic()

        def open_segment() -> None:
            nonlocal number, written, segment
            with self._lock:
                number = self._stroke_numbers.get(item.key, 0) + 1
                self._stroke_numbers[item.key] = number
            segment, written = [], 0

        def flush(end: bool = False, last: bool = False) -> None:
            nonlocal written, flushed_at
            # Keep the last point back until the segment ends (or streaming does), so its end
            # mark always comes with at least one point.
            upto = len(segment) if end or last else len(segment) - 1
            if upto > written:
                rows = [row for row, _ in segment[written:upto]]
                stamps = [stamp for _, stamp in segment[written:upto]]
                self._write_samples(item, number, channels, rows, stamps, by, end=end)
                written = upto
            flushed_at = time.monotonic()

        def next_result() -> Any:
            if pushed:
                try:
                    return self._stream_queue.get(timeout=timeout)
                except queue.Empty:
                    return None
            return self.gauges.capture(timeout)

        open_segment()
        try:
            while not self._stroke_stop.is_set() and self._status == "running":
                with self._lock:
                    if self._strokes.get(item.key, 0) >= target:
                        break
                result = next_result()
                if result is None:
                    continue
                if _set_problem(result, channels, self.setup.resolved_unit):
                    skipped += 1
                    continue
                row = [float(result.readings[ch].value) for ch in channels]
                stamp = max(result.readings[ch].t_mono for ch in channels)
                for event in tracker.add((row, stamp), row[scale], stamp):
                    if event.kind == "points":
                        segment.extend(event.points)
                        continue
                    flush(end=event.stroke, last=True)
                    if event.stroke:
                        self._stroke_done(item, number, segment, channels, event, on_stroke)
                    open_segment()
                self._stroke_points = len(segment)
                if (
                    len(segment) - written >= batch_points
                    or time.monotonic() - flushed_at >= batch_seconds
                ):
                    flush()
            segment.extend(tracker.flush())
            if self._status == "running":
                flush(last=True)  # a segment still open: recorded, without the end mark
        finally:
            with self._lock:
                with self._intake_lock:
                    self._stream_queue = None
                self._busy = False
                self._stroke_points = 0
        if skipped:
            self._say("warning", f"{skipped} incomplete reading sets were skipped.")
        with self._lock:
            return self._strokes.get(item.key, 0)

    def _stroke_done(
        self,
        item: _PlanItem,
        number: int,
        segment: Sequence[tuple[list[float], float]],
        channels: Sequence[str],
        event: Any,
        on_stroke: Callable[[StrokeOutcome], object] | None,
    ) -> None:
        with self._lock:
            count = self._strokes.get(item.key, 0) + 1
            self._strokes[item.key] = count
            target, _ = self._stroke_counts(item)
        profile = {
            channel: tuple(row[index] for row, _ in segment)
            for index, channel in enumerate(channels)
        }
        outcome = StrokeOutcome(
            stroke=number,
            points=len(segment),
            skipped=0,
            message=f"Stroke {count} of {target} ({event.direction}): {len(segment)} points.",
            direction=event.direction,
            count=count,
            profile=profile,
        )
        self._say("info", outcome.message)
        if on_stroke is not None:
            on_stroke(outcome)

    def _write_samples(
        self,
        item: _PlanItem,
        number: int,
        channels: Sequence[str],
        rows: Sequence[Sequence[float]],
        stamps: Sequence[float],
        by: str,
        *,
        end: bool,
    ) -> None:
        """One ``samples`` event of stroke ``number`` (``end``: the stroke's last points)."""
        with self._lock:
            self._ensure_open()
            self._append(
                "samples",
                step=item.step.id,
                placement=item.placement,
                stroke=number,
                channels=list(channels),
                values=[list(row) for row in rows],
                t_mono=list(stamps),
                by=by,
                end=True if end else None,
            )

    def end_stroke(self) -> None:
        """Stop the stroke under way (its last points are written before :meth:`stroke`
        returns)."""
        self._stroke_stop.set()

    def reject_last(self, reason: str, by: str = "operator") -> int:
        """Reject the most recent accepted cycle with ``reason`` (its readings stay in the file,
        the analysis leaves it out); returns its number."""
        reason = reason.strip()
        if not reason:
            raise StationError("give a reason for rejecting the cycle")
        with self._lock:
            self._ensure_open()
            accepted = [index for index, r in enumerate(self._cycles) if r.rejected is None]
            if not accepted:
                raise StationError("there is no recorded cycle to reject")
            index = accepted[-1]
            record = self._cycles[index]
            self._append("reject", cycle=record.cycle, reason=reason, by=by)
            self._cycles[index] = replace(record, rejected=reason)
            self._rebuild_live()
            self._say("info", f"Cycle {record.cycle} rejected: {reason}.")
            self._notify(None)
            return record.cycle

    def note(self, text: str, by: str = "operator") -> None:
        """Record the operator's note."""
        text = text.strip()
        if not text:
            raise StationError("the note is empty")
        with self._lock:
            self._ensure_open()
            self._append("note", text=text, by=by)

    def pause(self, by: str = "operator") -> None:
        """Refuse captures until :meth:`resume_capture` (recorded as a note, for the audit)."""
        with self._lock:
            self._ensure_open()
            if self._status == "paused":
                return
            self._status = "paused"
            self._append("note", text="capture paused", by=by, pause=True)

    def resume_capture(self, by: str = "operator") -> None:
        """Accept captures again after :meth:`pause`."""
        with self._lock:
            if self._status != "paused":
                return
            self._status = "running"
            self._append("note", text="capture resumed", by=by, pause=False)

    def finish(self, by: str = "operator") -> Analysis | None:
        """Write the ``finish`` event, close the file and return the analysis of the accepted
        cycles (``None`` when there is none). Finishing before every step is done is allowed;
        the event says so."""
        with self._lock:
            self._ensure_open()
            complete = self._position >= len(self._plan)
            accepted = self._accepted_total()
            self._record_snapshot_alarms()
            self._append(
                "finish",
                by=by,
                complete=complete,
                accepted=accepted,
                rejected=sorted(r.cycle for r in self._cycles if r.rejected is not None),
            )
            self._status = "finished"
            if not complete:
                self._say("warning", "Finished before every step was done.")
            self._close()
            self._notify(None)
            return self.analysis() if accepted else None

    def interrupt(self, reason: str) -> None:
        """Write an ``interrupted`` event (``reason``: the signal's name, or why) and close the
        file; the session stays resumable. Safe from any thread; does nothing once closed."""
        with self._lock:
            if self._status in ("finished", "interrupted", "failed"):
                return
            self._append("interrupted", reason=reason)
            self._status = "interrupted"
            self._close()
            self._outcome_ready.notify_all()
            self._notify(None)

    def close(self) -> None:
        """Close the file without a word (the session stays resumable as it is)."""
        with self._lock:
            self._close()

    # -- what the UI reads ----------------------------------------------------------------------

    @property
    def path(self) -> Path:
        """The session file."""
        return Path(self._writer.path)

    @property
    def failure(self) -> str | None:
        """Why the session failed (a write failed: the journal's sentence, e.g. a full disk),
        or ``None``. The session file keeps everything acknowledged before it."""
        with self._lock:
            return self._failure

    @property
    def last_hash(self) -> str:
        """The sha256 of the file's last line (print it: it anchors the file)."""
        return str(self._writer.last_hash)

    def analysis(self) -> Analysis:
        """The analysis of the accepted cycles so far: equal to the batch ``analyze`` of the
        session file (rejected cycles excluded). StationError before the first cycle."""
        with self._lock:
            snapshot = self._live.snapshot()
            rejected = tuple(r.cycle for r in self._cycles if r.rejected is not None)
            return replace(snapshot, excluded_cycles=rejected)

    def state(self) -> RunnerState:
        """An immutable snapshot of where the session is."""
        with self._lock:
            item = self._plan[self._position] if self._position < len(self._plan) else None
            cycles_item = item if item is not None and item.step.kind == "cycles" else None
            if cycles_item is None:
                cycles_item = next(
                    (p for p in reversed(self._plan[: self._position]) if p.step.kind == "cycles"),
                    None,
                )
            target, minimum = self._cycle_counts(cycles_item) if cycles_item else (0, 0)
            stroke_item = item is not None and item.step.kind == "stroke"
            views = self._step_views()
            return RunnerState(
                path=self.path,
                status=self._status,
                steps=views,
                current=views[self._position] if item is not None else None,
                cycle=self._step_accepted(cycles_item) if cycles_item else 0,
                cycles_target=target,
                cycles_min=minimum,
                placement=item.placement if item is not None else None,
                placements=item.placements if item is not None else None,
                cycles=tuple(self._cycles),
                instruments=self._instrument_states(),
                messages=tuple(self._messages),
                last_hash=self.last_hash,
                alarms=self._alarm_count,
                strokes=self._strokes.get(item.key, 0) if stroke_item else 0,
                strokes_target=self._stroke_counts(item)[0] if stroke_item else 0,
                stroke_points=self._stroke_points,
                failure=self._failure or "",
            )

    def prompt(self) -> str:
        """The current step's instruction for the operator (the per-cycle prompt in a
        ``cycles`` step), or what to do once every step is done."""
        with self._lock:
            if self._position >= len(self._plan):
                return "Every step is done: finish the session."
            item = self._plan[self._position]
            if item.step.kind == "cycles" and item.step.prompt:
                target, _ = self._cycle_counts(item)
                return item.step.prompt_for(self._step_accepted(item) + 1, target)
            return item.step.text or item.step.title

    # -- internals ------------------------------------------------------------------------------

    def _new_live(self) -> Any:
        from station.analysis.live import LiveAnalysis

        return LiveAnalysis(self.config, self.setup.channels)

    def _rebuild_live(self) -> None:
        self._recount()
        self._live = self._new_live()
        for record in self._cycles:
            if record.rejected is None:
                self._live.add_set(record.values, record.cycle, record.times)

    def _current_item(self) -> _PlanItem:
        self._ensure_open()
        if self._position >= len(self._plan):
            raise StationError("every step is done: finish the session")
        return self._plan[self._position]

    def _capture_step(self) -> _PlanItem | None:
        if self._position >= len(self._plan):
            return None
        item = self._plan[self._position]
        return item if item.step.kind in ("capture", "cycles") else None

    def _ensure_open(self) -> None:
        if self._status == "failed" and self._failure:
            raise StationError(self._failure)
        if self._status in ("finished", "interrupted", "failed"):
            raise StationError(f"the session is {self._status}: {self.path}")

    def _claim(self) -> None:
        """Mark a capture, zero or stroke under way, and the step it belongs to: its result
        is recorded only while that step is still current. Lock held."""
        if self._busy:
            raise StationError("a capture or zero is already under way: wait for it")
        self._busy = True
        self._claimed_position = self._position

    def _cycle_counts(self, item: _PlanItem) -> tuple[int, int]:
        """(target, minimum) accepted cycles for a cycles step; the set-up's count applies to
        steps outside repeat blocks."""
        step = item.step
        if step.kind != "cycles":
            return (1, 1)
        if item.placement is None:
            target = self.setup.resolved_cycles
        else:
            target = int(step.count_target or 1)
        return target, min(int(step.count_min or target), target)

    def _stroke_counts(self, item: _PlanItem) -> tuple[int, int]:
        """(target, minimum) strokes of a stroke step (the set-up's count when it gives one)."""
        target = int(self.setup.strokes or item.step.count_target or 1)
        return target, min(int(item.step.count_min or target), target)

    def _step_accepted(self, item: _PlanItem) -> int:
        return self._accepted_by_step.get(item.key, 0)

    def _accepted_total(self) -> int:
        return self._accepted_count

    def _recount(self) -> None:
        self._accepted_by_step = {}
        accepted = [r for r in self._cycles if r.rejected is None]
        for record in accepted:
            key = (record.step_id, record.placement)
            self._accepted_by_step[key] = self._accepted_by_step.get(key, 0) + 1
        self._accepted_count = len(accepted)

    def _step_views(self) -> tuple[StepView, ...]:
        if not self._views or self._views_position != self._position:
            self._views = tuple(
                StepView(
                    index=index,
                    step=item.step,
                    placement=item.placement,
                    mark="done"
                    if index < self._position
                    else "current"
                    if index == self._position
                    else "pending",
                )
                for index, item in enumerate(self._plan)
            )
            self._views_position = self._position
        return self._views

    def _instrument_states(self) -> tuple[PortState, ...]:
        return tuple(
            PortState(
                url=reader.url,
                status=reader.state,
                rejected_frames=reader.rejected_count,
                detail=reader.last_message,
            )
            for reader in getattr(self.gauges, "readers", ())
        )

    def _complete_step(self, item: _PlanItem, by: str) -> None:
        if item.step.kind in ("capture", "cycles"):
            self._record_snapshot_alarms()
        self._append(
            "step",
            step=item.step.id,
            placement=item.placement,
            kind=item.step.kind,
            action="confirmed",
            by=by,
        )
        self._position += 1
        self._notify(None)

    def _refuse(self, message: str) -> CycleOutcome:
        self._say("warning", message)
        return CycleOutcome(recorded=False, message=message)

    def _record(self, result: Any, by: str, position: int | None = None) -> CycleOutcome:
        """Record a reading set as the next cycle if it is whole and fresh, and (``position``)
        the step it was taken for is still current. Lock held."""
        if self._status != "running":
            return self._refuse(f"The session is {self._status}; the reading set was not recorded.")
        if position is not None and position != self._position:
            return self._refuse(
                "The step changed while the reading set was taken; it was not recorded."
            )
        item = self._capture_step()
        if item is None:
            return self._refuse("No capture step is current; the reading set was not recorded.")
        needed = tuple(item.step.channels)
        problem = _set_problem(result, needed, self.setup.resolved_unit)
        target, _ = self._cycle_counts(item)
        if item.step.kind == "cycles" and self._step_accepted(item) >= target:
            # The set-up asked for N: more is a change of plan, not a capture.
            outcome = self._refuse(
                f"All {target} cycles are recorded; this reading set was not. Go on, or finish."
            )
        elif problem:
            outcome = self._refuse(f"Not recorded: {problem} Capture again.")
            if getattr(result, "port_down", False):
                outcome = replace(outcome, port_down=True)
        else:
            outcome = self._write_cycle(item, {ch: result.readings[ch] for ch in needed}, by)
        self._last_outcome = outcome
        self._outcomes += 1
        self._outcome_ready.notify_all()
        return outcome

    def _write_cycle(self, item: _PlanItem, readings: Mapping[str, Any], by: str) -> CycleOutcome:
        number = self._next_cycle
        event = {
            "cycle": number,
            "step": item.step.id,
            "placement": item.placement,
            "by": by,
            "channels": {
                channel: {
                    "value": reading.value,
                    "unit": reading.unit,
                    "raw_value": reading.device_value,
                    "zero": reading.zero_offset,
                    "raw": reading.raw,
                    "t_wall": reading.t_wall,
                    "t_mono": reading.t_mono,
                }
                for channel, reading in readings.items()
            },
        }
        self._append("reading", notify=False, **event)
        self._next_cycle = number + 1
        record = CycleRecord(
            cycle=number,
            values={channel: float(r.value) for channel, r in readings.items()},
            step_id=item.step.id,
            placement=item.placement,
            resolution=self.setup.resolved_resolution,
            times=_reading_times(readings),
        )
        self._cycles.append(record)
        self._accepted_by_step[item.key] = self._accepted_by_step.get(item.key, 0) + 1
        self._accepted_count += 1
        # Acknowledged: the listener hears of the reading as soon as it is on disk, with the
        # state that includes it; the live figures and alarms follow.
        self._notify(self._last_event)
        self._record_alarms(self._live.add_set(record.values, number, record.times))
        if item.step.kind == "capture":
            self._complete_step(item, by)
        elif item.step.kind == "cycles":
            target, _ = self._cycle_counts(item)
            if self._step_accepted(item) == target:
                self._say("info", f"All {target} cycles are recorded: go on, or finish.")
        return CycleOutcome(recorded=True, message=record.line(), cycle=record)

    def _record_alarms(self, updates: Mapping[str, Any]) -> None:
        """Write ``alarm`` events for alarms that first appear.

        The live update's alarms (the windows the new point completes, judged against the
        limits as they are now; O(1)) are recorded as each cycle arrives. The full analysis
        (every point against the final limits, which can flag an earlier pattern once the limits
        have moved) costs O(n) (tens of ms at a few hundred cycles), so it is checked at the end
        of every capture or cycles step and before the finish, not per cycle.
        """
        for channel, update in updates.items():
            for alarm in update.alarms:
                self._record_alarm(channel, alarm)

    def _record_snapshot_alarms(self) -> None:
        if not self._accepted_total():
            return
        for channel, result in self._live.snapshot().channels.items():
            for alarm in sorted(result.alarms, key=lambda a: (max(a.points), a.rule)):
                self._record_alarm(channel, alarm)

    def _record_alarm(self, channel: str, alarm: Any) -> None:
        # The live analysis is fed each set with its cycle number: its alarms name cycles.
        cycles = list(alarm.cycles)
        if not cycles:
            return
        flagged = self._alarm_flagged.setdefault((channel, alarm.rule), set())
        known = not flagged.isdisjoint(cycles)
        flagged.update(cycles)
        if known:
            return
        self._append(
            "alarm",
            channel=channel,
            rule=alarm.rule,
            points=list(alarm.points),
            cycles=cycles,
            text=alarm.text,
        )
        self._alarm_count += 1
        self._say("warning", f"{channel}: {alarm.text}")

    def _append(self, event_type: str, *, notify: bool = True, **fields: Any) -> dict[str, Any]:
        """Write one event (fsynced when this returns). A failed write marks the runner failed
        and re-raises the journal's sentence."""
        fields = {k: v for k, v in fields.items() if v is not None}
        try:
            event = self._writer.append(event_type, **fields)
        except StationError as error:
            if self._writer.closed:
                self._status = "failed"
                self._failure = error.message
                self._say("error", error.message)
                self._outcome_ready.notify_all()
            raise
        self._last_event = event
        if notify:
            self._notify(event)
        return event

    def _close(self) -> None:
        """Close the file and let go of the gauges: their callbacks are put back as they were
        (a gauge set resumed on again and again never grows a chain of dead runners) and the
        intake thread ends."""
        self._writer.close()
        if getattr(self.gauges, "on_set", None) == self._on_push_set:
            self.gauges.on_set = None
        for reader, previous, chained in self._hooked:
            if reader.on_status is chained:
                reader.on_status = previous
        self._hooked = []
        if self._intake is not None:
            self._intake.put(None)

    def _say(self, level: MessageLevel, text: str) -> None:
        message = OperatorMessage(level, text)
        self._messages.append(message)
        self._tell(RunnerNotice(None, self.state(), message))

    def _notify(self, event: Mapping[str, Any] | None) -> None:
        self._tell(RunnerNotice(event, self.state()))

    def _tell(self, notice: RunnerNotice) -> None:
        if self._listener is None:
            return
        try:
            self._listener(notice)
        except Exception as error:  # a display's bug must not undo a recorded event
            self._messages.append(OperatorMessage("error", f"the display failed: {error!r}"))


def _set_problem(result: Any, needed: Sequence[str], unit: str) -> str:
    """Why a reading set cannot be a cycle ('' when it can): a needed channel missing, stale
    or duplicated, or in another unit than the session's."""
    problems = []
    missing = [c for c in needed if c not in result.readings]
    down = set(getattr(result, "disconnected", ()))
    stale = [c for c in missing if c in result.stale and c not in down]
    # A channel whose port is down is explained by the port's own sentence (in errors).
    absent = [c for c in missing if c not in stale and c not in down]
    if absent:
        problems.append("no reading from " + ", ".join(absent))
    if stale:
        problems.append("only readings from before the trigger on " + ", ".join(stale))
    duplicated = [c for c in needed if c in result.duplicated]
    if duplicated:
        problems.append("more than one reading from " + ", ".join(duplicated))
    mismatch = unit_mismatch(result.readings, needed, unit)
    if mismatch:
        problems.append(mismatch)
    if missing and result.errors:
        # A port's sentence may end in a full stop already; this one ends the whole list.
        problems.extend(error.rstrip(". ") for error in result.errors)
    elif down & set(missing):
        unexplained = [c for c in missing if c in down]
        problems.append(f"the port of {', '.join(unexplained)} is disconnected (reconnecting...)")
    return "; ".join(problems) + "." if problems else ""


def resume_setup(
    path: str | Path,
    *,
    procedures_dirs: Sequence[str | Path] = (),
    ports: Sequence[PortSetup] | None = None,
) -> SessionSetup:
    """The set-up of the session in ``path`` (its procedure found by id), to resume it."""
    from station.procedures import discover_procedures
    from station.session.model import load_session

    session = load_session(path, recover=False)
    if session.finished:
        raise StationError(f"session {path} is finished; start a new session instead")
    procedure = discover_procedures(procedures_dirs).get(session.procedure_id)
    return setup_from_header(session.header, procedure, ports=ports)


def plan_steps(setup: SessionSetup) -> tuple[tuple[Step, int | None], ...]:
    """The steps a session of ``setup`` walks, in order, each with its placement (a repeat
    block's steps once per placement; ``None`` outside one)."""
    return tuple((item.step, item.placement) for item in _unroll(setup.procedure, setup.placements))
