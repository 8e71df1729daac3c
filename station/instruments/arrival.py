"""Cycles paced by the robot's own motion: departure, arrival, stillness, one set.

The ``arrival`` trigger reads the gauges continuously and takes a reading set only when the
robot has been away and has come back to rest. :class:`ArrivalDetector` is the state machine,
pure (no threads, no clock: the time is each reading's own ``t``), fed one reading at a time:

* **at the fixture** (``waiting``): nothing is taken. A channel farther than ``band`` from its
  centre (the zero taken at the fixture, so 0 by default) is a **departure**: the robot left.
* **away**: waiting for every channel to be back inside its band (an **arrival**; the moment of
  the first arrival after a departure is kept).
* **returned**: every channel back; waiting for **stillness**: each channel's readings of the
  last ``settle`` seconds lie within ``still`` resolutions of each other (and no two of them
  are a whole settle time apart: a silent line is no proof of stillness). Then the
  latest reading of every channel is one set, and the detector waits for the next departure.
  A channel leaving its band again after less than a quarter of the settle time is a bounce
  (back to *away*, keeping the first arrival's moment); after longer, the robot came back
  without settling and left: that return is reported (``unsettled``) and this is a departure.
* A robot that came back but is not still ``timeout`` seconds after its first arrival is
  **reported** (an ``unsettled`` event with a sentence naming the channels that still move) and
  nothing is taken for that return: the next departure starts afresh.

So nothing is taken during motion, and one departure gives at most one set. :meth:`tick`
advances the clock without a reading, so a timeout is reported even when the line goes quiet.

With ``trace`` (points per return) the detector also keeps each return's **trace**: a row of
every channel each time all of them have read again, from a few rows before the first arrival
(the approach) until the set is taken, handed over with the ``settled`` event
(:class:`ReturnTrace`). It is bounded: once it holds ``trace`` rows every other row is dropped
and only every second row kept from then on (and so on), so a slow settling is kept whole at a
coarser sampling interval, which the trace states.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Generic, Literal, TypeVar

from station.errors import StationError
from station.instruments.travel import MIN_REST_READINGS, STOP_SIDES, StopSide

DEFAULT_BAND_RESOLUTIONS = 100.0
"""Without a band, a channel has left the fixture beyond 100 resolutions from its centre."""
DEFAULT_STILL_RESOLUTIONS = 2.0
DEFAULT_SETTLE = 0.5
DEFAULT_TIMEOUT = 10.0
TRACE_PREROLL = 8
"""Rows of the approach kept before the first arrival: the trace shows its entry."""
MAX_TRACE_POINTS = 2000
"""The most rows a return's trace may be asked to keep (a line of the session file each)."""

ArrivalState = Literal["waiting", "away", "returned"]
EventKind = Literal["departed", "returned", "settled", "unsettled"]

Item = TypeVar("Item")


@dataclass(frozen=True)
class ArrivalConfig:
    """The arrival trigger's parameters (every one has a default).

    ``band``: half-width of each channel's working band about its centre, in the session's
    unit (None: ``DEFAULT_BAND_RESOLUTIONS`` × the channel's resolution). ``still``: how many
    resolutions the readings of a settle window may spread. ``settle``: seconds of stillness
    before the set is taken. ``timeout``: seconds after the arrival by which the robot must be
    still, else the return is reported and not recorded. ``centre``: each channel's rest value
    at the fixture (default 0: the gauges were zeroed there). ``stop``: the end of its travel
    an indicator shows with nothing touching it (``low``: a plunger pushed in reads higher);
    ``free_travel``: the device reading there per channel, where it is known (else the gauge
    layer learns it from the robot's motion: :mod:`station.instruments.travel`).
    """

    band: float | None = None
    still: float = DEFAULT_STILL_RESOLUTIONS
    settle: float = DEFAULT_SETTLE
    timeout: float = DEFAULT_TIMEOUT
    centre: Mapping[str, float] = field(default_factory=dict)
    stop: StopSide = "low"
    free_travel: Mapping[str, float] = field(default_factory=dict)
    trace: int = 0
    """Rows of each return's trace to keep (0: none; see the module)."""

    def __post_init__(self) -> None:
        if self.band is not None and not self.band > 0:
            raise StationError(f"The arrival band must be greater than 0, not {self.band}.")
        if not self.still > 0:
            raise StationError(
                f"The arrival stillness must be over 0 resolutions, not {self.still}."
            )
        if not self.settle > 0:
            raise StationError(f"The arrival settle time must be over 0 s, not {self.settle}.")
        if self.stop not in STOP_SIDES:
            raise StationError(f"The indicators' stop must be 'low' or 'high', not {self.stop!r}.")
        if not 0 <= self.trace <= MAX_TRACE_POINTS or (0 < self.trace < 2 * TRACE_PREROLL):
            raise StationError(
                f"The arrival trace keeps 0 (none) or {2 * TRACE_PREROLL} to {MAX_TRACE_POINTS} "
                f"points per return, not {self.trace}."
            )
        if not self.timeout > self.settle:
            raise StationError(
                f"The arrival timeout ({self.timeout:g} s) must be longer than the settle time "
                f"({self.settle:g} s)."
            )

    def band_of(self, resolution: float) -> float:
        """The half-width of the working band of a channel of this ``resolution``."""
        return self.band if self.band is not None else DEFAULT_BAND_RESOLUTIONS * resolution


@dataclass(frozen=True)
class ReturnTrace:
    """One return's trace: ``t`` the time of each row (the detector's clock), ``rows`` one
    value per channel of ``channels`` each; ``every``: rows that came per row kept (1: all);
    ``arrived``: the first arrival's time."""

    channels: tuple[str, ...]
    t: tuple[float, ...]
    rows: tuple[tuple[float, ...], ...]
    every: int
    arrived: float


class _TraceRecorder:
    """Rows of every channel, complete each time all have read again; the approach's last
    :data:`TRACE_PREROLL` rows until a return starts, then every row (decimated to the bound)."""

    def __init__(self, channels: tuple[str, ...], limit: int) -> None:
        self.channels = channels
        self.limit = limit
        self._pending: dict[str, float] = {}
        self._preroll: deque[tuple[float, tuple[float, ...]]] = deque(maxlen=TRACE_PREROLL)
        self._rows: list[tuple[float, tuple[float, ...]]] = []
        self._recording = False
        self._every = 1
        self._count = 0

    def feed(self, channel: str, value: float, t: float) -> None:
        self._pending[channel] = value
        if len(self._pending) < len(self.channels):
            return
        # Two ports' clocks may disagree by a hair: a trace's rows never go back in time.
        last = self._rows[-1][0] if self._rows else (self._preroll[-1][0] if self._preroll else t)
        row = (max(t, last), tuple(self._pending[c] for c in self.channels))
        self._pending = {}
        if not self._recording:
            self._preroll.append(row)
            return
        if self._count % self._every == 0:
            self._rows.append(row)
            if len(self._rows) >= self.limit:
                # Full: keep every other row, and from now on every other row of what comes.
                self._rows = self._rows[::2]
                self._every *= 2
        self._count += 1

    def start(self) -> None:
        """A return began (the first arrival): the approach's rows open its trace."""
        self._recording = True
        self._rows = list(self._preroll)
        self._count = len(self._rows)
        self._every = 1

    def take(self, arrived: float) -> ReturnTrace | None:
        """The return's trace (None without two rows), and forget it."""
        rows = self._rows
        every = self._every
        self.forget()
        if len(rows) < 2:
            return None
        return ReturnTrace(
            self.channels,
            tuple(t for t, _ in rows),
            tuple(values for _, values in rows),
            every,
            arrived,
        )

    def forget(self) -> None:
        """Drop the return under way (it did not settle, or the detector was re-armed)."""
        self._recording = False
        self._rows = []
        self._preroll.clear()
        self._count = 0
        self._every = 1


@dataclass(frozen=True)
class ArrivalEvent(Generic[Item]):
    """What the detector saw at time ``t``.

    ``departed``: the robot left (``channels`` = those out of their band). ``returned``: every
    channel is back in its band. ``settled``: the set to take, ``readings`` = the latest item
    per channel. ``unsettled``: the return was not still within the timeout (``channels`` = those
    still moving; ``message`` says so); nothing is taken.
    """

    kind: EventKind
    t: float
    channels: tuple[str, ...] = ()
    readings: Mapping[str, Item] = field(default_factory=dict)
    t_arrived: float | None = None
    message: str = ""
    trace: ReturnTrace | None = None
    """A ``settled`` event's trace of the return, when the detector keeps traces."""


@dataclass
class _Channel(Generic[Item]):
    resolution: float
    band: float
    centre: float
    window: deque = field(default_factory=deque)
    """(t, value, item) since the arrival, oldest first, trimmed to about a settle time."""
    latest: tuple[float, float, Item] | None = None


class ArrivalDetector(Generic[Item]):
    """The departure → arrival → stillness state machine of the ``arrival`` trigger.

    ``channels`` are the station channels of one set, ``resolution`` their resolutions (one
    number or one per channel). Feed every reading with :meth:`feed`; it returns the events the
    reading caused (most readings cause none).
    """

    def __init__(
        self,
        channels: Sequence[str],
        resolution: float | Mapping[str, float],
        config: ArrivalConfig | None = None,
    ) -> None:
        if not channels:
            raise StationError("The arrival trigger needs at least one channel.")
        self.config = config or ArrivalConfig()
        self.channels = tuple(channels)
        self._channels: dict[str, _Channel[Item]] = {}
        for channel in self.channels:
            res = float(resolution[channel] if isinstance(resolution, Mapping) else resolution)
            if not res > 0:
                raise StationError(f"The resolution of {channel} must be over 0, not {res}.")
            self._channels[channel] = _Channel(
                res, self.config.band_of(res), float(self.config.centre.get(channel, 0.0))
            )
        self.state: ArrivalState = "waiting"
        self.t_arrived: float | None = None
        """The first arrival after the current departure (None while none)."""
        self.now = float("-inf")
        self._t_in_band = float("-inf")
        """When every channel last came (back) into its band."""
        self._trace = (
            _TraceRecorder(self.channels, self.config.trace) if self.config.trace else None
        )

    def reset(self) -> None:
        """Forget the motion seen so far: only a departure after this counts (arm)."""
        self.state = "waiting"
        self.t_arrived = None
        for state in self._channels.values():
            state.window.clear()
        if self._trace is not None:
            self._trace.forget()

    def out_of_band(self) -> tuple[str, ...]:
        """Channels whose latest reading lies outside their working band."""
        return tuple(
            c
            for c, state in self._channels.items()
            if state.latest is not None and abs(state.latest[1] - state.centre) > state.band
        )

    def feed(self, channel: str, value: float, t: float, item: Item) -> list[ArrivalEvent[Item]]:
        """One reading of ``channel`` (``value`` at time ``t``; ``item`` is handed back in a
        settled set). Readings of channels outside the set are ignored."""
        state = self._channels.get(channel)
        if state is None:
            return []
        events = self.tick(t)
        state.latest = (t, value, item)
        if self._trace is not None:
            self._trace.feed(channel, value, t)
        outside = self.out_of_band()
        if self.state == "waiting":
            if outside:
                self.state = "away"
                events.append(ArrivalEvent("departed", t, outside))
            return events
        if self.state == "away":
            if outside or any(s.latest is None for s in self._channels.values()):
                return events
            self.state = "returned"
            self._t_in_band = t
            if self.t_arrived is None:
                self.t_arrived = t
                if self._trace is not None:
                    self._trace.start()
            for each in self._channels.values():
                each.window.clear()
                each.window.append(each.latest)
            events.append(ArrivalEvent("returned", t, self.channels, t_arrived=self.t_arrived))
            return events
        # returned
        if outside:
            self.state = "away"
            arrived = self.t_arrived
            if arrived is not None and t - self._t_in_band >= self.config.settle / 4:
                # Back (in the band throughout) for a while, never still, and gone again:
                # that return is lost (reported), and this is a departure of its own. A stay
                # shorter than a quarter of the settle time is a bounce of the approach (an
                # overshoot past the band) and keeps the first arrival.
                # Name the channels that moved; only when none did was it the reading rate.
                spread_out = self._spread_out()
                moving = spread_out or self._unsettled_in_windows() or outside
                message = unsettled_message(
                    moving,
                    self.config,
                    t - arrived,
                    left=True,
                    sparse=() if spread_out else self.sparse_channels(),
                )
                events.append(
                    ArrivalEvent("unsettled", t, moving, t_arrived=arrived, message=message)
                )
                events.append(ArrivalEvent("departed", t, outside))
                self.t_arrived = None
                if self._trace is not None:
                    self._trace.forget()
            return events
        state.window.append((t, value, item))
        self._trim(state, t)
        if all(self._settled(s, t) for s in self._channels.values()) and self._fresh(t):
            readings = {c: s.latest[2] for c, s in self._channels.items()}
            arrived = self.t_arrived
            self.state = "waiting"
            self.t_arrived = None
            trace = (
                self._trace.take(arrived)
                if self._trace is not None and arrived is not None
                else None
            )
            events.append(ArrivalEvent("settled", t, self.channels, readings, arrived, trace=trace))
        return events

    def tick(self, t: float) -> list[ArrivalEvent[Item]]:
        """Advance the clock to ``t`` without a reading: reports a return that did not settle
        within the timeout (and forgets it)."""
        self.now = max(self.now, t)
        arrived = self.t_arrived
        if arrived is None or self.now - arrived <= self.config.timeout:
            return []
        spread_out = self._spread_out()
        moving = spread_out or self.moving_channels()
        message = unsettled_message(
            moving,
            self.config,
            self.now - arrived,
            sparse=() if spread_out else self.sparse_channels(),
        )
        event: ArrivalEvent[Item] = ArrivalEvent(
            "unsettled", self.now, moving, t_arrived=arrived, message=message
        )
        self.t_arrived = None
        if self._trace is not None:
            self._trace.forget()
        # Still back at the fixture (but moving), or away again: either way the next set needs
        # a new departure.
        self.state = "away" if self.out_of_band() else "waiting"
        for state in self._channels.values():
            state.window.clear()
        return [event]

    def _spread_out(self) -> tuple[str, ...]:
        """Channels whose kept readings spread over more than ``still`` resolutions: they
        moved (as against channels merely seen too rarely to be judged still)."""
        return tuple(
            channel
            for channel, state in self._channels.items()
            if self.spread(channel) > self.config.still * state.resolution + 1e-12
        )

    def _unsettled_in_windows(self) -> tuple[str, ...]:
        """Channels whose kept readings were not still for a settle time."""
        return tuple(
            channel
            for channel, state in self._channels.items()
            if not state.window or not self._settled(state, state.window[-1][0])
        )

    def moving_channels(self) -> tuple[str, ...]:
        """Channels not still for a settle time (or out of their band) at the detector's time."""
        moving = []
        for channel, state in self._channels.items():
            latest = state.latest
            out = latest is None or abs(latest[1] - state.centre) > state.band
            if (
                out
                or not self._settled(state, self.now)
                or not self._fresh_channel(state, self.now)
            ):
                moving.append(channel)
        return tuple(moving)

    def sparse_channels(self) -> tuple[str, ...]:
        """Channels whose readings since the return came more than half a settle time apart
        on average: too rarely to see the robot settle at all."""
        sparse = []
        for channel, state in self._channels.items():
            window = state.window
            if len(window) >= 2:
                mean_gap = (window[-1][0] - window[0][0]) / (len(window) - 1)
                if mean_gap > self._max_gap():
                    sparse.append(channel)
            elif self.t_arrived is not None and self.now - self.t_arrived > self._max_gap():
                sparse.append(channel)
        return tuple(sparse)

    # -- stillness -----------------------------------------------------------------------

    def _max_gap(self) -> float:
        """The longest pause between two readings of a channel that still counts as watching
        it: half a settle time. Two readings that happen to agree across a longer pause (a
        swing's turning point seen at a slow push rate, or under load) prove no stillness."""
        return self.config.settle / 2

    def _settled(self, state: _Channel[Item], t: float) -> bool:
        """True when the channel has been still for a settle time up to ``t``, seen by at
        least ``MIN_REST_READINGS`` readings of that stretch."""
        since = self._still_since(state)
        if since is None or t - since < self.config.settle:
            return False
        return sum(1 for stamp, _, _ in state.window if stamp >= since) >= MIN_REST_READINGS

    def _trim(self, state: _Channel[Item], t: float) -> None:
        """Keep the readings of the last settle time, and one before it (the window's start)."""
        horizon = t - self.config.settle
        window = state.window
        while len(window) >= 2 and window[1][0] <= horizon:
            window.popleft()

    def _still_since(self, state: _Channel[Item]) -> float | None:
        """Since when the channel's readings stay within ``still`` resolutions of each other
        with no long gap (walking back from the latest); None without readings."""
        window = state.window
        if not window:
            return None
        limit = self.config.still * state.resolution + 1e-12
        low = high = window[-1][1]
        since = window[-1][0]
        later_t = since
        for t, value, _ in reversed(window):
            low, high = min(low, value), max(high, value)
            if high - low > limit or later_t - t > self._max_gap():
                break
            since = later_t = t
        return since

    def _fresh_channel(self, state: _Channel[Item], t: float) -> bool:
        return state.latest is not None and t - state.latest[0] <= self._max_gap()

    def _fresh(self, t: float) -> bool:
        """True when every channel has a reading from the last half settle time."""
        return all(self._fresh_channel(s, t) for s in self._channels.values())

    def spread(self, channel: str) -> float:
        """Max − min of ``channel``'s readings over the current settle window (0 without)."""
        values = [v for _, v, _ in self._channels[channel].window]
        return max(values) - min(values) if values else 0.0


def unsettled_message(
    moving: Sequence[str],
    config: ArrivalConfig,
    waited: float,
    *,
    left: bool = False,
    sparse: Sequence[str] = (),
) -> str:
    """The sentence for a return that did not settle: ``left`` when the robot went away again
    before it was still, else it was not still within the timeout; ``sparse`` names channels
    whose readings came too rarely to judge stillness at all."""
    who = ", ".join(moving) if moving else "the gauges"
    verb = "was" if len(moving) == 1 else "were"
    when = f"before it left again ({waited:.1f} s)" if left else f"after {waited:.1f} s"
    if sparse:
        return (
            f"The robot came back to the fixture but {', '.join(sparse)} sent readings more "
            f"than {config.settle / 2:g} s apart, too rarely to see it settle within "
            f"{config.settle:g} s {when}; no set was taken for this return. Make the gauges "
            "send faster (a push device's rate, or a shorter poll) or lengthen the arrival "
            "settle time."
        )
    return (
        f"The robot came back to the fixture but {who} {verb} not still within "
        f"{config.still:g} resolutions for {config.settle:g} s {when}; "
        "no set was taken for this return. Let the robot come to rest at the fixture (check "
        "the robot and the fixture), then run the cycle again."
    )


__all__ = [
    "ArrivalConfig",
    "ArrivalDetector",
    "ArrivalEvent",
    "ArrivalState",
    "DEFAULT_BAND_RESOLUTIONS",
    "DEFAULT_SETTLE",
    "DEFAULT_STILL_RESOLUTIONS",
    "DEFAULT_TIMEOUT",
    "MAX_TRACE_POINTS",
    "ReturnTrace",
    "TRACE_PREROLL",
    "unsettled_message",
]
