"""What the instruments send the engine, on their threads: completed sets (push, arrival), port
changes and the arrival detector's news. Each is queued, without the engine's lock, to the
engine's own intake thread, which writes it (so a reader keeps draining its line while the disk
syncs); a stream under way takes every set in order instead.

:class:`InstrumentIntake` is a part of :class:`~station.run.engine.Runner` (its attributes are
set up there).
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from typing import TYPE_CHECKING, Any

from station.analysis.diagnostics import import_scipy
from station.errors import StationError
from station.run.readings import DEVICE_DRIVEN_TRIGGERS
from station.run.state import (
    MessageLevel,
    PortState,
)
from station.run.steps import handler_for

if TYPE_CHECKING:
    from station.instruments.capture import CaptureResult
    from station.instruments.reader import PortStatus


class InstrumentIntake:
    """The engine's intake of sets, port changes and arrivals (a part of the Runner)."""

    def _attach(self, moment: str) -> None:
        """Start the intake thread, subscribe to the gauges' sets and port changes (cancelled
        by :meth:`_close`) and record how each line stands now. On failure everything is undone
        and the file closed."""
        # scipy loads here, on the thread that starts the session and before the threads that
        # analyse start: not on the intake under the lock when the live limits freeze
        # mid-session, and never on two threads at once (that deadlocked under load).
        import_scipy()
        self._intake = queue.SimpleQueue()
        self._intake_thread = threading.Thread(
            target=self._take_in, name="runner intake", daemon=True
        )
        self._intake_thread.start()
        self._start_analysis_thread()
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

    def open_stream_queue(self) -> queue.SimpleQueue[Any]:
        """Route every pushed set to a stream under way (in order, none dropped)."""
        with self._intake_lock:
            self._stream_queue = queue.SimpleQueue()
            return self._stream_queue

    def close_stream_queue(self) -> None:
        """Pushed sets go back to the intake."""
        with self._intake_lock:
            self._stream_queue = None

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
