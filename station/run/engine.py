"""The procedure engine: one state machine that turns a procedure's steps, the operator's
actions and the instruments' readings into session events.

The TUI, ``station capture`` and the demo's autopilot all drive a :class:`Runner`; how a step
behaves lives in its kind's handler (:mod:`station.run.steps`), how a session is judged in its
analysis kind (:mod:`station.verdicts`). The engine itself holds no step-kind or analysis-kind
branch. Its rules:

* A step is *done* when its ``step`` event is on disk. What completes it is its handler's
  answer; the operator's next :class:`~station.run.state.Action` is too.
* *Acknowledged* means: the event is fsynced (the journal's ``append`` returns only then). The
  listener hears of a reading after that, with the state and the live analysis that include it
  (:class:`~station.run.state.RunnerNotice`): a display never takes the engine's lock.
* Cycles are numbered 1, 2, ... over the whole session; a rejected cycle keeps its number
  (readings are never deleted), a resumed session continues the numbering.
* Alarms of the live analysis are written as ``alarm`` events (``live`` true, the rule named
  in words) when they first appear; an alarm is new unless it flags a cycle an alarm of the
  same rule and channel already flagged (a run growing by a point is one alarm). The live
  analysis judges against frozen (phase II) limits, so a written alarm never goes away, and a
  replay of the file (:func:`~station.analysis.live.replay_live_alarms`) gives exactly the
  alarm events written. The retrospective chart (limits from every reading) is not
  journalled: it is a function of the readings, and the reports compute it and mark each of
  its alarms live or retrospective.
* :meth:`Runner.acknowledge` writes an ``ack`` event naming an alarm event with a cause from
  the procedure's list; the state carries every alarm with its acknowledgements
  (:attr:`~station.run.state.RunnerState.alarm_list`).

Threads: every public method may be called from any thread. A lock serialises journal writes
and state changes; blocking waits on the instruments happen outside it, so :meth:`interrupt`
(from a signal handler's thread) never waits for a capture timeout. Whatever arrives on a
reader's thread (a completed push or arrival set, a port's state change) is queued, without
the lock, to the engine's own intake thread, which writes it (so the reader keeps draining the
line while the disk syncs). A pushed set becomes a cycle while the step that was current when
it arrived still is and takes sets. A capture, zero or stroke records only into the step it
was started in.

With the ``arrival`` trigger the engine also hears the robot's going and coming (said as
information; a return that did not settle as a warning, never recorded), and arms the gauges
each time a step that takes sets becomes current (its handler's ``entered``): a round trip under
way before that step is not one of its cycles. A ``zero`` event updates the zero uncertainty
the analysis weighs an offset from nominal against.

A resumed session puts the recorded zero back on the gauges (each channel's last ``zero``
event). A failed write (a full disk) makes the engine ``failed``; every later action raises the
journal's own sentence (:attr:`Runner.failure`).
"""

from __future__ import annotations

import contextlib
import math
import queue
import threading
import time
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from station import verdicts
from station.analysis.rules import rule_name
from station.errors import StationError
from station.instruments.gauge import unit_mismatch
from station.run.setup import SessionSetup, resume_setup, unroll
from station.run.state import (
    Action,
    CycleOutcome,
    CycleRecord,
    Listener,
    MessageLevel,
    OperatorMessage,
    PortState,
    Progress,
    RunnerNotice,
    RunnerState,
    RunnerStatus,
    StepView,
    StrokeOutcome,
)
from station.run.steps import handler_for
from station.run.steps.base import PlanItem, StepHandler
from station.session.alarms import (
    RecordedAlarm,
    ack_fields,
    acknowledgement,
    recorded_alarm,
    recorded_alarms,
)
from station.session.header import analysis_config
from station.session.journal import SessionWriter
from station.session.model import Session, event_seconds

if TYPE_CHECKING:
    from station.instruments.gauge import CaptureResult, PortStatus, Subscription

CAPTURE_BY = "station capture"
"""The ``by`` recorded when the headless command confirms a step itself."""

_MESSAGES_KEPT = 20

DEVICE_DRIVEN_TRIGGERS = ("push", "arrival")
"""Triggers where the devices (a DATA press, the robot's arrival) decide when a set is taken:
the engine records the sets they send instead of polling."""


class Gauges(Protocol):
    """What the engine needs of the instruments (a
    :class:`~station.instruments.gauge.GaugeSet`)."""

    trigger: str
    channels: tuple[str, ...]
    readers: Sequence[Any]

    def capture(self, timeout: float = 2.0) -> CaptureResult: ...
    def zero(
        self,
        channels: list[str],
        timeout: float,
        *,
        unit: str,
        readings: int = 1,
        settle: float = 0.0,
        still: float = 3.0,
    ) -> Any: ...
    def set_zero_offsets(self, offsets: Mapping[str, float]) -> None: ...
    def subscribe(
        self, *, on_set: Any = None, on_status: Any = None, on_arrival: Any = None
    ) -> Subscription: ...
    def arm(self, timeout: float = 1.0) -> list[str]: ...


class Journal(Protocol):
    """What the engine needs of the session file (a
    :class:`~station.session.journal.SessionWriter`)."""

    path: Path
    closed: bool
    last_hash: str

    def append(self, type: str, **fields: Any) -> dict[str, Any]: ...
    def snapshot(self) -> Session: ...
    def close(self) -> None: ...


class Runner:
    """The state machine of one session; build it with :meth:`start` or :meth:`resume`.

    ``gauges`` is a started gauge set (:func:`~station.run.setup.open_gauges`); the engine
    subscribes to its sets and port changes while the file is open, and the caller stops the
    set after :meth:`finish` or :meth:`interrupt`.
    """

    def __init__(
        self,
        setup: SessionSetup,
        gauges: Gauges,
        writer: Journal,
        *,
        listener: Listener | None = None,
    ) -> None:
        self.setup = setup
        self.gauges = gauges
        self._writer = writer
        self._listener = listener
        self.lock = threading.RLock()
        """Serialises journal writes and state changes (handlers take it around their waits)."""
        self._outcome_ready = threading.Condition(self.lock)
        self._outcomes = 0
        self._last_outcome: CycleOutcome | None = None
        self._plan = unroll(setup.procedure, setup.placements)
        self._position = 0
        self.status: RunnerStatus = "running"
        self.busy = False
        """A capture, zero or stroke is under way."""
        self._claimed_position = -1
        self._cycles: list[CycleRecord] = []
        # Accepted cycles per plan item and in all: counts, so that a state snapshot costs the
        # same at the 10 000th cycle as at the first.
        self._accepted_by_step: dict[tuple[str, int | None], int] = {}
        self._accepted_count = 0
        self._next_cycle = 1
        self._step_states: dict[tuple[str, int | None], dict[str, Any]] = {}
        self.recorded_zero: dict[str, dict[str, Any]] = {}
        """The last zero event's entry per channel (``{"method", "offset"}``), kept on resume."""
        self.stop_stream = threading.Event()
        """Set by :meth:`end_stroke`: a stream under way stops."""
        self.stroke_marks = True
        """Whether the file's strokes carry end marks (False only for old files)."""
        self._stream_queue: queue.SimpleQueue[Any] | None = None
        # Hands the stream queue over between a stream and the reader thread, so a pushed set
        # never waits for the engine's lock.
        self._intake_lock = threading.Lock()
        self._intake: queue.SimpleQueue[tuple[Any, ...] | None] | None = None
        self._subscription: Subscription | None = None
        self._failure: str | None = None
        self._warned_position = -1
        self._messages: deque[OperatorMessage] = deque(maxlen=_MESSAGES_KEPT)
        self._alarm_count = 0
        self._alarm_flagged: dict[tuple[str, str], set[int]] = {}
        self._alarm_list: tuple[RecordedAlarm, ...] = ()
        self._port_states: dict[str, str] = {}
        self._arm_pending = False
        self._armed_at = float("-inf")
        self.header: Mapping[str, Any] = writer.snapshot().header
        self.config = analysis_config(self.header)
        self.kind = verdicts.kind_of(setup.procedure.analysis)
        self._live: verdicts.LiveVerdict = self.kind.live(self.config, setup.channels, self.header)
        self._views: tuple[StepView, ...] = ()
        self._views_position = -1
        self._last_event: dict[str, Any] | None = None

    # -- construction -----------------------------------------------------------------------

    @classmethod
    def start(
        cls,
        setup: SessionSetup,
        gauges: Gauges,
        sessions_dir: str | Path,
        *,
        listener: Listener | None = None,
    ) -> Runner:
        """Create the session file (its header is on disk when this returns) and begin at the
        procedure's first step."""
        writer = SessionWriter.create(sessions_dir, setup.header_fields())
        runner = cls(setup, gauges, writer, listener=listener)
        runner._attach("when the session started")
        runner.say("info", f"Session file {writer.path}.")
        return runner

    @classmethod
    def resume(
        cls,
        path: str | Path,
        gauges: Gauges,
        *,
        setup: SessionSetup | None = None,
        procedures_dirs: Sequence[str | Path] = (),
        listener: Listener | None = None,
        by: str = "operator",
    ) -> Runner:
        """Continue an unfinished session: a torn tail is moved aside, a ``resume`` event is
        written, the steps already done stay done and cycle numbering continues."""
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
        # Only now may readings and port changes reach the engine: its state is the file's.
        runner._attach("when the session resumed")
        if session.torn is not None:
            runner.say("warning", session.torn.message)
        if device_zeroed:
            runner.say(
                "warning",
                f"{', '.join(device_zeroed)} {'was' if len(device_zeroed) == 1 else 'were'} "
                "zeroed by the gauges' own command: if they were switched off since, they no "
                "longer are. Check that they read zero at the zero position before going on.",
            )
        if setup.procedure.sha256 != session.header["procedure"]["sha256"]:
            runner.say(
                "warning",
                f"The procedure file {setup.procedure.path} changed since this session began; "
                "its steps are followed as they are now.",
            )
        runner.say(
            "info",
            f"Resumed {writer.path}: {runner._accepted_count} cycles so far; "
            f"the next cycle is {runner._next_cycle}.",
        )
        runner._notify(None)
        return runner

    def _replay(self, session: Session) -> None:
        """Rebuild the state from a session's events (resume)."""
        items = {item.key: item for item in self._plan}
        with self.lock:
            self.stroke_marks = any(event.get("end") for event in session.events)
            for event in session.events:
                kind = event["type"]
                if kind == "step" and self._position < len(self._plan):
                    if self._plan[self._position].key == (event["step"], event.get("placement")):
                        self._position += 1
                elif kind == "zero":
                    for channel, zeroed in dict(event.get("channels") or {}).items():
                        self.recorded_zero[str(channel)] = dict(zeroed)
                elif kind == "alarm":
                    self._alarm_count += 1
                    key = (str(event.get("channel")), str(event.get("rule")))
                    self._alarm_flagged.setdefault(key, set()).update(event.get("cycles") or ())
                item = items.get((str(event.get("step")), event.get("placement")))
                if item is not None and kind != "step":
                    handler_for(item.step.kind).replay(self, item, event)
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
                        times=cycle_times(list(cycle.readings), {"t": cycle.t}),
                    )
                )
            self._next_cycle = session.next_cycle
            self._alarm_list = recorded_alarms(session)
            self._zero_config()
            self._rebuild_live(session)
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
            for channel, zeroed in self.recorded_zero.items()
            if channel in getattr(self.gauges, "channels", ())
        }
        if offsets:
            self.gauges.set_zero_offsets(offsets)
        return [c for c, zeroed in self.recorded_zero.items() if zeroed.get("method") == "device"]

    # -- what the instruments send ----------------------------------------------------------

    def _attach(self, moment: str) -> None:
        """Start the intake thread, subscribe to the gauges' sets and port changes (cancelled
        by :meth:`_close`) and record how each line stands now. On failure everything is undone
        and the file closed."""
        self._intake = queue.SimpleQueue()
        self._intake_thread = threading.Thread(
            target=self._take_in, name="runner intake", daemon=True
        )
        self._intake_thread.start()
        try:
            for reader in getattr(self.gauges, "readers", ()):
                self._port_states[reader.url] = reader.state
            self._subscription = self.gauges.subscribe(
                on_set=self._on_set if self.gauges.trigger in DEVICE_DRIVEN_TRIGGERS else None,
                on_status=self._on_port_status,
                on_arrival=self._on_arrival if self.gauges.trigger == "arrival" else None,
            )
            with self.lock:
                # The file says how each line stood when the session (re)started; changes
                # follow.
                for url, state in self._port_states.items():
                    self.append("instrument", port=url, state=state, message=moment)
                self._step_entered()
        except BaseException:
            with self.lock:
                self._close()
            raise

    def _on_port_status(self, status: PortStatus) -> None:
        """A port's state changed, on its reader's thread: handed to the intake thread, which
        writes the ``instrument`` event (the reader never waits for the disk)."""
        if self._intake is not None:
            self._intake.put(("status", status))

    def _record_port_status(self, status: PortStatus) -> None:
        """The intake side of :meth:`_on_port_status`. Lock held."""
        if status.state == self._port_states.get(status.port):
            return
        self._port_states[status.port] = status.state
        if self.status in ("running", "paused") and status.state in (
            "connected",
            "disconnected",
        ):
            self.append("instrument", port=status.port, state=status.state, message=status.message)
            level: MessageLevel = "info" if status.state == "connected" else "warning"
            self.say(level, f"{status.port}: {status.state} ({status.message})")

    def _on_arrival(self, event: Any) -> None:
        """The arrival trigger's news (departed, returned, unsettled), on a reader's thread:
        handed to the intake thread, which says it (reported, never recorded)."""
        if self._intake is not None:
            self._intake.put(("arrival", event))

    def _say_arrival(self, event: Any) -> None:
        """Say an arrival event: the robot's going and coming as information, a return that
        did not settle as a warning (no set was taken for it). Lock held."""
        if self.status not in ("running", "paused"):
            return
        if event.kind == "departed":
            self.say("info", f"The robot left the fixture ({', '.join(event.channels)} away).")
        elif event.kind == "returned":
            self.say("info", "The robot returned to the fixture; waiting for it to be still.")
        elif event.kind == "unsettled":
            self.say("warning", event.message)

    def arm_trigger(self) -> None:
        """A step that takes sets became current: with the ``arrival`` trigger, only a
        departure from now on starts a cycle (a robot already on its way back when the step
        began is not one). The gauges are armed on the intake thread, without the lock; sets
        that arrived before are not recorded. Lock held."""
        if self.setup.trigger != "arrival" or self._intake is None:
            return
        self._arm_pending = True
        self._intake.put(("arm",))

    def _step_entered(self) -> None:
        """Tell the current step's handler that it became current. Lock held."""
        item = self._item_or_none()
        if item is not None and self.status == "running":
            handler_for(item.step.kind).entered(self, item)

    def _on_set(self, result: CaptureResult) -> None:
        """A completed set the devices sent (push, arrival), on the reader's thread: note which
        step was current and hand it over, without the engine's lock."""
        with self._intake_lock:
            stream = self._stream_queue
            position, busy = self._position, self.busy
        if stream is not None:
            stream.put(result)  # a stream takes every set, in order
            return
        if self._intake is not None:
            self._intake.put(("set", position, busy, result))

    def _take_in(self) -> None:
        """The intake thread: records queued sets and port changes, in order, until the
        engine closes."""
        assert self._intake is not None
        intake = self._intake
        while True:
            queued = intake.get()
            if queued is None:
                return
            if queued[0] == "arm":
                # Waits on the reader threads (a flush): never under the engine's lock.
                with contextlib.suppress(StationError):
                    self.gauges.arm(1.0)
                with self.lock:
                    self._armed_at = time.monotonic()
                    self._arm_pending = False
                continue
            with self.lock:
                if self._writer.closed:
                    continue  # closed while this waited: the file takes nothing more
                # A failed write is already the operator's message and the engine's failure.
                with contextlib.suppress(StationError):
                    if queued[0] == "status":
                        self._record_port_status(queued[1])
                    elif queued[0] == "arrival":
                        self._say_arrival(queued[1])
                    else:
                        self._record_pushed_set(*queued[1:])

    def _record_pushed_set(self, position: int, busy: bool, result: CaptureResult) -> None:
        """Record a pushed set if the step current when it arrived still is. Lock held."""
        if busy or self.status != "running" or position != self._position:
            # A software zero took this set, the session is not running, or the step moved on
            # since the set arrived.
            return
        if result.trigger == "arrival" and (self._arm_pending or result.t_trigger < self._armed_at):
            return  # the robot came back before this step was armed: not one of its cycles
        item = self._item_or_none()
        if item is None or not handler_for(item.step.kind).takes_sets:
            # Said once per step: a streaming device sends many sets a second, which is
            # normal, not a fault, so it is said calmly.
            if self._warned_position != self._position:
                self._warned_position = self._position
                self.say(
                    "info",
                    "The gauges are sending readings; none is recorded while no capture step "
                    "is current.",
                )
            return
        self.record_set(result, by="operator", position=position)

    # -- operator actions (the Action kinds) ----------------------------------------------------

    def confirm(self, by: str = "operator") -> None:
        """Complete the current step as its handler defines confirming it (a check; a cycles
        step with its minimum; a zero step zeroes). StationError when it cannot be."""
        with self.lock:
            item = self._current_item()
            handler = handler_for(item.step.kind)
            if not handler.confirm_waits:
                handler.confirm(self, item, by)
                return
        handler.confirm(self, item, by)  # it waits on the gauges: outside the lock

    def submit_input(self, values: Mapping[str, str], by: str = "operator") -> None:
        """Record the current step's typed values and complete it."""
        with self.lock:
            item = self._current_item()
            handler_for(item.step.kind).submit(self, item, values, by)

    def zero(self, by: str = "operator", timeout: float = 5.0) -> None:
        """Zero the current step's channels, record a ``zero`` event and complete the step."""
        with self.lock:
            item = self._current_item()
        handler_for(item.step.kind).zero(self, item, by, timeout)

    def capture(self, timeout: float = 5.0, by: str = "operator") -> CycleOutcome:
        """Take one reading set and record it as the next cycle (blocking: up to ``timeout``).
        A refused set records nothing and says why; a failed write raises StationError."""
        with self.lock:
            item = self._current_item()
            self.ensure_running()
            handler = handler_for(item.step.kind)
        return handler.capture(self, item, timeout, by)

    def stream_strokes(self, timeout: float = 1.0, **options: Any) -> int:
        """Stream the current step's readings until it has what it needs (see the stroke
        handler); returns the whole strokes recorded. Blocking: call from a worker thread."""
        with self.lock:
            item = self._current_item()
            handler = handler_for(item.step.kind)
        return handler.stream(self, item, timeout=timeout, **options)

    def end_stroke(self) -> None:
        """Stop the stream under way (its last points are written before it returns)."""
        self.stop_stream.set()

    def reject_last(self, reason: str, by: str = "operator") -> int:
        """Reject the most recent accepted cycle with ``reason`` (its readings stay in the file,
        the analysis leaves it out); returns its number."""
        reason = reason.strip()
        if not reason:
            raise StationError("give a reason for rejecting the cycle")
        with self.lock:
            self.ensure_open()
            accepted = [index for index, r in enumerate(self._cycles) if r.rejected is None]
            if not accepted:
                raise StationError("there is no recorded cycle to reject")
            index = accepted[-1]
            record = self._cycles[index]
            self.append("reject", cycle=record.cycle, reason=reason, by=by, notify=False)
            self._cycles[index] = replace(record, rejected=reason)
            self._rebuild_live()
            self.say("info", f"Cycle {record.cycle} rejected: {reason}.")
            self._notify(self._last_event, analysis=True)
            return record.cycle

    def acknowledge(
        self,
        alarm_ref: int,
        cause: str,
        text: str | None = None,
        action: str | None = None,
        by: str = "operator",
    ) -> RecordedAlarm:
        """Acknowledge the alarm event whose ``seq`` is ``alarm_ref`` with ``cause`` (one of
        the procedure's causes; "other" needs ``text``) and the corrective ``action``: an
        ``ack`` event, fsynced. Returns the alarm with its acknowledgements. StationError for
        an unknown alarm or cause, or a closed file."""
        with self.lock:
            self.ensure_open()
            index = next(
                (i for i, alarm in enumerate(self._alarm_list) if alarm.seq == alarm_ref), None
            )
            if index is None:
                known = ", ".join(f"#{alarm.seq}" for alarm in self._alarm_list) or "none yet"
                raise StationError(
                    f"there is no alarm #{alarm_ref} in this session (alarms: {known})"
                )
            fields = ack_fields(
                alarm_ref,
                cause,
                causes=self.setup.procedure.causes,
                text=text or "",
                action=action or "",
                by=by,
            )
            event = self.append("ack", **fields)
            alarm = self._alarm_list[index]
            acknowledged = replace(alarm, acks=(*alarm.acks, acknowledgement(event)))
            alarms = list(self._alarm_list)
            alarms[index] = acknowledged
            self._alarm_list = tuple(alarms)
            self.say(
                "info", f"Alarm #{alarm_ref} acknowledged: {acknowledged.acks[-1].describe()}."
            )
            return acknowledged

    def note(self, text: str, by: str = "operator") -> None:
        """Record the operator's note."""
        text = text.strip()
        if not text:
            raise StationError("the note is empty")
        with self.lock:
            self.ensure_open()
            self.append("note", text=text, by=by)

    def pause(self, by: str = "operator") -> None:
        """Refuse captures until :meth:`resume_capture` (recorded as a note, for the audit)."""
        with self.lock:
            self.ensure_open()
            if self.status == "paused":
                return
            self.status = "paused"
            self.append("note", text="capture paused", by=by, pause=True)

    def resume_capture(self, by: str = "operator") -> None:
        """Accept captures again after :meth:`pause`."""
        with self.lock:
            if self.status != "paused":
                return
            self.status = "running"
            self.append("note", text="capture resumed", by=by, pause=False)

    def finish(self, by: str = "operator") -> Any:
        """Close the current step where its handler allows (a cycles step with its minimum, a
        stroke step with its minimum), write the ``finish`` event, close the file and return
        the live analysis (``None`` when there is nothing to analyse). Finishing before every
        step is done is allowed; the event says so."""
        with self.lock:
            self.ensure_open()
            item = self._item_or_none()
            if item is not None:
                handler = handler_for(item.step.kind)
                action = handler.action(self, item)
                if action.may_confirm and not self.busy:
                    handler.confirm(self, item, by)
            complete = self._position >= len(self._plan)
            self.append(
                "finish",
                by=by,
                complete=complete,
                accepted=self._accepted_count,
                rejected=sorted(r.cycle for r in self._cycles if r.rejected is not None),
            )
            self.status = "finished"
            if not complete:
                self.say("warning", "Finished before every step was done.")
            self._close()
            self._kind_finished()
            self._notify(None, analysis=True)
            return self.analysis_or_none()

    def _kind_finished(self) -> None:
        """What the analysis kind does with a finished session (a gauge check files itself in
        the gauge register); its failure is a warning: the session is safe on disk."""
        if self.kind.finished is None:
            return
        try:
            for sentence in self.kind.finished(self.path):
                self.say("info", sentence)
        except StationError as error:
            self.say("warning", error.message)

    def interrupt(self, reason: str) -> None:
        """Write an ``interrupted`` event (``reason``: the signal's name, or why) and close the
        file; the session stays resumable. Safe from any thread; does nothing once closed."""
        with self.lock:
            if self.status in ("finished", "interrupted", "failed"):
                return
            self.append("interrupted", reason=reason)
            self.status = "interrupted"
            self._close()
            self._outcome_ready.notify_all()
            self._notify(None)

    def close(self) -> None:
        """Close the file without a word (the session stays resumable as it is)."""
        with self.lock:
            self._close()

    # -- what the front ends read -----------------------------------------------------------

    @property
    def path(self) -> Path:
        """The session file."""
        return Path(self._writer.path)

    @property
    def failure(self) -> str | None:
        """Why the session failed (a write failed: the journal's sentence, e.g. a full disk),
        or ``None``. The session file keeps everything acknowledged before it."""
        with self.lock:
            return self._failure

    @property
    def last_hash(self) -> str:
        """The sha256 of the file's last line (print it: it anchors the file)."""
        return str(self._writer.last_hash)

    def analysis(self) -> Any:
        """The live analysis of the session so far (the analysis kind's; for repeatability equal
        to the batch analysis of the session file). StationError before there is anything."""
        with self.lock:
            snapshot = self._live.snapshot()
            if hasattr(snapshot, "excluded_cycles"):
                rejected = tuple(r.cycle for r in self._cycles if r.rejected is not None)
                snapshot = replace(snapshot, excluded_cycles=rejected)
            return snapshot

    def analysis_or_none(self) -> Any:
        """:meth:`analysis`, or ``None`` while there is nothing to analyse."""
        try:
            return self.analysis()
        except StationError:
            return None

    def state(self) -> RunnerState:
        """An immutable snapshot of where the session is."""
        with self.lock:
            item = self._item_or_none()
            views = self._step_views()
            if item is None:
                action = Action(
                    "done" if self.status in ("finished", "interrupted", "failed") else "finish",
                    prompt="Every step is done: finish the session.",
                )
                progress = None
            elif self.status in ("finished", "interrupted", "failed"):
                action, progress = Action("done"), None
            else:
                handler = handler_for(item.step.kind)
                action, progress = handler.action(self, item), handler.progress(self, item)
            return RunnerState(
                path=self.path,
                status=self.status,
                steps=views,
                current=views[self._position] if item is not None else None,
                action=action,
                progress=progress,
                placement=item.placement if item is not None else None,
                placements=item.placements if item is not None else None,
                cycles=tuple(self._cycles),
                instruments=self._instrument_states(),
                messages=tuple(self._messages),
                last_hash=self.last_hash,
                alarms=self._alarm_count,
                alarm_list=self._alarm_list,
                failure=self._failure or "",
                next_cycle=self._next_cycle,
                zero={channel: dict(zeroed) for channel, zeroed in self.recorded_zero.items()},
            )

    def prompt(self) -> str:
        """The current step's instruction for the operator, or what to do once every step is
        done."""
        with self.lock:
            item = self._item_or_none()
            if item is None:
                return "Every step is done: finish the session."
            return handler_for(item.step.kind).prompt(self, item)

    # -- for step handlers ------------------------------------------------------------------
    # Called by the handlers in station/run/steps with the lock held unless said otherwise.

    def handler(self, item: PlanItem) -> StepHandler:
        """The handler of a plan item's step kind."""
        return handler_for(item.step.kind)

    def step_state(self, item: PlanItem) -> dict[str, Any]:
        """A plan item's own mutable state (a handler's counters), kept for the session."""
        return self._step_states.setdefault(item.key, {})

    @property
    def devices_pace(self) -> bool:
        """True when the devices decide when a set is taken (push, arrival)."""
        return self.setup.trigger in DEVICE_DRIVEN_TRIGGERS

    @property
    def next_cycle(self) -> int:
        """The number the next recorded cycle gets."""
        return self._next_cycle

    def accepted_in(self, item: PlanItem) -> int:
        """Accepted cycles recorded in a plan item."""
        return self._accepted_by_step.get(item.key, 0)

    def claim(self) -> None:
        """Mark a capture, zero or stroke under way, and the step it belongs to: its result
        is recorded only while that step is still current."""
        if self.busy:
            raise StationError("a capture or zero is already under way: wait for it")
        self.busy = True
        self._claimed_position = self._position

    def release(self) -> None:
        """End what :meth:`claim` began."""
        self.busy = False

    def ensure_open(self) -> None:
        """StationError when the file takes nothing more (failed, finished, interrupted)."""
        if self.status == "failed" and self._failure:
            raise StationError(self._failure)
        if self.status in ("finished", "interrupted", "failed"):
            raise StationError(f"the session is {self.status}: {self.path}")

    def ensure_running(self) -> None:
        """:meth:`ensure_open`, and StationError while captures are paused."""
        self.ensure_open()
        if self.status == "paused":
            raise StationError("capture is paused: resume it first")

    def complete_step(self, item: PlanItem, by: str) -> None:
        """Write the plan item's ``step`` event and move on."""
        handler_for(item.step.kind).closing(self, item)
        self.append(
            "step",
            step=item.step.id,
            placement=item.placement,
            kind=item.step.kind,
            action="confirmed",
            by=by,
        )
        self._position += 1
        self._step_entered()
        self._notify(None)

    def take_set(self, timeout: float, by: str) -> CycleOutcome:
        """Take one reading set for the current step (called without the lock): with a trigger
        the devices drive (push, arrival) wait for the next set, which the intake records;
        otherwise poll the gauges and record what they give."""
        with self.lock:
            if self.setup.trigger in DEVICE_DRIVEN_TRIGGERS:
                seen = self._outcomes
                if not self._outcome_ready.wait_for(
                    lambda: self._outcomes != seen or self.status != "running", timeout
                ):
                    outcome = self.refuse(
                        f"No reading set arrived within {timeout:g} s: "
                        + (
                            "press DATA on the gauges (or check the cable)."
                            if self.setup.trigger == "push"
                            else "run the robot's playback (or check the cable)."
                        )
                    )
                    return replace(outcome, waited=True)
                if self.status == "failed":
                    self.ensure_open()  # raises the failure's own sentence
                if self.status != "running" or self._last_outcome is None:
                    return self.refuse(f"The session is {self.status}; nothing recorded.")
                return self._last_outcome
            self.claim()
        try:
            result = self.gauges.capture(timeout)
        except BaseException:
            with self.lock:
                self.release()
            raise
        with self.lock:
            self.release()
            return self.record_set(result, by=by, position=self._claimed_position)

    def record_set(
        self, result: CaptureResult, by: str, position: int | None = None
    ) -> CycleOutcome:
        """Hand a reading set to the current step if it takes sets and (``position``) is still
        the step the set was taken for. Lock held."""
        if self.status != "running":
            outcome = self.refuse(
                f"The session is {self.status}; the reading set was not recorded."
            )
        elif position is not None and position != self._position:
            outcome = self.refuse(
                "The step changed while the reading set was taken; it was not recorded."
            )
        else:
            item = self._item_or_none()
            handler = handler_for(item.step.kind) if item is not None else None
            if item is None or handler is None or not handler.takes_sets:
                outcome = self.refuse(
                    "No capture step is current; the reading set was not recorded."
                )
            else:
                outcome = handler.accept_set(self, item, result, by)
        self._last_outcome = outcome
        self._outcomes += 1
        self._outcome_ready.notify_all()
        return outcome

    def set_problem(self, result: CaptureResult, needed: Sequence[str]) -> str:
        """Why a reading set cannot be a cycle ('' when it can): a needed channel missing,
        stale or duplicated, or in another unit than the session's."""
        return set_problem(result, needed, self.setup.resolved_unit)

    def write_cycle(self, item: PlanItem, readings: Mapping[str, Any], by: str) -> CycleOutcome:
        """Write a whole reading set as the next cycle of ``item``; the listener hears of it
        as soon as it is on disk, the live analysis and its alarms follow."""
        number = self._next_cycle
        self.append(
            "reading",
            notify=False,
            cycle=number,
            step=item.step.id,
            placement=item.placement,
            by=by,
            channels={
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
        )
        self._next_cycle = number + 1
        record = CycleRecord(
            cycle=number,
            values={channel: float(r.value) for channel, r in readings.items()},
            step_id=item.step.id,
            placement=item.placement,
            resolution=self.setup.resolved_resolution,
            times=cycle_times(list(readings), self._last_event or {}),
        )
        self._cycles.append(record)
        self._accepted_by_step[item.key] = self._accepted_by_step.get(item.key, 0) + 1
        self._accepted_count += 1
        # Acknowledged: the listener hears of the reading as soon as it is on disk, with the
        # state that includes it (the last-reading line); the live figures and alarms follow.
        self._notify(self._last_event)
        self._record_alarms(self._live.add_cycle(record.values, number, record.times), number)
        self._notify(None, analysis=True)
        return CycleOutcome(recorded=True, message=record.line(), cycle=record)

    def stroke_recorded(self, outcome: StrokeOutcome) -> None:
        """A whole stroke is on disk: the live analysis takes it and the listener hears."""
        with self.lock:
            self._live.add_stroke(outcome)
            self._notify(None, analysis=True)

    def refuse(self, message: str) -> CycleOutcome:
        """A set not recorded, with the operator's sentence."""
        self.say("warning", message)
        return CycleOutcome(recorded=False, message=message)

    def open_stream_queue(self) -> queue.SimpleQueue[Any]:
        """Route every pushed set to a stream under way (in order, none dropped)."""
        with self._intake_lock:
            self._stream_queue = queue.SimpleQueue()
            return self._stream_queue

    def close_stream_queue(self) -> None:
        """Pushed sets go back to the intake."""
        with self._intake_lock:
            self._stream_queue = None

    def append(self, event_type: str, *, notify: bool = True, **fields: Any) -> dict[str, Any]:
        """Write one event (fsynced when this returns). A failed write marks the engine failed
        and re-raises the journal's sentence."""
        fields = {k: v for k, v in fields.items() if v is not None}
        try:
            event = self._writer.append(event_type, **fields)
        except StationError as error:
            if self._writer.closed:
                self.status = "failed"
                self._failure = error.message
                self.say("error", error.message)
                self._outcome_ready.notify_all()
            raise
        self._last_event = event
        if notify:
            self._notify(event)
        return event

    def say(self, level: MessageLevel, text: str) -> None:
        """An operator message (kept, and sent to the listener)."""
        message = OperatorMessage(level, text)
        self._messages.append(message)
        self._tell(RunnerNotice(None, self.state(), message))

    # -- internals --------------------------------------------------------------------------

    def _rebuild_live(self, session: Session | None = None) -> None:
        """Recount the accepted cycles and rebuild the live analysis from them (after a
        reject; on resume with the session's own record of what is not a cycle)."""
        self._accepted_by_step = {}
        accepted = [r for r in self._cycles if r.rejected is None]
        for record in accepted:
            key = (record.step_id, record.placement)
            self._accepted_by_step[key] = self._accepted_by_step.get(key, 0) + 1
        self._accepted_count = len(accepted)
        self._live = self._live.rebuilt([(r.values, r.cycle, r.times) for r in accepted], session)

    def zero_recorded(self, event: Mapping[str, Any]) -> None:
        """A ``zero`` event is on disk: the zero in force changed, and with it what the
        analysis takes as the zero's own uncertainty (the live analysis is rebuilt on it, so it
        stays equal to the batch analysis of the file). Lock held."""
        for channel, zeroed in dict(event.get("channels") or {}).items():
            self.recorded_zero[str(channel)] = dict(zeroed)
        self._zero_config()
        self._rebuild_live()

    def _zero_config(self) -> None:
        """The analysis config with the recorded zeros' uncertainties; a new live analysis on
        it (the caller rebuilds it from the cycles)."""
        config = analysis_config(self.header, [{"channels": self.recorded_zero}])
        if config.zero_uncertainty != self.config.zero_uncertainty:
            self.config = config
            self._live = self.kind.live(self.config, self.setup.channels, self.header)

    def _item_or_none(self) -> PlanItem | None:
        return self._plan[self._position] if self._position < len(self._plan) else None

    def _current_item(self) -> PlanItem:
        self.ensure_open()
        item = self._item_or_none()
        if item is None:
            raise StationError("every step is done: finish the session")
        return item

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

    def _record_alarms(self, updates: Mapping[str, Any], raised_at: int) -> None:
        """Write ``alarm`` events for the alarms cycle ``raised_at`` raised (the windows it
        completes, O(1))."""
        for channel, update in updates.items():
            for alarm in update.alarms:
                self._record_alarm(channel, alarm, raised_at)

    def _record_alarm(self, channel: str, alarm: Any, raised_at: int) -> None:
        # The live analysis is fed each set with its cycle number: its alarms name cycles.
        cycles = list(alarm.cycles)
        if not cycles:
            return
        flagged = self._alarm_flagged.setdefault((channel, alarm.rule), set())
        known = not flagged.isdisjoint(cycles)
        flagged.update(cycles)
        if known:
            return
        # The fields of LiveAlarm.event_fields: what a replay of the file gives back.
        event = self.append(
            "alarm",
            channel=channel,
            rule=alarm.rule,
            rule_name=rule_name(alarm.rule),
            points=list(alarm.points),
            cycles=cycles,
            text=alarm.text,
            raised_at=raised_at,
            live=True,
        )
        self._alarm_count += 1
        self._alarm_list = (*self._alarm_list, recorded_alarm(event))
        self.say("warning", f"{channel}: {rule_name(alarm.rule)}: {alarm.text}")

    def _close(self) -> None:
        """Close the file and let go of the gauges (the subscription is cancelled, so a gauge
        set resumed on again and again never keeps dead engines) and end the intake thread."""
        self._writer.close()
        if self._subscription is not None:
            self._subscription.cancel()
            self._subscription = None
        if self._intake is not None:
            self._intake.put(None)

    def _notify(self, event: Mapping[str, Any] | None, *, analysis: bool = False) -> None:
        if self._listener is None:
            return
        live = self.analysis_or_none() if analysis else None
        result = self._live.result() if analysis else None
        self._tell(RunnerNotice(event, self.state(), analysis=live, result=result))

    def _tell(self, notice: RunnerNotice) -> None:
        if self._listener is None:
            return
        try:
            self._listener(notice)
        except Exception as error:  # a display's bug must not undo a recorded event
            self._messages.append(OperatorMessage("error", f"the display failed: {error!r}"))


def cycle_times(channels: Sequence[str], event: Mapping[str, Any]) -> dict[str, float] | None:
    """The time of a cycle's readings for the drift's trend: its ``reading`` event's ``t``
    (what the session file's analysis and its exports use), for every channel."""
    stamp = event_seconds(str(event.get("t") or ""))
    return None if math.isnan(stamp) else dict.fromkeys(channels, stamp)


def set_problem(result: CaptureResult, needed: Sequence[str], unit: str) -> str:
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


__all__ = ["CAPTURE_BY", "Gauges", "Journal", "Progress", "Runner", "set_problem"]
