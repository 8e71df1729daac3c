"""One gauge port, one thread: frames in, readings and rejections out, reconnecting.

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

The readers of one station are grouped by :class:`~station.instruments.gauge.GaugeSet`. No
Textual here: the TUI wraps the callbacks (they run on reader threads).
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Literal

from station.errors import StationError
from station.instruments.base import Protocol, Reading, Rejected, Rejection, SerialSettings
from station.instruments.framing import FrameSplitter, Overflow
from station.instruments.transport import open_port

State = Literal["connecting", "connected", "disconnected", "stopped"]

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


def call_quietly(callback: Callable[..., object] | None, *args: object) -> BaseException | None:
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
            ticket.error = self.down_message()
            ticket.done.set()
            return ticket
        self._commands.append(ticket)
        self._wake()
        return ticket

    def send(self, data: bytes) -> None:
        """Queue raw bytes for the device (a zero command, for instance)."""
        if self.state != "connected":
            raise StationError(self.down_message())
        self._commands.append(bytes(data))
        self._wake()

    def down_message(self) -> str:
        """Why nothing can be sent now, in a few words (the port is closed, opening or
        reconnecting)."""
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
        error = call_quietly(self.on_status, status)
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
                command.error = self.down_message()
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
        error = call_quietly(self.on_reading, reading)
        if error is not None:
            self._callback_failed("reading", error)
        self._put(reading)

    def _reject(self, rejection: Rejection) -> None:
        if not rejection.port:
            rejection = replace(rejection, port=self.url)
        with self._lock:
            self.rejected_count += 1
            self.rejections.append(rejection)
        error = call_quietly(self.on_rejection, rejection)
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
