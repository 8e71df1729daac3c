"""A virtual robot with its end effector in a fixture, speaking a gauge protocol on a pty or TCP.

Two halves, so later procedures add models without touching the server:

* A **model** (:class:`RobotModel`) is a pure function ``value(channel, k, seed)``: what the
  gauge on ``channel`` shows for its ``k``-th reading. :class:`FixtureModel` is the repeatability
  set-up (per-axis bias, noise, skew, warm-up drift, backlash, outliers; a gauge with a
  resolution and a range). An accuracy model (two fixtures, a pendant display) or a linearity
  model (a bar with straightness error and sag, a linear scale, strokes) is another subclass with
  its own state (placement, stroke position); the server only calls ``value``.
* The **server** (:class:`Simulator`) owns a pseudo-terminal master or a TCP port bound to
  127.0.0.1, answers the protocol's requests (or pushes sets at a rate, or on demand for
  tests) with ``protocol.encode`` frames, and injects faults with seeded rates (:class:`Faults`).

Determinism: the k-th reading of a channel depends only on the seed and k (each value draws from
its own generator seeded with ``(seed, channel index, k)``); fault decisions come from one
generator seeded with the seed, in the order frames are sent. A *moving* simulator
(``motion``, a :class:`~station.instruments.motion.CycleMotion`) shows the robot's round trips
instead: what a reading shows depends on when it is sent, and the c-th rest position is the
model's c-th value.

Disconnect and return on a pty: closing the master makes the reader see EIO /
``SerialException`` at once, but the kernel then removes ``/dev/pts/N``, and the next pty may get
another number. So a pty simulator that will disconnect hands out a *symlink* (in a private
temporary folder, or a path you choose) and re-points it at the new pty when it comes back, the
way ``socat``'s ``link=`` does; the reader reopens the same URL. Over TCP the listener is closed
too (a device-server restart: the reader sees "refused") and bound again on the same port.
"""

from __future__ import annotations

import contextlib
import math
import os
import random
import select
import shutil
import socket
import tempfile
import threading
import time
import tty
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from station.errors import StationError
from station.instruments.base import Protocol
from station.instruments.motion import CycleMotion

# Garbage is drawn from bytes no protocol reads as a value (no digits, signs, points or letters
# that start a frame), so a garbage line is always a rejection, never a reading.
_GARBAGE_BYTES = bytes(range(0x80, 0x100)) + b"!#$%&*@^_`|~"


@dataclass(frozen=True)
class AxisModel:
    """What one axis of the robot does at one gauge, in the gauge's unit.

    ``skew`` is the shape α of a skew-normal error (0 = normal; the noise keeps σ = ``noise``).
    ``drift`` is the warm-up offset approached exponentially with a time constant of
    ``drift_tau`` readings. ``backlash`` is the full difference between approaching from the
    two directions (each reading's direction is drawn at random). An outlier (probability
    ``outlier_rate``) adds ± ``outlier_size`` × ``noise``.
    """

    bias: float = 0.0
    noise: float = 0.0005
    skew: float = 0.0
    drift: float = 0.0
    drift_tau: float = 10.0
    backlash: float = 0.0
    outlier_rate: float = 0.0
    outlier_size: float = 8.0


@dataclass(frozen=True)
class GaugeSpec:
    """The indicator: what it can show. Values are quantised and clipped to the range."""

    resolution: float = 0.001
    low: float = -12.5
    high: float = 12.5
    unit: str = "mm"

    def show(self, value: float) -> float:
        """``value`` as the gauge displays it: clipped to its range, at its resolution."""
        clipped = min(self.high, max(self.low, value))
        steps = round(clipped / self.resolution)
        decimals = max(0, -math.floor(math.log10(self.resolution)) + 1)
        return round(steps * self.resolution, decimals)


class RobotModel:
    """The interface the server needs: channels, a gauge per channel, and the k-th value."""

    channels: tuple[str, ...] = ()

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        raise NotImplementedError

    def value(self, channel: str, k: int, seed: int) -> float:
        """What ``channel``'s gauge shows for its ``k``-th reading (0-based), for ``seed``."""
        raise NotImplementedError

    def zero_reference(self, channel: str, k_next: int, seed: int) -> float:
        """What the gauge shows when its zero key is pressed before its ``k_next``-th reading:
        by default the last value it showed (the first one before any)."""
        return self.value(channel, max(k_next - 1, 0), seed)


def _skew_normal_unit(alpha: float, z0: float, z1: float) -> float:
    """A skew-normal draw with shape ``alpha``, standardised to mean 0 and σ 1."""
    if alpha == 0:
        return z1
    delta = alpha / math.sqrt(1 + alpha * alpha)
    x = delta * abs(z0) + math.sqrt(1 - delta * delta) * z1
    mean = delta * math.sqrt(2 / math.pi)
    sd = math.sqrt(1 - 2 * delta * delta / math.pi)
    return (x - mean) / sd


class FixtureModel(RobotModel):
    """The repeatability set-up: the end effector returns to one fixture; a gauge per axis."""

    def __init__(
        self,
        axes: Mapping[str, AxisModel],
        gauge: GaugeSpec | Mapping[str, GaugeSpec] = GaugeSpec(),
    ) -> None:
        if not axes:
            raise StationError("A simulated fixture needs at least one channel, e.g. x.")
        self.axes = dict(axes)
        self.channels = tuple(self.axes)
        self._gauges = (
            {c: gauge.get(c, GaugeSpec()) for c in self.channels}
            if isinstance(gauge, Mapping)
            else dict.fromkeys(self.channels, gauge)
        )

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauges[channel]

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The indicator's reading before quantisation and clipping."""
        axis = self.axes[channel]
        index = self.channels.index(channel)
        # One generator per (seed, channel, k): the k-th value never depends on other draws.
        rng = random.Random(f"{seed}/{index}/{k}")
        z0, z1 = rng.gauss(0.0, 1.0), rng.gauss(0.0, 1.0)
        direction = 1.0 if rng.random() < 0.5 else -1.0
        outlier = rng.random() < axis.outlier_rate
        outlier_sign = 1.0 if rng.random() < 0.5 else -1.0
        value = axis.bias + axis.noise * _skew_normal_unit(axis.skew, z0, z1)
        if axis.drift:
            value += axis.drift * (1.0 - math.exp(-k / max(axis.drift_tau, 1e-9)))
        value += direction * axis.backlash / 2.0
        if outlier:
            value += (
                outlier_sign * axis.outlier_size * max(axis.noise, self.gauge(channel).resolution)
            )
        return value

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th displayed reading of ``channel``."""
        return self.gauge(channel).show(self.true_value(channel, k, seed))


class RampModel(RobotModel):
    """Every reading distinct: ``start + k × step`` per channel, wrapping inside the gauge range.

    For checking a line end to end: a lost, invented or duplicated reading is visible by value
    (the reconnect tests and the reader benchmark use it).
    """

    def __init__(
        self, channels: Sequence[str], gauge: GaugeSpec = GaugeSpec(), step: float | None = None
    ) -> None:
        self.channels = tuple(channels)
        self._gauge = gauge
        self.step = gauge.resolution if step is None else step
        self._span = round((gauge.high - gauge.low) / self.step)

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauge

    def value(self, channel: str, k: int, seed: int) -> float:
        """``low`` + ((k + channel index × 1000 + seed) mod span) × step, at the resolution."""
        index = self.channels.index(channel)
        steps = (k + index * 1000 + seed) % self._span
        return self._gauge.show(self._gauge.low + steps * self.step)


@dataclass(frozen=True)
class Faults:
    """Fault injection rates (probability per frame sent) and the disconnect schedule.

    * ``garbage_rate``: a line of noise bytes (ending with the terminator) before the frame.
    * ``torn_rate``: the frame is written in two pieces with a short pause (must be rejoined).
    * ``error_rate``: an error/status frame of the protocol instead of the reading.
    * ``silence_rate``: no answer to a request (a pushed set is skipped).
    * ``stale_rate``: after the frame, copies of up to ``stale_count`` earlier frames (old
      frames delivered late).
    * ``disconnect_every``: seconds between disconnects (0 = never); each lasts ``down_time``.
    """

    garbage_rate: float = 0.0
    torn_rate: float = 0.0
    error_rate: float = 0.0
    silence_rate: float = 0.0
    stale_rate: float = 0.0
    stale_count: int = 3
    disconnect_every: float = 0.0
    down_time: float = 1.0
    torn_pause: float = 0.02

    def __post_init__(self) -> None:
        for name in ("garbage_rate", "torn_rate", "error_rate", "silence_rate", "stale_rate"):
            rate = getattr(self, name)
            if not 0.0 <= rate <= 1.0:
                raise StationError(f"The {name.replace('_', ' ')} must lie in 0..1, not {rate}.")


@dataclass
class SentFrame:
    """A reading the simulator sent: which channel, its index k, the value and the bytes."""

    channel: str
    k: int
    value: float
    frame: bytes
    t_mono: float
    cycle: int | None = None
    """The robot's cycle when it was sent (a moving simulator); None otherwise."""


@dataclass
class _Link:
    """Where the simulator's side of the line is, and how to rebuild it after a disconnect."""

    kind: str
    url: str = ""
    master: int | None = None
    slave: int | None = None
    link_path: Path | None = None
    own_dir: Path | None = None
    listener: socket.socket | None = None
    conn: socket.socket | None = None
    port: int = 0


def _is_pty_link(path: Path) -> bool:
    """True when ``path`` is a symlink to a pseudo-terminal (live or gone): what a simulator
    makes, so one may replace or remove it; never a file someone else put there."""
    try:
        target = os.readlink(path)
    except OSError:
        return False
    return target.startswith(("/dev/pts/", "/dev/tty"))


class Simulator:
    """Serve ``model``'s readings in ``protocol``'s frames, with ``faults``, on a pty or TCP.

    ``channel_map`` maps device channels to the model's channels (default ``1``, ``2``, ``3``
    … in the model's order, or the protocol's own channels when it lists enough). ``push_rate``
    (sets per second) makes a push device send by itself; 0 means push only on :meth:`push`.
    Polled protocols answer requests and zero commands. :attr:`sent` records every reading
    sent, per channel, for tests to compare with.
    """

    def __init__(
        self,
        protocol: Protocol,
        model: RobotModel,
        faults: Faults | None = None,
        seed: int = 0,
        *,
        channel_map: Mapping[str, str] | None = None,
        push_rate: float = 0.0,
        answer_delay: float = 0.0,
        motion: CycleMotion | None = None,
    ) -> None:
        self.protocol = protocol
        self.model = model
        self.faults = faults or Faults()
        self.seed = seed
        self.push_rate = push_rate
        self.motion = motion
        """The robot's round trips (:mod:`~station.instruments.motion`); None: every reading is
        a new rest position (the k-th reading of the model)."""
        self.motion_t0 = 0.0
        """``time.monotonic()`` when serving started: the origin of the motion's time."""
        self.answer_delay = answer_delay
        if channel_map is None:
            own = tuple(protocol.channels)
            devices = (
                own
                if len(own) >= len(model.channels)
                else tuple(str(i + 1) for i in range(len(model.channels)))
            )
            channel_map = dict(zip(devices, model.channels, strict=False))
        self.channel_map = dict(channel_map)
        self._check_channels()
        self.sent: dict[str, list[SentFrame]] = {c: [] for c in self.channel_map.values()}
        self.zero_requests: list[str] = []
        self.zero_offsets: dict[str, float] = {}
        """Per channel, the value the gauge showed when its zero command came (then subtracted)."""
        self.dropped_bytes = 0
        self.disconnects = 0
        self.on_sent: Callable[[str, int], object] | None = None
        """Called (server thread, lock held; must not block) after the k-th reading of a
        channel is sent: ``station simulate`` shows the pendant display as placements change."""
        self._k = dict.fromkeys(self.channel_map.values(), 0)
        self._fault_rng = random.Random(f"faults/{seed}")
        self._recent: deque[bytes] = deque(maxlen=16)
        self._requests = self._command_table(protocol.request)
        self._zeros = self._command_table(protocol.zero_command)
        self._inbox = b""
        self._lock = threading.RLock()
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self._link: _Link | None = None
        self._down_until = 0.0
        self._connected = threading.Event()

    # -- configuration checks ------------------------------------------------------------

    def _check_channels(self) -> None:
        unknown = [c for c in self.channel_map.values() if c not in self.model.channels]
        if unknown:
            raise StationError(
                f"The simulator has no channel {', '.join(unknown)}: its channels are "
                f"{', '.join(self.model.channels)}."
            )
        if len(self.channel_map) > 1:
            # A format that cannot carry the channel (one gauge per port) would merge channels.
            for device in self.channel_map:
                gauge = self.model.gauge(self.channel_map[device])
                frame = self.protocol.encode(device, 0.0, gauge.resolution, gauge.unit)
                parsed = self.protocol.parse(frame.rstrip(b"\r\n"))
                if getattr(parsed, "device_channel", device) != device:
                    raise StationError(
                        f"The {self.protocol.name} protocol carries one gauge per port (or use "
                        "a multiplexed protocol such as mitutoyo)",
                        remedy="split_channels",
                    )

    def _command_table(self, builder) -> dict[bytes, list[str]]:
        table: dict[bytes, list[str]] = {}
        for device in self.channel_map:
            command = builder(device)
            if command:
                table.setdefault(command, []).append(device)
        return table

    # -- life cycle ----------------------------------------------------------------------

    @property
    def url(self) -> str:
        """What a reader opens: the pty path (or its stable link) or ``socket://127.0.0.1:P``."""
        return self._link.url if self._link else ""

    def start_pty(self, link: str | os.PathLike | bool | None = None) -> str:
        """Serve on a new pseudo-terminal; return the path to open.

        ``link``: a path for a symlink to the pty that survives disconnects, ``True`` for one in
        a private temporary folder, None for the plain ``/dev/pts/N`` (then a disconnect comes
        back on whatever pty number the kernel gives). A disconnect schedule in the faults
        implies ``True``.
        """
        if link is None and self.faults.disconnect_every > 0:
            link = True
        state = _Link("pty")
        if link is True:
            state.own_dir = Path(tempfile.mkdtemp(prefix="station-sim-"))
            state.link_path = state.own_dir / "gauge"
        elif link:
            state.link_path = Path(link)
            taken = state.link_path.exists() or state.link_path.is_symlink()
            if taken and not _is_pty_link(state.link_path):
                raise StationError(
                    f"{state.link_path} exists and is not a simulator's link (a symlink to "
                    "a pseudo-terminal): remove it",
                    remedy="choose_link_path",
                )
        self._link = state
        self._open_pty()
        state.url = str(state.link_path) if state.link_path else os.ttyname(state.slave)
        self._start_thread()
        return state.url

    def start_tcp(self, port: int = 0) -> str:
        """Serve on TCP 127.0.0.1:``port`` (0 = a free port); return ``socket://127.0.0.1:P``."""
        state = _Link("tcp", port=port)
        self._link = state
        self._listen()
        state.url = f"socket://127.0.0.1:{state.port}"
        self._start_thread()
        return state.url

    def _start_thread(self) -> None:
        self._stopping.clear()
        self.motion_t0 = time.monotonic()
        self._thread = threading.Thread(target=self._serve, name="gauge-simulator", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop serving, close the line and remove any link this simulator made."""
        self._stopping.set()
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None
        with self._lock:
            self._close_line(listener=True)
            state = self._link
            if state and state.link_path is not None and _is_pty_link(state.link_path):
                with contextlib.suppress(OSError):
                    state.link_path.unlink()
            if state and state.own_dir is not None:
                shutil.rmtree(state.own_dir, ignore_errors=True)

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    # -- the line ------------------------------------------------------------------------

    def _open_pty(self) -> None:
        state = self._link
        master, slave = os.openpty()
        # The slave starts cooked (echo, CR->LF): make it raw before anything can touch it.
        tty.setraw(slave)
        os.set_blocking(master, False)
        state.master, state.slave = master, slave
        if state.link_path is not None:
            # A name nobody else uses (symlink() never replaces), renamed over the link at once.
            temporary = state.link_path.with_name(
                f".{state.link_path.name}.{os.getpid()}.{os.urandom(4).hex()}.new"
            )
            os.symlink(os.ttyname(slave), temporary)
            os.replace(temporary, state.link_path)
        self._connected.set()

    def _listen(self) -> None:
        state = self._link
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", state.port))
        listener.listen(1)
        state.listener = listener
        state.port = listener.getsockname()[1]
        self._connected.set()

    def _close_line(self, listener: bool) -> None:
        state = self._link
        if state is None:
            return
        self._connected.clear()
        if state.link_path is not None and _is_pty_link(state.link_path):
            # While down the link must not point at a pty number the kernel may hand to
            # someone else: the reader then sees "no such port" until the return.
            with contextlib.suppress(OSError):
                state.link_path.unlink()
        for name in ("master", "slave"):
            fd = getattr(state, name)
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(state, name, None)
        if state.conn is not None:
            with contextlib.suppress(OSError):
                state.conn.close()
            state.conn = None
        if listener and state.listener is not None:
            with contextlib.suppress(OSError):
                state.listener.close()
            state.listener = None
        self._inbox = b""

    def disconnect(self, down_time: float | None = None) -> None:
        """Drop the line now (pty master closed / TCP server gone) and return after ``down_time``.

        The return happens on the serving thread; :meth:`wait_up` waits for it.
        """
        with self._lock:
            self.disconnects += 1
            self._close_line(listener=True)
            self._down_until = time.monotonic() + (
                self.faults.down_time if down_time is None else down_time
            )

    def wait_up(self, timeout: float = 5.0) -> bool:
        """Wait until the line is back after a disconnect."""
        return self._connected.wait(timeout)

    def _come_back(self) -> None:
        with self._lock:
            if self._link.kind == "pty":
                self._open_pty()
            else:
                self._listen()
            self._down_until = 0.0

    def _write(self, data: bytes) -> bool:
        """Write all of ``data`` to the reader's side; False (and counted) when it cannot."""
        state = self._link
        if state is None:
            return False
        if state.kind == "tcp":
            if state.conn is None:
                self.dropped_bytes += len(data)
                return False
            try:
                state.conn.sendall(data)
                return True
            except OSError:
                self._drop_client()
                self.dropped_bytes += len(data)
                return False
        if state.master is None:
            self.dropped_bytes += len(data)
            return False
        view = memoryview(data)
        # Nobody drains the pty (no reader yet): wait briefly, then drop, so the server stays
        # responsive; the reader flushes on open anyway.
        deadline = time.monotonic() + 0.1
        while view:
            try:
                written = os.write(state.master, view)
                view = view[written:]
            except BlockingIOError:
                # The reader is not draining the pty; wait a little, then give up on this frame.
                if time.monotonic() > deadline:
                    self.dropped_bytes += len(view)
                    return False
                select.select([], [state.master], [], 0.05)
            except OSError:
                self.dropped_bytes += len(view)
                return False
        return True

    def _drop_client(self) -> None:
        state = self._link
        if state is not None and state.conn is not None:
            with contextlib.suppress(OSError):
                state.conn.close()
            state.conn = None

    # -- serving -------------------------------------------------------------------------

    def _serve(self) -> None:
        next_push: float | None = None
        every = self.faults.disconnect_every
        next_disconnect = time.monotonic() + every if every > 0 else math.inf
        while not self._stopping.is_set():
            now = time.monotonic()
            if self._down_until:
                if now >= self._down_until:
                    self._come_back()
                    next_push = None
                else:
                    self._stopping.wait(min(0.02, self._down_until - now))
                continue
            if now >= next_disconnect:
                self.disconnect()
                next_disconnect = now + every
                continue
            rate = self.push_rate
            if rate <= 0:
                next_push = None  # the schedule starts afresh when a rate is set
            else:
                if next_push is None or now - next_push > 1.0:
                    next_push = now  # never burst a backlog a real device would not send
                if now >= next_push:
                    due = min(int((now - next_push) * rate) + 1, 100)
                    self.push(due)
                    next_push += due / rate
            wait = 0.05
            if next_push is not None:
                wait = max(0.0, min(wait, next_push - time.monotonic()))
            self._wait_for_input(wait)

    def _wait_for_input(self, wait: float) -> None:
        state = self._link
        with self._lock:
            if state.kind == "pty":
                sources = [state.master] if state.master is not None else []
            else:
                sources = [s for s in (state.listener, state.conn) if s is not None]
        if not sources:
            self._stopping.wait(wait)
            return
        try:
            ready, _, _ = select.select(sources, [], [], wait)
        except (OSError, ValueError):
            return  # a descriptor closed under us by disconnect(); the loop sees the new state
        for source in ready:
            with self._lock:
                if state.kind == "pty":
                    if source != state.master:
                        continue
                    try:
                        data = os.read(state.master, 4096)
                    except (BlockingIOError, OSError):
                        continue
                    self._received(data)
                elif source is state.listener and state.listener is not None:
                    conn, _ = state.listener.accept()
                    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    self._drop_client()  # one client at a time, like a serial line
                    state.conn = conn
                    self._inbox = b""
                elif source is state.conn and state.conn is not None:
                    try:
                        data = state.conn.recv(4096)
                    except OSError:
                        data = b""
                    if not data:
                        self._drop_client()
                        continue
                    self._received(data)

    def _received(self, data: bytes) -> None:
        """Find requests and zero commands in the incoming bytes and answer them in order."""
        self._inbox += data
        commands = {
            **{c: ("read", d) for c, d in self._requests.items()},
            **{c: ("zero", d) for c, d in self._zeros.items()},
        }
        longest = max((len(c) for c in commands), default=1)
        while self._inbox:
            found = [(self._inbox.find(c), c) for c in commands]
            found = [(i, c) for i, c in found if i >= 0]
            if not found:
                self._inbox = self._inbox[-(longest - 1) :] if longest > 1 else b""
                return
            index, command = min(found, key=lambda item: (item[0], -len(item[1])))
            self._inbox = self._inbox[index + len(command) :]
            kind, devices = commands[command]
            if kind == "zero":
                for device in devices:
                    self._zero(self.channel_map[device])
                continue
            if self.answer_delay:
                time.sleep(self.answer_delay)
            for device in devices:
                self._send_reading(device, can_be_silent=True)

    def push(self, sets: int = 1) -> None:
        """Send ``sets`` reading sets now (one frame per channel), as a DATA press would."""
        with self._lock:
            for _ in range(sets):
                silent = self._chance(self.faults.silence_rate)
                for device in self.channel_map:
                    if not silent:
                        self._send_reading(device, can_be_silent=False)
                # A set is one instant: a channel whose frame was lost (a full pty, nobody
                # reading) skips that instant too, so the channels never drift apart.
                latest = max(self._k.values())
                self._k = dict.fromkeys(self._k, latest)

    def stale_burst(self, count: int | None = None) -> None:
        """Send copies of the last ``count`` frames again now (old frames delivered late)."""
        with self._lock:
            count = self.faults.stale_count if count is None else count
            old = list(self._recent)[-count:] if count else []
            if old:
                self._write(b"".join(old))

    def inject(self, reason: str, device_channel: str | None = None) -> bytes:
        """Send the protocol's ``reason`` frame (``error``/``status``) now; returns the bytes."""
        device = device_channel or next(iter(self.channel_map))
        frames = self.protocol_fault_frames(device)
        if reason not in frames:
            raise StationError(
                f"The {self.protocol.name} protocol has no {reason} frame; it has "
                f"{', '.join(frames) or 'none'}."
            )
        with self._lock:
            self._write(frames[reason])
        return frames[reason]

    def protocol_fault_frames(self, device_channel: str) -> dict[str, bytes]:
        """The protocol's example error/status frames for ``device_channel``."""
        getter = getattr(self.protocol, "fault_frames", None)
        return dict(getter(device_channel)) if getter else {}

    def _chance(self, rate: float) -> bool:
        # Always draw, so that one fault's rate does not shift the others' decisions.
        return self._fault_rng.random() < rate

    def _send_reading(self, device: str, can_be_silent: bool) -> None:
        faults = self.faults
        silent = self._chance(faults.silence_rate)
        error = self._chance(faults.error_rate)
        garbage = self._chance(faults.garbage_rate)
        torn = self._chance(faults.torn_rate)
        stale = self._chance(faults.stale_rate)
        if can_be_silent and silent:
            return
        if error:
            frames = self.protocol_fault_frames(device)
            frame = frames.get("error") or frames.get("status")
            if frame:
                self._write(frame)
                return
        channel = self.channel_map[device]
        gauge = self.model.gauge(channel)
        k = self._k[channel]
        now = time.monotonic()
        cycle = None
        if self.motion is not None:
            cycle = self.motion.stage(now - self.motion_t0)[0]
            value = self.expected_at(channel, now)
        else:
            value = self.expected(channel, k)
        frame = self.protocol.encode(device, value, gauge.resolution, gauge.unit)
        if garbage:
            noise = bytes(
                self._fault_rng.choice(_GARBAGE_BYTES)
                for _ in range(self._fault_rng.randint(1, 12))
            )
            self._write(noise + self.protocol.terminator)
        if torn and len(frame) > 2:
            cut = self._fault_rng.randint(1, len(frame) - 1)
            delivered = self._write(frame[:cut])
            time.sleep(faults.torn_pause)
            delivered = self._write(frame[cut:]) and delivered
        else:
            delivered = self._write(frame)
        if not delivered:
            return  # the line is down: this value was never seen, and k is not used up
        self._k[channel] = k + 1
        self.sent[channel].append(SentFrame(channel, k, value, frame, time.monotonic(), cycle))
        if self.on_sent is not None:
            self.on_sent(channel, k)
        if stale and self._recent:
            self._write(b"".join(list(self._recent)[-faults.stale_count :]))
        self._recent.append(frame)

    # -- for tests and the demo ---------------------------------------------------------

    def expected(self, channel: str, k: int) -> float:
        """The value the k-th reading of ``channel`` shows (sent or not), after any zeroing."""
        value = self.model.value(channel, k, self.seed)
        offset = self.zero_offsets.get(channel)
        if offset is None:
            return value
        return self.model.gauge(channel).show(value - offset)

    def _zero(self, channel: str) -> None:
        """The device's zero key: what it shows now (its last reading) becomes 0."""
        self.zero_requests.append(channel)
        if self.motion is not None:
            # A moving robot's gauge zeroes on what it shows at this instant.
            self.zero_offsets[channel] = self.shown_at(channel, time.monotonic())
            return
        self.zero_offsets[channel] = self.model.zero_reference(channel, self._k[channel], self.seed)

    def rest_value(self, channel: str, cycle: int) -> float:
        """Where ``channel``'s indicator comes to rest in ``cycle`` (a moving simulator), as
        the gauge shows it before any zero: the model's ``cycle``-th value."""
        return self.model.value(channel, cycle, self.seed)

    def shown_at(self, channel: str, t_mono: float) -> float:
        """What ``channel``'s gauge shows at ``t_mono`` (a moving simulator), before any zero."""
        motion = self.motion
        if motion is None:
            raise StationError("this simulator does not move (no cycle period)")
        cycle = motion.stage(t_mono - self.motion_t0)[0]
        exact = getattr(self.model, "true_value", self.model.value)
        position = motion.position(
            channel,
            t_mono - self.motion_t0,
            exact(channel, cycle, self.seed),
            exact(channel, cycle + 1, self.seed),
        )
        return self.model.gauge(channel).show(position)

    def expected_at(self, channel: str, t_mono: float) -> float:
        """What ``channel``'s gauge shows at ``t_mono`` after any zeroing (a moving simulator)."""
        value = self.shown_at(channel, t_mono)
        offset = self.zero_offsets.get(channel)
        if offset is None:
            return value
        return self.model.gauge(channel).show(value - offset)

    def sent_values(self, channel: str) -> list[float]:
        """The values sent so far on ``channel``, in order."""
        with self._lock:
            return [s.value for s in self.sent[channel]]

    def wait_client(self, timeout: float = 5.0) -> bool:
        """TCP: wait until a reader has connected."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            state = self._link
            if state is not None and (state.kind == "pty" or state.conn is not None):
                return True
            time.sleep(0.01)
        return False


@dataclass(frozen=True)
class Placement:
    """One placement of the two fixtures (1-based ``number``): the teach pendant's X, Y, Z at
    the second fixture (home at the first), and the straight distance between the fixtures."""

    number: int
    pendant: tuple[float, float, float]

    @property
    def distance(self) -> float:
        """The length of the move between the fixtures: sqrt(X² + Y² + Z²)."""
        return math.sqrt(sum(c * c for c in self.pendant))

    def pendant_text(self, unit: str = "in") -> str:
        """What the pendant shows, e.g. ``X=+31.250 Y=-12.004 Z=+20.117 in``."""
        x, y, z = self.pendant
        return f"X={x:+.3f} Y={y:+.3f} Z={z:+.3f} {unit}"


class TwoFixtureModel(RobotModel):
    """The relative-accuracy set-up (§2.8): two 3-D fixtures, the robot homed at each in turn.

    At placement p the second fixture sits at the pendant coordinates P (seeded, each axis
    between ``reach_min`` and ``reach_max`` from the first, either sign). The robot returns
    from the second fixture by the inverse of P, and the first fixture's indicators read its
    error: a scale error per axis (``scale``, per unit moved) and a small rotation
    (``rotation``, radians about x, y, z: the error ω × P), both growing with the distance moved,
    plus a constant ``bias`` and repeatability ``noise`` (σ) per reading.

    Each placement is ``home_readings`` readings at home (the indicators show their preload,
    seeded per placement and axis within ±``preload``, plus noise) followed by ``captures``
    readings after the return (preload + error + noise); the k-th reading belongs to placement
    ``k // (home_readings + captures) + 1`` unless :attr:`placement` is set (a runner or the
    autopilot that knows which placement it is at). :meth:`placement_of` gives the pendant
    display to type in.

    Zeroing at the first fixture must take out the preload and nothing else: a software zero
    reads the home readings (so a procedure run with a software-zero protocol wants
    ``home_readings=1``: its zero step reads one set per placement); a device zero
    (:meth:`zero_reference`) takes the placement's preload itself, with no reading
    (``home_readings=0``). Either way the capture after the return shows the placement's error.
    """

    channels = ("x", "y", "z")

    def __init__(
        self,
        *,
        scale: tuple[float, float, float] = (2.0e-5, -1.5e-5, 1.0e-5),
        rotation: tuple[float, float, float] = (0.0, 0.0, 5.0e-6),
        bias: tuple[float, float, float] = (0.0, 0.0, 0.0),
        noise: float = 0.0002,
        reach_min: float = 10.0,
        reach_max: float = 40.0,
        captures: int = 1,
        home_readings: int = 0,
        preload: float = 0.0,
        pendant_resolution: float = 0.001,
        gauge: GaugeSpec = GaugeSpec(0.0001, -0.5, 0.5, "in"),
        seed: int = 0,
        lead_readings: int = 0,
    ) -> None:
        if captures < 1:
            raise StationError(f"captures per placement must be 1 or more, not {captures}.")
        if not 0 <= reach_min <= reach_max:
            raise StationError("the fixtures' reach must satisfy 0 <= reach_min <= reach_max.")
        self.scale = tuple(float(v) for v in scale)
        self.rotation = tuple(float(v) for v in rotation)
        self.bias = tuple(float(v) for v in bias)
        self.noise = float(noise)
        self.reach = (float(reach_min), float(reach_max))
        if home_readings < 0 or preload < 0:
            raise StationError("home readings and the preload must not be negative.")
        self.captures = int(captures)
        self.home_readings = int(home_readings)
        self.preload = float(preload)
        self.pendant_resolution = float(pendant_resolution)
        self._gauge = gauge
        self.seed = seed
        self.lead_readings = max(0, int(lead_readings))
        """Readings at home before the first placement begins (the station reads one set to
        check the gauges' frames before a session starts)."""
        self.placement: int | None = None
        """The placement the robot is at now; None: derived from the reading index."""

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauge

    def placement_of(self, number: int) -> Placement:
        """Placement ``number`` (1-based): where the pendant says the second fixture is."""
        if number < 1:
            raise StationError(f"placements are numbered from 1, not {number}.")
        rng = random.Random(f"placement/{self.seed}/{number}")
        low, high = self.reach
        step = self.pendant_resolution
        coordinates = []
        for _ in range(3):
            magnitude = rng.uniform(low, high) * (1.0 if rng.random() < 0.5 else -1.0)
            coordinates.append(round(round(magnitude / step) * step, 6))
        return Placement(number, (coordinates[0], coordinates[1], coordinates[2]))

    def systematic_error(self, number: int) -> tuple[float, float, float]:
        """The error per axis at placement ``number`` without noise: bias + S·P + ω × P."""
        px, py, pz = self.placement_of(number).pendant
        wx, wy, wz = self.rotation
        rotated = (wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px)
        return tuple(  # type: ignore[return-value]
            b + s * p + r
            for b, s, p, r in zip(self.bias, self.scale, (px, py, pz), rotated, strict=True)
        )

    @property
    def readings_per_placement(self) -> int:
        """Readings of each channel per placement: at home, then after the return."""
        return self.home_readings + self.captures

    def current_placement(self, k: int) -> int:
        """The placement of the k-th reading."""
        if self.placement is not None:
            return self.placement
        return max(k - self.lead_readings, 0) // self.readings_per_placement + 1

    def at_home(self, k: int) -> bool:
        """True when the k-th reading is taken at home (before the round trip)."""
        if k < self.lead_readings:
            return True
        return (k - self.lead_readings) % self.readings_per_placement < self.home_readings

    def preload_of(self, number: int) -> tuple[float, float, float]:
        """How far the cube depresses each indicator at placement ``number``, about its mid
        travel (what zeroing at the first fixture takes out)."""
        rng = random.Random(f"preload/{self.seed}/{number}")
        return tuple(rng.uniform(-self.preload, self.preload) for _ in range(3))  # type: ignore[return-value]

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The indicator's reading before quantisation and clipping."""
        index = self.channels.index(channel)
        rng = random.Random(f"{seed}/{index}/{k}")
        number = self.current_placement(k)
        error = 0.0 if self.at_home(k) else self.systematic_error(number)[index]
        return self.preload_of(number)[index] + error + self.noise * rng.gauss(0.0, 1.0)

    def zero_reference(self, channel: str, k_next: int, seed: int) -> float:
        """A device zero at the first fixture takes the placement's preload: the robot is at
        home, so the indicator shows no error there."""
        number = self.current_placement(k_next)
        return self._gauge.show(self.preload_of(number)[self.channels.index(channel)])

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th displayed reading of ``channel``."""
        return self._gauge.show(self.true_value(channel, k, seed))


class BarModel(RobotModel):
    """The linearity set-up (§2.9): indicators h and v ride along a parallel bar, scale s.

    The robot shuttles A→B→A… over ``length``: each stroke is a dwell of ``dwell`` readings at
    its start, then ``points`` readings while moving (a smooth start and stop), so the k-th
    reading of every channel belongs to one instant. The indicators read, at position s
    (u = s / length):

    * h: the bar's bow in the horizontal plane, a parabola of sagitta ``bow`` (0 at the ends),
    * v: the bar's sag under its own weight, the simply supported beam's shape of sagitta
      ``sag``,
    * both: the robot path's wobble, ``wobble`` (h) / ``wobble_v`` (v) × sin(2π s / ``period``),
      the misalignment of the bar to the robot's straight line (``tilt_h``, ``tilt_v`` per unit
      of travel; a straightness fit removes it), a random offset per stroke (σ
      ``stroke_jitter``: the path does not repeat exactly) and reading noise (σ ``noise``).

    The scale s reads the position with its own resolution and noise ``scale_noise``.
    """

    channels = ("h", "v", "s")

    def __init__(
        self,
        *,
        length: float = 20.0,
        points: int = 400,
        dwell: int = 20,
        bow: float = 0.0012,
        sag: float = 0.0006,
        wobble: float = 0.0004,
        wobble_v: float = 0.0002,
        period: float = 5.0,
        tilt_h: float = 5.0e-5,
        tilt_v: float = -3.0e-5,
        stroke_jitter: float = 0.00005,
        noise: float = 0.00005,
        scale_noise: float = 0.0,
        indicator: GaugeSpec = GaugeSpec(0.0001, -0.5, 0.5, "in"),
        scale: GaugeSpec | None = None,
    ) -> None:
        if points < 2 or dwell < 0:
            raise StationError("a stroke needs at least 2 points and a dwell of 0 or more.")
        if not length > 0 or not period > 0:
            raise StationError("the bar's length and the wobble's period must be positive.")
        self.length = float(length)
        self.points = int(points)
        self.dwell = int(dwell)
        self.bow, self.sag = float(bow), float(sag)
        self.wobble, self.wobble_v, self.period = float(wobble), float(wobble_v), float(period)
        self.tilt_h, self.tilt_v = float(tilt_h), float(tilt_v)
        self.stroke_jitter, self.noise, self.scale_noise = (
            float(stroke_jitter),
            float(noise),
            float(scale_noise),
        )
        self._indicator = indicator
        self._scale = scale or GaugeSpec(indicator.resolution, -1.0, self.length + 1.0, "in")

    @property
    def readings_per_stroke(self) -> int:
        """Readings of each channel per stroke (dwell and motion)."""
        return self.dwell + self.points

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on h and v, the linear scale on s."""
        return self._scale if channel == "s" else self._indicator

    def stroke_of(self, k: int) -> tuple[int, float]:
        """The 1-based stroke of the k-th reading and the true position s along the bar."""
        stroke, i = divmod(k, self.readings_per_stroke)
        t = 0.0 if i < self.dwell else (i - self.dwell + 1) / self.points
        u = (1.0 - math.cos(math.pi * t)) / 2.0  # a smooth start and stop
        fraction = u if stroke % 2 == 0 else 1.0 - u
        return stroke + 1, fraction * self.length

    def profile(self, channel: str, s: float) -> float:
        """The systematic reading of h or v at position s (bar shape, wobble, tilt), no noise."""
        u = s / self.length
        wave = math.sin(2.0 * math.pi * s / self.period)
        if channel == "h":
            return 4.0 * self.bow * u * (1.0 - u) + self.wobble * wave + self.tilt_h * s
        if channel == "v":
            beam = 16.0 / 5.0 * (u - 2.0 * u**3 + u**4)
            return self.sag * beam + self.wobble_v * wave + self.tilt_v * s
        raise StationError(f"the bar model has no indicator {channel!r}.")

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The reading before quantisation and clipping."""
        stroke, s = self.stroke_of(k)
        index = self.channels.index(channel)
        rng = random.Random(f"{seed}/{index}/{k}")
        if channel == "s":
            return s + self.scale_noise * rng.gauss(0.0, 1.0)
        jitter = random.Random(f"{seed}/{index}/stroke/{stroke}").gauss(0.0, 1.0)
        return (
            self.profile(channel, s)
            + self.stroke_jitter * jitter
            + self.noise * rng.gauss(0.0, 1.0)
        )

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th displayed reading of ``channel``."""
        return self.gauge(channel).show(self.true_value(channel, k, seed))

    def stream(self, strokes: int, seed: int = 0) -> dict[str, list[float]]:
        """The displayed readings of ``strokes`` whole strokes plus a final dwell, per channel
        (what a capture would record from the server, without the server)."""
        count = strokes * self.readings_per_stroke + self.dwell
        return {c: [self.value(c, k, seed) for k in range(count)] for c in self.channels}


def fixture_model(
    channels: Sequence[str],
    *,
    axis: AxisModel | Mapping[str, AxisModel] = AxisModel(),
    gauge: GaugeSpec = GaugeSpec(),
) -> FixtureModel:
    """A :class:`FixtureModel` with the same (or a per-channel) axis model on ``channels``."""
    if isinstance(axis, Mapping):
        axes = {c: axis.get(c, AxisModel()) for c in channels}
    else:
        axes = dict.fromkeys(channels, axis)
    return FixtureModel(axes, gauge)


def demo_model(channels: Sequence[str] = ("x", "y", "z"), unit: str = "in") -> FixtureModel:
    """A fixture like the report's Table 2-1 (X: mean +0.00008 in, σ 0.00026 in, a₁ ≈ −0.36).

    Every axis has that spread at a 0.0001 in (0.001 mm) indicator; y sits a little off
    nominal with a short warm-up drift, z has some backlash and a rare outlier, so the demo's
    verdicts, histograms and control-chart rules have something to show.
    """
    scale = 25.4 if unit == "mm" else 1.0
    resolution = 0.001 if unit == "mm" else 0.0001
    base = AxisModel(bias=0.00008 * scale, noise=0.00026 * scale, skew=-2.0)
    variants = [
        base,
        AxisModel(
            bias=0.00025 * scale,
            noise=0.00022 * scale,
            skew=-1.0,
            drift=0.0002 * scale,
            drift_tau=6.0,
        ),
        AxisModel(
            bias=-0.0001 * scale,
            noise=0.00024 * scale,
            backlash=0.0002 * scale,
            outlier_rate=0.02,
            outlier_size=5.0,
        ),
    ]
    axes = {c: variants[i % len(variants)] for i, c in enumerate(channels)}
    return FixtureModel(axes, GaugeSpec(resolution, -0.5 * scale, 0.5 * scale, unit))


__all__ = [
    "AxisModel",
    "BarModel",
    "Faults",
    "FixtureModel",
    "GaugeSpec",
    "RampModel",
    "demo_model",
    "RobotModel",
    "SentFrame",
    "Simulator",
    "fixture_model",
    "Placement",
    "TwoFixtureModel",
]
