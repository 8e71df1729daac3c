"""What the step handlers (:mod:`station.run.steps`) call on the engine: the plan item's state,
claiming a capture, completing a step, taking and recording reading sets, writing events and
saying things to the operator. Called with the engine's lock held unless a method says
otherwise. :class:`StepServices` is a part of :class:`~station.run.engine.Runner` (its
attributes are set up there).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.run.readings import DEVICE_DRIVEN_TRIGGERS, cycle_times, set_problem
from station.run.state import (
    CycleOutcome,
    CycleRecord,
    MessageLevel,
    OperatorMessage,
    RunnerNotice,
    StrokeOutcome,
)
from station.run.steps import handler_for
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.instruments.arrival import ReturnTrace
    from station.instruments.capture import CaptureResult


class StepServices:
    """The engine's services to the step handlers (a part of the Runner)."""

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

    def accepted_parts(self, item: PlanItem) -> set[int]:
        """The parts an accepted cycle of a plan item measured (a ``parts`` step's)."""
        return {
            record.part
            for record in self._cycles
            if record.rejected is None
            and record.part is not None
            and (record.step_id, record.placement) == item.key
        }

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

    def write_cycle(
        self, item: PlanItem, readings: Mapping[str, Any], by: str, *, part: int | None = None
    ) -> CycleOutcome:
        """Write a whole reading set as the next cycle of ``item`` (``part``: the part it is a
        reading of, for a step that presents parts); the listener hears of it as soon as it is
        on disk, the live analysis and its alarms follow."""
        number = self._next_cycle
        self.append(
            "reading",
            notify=False,
            cycle=number,
            step=item.step.id,
            placement=item.placement,
            part=part,
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
            part=part,
        )
        self._cycles.append(record)
        self._accepted_by_step[item.key] = self._accepted_by_step.get(item.key, 0) + 1
        self._accepted_count += 1
        # Acknowledged: the listener hears of the reading as soon as it is on disk, with the
        # state that includes it (the last-reading line); the alarms follow, and the live
        # analysis comes from the analysis thread (station.run.notices).
        self._notify(self._last_event)
        self._record_alarms(self.feed_live(record), number)
        self._live_changed()
        return CycleOutcome(recorded=True, message=record.line(), cycle=record)

    def feed_live(self, record: CycleRecord) -> Mapping[str, Any]:
        """Give the live analysis one accepted cycle; its new alarms per channel. A cycle of a
        part is given with its ``part`` (a method whose procedure presents parts takes it)."""
        extra = {} if record.part is None else {"part": record.part}
        return self._live.add_cycle(
            record.values, record.cycle, record.times, record.placement, **extra
        )

    def stroke_recorded(self, outcome: StrokeOutcome) -> None:
        """A whole stroke is on disk: the live analysis takes it and the listener hears."""
        with self.lock:
            self._live.add_stroke(outcome)
            self._live_changed()

    def refuse(self, message: str) -> CycleOutcome:
        """A set not recorded, with the operator's sentence."""
        self.say("warning", message)
        return CycleOutcome(recorded=False, message=message)

    def write_trace(self, item: PlanItem, cycle: int, trace: ReturnTrace) -> None:
        """Write the trace of the return that ended in ``cycle`` (the step's channels of it),
        after its reading: times in seconds after the first arrival, rounded to the µs the
        reading clock is worth."""
        columns = [i for i, c in enumerate(trace.channels) if c in item.step.channels]
        if not columns:
            return
        self.append(
            "trace",
            notify=False,
            cycle=cycle,
            step=item.step.id,
            channels=[trace.channels[i] for i in columns],
            times=[round(t - trace.arrived, 6) for t in trace.t],
            values=[[row[i] for i in columns] for row in trace.rows],
            every=trace.every,
            t0=trace.arrived,
        )

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
