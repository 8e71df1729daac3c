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
        if not self.timeout > self.settle:
            raise StationError(
                f"The arrival timeout ({self.timeout:g} s) must be longer than the settle time "
                f"({self.settle:g} s)."
            )

    def band_of(self, resolution: float) -> float:
        """The half-width of the working band of a channel of this ``resolution``."""
        return self.band if self.band is not None else DEFAULT_BAND_RESOLUTIONS * resolution


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

    def reset(self) -> None:
        """Forget the motion seen so far: only a departure after this counts (arm)."""
        self.state = "waiting"
        self.t_arrived = None
        for state in self._channels.values():
            state.window.clear()

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
            return events
        state.window.append((t, value, item))
        self._trim(state, t)
        if all(self._settled(s, t) for s in self._channels.values()) and self._fresh(t):
            readings = {c: s.latest[2] for c, s in self._channels.items()}
            arrived = self.t_arrived
            self.state = "waiting"
            self.t_arrived = None
            events.append(ArrivalEvent("settled", t, self.channels, readings, arrived))
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
    "unsettled_message",
]
