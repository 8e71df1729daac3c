"""The procedure engine: one state machine that turns a procedure's steps, the operator's
actions and the instruments' readings into session events.

The TUI, ``station capture`` and the demo's autopilot all drive a :class:`Runner`; how a step
behaves lives in its kind's handler (:mod:`station.run.steps`), how a session is judged in its
method (:mod:`station.methods`). The engine itself holds no step-kind or method branch. Its rules:

* A step is *done* when its ``step`` event is on disk. What completes it is its handler's
  answer; the operator's next :class:`~station.run.state.Action` is too.
* *Acknowledged* means: the event is fsynced (the journal's ``append`` returns only then). The
  listener hears of a reading after that, with the state and the live analysis that include it
  (:class:`~station.run.state.RunnerNotice`): a display never takes the engine's lock.
* Cycles are numbered 1, 2, ... over the whole session; a rejected cycle keeps its number
  (readings are never deleted), a resumed session continues the numbering. A reject names
  its cycle (:meth:`Runner.reject`): cycles may arrive while the operator types the reason.
* Alarms of the live analysis are written as ``alarm`` events (``live`` true, the rule named
  in words) when they first appear; an alarm is new unless it flags a cycle an alarm of the
  same rule and channel already flagged (a run growing by a point is one alarm). The live
  analysis judges against frozen (phase II) limits, so a written alarm never goes away, and a
  replay of the file (:func:`~station.analysis.monitor.replay_live_alarms`) gives exactly the
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

import queue
import threading
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from station.errors import StationError
from station.methods import method_of
from station.methods.contract import LiveVerdict
from station.run.alarms import AlarmJournal
from station.run.intake import InstrumentIntake
from station.run.notices import LiveNotices
from station.run.readings import cycle_times
from station.run.services import StepServices
from station.run.setup import SessionSetup, resume_setup, unroll
from station.run.state import (
    Action,
    CycleLog,
    CycleOutcome,
    CycleRecord,
    Listener,
    OperatorMessage,
    RunnerState,
    RunnerStatus,
    StepView,
)
from station.run.steps import handler_for
from station.run.steps.base import PlanItem
from station.session.alarms import (
    RecordedAlarm,
    recorded_alarms,
)
from station.session.header import analysis_config
from station.session.journal import SessionWriter
from station.session.model import Session

if TYPE_CHECKING:
    from station.instruments.capture import CaptureResult
    from station.instruments.gauge import Subscription

CAPTURE_BY = "station capture"
"""The ``by`` recorded when the headless command confirms a step itself."""

_MESSAGES_KEPT = 20


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
    def stops(self) -> dict[str, float]: ...
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


class Runner(InstrumentIntake, AlarmJournal, StepServices, LiveNotices):
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
        self._rejected_cycles: tuple[int, ...] = ()
        """The numbers of the rejected cycles, in order (kept on every reject: the live
        analysis names them as excluded without a walk through every cycle)."""
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
        self._alarm_flagged: dict[tuple[str, str], set[int]] = {}
        self._alarm_list: tuple[RecordedAlarm, ...] = ()
        self._port_states: dict[str, str] = {}
        self._arm_pending = False
        self._armed_at = float("-inf")
        self.header: Mapping[str, Any] = writer.snapshot().header
        self.config = analysis_config(self.header)
        self.method = method_of(setup.procedure.analysis)
        self._live: LiveVerdict = self.method.live(self.config, setup.channels, self.header)
        # The live analysis's changes, the last one computed (version, analysis, result,
        # problem) and the thread that sends it to the listener (station.run.notices).
        self._live_version = 0
        self._analysed: tuple[int, Any, Any, StationError | None] | None = None
        self._analysis_wanted = threading.Event()
        self._analysis_stop = False
        self._analysis_thread: threading.Thread | None = None
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
                        part=cycle.part,
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

    def reject(self, cycle: int, reason: str, by: str = "operator") -> None:
        """Reject cycle number ``cycle`` with ``reason`` (its readings stay in the file, the
        analysis leaves it out). The cycle is named, never "the last one": a cycle that
        arrives while the operator types the reason is not the one rejected. StationError,
        with nothing written, for a cycle the session has not recorded or one already
        rejected."""
        reason = reason.strip()
        if not reason:
            raise StationError(f"give a reason for rejecting cycle {cycle}")
        with self.lock:
            self.ensure_open()
            index = next(
                (i for i in range(len(self._cycles) - 1, -1, -1) if self._cycles[i].cycle == cycle),
                None,
            )
            if index is None:
                recorded = (
                    f"the last recorded is cycle {self._cycles[-1].cycle}"
                    if self._cycles
                    else "no cycle is recorded yet"
                )
                raise StationError(f"there is no cycle {cycle} to reject ({recorded})")
            record = self._cycles[index]
            if record.rejected is not None:
                raise StationError(
                    f"cycle {cycle} is already rejected ({record.rejected}); nothing was written"
                )
            self.append("reject", cycle=record.cycle, reason=reason, by=by, notify=False)
            # A new list: the states already taken keep the cycles as they were.
            self._cycles = list(self._cycles)
            self._cycles[index] = replace(record, rejected=reason)
            self._rebuild_live()
            self.say("info", f"Cycle {record.cycle} rejected: {reason}.")
            self._notify(self._last_event)  # the analysis without it follows

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
            self._method_finished()
            self._notify(None, analysis=True)
            return self.analysis_or_none()

    def _method_finished(self) -> None:
        """What the method does with a finished session (a gauge study files itself in the
        gauge register); its failure is a warning: the session is safe on disk."""
        try:
            for sentence in self.method.finished(self.path):
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
                cycles=CycleLog(self._cycles, self._accepted_count),
                instruments=self._instrument_states(),
                messages=tuple(self._messages),
                last_hash=self.last_hash,
                alarms=len(self._alarm_list),
                alarm_list=self._alarm_list,
                failure=self._failure or "",
                next_cycle=self._next_cycle,
                # Entries are replaced whole, never changed in place: a shallow copy will do.
                zero=dict(self.recorded_zero),
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

    def _rebuild_live(self, session: Session | None = None) -> None:
        """Recount the accepted cycles and rebuild the live analysis from them (after a
        reject; on resume with the session's own record of what is not a cycle)."""
        self._accepted_by_step = {}
        accepted = [r for r in self._cycles if r.rejected is None]
        self._rejected_cycles = tuple(r.cycle for r in self._cycles if r.rejected is not None)
        for record in accepted:
            key = (record.step_id, record.placement)
            self._accepted_by_step[key] = self._accepted_by_step.get(key, 0) + 1
        self._accepted_count = len(accepted)
        self._live = self._live.rebuilt(
            [(r.values, r.cycle, r.times, r.placement, r.part) for r in accepted], session
        )
        self._live_changed()

    def zero_recorded(self, event: Mapping[str, Any]) -> None:
        """A ``zero`` event is on disk: the zero in force changed, and with it what the
        analysis takes as the zero's own uncertainty (the live analysis is rebuilt on it, so it
        stays equal to the batch analysis of the file). Lock held."""
        for channel, zeroed in dict(event.get("channels") or {}).items():
            self.recorded_zero[str(channel)] = dict(zeroed)
        if not self._zero_config():
            return
        # A live analysis on the new config, fed the cycles taken so far in order (rebuilt as
        # after a reject it would adopt the new, empty one's monitor and drop them all). Their
        # alarms are on disk already: what the feeding raises again is not recorded twice.
        for record in self._cycles:
            if record.rejected is None:
                self.feed_live(record)
        self._live_changed()

    def _zero_config(self) -> bool:
        """The analysis config with the recorded zeros' uncertainties, and a new (empty) live
        analysis on it when that changed (the caller feeds it the cycles); True then."""
        config = analysis_config(self.header, [{"channels": self.recorded_zero}])
        if (config.zero_uncertainty, config.zero_draws) == (
            self.config.zero_uncertainty,
            self.config.zero_draws,
        ):
            return False
        self.config = config
        self._live = self.method.live(self.config, self.setup.channels, self.header)
        return True

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

    def _close(self) -> None:
        """Close the file and let go of the gauges (the subscription is cancelled, so a gauge
        set resumed on again and again never keeps dead engines) and end the intake thread."""
        self._writer.close()
        self._stop_analysis_thread()
        if self._subscription is not None:
            self._subscription.cancel()
            self._subscription = None
        if self._intake is not None:
            self._intake.put(None)


__all__ = ["CAPTURE_BY", "Gauges", "Journal", "Runner"]
