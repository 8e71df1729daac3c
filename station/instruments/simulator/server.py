"""The simulator's server: a fixture model's readings in a gauge protocol's frames, on a line.

:class:`Simulator` owns a :class:`~station.instruments.simulator.line.Line` (a pseudo-terminal
master or a TCP port bound to 127.0.0.1), answers the protocol's requests (or pushes sets at a
rate, or on demand for tests) with ``protocol.encode`` frames, and injects faults with seeded
rates (:class:`Faults`). Fault decisions come from one generator seeded with the seed, in the
order frames are sent. A *moving* simulator (``motion``, a
:class:`~station.instruments.motion.CycleMotion`) shows the robot's round trips: what a reading
shows depends on when it is sent, and the c-th rest position is the model's c-th value.
"""

from __future__ import annotations

import math
import os
import random
import select
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from station.errors import StationError
from station.instruments.base import Protocol
from station.instruments.motion import CycleMotion
from station.instruments.simulator.line import Line
from station.instruments.simulator.models import RobotModel

# Garbage is drawn from bytes no protocol reads as a value (no digits, signs, points or letters
# that start a frame), so a garbage line is always a rejection, never a reading.
_GARBAGE_BYTES = bytes(range(0x80, 0x100)) + b"!#$%&*@^_`|~"


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
    """The robot's rest (its cycle) when it was sent."""


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
        returns_each_set: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.protocol = protocol
        self.model = model
        self.faults = faults or Faults()
        self.seed = seed
        self.push_rate = push_rate
        self.motion = motion
        """The robot's round trips (:mod:`~station.instruments.motion`); None: every reading is
        a new rest position (the k-th reading of the model)."""
        self.clock = clock
        """The robot's time (seconds, monotonic): its motion, the pause in the polls that moves
        a still robot, the first rest's hold and the times of :attr:`sent`. A test passes a
        clock it advances itself, so that what the robot does never depends on the machine's
        load; the line's own pacing (pushes, disconnects) keeps real time."""
        self.motion_t0 = 0.0
        self.return_gap: float | None = None
        """When set (a still robot, polled): the operator moves the robot to its next rest
        whenever the station has not asked for a reading for this many seconds, as a technician
        moves the robot while the station waits between its steps (``station capture --every``
        longer than the gap). The readings of one zero, or of the frames check, come closer
        together: one rest."""
        self._last_request: float | None = None
        self.rest = 0
        self.returns_each_set = returns_each_set
        """True: the still robot leaves and comes back between every two reading sets (a
        robot paced exactly by the station's polls or DATA presses, for sessions without a
        zero step: a zero of several readings is refused as moving)."""
        self._rest_began: dict[str, int] = {}
        self.leave_first_rest_after: float | None = None
        """When set, the still robot leaves its first rest (for rest 1) this many seconds after
        its first frame is sent: the bar's robot starts shuttling once the zeros are taken."""
        self._first_read_at: float | None = None
        """The still robot's state (no ``motion``): which rest it is at, 0 first; it stays there
        however often the gauges are read, and steps on :meth:`robot_returns` /
        :meth:`move_to_rest`. Every reading at a rest shows the model's rest position plus the
        indicator's own noise."""
        """:attr:`clock` when serving started: the origin of the motion's time."""
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
        self._line: Line | None = None
        self._down_until = 0.0

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
        return self._line.url if self._line else ""

    def start_pty(self, link: str | os.PathLike | bool | None = None) -> str:
        """Serve on a new pseudo-terminal; return the path to open.

        ``link``: a path for a symlink to the pty that survives disconnects, ``True`` for one in
        a private temporary folder, None for the plain ``/dev/pts/N`` (then a disconnect comes
        back on whatever pty number the kernel gives). A disconnect schedule in the faults
        implies ``True``.
        """
        if link is None and self.faults.disconnect_every > 0:
            link = True
        self._line = Line.pty(link)
        self._start_thread()
        return self._line.url

    def start_tcp(self, port: int = 0) -> str:
        """Serve on TCP 127.0.0.1:``port`` (0 = a free port); return ``socket://127.0.0.1:P``."""
        self._line = Line.tcp(port)
        self._start_thread()
        return self._line.url

    def _start_thread(self) -> None:
        self._stopping.clear()
        self.motion_t0 = self.clock()
        self._thread = threading.Thread(target=self._serve, name="gauge-simulator", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop serving, close the line and remove any link this simulator made."""
        self._stopping.set()
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None
        with self._lock:
            if self._line is not None:
                self._line.remove()
            self._inbox = b""

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    # -- the line ------------------------------------------------------------------------

    @property
    def dropped_bytes(self) -> int:
        """Bytes that could not be delivered (the line down, nobody reading)."""
        return self._line.dropped_bytes if self._line is not None else 0

    def disconnect(self, down_time: float | None = None) -> None:
        """Drop the line now (pty master closed / TCP server gone) and return after ``down_time``.

        The return happens on the serving thread; :meth:`wait_up` waits for it.
        """
        with self._lock:
            self.disconnects += 1
            if self._line is not None:
                self._line.close(listener=True)
            self._inbox = b""
            self._down_until = time.monotonic() + (
                self.faults.down_time if down_time is None else down_time
            )

    def wait_up(self, timeout: float = 5.0) -> bool:
        """Wait until the line is back after a disconnect."""
        link = self._line
        return link is not None and link.connected.wait(timeout)

    def _come_back(self) -> None:
        with self._lock:
            self._line.open()
            self._down_until = 0.0

    def _write(self, data: bytes) -> bool:
        """Write all of ``data`` to the reader's side; False (and counted) when it cannot."""
        return self._line.write(data) if self._line is not None else False

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
        line = self._line
        with self._lock:
            sources = line.sources()
        if not sources:
            self._stopping.wait(wait)
            return
        try:
            ready, _, _ = select.select(sources, [], [], wait)
        except (OSError, ValueError):
            return  # a descriptor closed under us by disconnect(); the loop sees the new state
        for source in ready:
            with self._lock:
                data, new_client = line.take(source)
                if new_client:
                    self._inbox = b""
                if data:
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
            self._asked(self.clock())
            if self.answer_delay:
                time.sleep(self.answer_delay)
            for device in devices:
                self._send_reading(device, can_be_silent=True)

    def push(self, sets: int = 1) -> None:
        """Send ``sets`` reading sets now (one frame per channel), as a DATA press would."""
        with self._lock:
            for _ in range(sets):
                if self._stopping.is_set():
                    # Nobody drains a line being closed: each frame would wait out its write
                    # deadline, and a backlog of sets would hold up the stop for seconds.
                    break
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
        now = self.clock()
        if self.motion is not None:
            cycle = self.motion.stage(now - self.motion_t0)[0]
            value = self.expected_at(channel, now, k)
        else:
            if self.leave_first_rest_after is not None and self.rest == 0:
                self._leave_first_rest(now)
            cycle = k if self.returns_each_set else self.rest
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
        self.sent[channel].append(SentFrame(channel, k, value, frame, self.clock(), cycle))
        if self.on_sent is not None:
            self.on_sent(channel, k)
        if stale and self._recent:
            self._write(b"".join(list(self._recent)[-faults.stale_count :]))
        self._recent.append(frame)

    # -- for tests and the demo ---------------------------------------------------------

    def robot_returns(self, times: int = 1) -> int:
        """The still robot leaves and comes back ``times`` times (to its next rest); returns
        the rest it is at now. A moving simulator's robot follows its motion instead."""
        if self.motion is not None:
            raise StationError("this simulator's robot moves by itself (it has a cycle period)")
        with self._lock:
            self._set_rest(self.rest + times)
            return self.rest

    def move_to_rest(self, rest: int) -> None:
        """Put the still robot at its ``rest``-th rest (whoever plays the robot: the demo
        following the procedure's steps, a test)."""
        if self.motion is not None:
            raise StationError("this simulator's robot moves by itself (it has a cycle period)")
        with self._lock:
            self._set_rest(max(0, int(rest)))

    def _set_rest(self, rest: int) -> None:
        if rest != self.rest:
            self.rest = rest
            # A model that moves per set counts its sets from the start of the rest.
            self._rest_began = dict(self._k)

    def expected(self, channel: str, k: int) -> float:
        """The value the k-th reading of ``channel`` shows (sent or not) with the still robot
        at its current rest, after any zeroing."""
        if self.returns_each_set:
            return self._zeroed(channel, self.model.reading(channel, k, k, self.seed))
        if self.model.moves_per_set:
            k -= self._rest_began.get(channel, 0)
        return self._zeroed(channel, self.model.reading(channel, self.rest, k, self.seed))

    def _asked(self, now: float) -> None:
        """A request arrived at ``now``: after a pause of ``return_gap`` the robot has moved."""
        gap = self.return_gap
        last, self._last_request = self._last_request, now
        if gap and self.motion is None and last is not None and now - last >= gap:
            self._set_rest(self.rest + 1)

    def _leave_first_rest(self, now: float) -> None:
        """Time the first rest from the first reading; leave it once it has lasted."""
        if self._first_read_at is None:
            self._first_read_at = now
        elif now - self._first_read_at >= self.leave_first_rest_after:
            self._set_rest(1)

    def _zeroed(self, channel: str, value: float) -> float:
        offset = self.zero_offsets.get(channel)
        if offset is None:
            return value
        return self.model.gauge(channel).show(value - offset)

    def _zero(self, channel: str) -> None:
        """The device's zero key: what it shows now (its last reading) becomes 0, unless the
        model knows the fixture's own zero (a preload, a surface plate)."""
        self.zero_requests.append(channel)
        if self.motion is not None:
            # A moving robot's gauge zeroes on what it shows at this instant.
            self.zero_offsets[channel] = self.shown_at(channel, self.clock())
            return
        reference = self.model.zero_reference(channel, self.rest, self.seed)
        if reference is None:
            last = self.sent[channel][-1].value if self.sent[channel] else None
            shown = self.model.reading(channel, self.rest, self._k[channel], self.seed)
            # The frame sent last is already zeroed by any earlier zero: undo that.
            reference = shown if last is None else last + self.zero_offsets.get(channel, 0.0)
        self.zero_offsets[channel] = reference

    def rest_value(self, channel: str, cycle: int) -> float:
        """Where ``channel``'s indicator comes to rest in ``cycle``, as the gauge shows it
        before any zero (without the indicator's own noise): the model's ``cycle``-th rest."""
        return self.model.value(channel, cycle, self.seed)

    def shown_at(self, channel: str, t_mono: float, k: int | None = None) -> float:
        """What ``channel``'s gauge shows at ``t_mono`` (a moving simulator), before any zero;
        with ``k``, the indicator's own noise of its k-th reading on top."""
        motion = self.motion
        if motion is None:
            raise StationError("this simulator does not move (no cycle period)")
        cycle = motion.stage(t_mono - self.motion_t0)[0]
        model = self.model
        position = motion.position(
            channel,
            t_mono - self.motion_t0,
            model.rest_position(channel, cycle, self.seed),
            model.rest_position(channel, cycle + 1, self.seed),
        )
        if k is None:
            return model.gauge(channel).show(position)
        return model.shown(channel, position, k, self.seed)

    def expected_at(self, channel: str, t_mono: float, k: int | None = None) -> float:
        """What ``channel``'s gauge shows at ``t_mono`` after any zeroing (a moving simulator);
        with ``k``, with the indicator's own noise of its k-th reading."""
        return self._zeroed(channel, self.shown_at(channel, t_mono, k))

    def sent_values(self, channel: str) -> list[float]:
        """The values sent so far on ``channel``, in order."""
        with self._lock:
            return [s.value for s in self.sent[channel]]

    def wait_client(self, timeout: float = 5.0) -> bool:
        """TCP: wait until a reader has connected."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            line = self._line
            if line is not None and line.has_reader():
                return True
            time.sleep(0.01)
        return False


__all__ = ["Faults", "SentFrame", "Simulator"]
