"""The gauge set: the readers of one station, read together, captured by trigger.

:class:`GaugeSet` groups the :class:`~station.instruments.reader.GaugeReader` of each port of a
station (x, y, z on one multiplexed port, on three cables, or a mix), keeps each channel's recent
readings, assembles push and arrival sets as readings come in, and tells its subscribers of sets,
port changes and arrival events. Its parts: captures by trigger
(:mod:`station.instruments.capture`), zeros (:mod:`station.instruments.zero_gauges`) and the
frames' unit and resolution (:mod:`station.instruments.frame_check`).

No Textual here: the TUI wraps the callbacks (they run on reader threads).
"""

from __future__ import annotations

import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig, ArrivalDetector, ArrivalEvent
from station.instruments.base import Protocol, Rejection, SerialSettings
from station.instruments.capture import CaptureResult, SetCaptures
from station.instruments.frame_check import SetFrameChecks
from station.instruments.motion import default_free_travel
from station.instruments.reader import (
    DEFAULT_BACKOFF,
    GaugeReader,
    GaugeReading,
    PortStatus,
    State,
    TriggerTicket,
    call_quietly,
)
from station.instruments.travel import TravelWatch
from station.instruments.triggers import TRIGGERS, Trigger
from station.instruments.zero_gauges import SetZeroing
from station.text import format_figure


@dataclass(frozen=True)
class PortSpec:
    """One port of a station: where, which protocol, and its device→station channel map."""

    url: str
    protocol: Protocol
    channel_map: Mapping[str, str] = field(default_factory=dict)
    settings: SerialSettings | None = None


class Subscription:
    """A listener's hold on a :class:`GaugeSet`: :meth:`cancel` ends it (idempotent)."""

    def __init__(self, cancel: Callable[[], None]) -> None:
        self._cancel = cancel

    def cancel(self) -> None:
        """Stop hearing of sets and port changes."""
        self._cancel()


class GaugeSet(SetCaptures, SetZeroing, SetFrameChecks):
    """The gauges of one station over one or more ports, captured together by trigger.

    ``resolution`` (one number or one per channel) and ``stable_k``/``stable_ms`` define the
    ``stable`` trigger; ``poll_interval`` is how often a polled device is asked while streaming.
    ``on_set`` receives each completed push or arrival set (on a reader thread); :meth:`wait_set`
    returns them in order. ``arrival`` configures the ``arrival`` trigger (defaults otherwise);
    ``on_arrival`` receives its other events (departed, returned, and ``unsettled`` with its
    sentence in ``message``), on a reader or the streaming thread. The callbacks and ``events``
    go to every reader.
    """

    def __init__(
        self,
        ports: Sequence[PortSpec],
        *,
        trigger: Trigger = "poll",
        unit: str = "mm",
        resolution: float | Mapping[str, float] = 0.001,
        stable_k: float = 2.0,
        stable_ms: float = 500.0,
        poll_interval: float = 0.1,
        on_reading: Callable[[GaugeReading], object] | None = None,
        on_rejection: Callable[[Rejection], object] | None = None,
        on_status: Callable[[PortStatus], object] | None = None,
        on_set: Callable[[CaptureResult], object] | None = None,
        events: queue.Queue | None = None,
        backoff: tuple[float, float] = DEFAULT_BACKOFF,
        history: int = 256,
        arrival: ArrivalConfig | None = None,
        on_arrival: Callable[[ArrivalEvent], object] | None = None,
    ) -> None:
        if trigger not in TRIGGERS:
            raise StationError(f"Unknown trigger {trigger!r}: use one of {', '.join(TRIGGERS)}.")
        self.trigger = trigger
        self.on_reading = on_reading
        self.on_set = on_set
        self.on_status = on_status
        # Listeners added by subscribe(): each gets every set and port change, and leaves by
        # cancelling its subscription (nobody swaps another's callback).
        self._set_listeners: list[Callable[[CaptureResult], object]] = []
        self._status_listeners: list[Callable[[PortStatus], object]] = []
        self._arrival_listeners: list[Callable[[ArrivalEvent], object]] = []
        self.stable_k = stable_k
        self.stable_ms = stable_ms
        self.poll_interval = poll_interval
        self.readers = [
            GaugeReader(
                spec.url,
                spec.protocol,
                spec.channel_map,
                settings=spec.settings,
                unit=unit,
                on_reading=self._on_reading,
                on_rejection=on_rejection,
                on_status=self._on_status,
                events=events,
                backoff=backoff,
            )
            for spec in ports
        ]
        channels: list[str] = []
        for reader in self.readers:
            for channel in reader.channels:
                if channel in channels:
                    raise StationError(
                        f"Channel {channel!r} is served by two ports: map each station "
                        "channel to one device channel."
                    )
                channels.append(channel)
        self.channels = tuple(channels)
        if isinstance(resolution, Mapping):
            self.resolution = {c: float(resolution.get(c, 0.001)) for c in channels}
        else:
            self.resolution = dict.fromkeys(channels, float(resolution))
        self._reader_of = {c: r for r in self.readers for c in r.channels}
        self._history: dict[str, deque[GaugeReading]] = {c: deque(maxlen=history) for c in channels}
        self._changed = threading.Condition()
        self._pending: dict[str, GaugeReading] = {}
        self._pending_duplicated: set[str] = set()
        self._sets: deque[CaptureResult] = deque(maxlen=64)
        self._push_armed_at = 0.0
        self.on_arrival = on_arrival
        self.arrival_config = arrival or ArrivalConfig()
        self._detector: ArrivalDetector[GaugeReading] | None = (
            ArrivalDetector(self.channels, self.resolution, self.arrival_config)
            if trigger == "arrival"
            else None
        )
        config = self.arrival_config
        self.travel = TravelWatch(
            self.resolution,
            {c: config.band_of(res) for c, res in self.resolution.items()},
            still=config.still,
            settle=config.settle,
            side=config.stop,
            free_travel=config.free_travel,
            depth=abs(default_free_travel(unit)) / 2,
        )
        """Where each plunger rests with nothing touching it (stated, or learned from the
        robot's motion), so that no zero and no set is taken with the robot away."""
        self._collectors: list[dict[str, list[GaugeReading]]] = []
        self._streaming = threading.Event()
        self._stream_thread: threading.Thread | None = None

    # -- life cycle ----------------------------------------------------------------------

    def start(self) -> None:
        """Start every reader (each connects in the background); with the ``arrival`` trigger
        also the thread that polls continuously and keeps the detector's clock."""
        for reader in self.readers:
            reader.start()
        if self._detector is not None and self._stream_thread is None:
            self._streaming.set()
            self._stream_thread = threading.Thread(
                target=self._stream, name="gauge-set arrival", daemon=True
            )
            self._stream_thread.start()

    def stop(self) -> None:
        """Stop every reader; returns within about a second."""
        self._streaming.clear()
        if self._stream_thread is not None:
            self._stream_thread.join(1.0)
            self._stream_thread = None
        for reader in self.readers:
            reader.stop(timeout=1.0)

    def _stream(self) -> None:
        """The ``arrival`` trigger's thread: poll every polled port each ``poll_interval``
        (no flush: every answer counts; no pile-up: one request in flight per port) and tell
        the detector the time, so a return that never settles is reported even when the line
        goes quiet."""
        in_flight: dict[GaugeReader, TriggerTicket] = {}
        while self._streaming.is_set():
            for reader in self.readers:
                if not reader.protocol.polled or reader.state != "connected":
                    continue
                ticket = in_flight.get(reader)
                if ticket is None or ticket.done.is_set():
                    in_flight[reader] = reader.trigger(True, flush=False)
            with self._changed:
                events = self._detector.tick(time.monotonic()) if self._detector else []
            self._deliver_arrival(events)
            time.sleep(self.poll_interval)

    @property
    def arrival_state(self) -> str:
        """Where the ``arrival`` trigger thinks the robot is: ``waiting`` (at the fixture, or
        not yet seen leaving), ``away`` or ``returned`` (back, waiting for stillness); '' for
        another trigger."""
        return self._detector.state if self._detector is not None else ""

    def __enter__(self) -> GaugeSet:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    def wait_connected(self, timeout: float) -> bool:
        """Wait until every port is open; True when they all are."""
        deadline = time.monotonic() + timeout
        return all(r.wait_connected(max(0.0, deadline - time.monotonic())) for r in self.readers)

    def status(self) -> dict[str, State]:
        """Each port's state, by URL."""
        return {reader.url: reader.state for reader in self.readers}

    def subscribe(
        self,
        *,
        on_set: Callable[[CaptureResult], object] | None = None,
        on_status: Callable[[PortStatus], object] | None = None,
        on_arrival: Callable[[ArrivalEvent], object] | None = None,
    ) -> Subscription:
        """Hear of every completed push or arrival set, every port change and (``on_arrival``)
        the arrival trigger's other events (departed, returned, unsettled), on reader threads,
        until the returned subscription is cancelled."""
        with self._changed:
            if on_set is not None:
                self._set_listeners.append(on_set)
            if on_status is not None:
                self._status_listeners.append(on_status)
            if on_arrival is not None:
                self._arrival_listeners.append(on_arrival)

        def cancel() -> None:
            with self._changed:
                if on_set is not None and on_set in self._set_listeners:
                    self._set_listeners.remove(on_set)
                if on_status is not None and on_status in self._status_listeners:
                    self._status_listeners.remove(on_status)
                if on_arrival is not None and on_arrival in self._arrival_listeners:
                    self._arrival_listeners.remove(on_arrival)

        return Subscription(cancel)

    @property
    def listeners(self) -> int:
        """How many set, status and arrival listeners are subscribed now."""
        with self._changed:
            return (
                len(self._set_listeners)
                + len(self._status_listeners)
                + len(self._arrival_listeners)
            )

    def _on_status(self, status: PortStatus) -> None:
        for listener in (self.on_status, *self._status_listeners):
            error = call_quietly(listener, status)
            if error is not None:
                raise error  # GaugeReader reports it as a status message

    # -- readings from the threads -------------------------------------------------------

    def _on_reading(self, reading: GaugeReading) -> None:
        completed = None
        arrival: list[ArrivalEvent] = []
        with self._changed:
            history = self._history.get(reading.channel)
            if history is not None:
                history.append(reading)
                self.travel.feed(reading.channel, reading.device_value, reading.t_mono)
                for collector in self._collectors:
                    collector[reading.channel].append(reading)
                if self.trigger == "push" and reading.t_mono >= self._push_armed_at:
                    completed = self._add_to_push_set(reading)
                elif self._detector is not None and reading.t_mono >= self._push_armed_at:
                    arrival = self._detector.feed(
                        reading.channel, reading.value, reading.t_mono, reading
                    )
                    completed = self._arrival_set(arrival)
            self._changed.notify_all()
        if completed is not None:
            for listener in (self.on_set, *self._set_listeners):
                error = call_quietly(listener, completed)
                if error is not None:
                    self.readers[0].report(f"set callback failed: {error!r}")
        self._deliver_arrival(arrival)
        error = call_quietly(self.on_reading, reading)
        if error is not None:
            raise error  # GaugeReader reports it as a status message

    def _arrival_set(self, events: list[ArrivalEvent]) -> CaptureResult | None:
        """The set of a ``settled`` event, queued for :meth:`wait_set`. Lock held."""
        for event in events:
            if event.kind == "settled":
                result = CaptureResult(
                    "arrival",
                    self.channels,
                    dict(event.readings),
                    t_trigger=event.t_arrived if event.t_arrived is not None else event.t,
                    at_stop=self.at_stop(event.readings),
                    trace=event.trace,
                )
                self._sets.append(result)
                return result
        return None

    def _deliver_arrival(self, events: list[ArrivalEvent]) -> None:
        """Hand the detector's events other than a set to ``on_arrival`` and the subscribers
        (no lock held)."""
        if not events:
            return
        with self._changed:
            listeners = (self.on_arrival, *self._arrival_listeners)
        for event in events:
            if event.kind == "settled":
                continue
            for listener in listeners:
                error = call_quietly(listener, event)
                if error is not None:
                    self.readers[0].report(f"arrival callback failed: {error!r}")

    def _add_to_push_set(self, reading: GaugeReading) -> CaptureResult | None:
        if not self._pending and len(self.readers) == 1 and reading.channel != self.channels[0]:
            # One port sends a set as a burst in its channels' order: a set starts with the
            # first, so the tail of a burst cut by arm() never joins the next burst's head.
            return None
        if reading.channel in self._pending:
            self._pending_duplicated.add(reading.channel)
            return None
        self._pending[reading.channel] = reading
        if len(self._pending) < len(self.channels):
            return None
        result = CaptureResult(
            "push",
            self.channels,
            dict(self._pending),
            duplicated=tuple(c for c in self.channels if c in self._pending_duplicated),
            t_trigger=min(r.t_mono for r in self._pending.values()),
            at_stop=self.at_stop(self._pending),
        )
        self._pending.clear()
        self._pending_duplicated.clear()
        self._sets.append(result)
        return result

    def waiting_sentence(self) -> str:
        """What the gauges see while no set comes, for an operator waiting on the robot: where
        the ``arrival`` trigger thinks the robot is and each channel's latest reading (empty
        for another trigger)."""
        if self._detector is None:
            return ""
        with self._changed:
            latest = {c: h[-1] for c, h in self._history.items() if h}
            state = self._detector.state
            at_stop = self.travel.at_stop({c: r.device_value for c, r in latest.items()})
        where = {
            "waiting": "the robot has not left the fixture since the last set (a set is taken "
            "each time it leaves and comes back to rest)",
            "away": "the robot is away from the fixture",
            "returned": "the robot came back to the fixture but is not still",
        }[state]
        if state == "away" and at_stop and len(at_stop) == len(self.channels):
            where = "the indicators rest at their free-travel stop: the robot is away"
        missing = [c for c in self.channels if c not in latest]
        shown = " ".join(
            f"{c} {format_figure(r.value, self.resolution[c])}" for c, r in latest.items()
        )
        reads = f"; the gauges read {shown}" if shown else ""
        silent = f"; no reading from {', '.join(missing)}" if missing else ""
        return f"{where}{reads}{silent}"

    def stops(self) -> dict[str, float]:
        """Each channel's free-travel stop as a device reading, where it is known (stated by
        the procedure, or learned from the robot's round trips)."""
        with self._changed:
            return self.travel.stops()

    def at_stop(self, readings: Mapping[str, GaugeReading]) -> tuple[str, ...]:
        """The channels of ``readings`` that sit at their known free-travel stop (the robot
        is away: such a set is never a cycle)."""
        return self.travel.at_stop({c: r.device_value for c, r in readings.items()})

    def set_zero_offsets(self, offsets: Mapping[str, float]) -> None:
        """Put recorded software-zero offsets back (a resumed session on fresh gauges):
        ``offsets`` by station channel, 0.0 for a channel zeroed by the device itself."""
        unknown = [c for c in offsets if c not in self._reader_of]
        if unknown:
            raise StationError(
                f"Cannot restore the zero of {', '.join(unknown)}: this station's channels are "
                f"{', '.join(self.channels)}."
            )
        for channel, offset in offsets.items():
            self._reader_of[channel].set_zero_offset(channel, float(offset))

    def zero_offsets(self) -> dict[str, float]:
        """The software zero offsets in force, by station channel (0.0 where none is)."""
        return {c: self._reader_of[c].zero_offsets().get(c, 0.0) for c in self.channels}
