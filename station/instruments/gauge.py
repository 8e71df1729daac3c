"""The gauge reader: one thread per port, reconnecting, and reading sets across ports.

:class:`GaugeReader` owns one port (a device path, ``rfc2217://`` or ``socket://`` URL). Its
thread opens the port, reads whatever arrived, cuts it into frames with the protocol's
:class:`~station.instruments.framing.FrameSplitter`, parses each frame and delivers a
:class:`GaugeReading` or a :class:`~station.instruments.base.Rejection` through callbacks
and/or a queue. All port I/O happens on that thread: requests and zero commands are queued to
it, so a poll flushes stale input, takes its timestamp and writes in one place, and every byte
read afterwards is stamped later than the request.

On ``OSError(EIO)`` or ``SerialException`` (unplug, device-server restart) the port is closed,
the status goes ``disconnected``, and the thread reopens with back-off (0.5 s doubling to 5 s)
until it is ``connected`` again. Bytes are consumed once and the partial frame is dropped on
reconnect, so no reading is invented or duplicated. ``stop()`` returns within about a second.

:class:`GaugeSet` groups the readers of one station (x, y, z on one multiplexed port, on three
cables, or a mix) and turns their streams into reading sets by trigger:

* ``poll``: each capture sends the requests; only answers read after the request count.
* ``push``: the device sends (DATA button, foot switch, data logger); a set completes when every
  channel has a reading since the last set.
* ``stable``: stream (polling continuously when the device is polled) and take the set once every
  channel has stayed within ``k`` × resolution for ``T`` ms.
* ``arrival``: read continuously (a background thread polls a polled device); the robot's own
  motion paces the cycles: a set is taken when the indicators have left their working band and
  come back to rest (:mod:`station.instruments.arrival`). Sets go to ``on_set`` as push sets do;
  a return that does not settle goes to ``on_arrival`` with a sentence, and is not a set.

A zero takes several readings per channel over a settle window and refuses while a gauge moves
(:mod:`station.instruments.zeroing`); the frames' decimals, steps and stated units are compared
with the session's unit and resolution by :meth:`GaugeSet.check_frames`
(:mod:`station.instruments.units`).

No Textual here: the TUI wraps the callbacks (they run on reader threads).
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig, ArrivalDetector, ArrivalEvent
from station.instruments.base import Protocol, Reading, Rejected, Rejection, SerialSettings
from station.instruments.transport import open_port
from station.instruments.units import (
    FrameInference,
    FrameSample,
    frames_disagree,
    infer_channel,
    unit_mismatch,
)
from station.instruments.zeroing import DEFAULT_ZERO_STILL, ChannelZero, zero_from_readings

State = Literal["connecting", "connected", "disconnected", "stopped"]
Trigger = Literal["poll", "push", "stable", "arrival"]
TRIGGERS: tuple[str, ...] = ("poll", "push", "stable", "arrival")

DEFAULT_BACKOFF = (0.5, 5.0)
"""First retry delay and its cap, in seconds; the delay doubles between failed attempts."""


@dataclass(frozen=True)
class GaugeReading(Reading):
    """A :class:`Reading` whose ``value`` is zeroed, with what the device itself said.

    ``value`` = ``device_value`` − ``zero_offset``. ``zero_offset`` is non-zero only after a
    software zero (a device without a zero command); a device zeroed by its own command already
    reports zeroed values, so there both are equal.
    """

    device_value: float = 0.0
    zero_offset: float = 0.0
    frame_unit: str | None = None
    """The unit the frame itself stated; None when it stated none (``unit`` is then the
    session's)."""


@dataclass(frozen=True)
class PortStatus:
    """A change of a reader's state, or a message about it (``message`` says what happened)."""

    port: str
    state: State
    message: str
    t_wall: float


class TriggerTicket:
    """A trigger queued to the reader thread: flush stale input, then (maybe) send requests.

    ``done`` is set once the thread has acted; then ``t_sent`` (monotonic) is when the input
    was flushed and the requests written, or ``error`` says why not.
    """

    __slots__ = ("send_requests", "flush", "done", "t_sent", "error")

    def __init__(self, send_requests: bool, flush: bool = True) -> None:
        self.send_requests = send_requests
        self.flush = flush
        self.done = threading.Event()
        self.t_sent: float | None = None
        self.error: str | None = None


def _call_quietly(callback: Callable[..., object] | None, *args: object) -> BaseException | None:
    """Call a user callback; return (never raise) what it raised."""
    if callback is None:
        return None
    try:
        callback(*args)
    except Exception as error:  # a bad callback must not kill the reader thread
        return error
    return None


def _raw_text(frame: bytes) -> str:
    return frame.decode("ascii", errors="backslashreplace")


def _without_binary_noise(value: float) -> float:
    """A zeroed value as the display shows it: 0.0001 - 0.0003 is -0.00019999999999999998 in
    binary; rounding at 1e-10 (far below any gauge's resolution) gives back -0.0002."""
    return round(value, 10)


class GaugeReader:
    """One port, one thread: frames in, :class:`GaugeReading` / :class:`Rejection` out.

    ``channel_map`` maps device channels to station channels (``{"1": "x", "2": "y"}``); a
    device channel it does not name keeps its own name. ``unit`` applies when a frame has none.
    Callbacks run on the reader thread; an exception in one is caught and reported as a
    status message. ``events``, when given, also receives every reading and rejection
    (``put_nowait``; when it is full the item is dropped and counted in ``dropped_events``).
    ``backoff`` is (first delay, cap) in seconds: tests pass a short one.
    """

    def __init__(
        self,
        url: str,
        protocol: Protocol,
        channel_map: Mapping[str, str] | None = None,
        *,
        settings: SerialSettings | None = None,
        unit: str = "mm",
        on_reading: Callable[[GaugeReading], object] | None = None,
        on_rejection: Callable[[Rejection], object] | None = None,
        on_status: Callable[[PortStatus], object] | None = None,
        events: queue.Queue | None = None,
        backoff: tuple[float, float] = DEFAULT_BACKOFF,
        read_timeout: float = 0.05,
        max_rejections: int = 200,
        max_frame: int = 256,
        exclusive: bool = True,
    ) -> None:
        from station.instruments.framing import FrameSplitter

        self.url = url
        self.protocol = protocol
        self.channel_map = dict(channel_map or {})
        self.settings = settings or protocol.settings
        self.unit = unit
        self.on_reading = on_reading
        self.on_rejection = on_rejection
        self.on_status = on_status
        self.events = events
        self.backoff = backoff
        self.read_timeout = read_timeout
        self.exclusive = exclusive
        self.rejections: deque[Rejection] = deque(maxlen=max_rejections)
        self.rejected_count = 0
        self.reading_count = 0
        self.dropped_events = 0
        self.reconnects = 0
        self.state: State = "stopped"
        self.last_message = ""
        self._splitter = FrameSplitter(protocol.terminator, max_frame)
        self._offsets: dict[str, float] = {}
        self._commands: deque[TriggerTicket | bytes] = deque()
        self._port = None
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    # -- configuration -------------------------------------------------------------------

    def station_channel(self, device_channel: str) -> str:
        """The station channel a device channel is mapped to (itself when unmapped)."""
        return self.channel_map.get(device_channel, device_channel)

    @property
    def channels(self) -> tuple[str, ...]:
        """Station channels this port serves, in the protocol's device-channel order."""
        return tuple(self.station_channel(device) for device in self.device_channels)

    @property
    def device_channels(self) -> tuple[str, ...]:
        """Device channels this port serves: the map's keys, else the protocol's channels."""
        return tuple(self.channel_map) or tuple(self.protocol.channels)

    def set_zero_offset(self, station_channel: str, offset: float) -> None:
        """Subtract ``offset`` from every later reading of ``station_channel`` (software zero)."""
        with self._lock:
            self._offsets[station_channel] = offset

    def zero_offsets(self) -> dict[str, float]:
        """The software zero offsets in force, by station channel."""
        with self._lock:
            return dict(self._offsets)

    # -- life cycle ----------------------------------------------------------------------

    def start(self) -> None:
        """Start the reader thread (it connects in the background)."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stopping.clear()
        self._thread = threading.Thread(
            target=self._run, name=f"gauge-reader {self.url}", daemon=True
        )
        self._thread.start()

    def stop(self, timeout: float = 1.0) -> None:
        """Stop the thread and close the port; returns within about ``timeout`` seconds."""
        self._stopping.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout)
        self._thread = None

    def __enter__(self) -> GaugeReader:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    @property
    def alive(self) -> bool:
        """True while the reader thread runs."""
        return self._thread is not None and self._thread.is_alive()

    def wait_connected(self, timeout: float) -> bool:
        """Wait until the port is open; True when it is."""
        deadline = time.monotonic() + timeout
        while self.state != "connected":
            if time.monotonic() >= deadline or not self.alive:
                return self.state == "connected"
            time.sleep(0.01)
        return True

    # -- requests to the thread -----------------------------------------------------------

    def trigger(self, send_requests: bool = True, flush: bool = True) -> TriggerTicket:
        """Queue a trigger: drop buffered input, stamp ``t_sent``, send each channel's request.

        Wait on ``ticket.done``; readings with ``t_mono >= ticket.t_sent`` answer it. When the
        port is down the ticket is done at once with ``error`` set. ``flush=False`` keeps
        buffered input (a stream of polls, where earlier answers are still wanted).
        """
        ticket = TriggerTicket(send_requests and self.protocol.polled, flush)
        if self.state != "connected":
            ticket.error = self._down_message()
            ticket.done.set()
            return ticket
        self._commands.append(ticket)
        self._wake()
        return ticket

    def send(self, data: bytes) -> None:
        """Queue raw bytes for the device (a zero command, for instance)."""
        if self.state != "connected":
            raise StationError(self._down_message())
        self._commands.append(bytes(data))
        self._wake()

    def _down_message(self) -> str:
        # Short on purpose: it is repeated per refused set, and the full reason was already
        # reported once through on_status when the state changed.
        if self.state == "stopped":
            return f"the port {self.url} is closed"
        if self.state == "connecting":
            return f"the port {self.url} is not open yet (connecting...)"
        return f"the port {self.url} is disconnected (reconnecting...)"

    def _wake(self) -> None:
        port = self._port
        cancel = getattr(port, "cancel_read", None)
        if cancel is not None:
            with contextlib.suppress(Exception):
                cancel()

    # -- the thread ----------------------------------------------------------------------

    def _set_state(self, state: State, message: str) -> None:
        self.state = state
        self.last_message = message
        self._report(PortStatus(self.url, state, message, time.time()))

    def _report(self, status: PortStatus) -> None:
        error = _call_quietly(self.on_status, status)
        if error is not None:
            # Nothing left to report to; keep the message where the UI can still read it.
            self.last_message = f"status callback failed: {error!r}"

    def report(self, message: str) -> None:
        """Send ``message`` to ``on_status`` with the current state (a note, not a change)."""
        self._report(PortStatus(self.url, self.state, message, time.time()))

    def _callback_failed(self, what: str, error: BaseException) -> None:
        self.report(f"{what} callback failed: {error!r}")

    def recent_rejections(self) -> list[Rejection]:
        """The kept rejected frames, oldest first (a copy, safe from any thread)."""
        with self._lock:
            return list(self.rejections)

    def _run(self) -> None:
        first_delay, max_delay = self.backoff
        delay = first_delay
        self._set_state("connecting", f"opening {self.url}")
        while not self._stopping.is_set():
            try:
                port = open_port(
                    self.url, self.settings, timeout=self.read_timeout, exclusive=self.exclusive
                )
            except Exception as error:  # a StationError sentence, or an odd handler error
                message = (
                    error.message
                    if isinstance(error, StationError)
                    else f"could not open {self.url}: {error!r}"
                )
                self._set_state("disconnected", message)
                self._fail_pending()
                if self._stopping.wait(delay):
                    break
                delay = min(delay * 2, max_delay)
                continue
            delay = first_delay
            if getattr(port, "cancel_read", None) is None:
                # Network ports cannot be woken by cancel_read: a short read timeout keeps a
                # queued request from waiting long.
                port.timeout = min(self.read_timeout, 0.02)
            self._splitter.reset()
            self._port = port
            self._set_state("connected", f"{self.url} open ({self.settings.describe()})")
            try:
                self._pump(port)
                message = ""
            except OSError as error:  # SerialException is an OSError; EIO after an unplug too
                message = (
                    f"lost {self.url} (unplugged, switched off, or the device server "
                    f"restarted): {error}"
                )
            except Exception as error:
                message = f"lost {self.url}: unexpected {error!r}"
            finally:
                self._port = None
                with contextlib.suppress(Exception):
                    port.close()
            if self._stopping.is_set():
                break
            self.reconnects += 1
            self._splitter.reset()
            self._set_state("disconnected", message + "; reconnecting")
            self._fail_pending()
            if self._stopping.wait(delay):
                break
            delay = min(delay * 2, max_delay)
        self._fail_pending()
        self._set_state("stopped", f"{self.url} closed")

    def _fail_pending(self) -> None:
        while self._commands:
            command = self._commands.popleft()
            if isinstance(command, TriggerTicket):
                command.error = self._down_message()
                command.done.set()

    def _pump(self, port) -> None:
        splitter = self._splitter
        while not self._stopping.is_set():
            while self._commands:
                self._execute(port, self._commands.popleft())
            data = port.read(port.in_waiting or 1)
            if not data:
                continue
            t_mono = time.monotonic()
            t_wall = time.time()
            for item in splitter.feed(data):
                self._deliver(item, t_wall, t_mono)

    def _execute(self, port, command: TriggerTicket | bytes) -> None:
        if isinstance(command, bytes):
            port.write(command)
            port.flush()
            return
        # Stale bytes (still in the OS buffer, or half a frame in the splitter) must never
        # complete the answer to this trigger: drop them, then stamp, then ask.
        try:
            if command.flush:
                self._splitter.reset()
                port.reset_input_buffer()
            command.t_sent = time.monotonic()
            if command.send_requests:
                sent: set[bytes] = set()
                for device_channel in self.device_channels:
                    request = self.protocol.request(device_channel)
                    # One request can serve several channels (USB-ITN's `1\r`): send it once.
                    if request and request not in sent:
                        sent.add(request)
                        port.write(request)
                port.flush()
        except Exception as error:
            command.error = f"could not send the request to {self.url}: {error}"
            raise
        finally:
            command.done.set()

    def _deliver(self, item: object, t_wall: float, t_mono: float) -> None:
        from station.instruments.framing import Overflow

        if isinstance(item, Overflow):
            self._reject(Rejection("malformed", item.detail, _raw_text(item.head), t_wall, t_mono))
            return
        frame: bytes = item  # type: ignore[assignment]
        try:
            parsed = self.protocol.parse(frame)
        except Exception as error:  # a parser bug is still only a rejected frame
            parsed = Rejected("malformed", f"the parser failed: {error!r}")
        raw = _raw_text(frame)
        if isinstance(parsed, Rejected):
            self._reject(Rejection(parsed.reason, parsed.detail, raw, t_wall, t_mono, self.url))
            return
        channel = self.station_channel(parsed.device_channel)
        offset = self._offsets.get(channel, 0.0)
        reading = GaugeReading(
            channel=channel,
            value=_without_binary_noise(parsed.value - offset),
            unit=parsed.unit or self.unit,
            raw=raw,
            t_wall=t_wall,
            t_mono=t_mono,
            device_channel=parsed.device_channel,
            port=self.url,
            device_value=parsed.value,
            zero_offset=offset,
            frame_unit=parsed.unit,
        )
        self.reading_count += 1
        error = _call_quietly(self.on_reading, reading)
        if error is not None:
            self._callback_failed("reading", error)
        self._put(reading)

    def _reject(self, rejection: Rejection) -> None:
        if not rejection.port:
            rejection = replace(rejection, port=self.url)
        with self._lock:
            self.rejected_count += 1
            self.rejections.append(rejection)
        error = _call_quietly(self.on_rejection, rejection)
        if error is not None:
            self._callback_failed("rejection", error)
        self._put(rejection)

    def _put(self, item: object) -> None:
        if self.events is None:
            return
        try:
            self.events.put_nowait(item)
        except queue.Full:
            self.dropped_events += 1


@dataclass(frozen=True)
class PortSpec:
    """One port of a station: where, which protocol, and its device→station channel map."""

    url: str
    protocol: Protocol
    channel_map: Mapping[str, str] = field(default_factory=dict)
    settings: SerialSettings | None = None


@dataclass(frozen=True)
class CaptureResult:
    """One reading set: the reading per station channel and what went wrong, if anything."""

    trigger: str
    channels: tuple[str, ...]
    readings: Mapping[str, GaugeReading]
    missing: tuple[str, ...] = ()
    """Channels with no fresh reading (they are absent from ``readings``)."""
    stale: tuple[str, ...] = ()
    """Missing channels whose last reading predates the trigger (it was not taken)."""
    duplicated: tuple[str, ...] = ()
    """Channels that sent more than one reading for this set; the first one was taken."""
    errors: tuple[str, ...] = ()
    """Port problems met during the capture (a disconnected port, a failed request)."""
    t_trigger: float = 0.0
    disconnected: tuple[str, ...] = ()
    """Missing channels whose port was down for the whole wait (the set is not the gauges'
    fault: the line is reconnecting)."""

    @property
    def port_down(self) -> bool:
        """True when a channel is missing only because its port was down (not a refusal by
        the gauges: wait for the line and capture again)."""
        return bool(self.disconnected)

    @property
    def complete(self) -> bool:
        """True when every channel has a fresh reading."""
        return not self.missing

    @property
    def message(self) -> str:
        """One sentence for the operator: empty when the set is complete and clean."""
        parts = []
        if self.missing:
            fresh_less = [
                c for c in self.missing if c not in self.stale and c not in self.disconnected
            ]
            # An arrival that did not happen is said by its error, not as silent gauges.
            if fresh_less and (self.trigger != "arrival" or self.readings):
                parts.append("no reading from " + ", ".join(fresh_less))
            if self.stale:
                parts.append(
                    "only readings from before the trigger on "
                    + ", ".join(self.stale)
                    + " (not taken)"
                )
        if self.duplicated:
            parts.append(
                "more than one reading from " + ", ".join(self.duplicated) + " (the first taken)"
            )
        parts.extend(self.errors)
        if not parts:
            return ""
        return "; ".join(parts) + "."


ZeroResult = ChannelZero
"""How one channel was zeroed (:class:`~station.instruments.zeroing.ChannelZero`)."""


class Subscription:
    """A listener's hold on a :class:`GaugeSet`: :meth:`cancel` ends it (idempotent)."""

    def __init__(self, cancel: Callable[[], None]) -> None:
        self._cancel = cancel

    def cancel(self) -> None:
        """Stop hearing of sets and port changes."""
        self._cancel()


class GaugeSet:
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
            error = _call_quietly(listener, status)
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
                error = _call_quietly(listener, completed)
                if error is not None:
                    self.readers[0].report(f"set callback failed: {error!r}")
        self._deliver_arrival(arrival)
        error = _call_quietly(self.on_reading, reading)
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
                error = _call_quietly(listener, event)
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
        )
        self._pending.clear()
        self._pending_duplicated.clear()
        self._sets.append(result)
        return result

    # -- captures ------------------------------------------------------------------------

    def _trigger_all(self, send_requests: bool, timeout: float) -> tuple[dict[str, float], list]:
        """Trigger every reader; the send time per station channel, and the errors.

        A port that is down (a short dropout, a device server restarting) is waited for until
        ``timeout``: the trigger goes out once it is back, so a dropout shorter than the
        timeout costs a delay, not a refused set. A port still down at the deadline is one
        error, and its channels get no send time.
        """
        deadline = time.monotonic() + timeout
        tickets = [(reader, reader.trigger(send_requests)) for reader in self.readers]
        t_sent: dict[str, float] = {}
        errors = []
        for reader, ticket in tickets:
            while True:
                ticket.done.wait(max(0.0, deadline - time.monotonic()))
                if ticket.t_sent is not None and not ticket.error:
                    break
                remaining = deadline - time.monotonic()
                if not ticket.done.is_set() or remaining <= 0 or not reader.alive:
                    break
                # Nothing was sent (the port was or went down): wait for it and trigger again.
                if not reader.wait_connected(remaining):
                    break
                ticket = reader.trigger(send_requests)
            if ticket.error or ticket.t_sent is None:
                errors.append(ticket.error or f"{reader.url} did not take the trigger in time")
                continue
            for channel in reader.channels:
                t_sent[channel] = ticket.t_sent
        return t_sent, errors

    def capture(self, timeout: float = 2.0) -> CaptureResult:
        """Take one reading set by this set's trigger, waiting at most ``timeout`` seconds.

        Only readings that arrive after the trigger count (stale input is flushed first). For
        ``push`` this arms the set now and waits for the device to send every channel.
        """
        start = time.monotonic()
        if self.trigger == "push":
            errors = self.arm(timeout)
            result = self.wait_set(max(0.0, timeout - (time.monotonic() - start)))
            if result is not None:
                return result
            with self._changed:
                partial = dict(self._pending)
            return self._result("push", partial, self._push_armed_at, {}, errors)
        if self.trigger == "arrival":
            return self._capture_arrival(timeout)
        if self.trigger == "poll":
            return self._capture_poll(timeout)
        return self._capture_stable(timeout)

    def _capture_arrival(self, timeout: float) -> CaptureResult:
        """The next arrival set after now (the robot must leave and come back to rest)."""
        start = time.monotonic()
        errors = self.arm(timeout)
        result = self.wait_set(max(0.0, timeout - (time.monotonic() - start)))
        if result is not None:
            return result
        waiting = {
            "waiting": "the robot did not leave the fixture",
            "away": "the robot did not come back",
            "returned": "the robot came back but did not settle",
        }[self.arrival_state or "waiting"]
        return CaptureResult(
            "arrival",
            self.channels,
            {},
            missing=self.channels,
            errors=(*errors, f"{waiting} within {timeout:g} s"),
            t_trigger=start,
            disconnected=tuple(c for c in self.channels if self._reader_of[c].state != "connected"),
        )

    def _capture_poll(self, timeout: float) -> CaptureResult:
        deadline = time.monotonic() + timeout
        t_sent, errors = self._trigger_all(True, timeout)
        taken: dict[str, GaugeReading] = {}
        counts: dict[str, int] = {}
        with self._changed:
            while True:
                for channel, since in t_sent.items():
                    fresh = [r for r in self._history[channel] if r.t_mono >= since]
                    counts[channel] = len(fresh)
                    if fresh:
                        taken[channel] = fresh[0]
                if len(taken) == len(t_sent):
                    break
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._changed.wait(remaining)
        duplicated = {c: n for c, n in counts.items() if n > 1}
        t_trigger = min(t_sent.values(), default=time.monotonic())
        return self._result("poll", taken, t_trigger, duplicated, errors, t_sent)

    def _capture_stable(self, timeout: float) -> CaptureResult:
        deadline = time.monotonic() + timeout
        t_sent, errors = self._trigger_all(True, timeout)
        window = self.stable_ms / 1000.0
        next_poll = time.monotonic() + self.poll_interval
        polled = [r for r in self.readers if r.protocol.polled]
        in_flight: dict[GaugeReader, TriggerTicket] = {}
        taken: dict[str, GaugeReading] = {}
        while True:
            with self._changed:
                taken = {}
                for channel, since in t_sent.items():
                    chosen = self._stable_reading(channel, since, window)
                    if chosen is not None:
                        taken[channel] = chosen
            if t_sent and len(taken) == len(t_sent):
                break
            now = time.monotonic()
            if now >= deadline:
                break
            if now >= next_poll:
                for reader in polled:
                    # No flush (earlier answers still count) and no pile-up of requests.
                    if reader not in in_flight or in_flight[reader].done.is_set():
                        in_flight[reader] = reader.trigger(True, flush=False)
                next_poll = now + self.poll_interval
            with self._changed:
                self._changed.wait(min(deadline, next_poll) - time.monotonic())
        t_trigger = min(t_sent.values(), default=time.monotonic())
        return self._result("stable", taken, t_trigger, {}, errors, t_sent)

    def _stable_reading(self, channel: str, since: float, window: float) -> GaugeReading | None:
        """The latest reading when ``channel`` has stayed within k × resolution for the window."""
        fresh = [r for r in self._history[channel] if r.t_mono >= since]
        if not fresh:
            return None
        latest = fresh[-1]
        band = self.stable_k * self.resolution[channel] + 1e-12
        low = high = latest.value
        for reading in reversed(fresh):
            low = min(low, reading.value)
            high = max(high, reading.value)
            if high - low > band:
                return None
            if latest.t_mono - reading.t_mono >= window:
                return latest
        return None

    def _result(
        self,
        trigger: str,
        taken: Mapping[str, GaugeReading],
        t_trigger: float,
        duplicated: Mapping[str, int],
        errors: Iterable[str],
        t_sent: Mapping[str, float] | None = None,
    ) -> CaptureResult:
        missing = tuple(c for c in self.channels if c not in taken)
        stale = []
        disconnected = tuple(
            c
            for c in missing
            if self._reader_of[c].state != "connected" or (t_sent is not None and c not in t_sent)
        )
        with self._changed:
            for channel in missing:
                if channel in disconnected:
                    continue
                history = self._history[channel]
                since = (t_sent or {}).get(channel, t_trigger)
                if history and history[-1].t_mono < since:
                    stale.append(channel)
        return CaptureResult(
            trigger,
            self.channels,
            dict(taken),
            missing=missing,
            stale=tuple(stale),
            duplicated=tuple(c for c in self.channels if c in duplicated),
            errors=tuple(errors),
            t_trigger=t_trigger,
            disconnected=disconnected,
        )

    def arm(self, timeout: float = 1.0) -> list[str]:
        """Push: forget partial and completed sets and buffered input; later readings count.
        Arrival: the same, and only a departure after now starts a cycle.

        Returns the port problems met (empty when every port took the trigger). Call it when
        the operator is asked to press DATA, then :meth:`wait_set`.
        """
        _, errors = self._trigger_all(False, timeout)
        with self._changed:
            self._push_armed_at = time.monotonic()
            self._pending.clear()
            self._pending_duplicated.clear()
            self._sets.clear()
            if self._detector is not None:
                # Only a departure after this counts: a robot already back is not a cycle.
                self._detector.reset()
        return errors

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

    def read_units(self, timeout: float = 2.0) -> dict[str, str]:
        """Take one reading set (by this set's trigger) and return the unit each channel reads
        in (channels that sent nothing are absent): check it against the session's unit before
        a session starts."""
        return {channel: r.unit for channel, r in self.capture(timeout).readings.items()}

    def wait_set(self, timeout: float) -> CaptureResult | None:
        """The next completed push set, or None when none completes within ``timeout``."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while not self._sets:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self._changed.wait(remaining)
            return self._sets.popleft()

    # -- zeroing -------------------------------------------------------------------------

    def zero(
        self,
        channels: Iterable[str] | None = None,
        timeout: float = 2.0,
        *,
        unit: str | None = None,
        readings: int = 1,
        settle: float = 0.0,
        still: float = DEFAULT_ZERO_STILL,
    ) -> list[ChannelZero]:
        """Zero ``channels`` (all by default): the device's command, else a software offset.

        With ``readings`` > 1 every channel is read ``readings`` times over ``settle`` seconds
        (:meth:`collect`); the zero is refused (StationError naming the channel, nothing
        zeroed) while a channel's readings spread over more than ``still`` resolutions or too
        few arrive. Then a software channel's offset is the mean of its readings and a device
        channel gets its zero command. With ``readings`` = 1 (the old way) a software zero takes
        one fresh reading set and a device zero reads nothing. With ``unit`` it refuses a
        channel reading in another unit. A port that is down is waited for until ``timeout``
        (counted after the settle window). Returns one
        :class:`~station.instruments.zeroing.ChannelZero` per channel, in ``channels``' order:
        its :meth:`~station.instruments.zeroing.ChannelZero.record` is the zero event's entry.
        """
        wanted = list(self.channels if channels is None else channels)
        unknown = [c for c in wanted if c not in self._reader_of]
        if unknown:
            raise StationError(
                f"Cannot zero {', '.join(unknown)}: this station's channels are "
                f"{', '.join(self.channels)}."
            )
        if readings < 1:
            raise StationError(f"A zero needs at least 1 reading per channel, not {readings}.")
        commands = {c: self._zero_command(c) for c in wanted}
        if readings == 1:
            return self._zero_once(wanted, commands, timeout, unit)
        taken = self.collect(wanted, readings, settle, timeout)
        down = [
            c
            for c in wanted
            if len(taken[c]) < readings and self._reader_of[c].state != "connected"
        ]
        if down:
            reader = self._reader_of[down[0]]
            raise StationError(
                f"Could not zero {', '.join(down)}: {reader._down_message()}. Check the cable "
                "and try again."
            )
        if unit is not None:
            latest = {c: values[-1] for c, values in taken.items() if values}
            mismatch = unit_mismatch(latest, wanted, unit)
            if mismatch:
                raise StationError(f"Could not zero: {mismatch}.")
        spans = [v[-1].t_mono - v[0].t_mono for v in taken.values() if v]
        zeros = zero_from_readings(
            {c: [r.device_value for r in taken[c]] for c in wanted},
            self.resolution,
            methods={c: "device" if commands[c] else "software" for c in wanted},
            min_readings=readings,
            still=still,
            window=max(spans, default=0.0),
            unit=unit or "",
        )
        self._apply_zeros(zeros, commands, timeout)
        return list(zeros)

    def _zero_command(self, channel: str) -> bytes | None:
        reader = self._reader_of[channel]
        device_channel = next(
            d for d in reader.device_channels if reader.station_channel(d) == channel
        )
        return reader.protocol.zero_command(device_channel)

    def _apply_zeros(
        self,
        zeros: Iterable[ChannelZero],
        commands: Mapping[str, bytes | None],
        timeout: float,
    ) -> None:
        """Send the device zero commands and set the software offsets."""
        deadline = time.monotonic() + timeout
        for zero in zeros:
            reader = self._reader_of[zero.channel]
            command = commands[zero.channel]
            if zero.method == "device" and command:
                # A short dropout is waited out, as a capture waits for it.
                if not reader.wait_connected(max(0.0, deadline - time.monotonic())):
                    raise StationError(
                        f"Could not zero {zero.channel}: {reader._down_message()}. Check the "
                        "cable and try again."
                    )
                reader.send(command)
                reader.set_zero_offset(zero.channel, 0.0)
            else:
                reader.set_zero_offset(zero.channel, zero.offset)

    def _zero_once(
        self,
        wanted: list[str],
        commands: Mapping[str, bytes | None],
        timeout: float,
        unit: str | None,
    ) -> list[ChannelZero]:
        """The zero from one reading: a device zero reads nothing, a software zero one set."""
        deadline = time.monotonic() + timeout
        zeros = {c: ChannelZero(c, "device", 0.0, 0) for c in wanted if commands[c]}
        software = [c for c in wanted if not commands[c]]
        if software:
            result = self.capture(max(0.0, deadline - time.monotonic()))
            absent = [c for c in software if c not in result.readings]
            if absent:
                why = result.message.rstrip(".") or "timeout"
                raise StationError(
                    f"Could not zero {', '.join(absent)}: no fresh reading arrived ({why}). "
                    "Check the gauges and try again."
                )
            if unit is not None:
                mismatch = unit_mismatch(result.readings, software, unit)
                if mismatch:
                    raise StationError(f"Could not zero: {mismatch}.")
            for channel in software:
                value = result.readings[channel].device_value
                zeros[channel] = ChannelZero(
                    channel, "software", value, 1, value, 0.0, (value,), self.resolution[channel]
                )
        ordered = [zeros[c] for c in wanted]
        self._apply_zeros(ordered, commands, max(0.0, deadline - time.monotonic()))
        return ordered

    def collect(
        self,
        channels: Iterable[str] | None = None,
        readings: int = 10,
        settle: float = 1.0,
        timeout: float = 2.0,
    ) -> dict[str, list[GaugeReading]]:
        """Read ``channels`` until each has ``readings`` readings and ``settle`` seconds have
        passed (or ``settle`` + ``timeout`` seconds, whichever first); the readings by channel.

        A polled port is asked every ``settle / (readings − 1)`` seconds (never faster than
        every 10 ms, no input flushed, one request in flight); a pushing port is listened to
        (a streaming device sends by itself; a DATA button must be pressed ``readings``
        times). With the ``arrival`` trigger the streaming thread's polls count too. Only
        readings that arrive after the call count."""
        wanted = list(self.channels if channels is None else channels)
        collector: dict[str, list[GaugeReading]] = {c: [] for c in self.channels}
        interval = max(0.01, settle / max(readings - 1, 1))
        start = time.monotonic()
        deadline = start + settle + timeout
        polled = {self._reader_of[c] for c in wanted if self._reader_of[c].protocol.polled}
        in_flight: dict[GaugeReader, TriggerTicket] = {}
        with self._changed:
            self._collectors.append(collector)
        try:
            next_poll = start
            while True:
                now = time.monotonic()
                with self._changed:
                    enough = all(len(collector[c]) >= readings for c in wanted)
                if (enough and now - start >= settle) or now >= deadline:
                    break
                if now >= next_poll and not (
                    self._stream_thread and self.poll_interval <= interval
                ):
                    for reader in polled:
                        ticket = in_flight.get(reader)
                        if reader.state == "connected" and (ticket is None or ticket.done.is_set()):
                            in_flight[reader] = reader.trigger(True, flush=False)
                    next_poll = now + interval
                with self._changed:
                    self._changed.wait(max(0.0, min(next_poll, deadline) - time.monotonic()))
        finally:
            with self._changed:
                self._collectors.remove(collector)
        return {c: list(collector[c]) for c in wanted}

    # -- what the frames say -------------------------------------------------------------

    def frame_samples(self, channels: Iterable[str] | None = None) -> dict[str, list[FrameSample]]:
        """What the kept readings' frames show, per channel: the device value (before any
        software zero), the decimals written and the unit stated."""
        wanted = list(self.channels if channels is None else channels)
        with self._changed:
            kept = {c: list(self._history[c]) for c in wanted}
        samples: dict[str, list[FrameSample]] = {}
        for channel, readings in kept.items():
            protocol = self._reader_of[channel].protocol
            samples[channel] = [
                FrameSample(
                    r.device_value,
                    protocol.frame_decimals(r.raw.encode("ascii", "backslashreplace")),
                    r.frame_unit,
                )
                for r in readings
            ]
        return samples

    def infer_frames(self, channels: Iterable[str] | None = None) -> dict[str, FrameInference]:
        """The unit and resolution each channel's kept frames show (:func:`infer_channel`)."""
        return {
            channel: infer_channel(
                channel, samples, self._reader_of[channel].protocol.units_by_decimals
            )
            for channel, samples in self.frame_samples(channels).items()
        }

    def check_frames(
        self,
        unit: str,
        resolution: float | Mapping[str, float] | None = None,
        *,
        readings: int = 5,
        timeout: float = 2.0,
        channels: Iterable[str] | None = None,
    ) -> str:
        """'' when the frames agree with ``unit`` and ``resolution`` (default: this set's);
        else the sentence naming both (no full stop), e.g. "the gauges send steps of 0.001,
        which is mm on this protocol; the session is in inches at 0.0001".

        Reads up to ``readings`` more readings per channel first (:meth:`collect`, no settle
        window; a push device that is not pressed gives none within ``timeout``), then judges
        every kept frame. A channel that sent nothing says nothing.
        """
        wanted = list(self.channels if channels is None else channels)
        if self.trigger in ("poll", "stable") and all(
            self._reader_of[c].protocol.polled for c in wanted
        ):
            # One request per reading, each answered before the next: the gauges are asked
            # exactly ``readings`` times (a device, or a simulated robot, that counts its
            # readings sees a known number).
            deadline = time.monotonic() + timeout
            for _ in range(readings):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._capture_poll(remaining)
        else:
            self.collect(wanted, readings, 0.0, timeout)
        samples = self.frame_samples(wanted)
        inferred = {
            c: infer_channel(c, samples[c], self._reader_of[c].protocol.units_by_decimals)
            for c in wanted
        }
        return frames_disagree(
            inferred, unit, self.resolution if resolution is None else resolution, samples
        )
