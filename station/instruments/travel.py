"""Where each indicator's plunger rests with nothing touching it, and whether the robot is at
the fixture.

A dial indicator whose cube has gone sits at the end of its travel (its *stop*): still, often
perfectly still, and just as still as a robot at rest in the fixture. Still readings alone
cannot tell the two apart, so a zero taken "when the readings are still" may zero the
indicators at their stop, after which every cycle read there is a perfect +0.0000: a robot
that was never measured. :class:`TravelWatch` tells the two apart from the motion itself:

* a **rest** is a stretch of at least ``MIN_REST_READINGS`` readings over ``settle`` seconds,
  no two more than half a settle time apart, within ``still`` resolutions of each other;
* the robot's round trip shows as a rest reached from more than the working ``band`` away
  (the cube deflects each plunger by about 3/8 in at the fixture). Nothing reads beyond the
  plunger's free end, so the reading farthest toward it seen around such a trip is the
  **stop**: the lower end by default (a plunger pushed in reads higher, as on the report's
  indicators), the higher with ``side = "high"`` (an indicator that counts the other way).
  The robot need not wait at the stop for it to be seen. A move of less than ``depth`` (half
  the cube's deflection, by default) is the cube shifting in the fixture, or a fixture placed
  again with another preload, not the robot leaving: nothing is learned from it. A procedure
  may also state each stop's reading (its ``free_travel``), and then nothing needs learning;
* the robot is **at the fixture** when every channel rests more than the band away from its
  stop, on the side the cube pushes the plunger to.

Pure: no threads, no clock (each reading's own time ``t``), values as the device sends them
(before any software zero); a device that zeroes itself shifts what it sends, and
:meth:`TravelWatch.shift` moves what was learned with it.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

from station.errors import StationError

StopSide = Literal["low", "high"]
STOP_SIDES: tuple[StopSide, ...] = ("low", "high")

MIN_REST_READINGS = 3
"""Readings a rest needs at least: two readings that happen to agree prove no stillness."""
_EPSILON = 1e-9
"""Seconds of slack in comparing reading times (0.1 s polls add up to 0.3999999 s)."""


class SlidingWindow:
    """The readings of the last ``span`` seconds (and the one just before them, where the
    stretch starts), with their spread, mean and longest gap in O(1) amortized per reading:
    a stream of a thousand readings a second is watched as cheaply as one of ten."""

    def __init__(self, span: float, max_gap: float) -> None:
        self.span = span
        self.max_gap = max_gap
        self._items: deque[tuple[int, float, float]] = deque()  # (index, t, value)
        self._highs: deque[tuple[int, float]] = deque()  # (index, value), values decreasing
        self._lows: deque[tuple[int, float]] = deque()  # (index, value), values increasing
        self._gaps: deque[int] = deque()
        """Indices of readings that came more than ``max_gap`` after the one before."""
        self._sum = 0.0
        self._count = 0

    def __len__(self) -> int:
        return len(self._items)

    def append(self, t: float, value: float) -> None:
        """Add a reading and drop those older than the window needs."""
        items = self._items
        index = self._count
        self._count += 1
        if items and t - items[-1][1] > self.max_gap + _EPSILON:
            self._gaps.append(index)
        items.append((index, t, value))
        self._sum += value
        while self._highs and self._highs[-1][1] <= value:
            self._highs.pop()
        self._highs.append((index, value))
        while self._lows and self._lows[-1][1] >= value:
            self._lows.pop()
        self._lows.append((index, value))
        while len(items) >= 2 and items[1][1] <= t - self.span + _EPSILON:
            self._sum -= items.popleft()[2]
        first = items[0][0]
        for extremes in (self._highs, self._lows):
            while extremes[0][0] < first:
                extremes.popleft()
        # The gap before the oldest reading kept lies outside the window.
        while self._gaps and self._gaps[0] <= first:
            self._gaps.popleft()

    @property
    def start(self) -> float:
        """The time of the oldest reading kept."""
        return self._items[0][1]

    def duration(self) -> float:
        """Seconds from the oldest reading kept to the newest (0 without two)."""
        return self._items[-1][1] - self._items[0][1] if len(self._items) >= 2 else 0.0

    def spread(self) -> float:
        """Max − min of the readings kept."""
        return self._highs[0][1] - self._lows[0][1] if self._items else 0.0

    def mean(self) -> float:
        """The mean of the readings kept."""
        return self._sum / len(self._items)

    def gapless(self) -> bool:
        """True when no two consecutive readings kept are more than ``max_gap`` apart."""
        return not self._gaps

    def values(self) -> list[tuple[float, float]]:
        """The readings kept, oldest first, as ``(t, value)``."""
        return [(t, value) for _, t, value in self._items]


@dataclass
class _Track:
    resolution: float
    band: float
    stated_stop: float | None
    window: SlidingWindow
    rest: float | None = None
    """The level of the rest the channel is in now (None while it moves)."""
    rest_since: float = 0.0
    """The time of the first reading of the current rest."""
    previous_rest: float | None = None
    """The level of the rest before the current one (or before the motion under way)."""
    learned_stop: float | None = None
    excursion: float | None = None
    """The reading farthest toward the free end since the last rest ended (or the start)."""

    @property
    def stop(self) -> float | None:
        return self.stated_stop if self.stated_stop is not None else self.learned_stop


class TravelWatch:
    """Learns each channel's plunger stop from the robot's motion and says whether the robot
    rests at the fixture (see the module's docstring).

    ``band`` is the half-width of the working band per channel (the arrival trigger's);
    ``still`` (resolutions) and ``settle`` (seconds) say what a rest is; ``free_travel`` states
    stops (device readings per channel) where they are known; ``depth``: a stop is learned
    only from a rest reached from more than this (and more than the band) toward the free end.
    """

    def __init__(
        self,
        resolution: Mapping[str, float],
        band: Mapping[str, float],
        *,
        still: float,
        settle: float,
        side: StopSide = "low",
        free_travel: Mapping[str, float] | None = None,
        depth: float = 0.0,
    ) -> None:
        if side not in STOP_SIDES:
            raise StationError(
                f"The side of the indicators' stop must be 'low' or 'high', not {side!r}."
            )
        self.side: StopSide = side
        self.still = still
        self.settle = settle
        self.depth = float(depth)
        stated = dict(free_travel or {})
        self._tracks = {
            channel: _Track(float(res), float(band[channel]), stated.get(channel), self._window())
            for channel, res in resolution.items()
        }

    def _window(self) -> SlidingWindow:
        return SlidingWindow(self.settle, self.settle / 2)

    @property
    def channels(self) -> tuple[str, ...]:
        """The channels watched."""
        return tuple(self._tracks)

    def feed(self, channel: str, value: float, t: float) -> None:
        """One device reading of ``channel`` at time ``t`` (other channels are ignored)."""
        track = self._tracks.get(channel)
        if track is None:
            return
        window = track.window
        window.append(t, value)
        if track.rest is not None:
            if abs(value - track.rest) <= track.band:
                return
            # The channel left the rest it was in: the robot (or the cube) moves.
            track.previous_rest, track.rest = track.rest, None
            track.excursion = value
            return
        track.excursion = (
            value if track.excursion is None else self._free_most(track.excursion, value)
        )
        if not self._still(track):
            return
        level = window.mean()
        seen = [v for v in (track.previous_rest, track.excursion) if v is not None]
        track.rest, track.rest_since, track.excursion = level, window.start, None
        if not seen:
            return
        free = self._free_most(*seen)
        if self._pressed(level, free, max(track.band, self.depth)):
            # The channel came to rest from more than the band and the depth toward the free
            # end: an arrival. Nothing reads beyond the stop, so the farthest free reading
            # seen is (as far as is known) the stop.
            known = track.learned_stop
            track.learned_stop = free if known is None else self._free_most(known, free)

    def _free_most(self, *values: float) -> float:
        return min(values) if self.side == "low" else max(values)

    def _still(self, track: _Track) -> bool:
        window = track.window
        return (
            len(window) >= MIN_REST_READINGS
            and window.duration() >= self.settle - _EPSILON
            and window.spread() <= self.still * track.resolution + 1e-12
            and window.gapless()
        )

    def _pressed(self, value: float, stop: float, margin: float) -> bool:
        """True when ``value`` lies more than ``margin`` from ``stop`` on the cube's side."""
        return value > stop + margin if self.side == "low" else value < stop - margin

    def stop(self, channel: str) -> float | None:
        """The device reading at ``channel``'s stop (stated, or learned; None while unknown)."""
        return self._tracks[channel].stop

    def stops(self) -> dict[str, float]:
        """The known stops, by channel."""
        return {c: t.stop for c, t in self._tracks.items() if t.stop is not None}

    def resting(self, channel: str) -> float | None:
        """The level of the rest ``channel`` is in now (None while it moves)."""
        return self._tracks[channel].rest

    def rest_start(self, channels: Sequence[str]) -> float:
        """When the latest of ``channels`` came to its current rest (all must rest): readings
        from then on are all of this rest."""
        return max(self._tracks[c].rest_since for c in channels)

    def at_fixture(self, channels: Sequence[str] | None = None) -> bool:
        """True when every one of ``channels`` (all by default) rests more than its band from
        its known stop, on the side the cube pushes the plunger to."""
        for channel in channels if channels is not None else self.channels:
            track = self._tracks[channel]
            stop, rest = track.stop, track.rest
            if stop is None or rest is None or not self._pressed(rest, stop, track.band):
                return False
        return True

    def at_stop(self, values: Mapping[str, float]) -> tuple[str, ...]:
        """The channels whose device reading in ``values`` lies within the band of their known
        stop: the plunger rests free there, so such a set is no reading of the robot."""
        return tuple(
            channel
            for channel, value in values.items()
            if channel in self._tracks
            and (stop := self._tracks[channel].stop) is not None
            and abs(value - stop) <= self._tracks[channel].band
        )

    def shift(self, channel: str, delta: float) -> None:
        """The device now sends ``delta`` less for the same position (it zeroed itself): move
        what was learned of ``channel`` with it."""
        track = self._tracks.get(channel)
        if track is None or delta == 0.0:
            return
        readings = track.window.values()
        track.window = self._window()
        for t, v in readings:
            track.window.append(t, v - delta)
        for name in ("rest", "previous_rest", "learned_stop", "stated_stop"):
            value = getattr(track, name)
            if value is not None:
                setattr(track, name, value - delta)

    def waiting_sentence(self, channels: Sequence[str] | None = None) -> str:
        """Why the robot does not count as at the fixture yet, in one sentence for the
        operator (empty when it does)."""
        wanted = list(channels if channels is not None else self.channels)
        if self.at_fixture(wanted):
            return ""
        unknown = [c for c in wanted if self._tracks[c].stop is None]
        if unknown:
            return (
                "the indicators' free-travel stop is not known yet (" + ", ".join(unknown) + "): "
                "the zero is taken once the robot has been seen away from the fixture and back "
                "at rest; run the robot's loop, or move it away and back to the taught point"
            )
        free = [
            c
            for c in wanted
            if (rest := self._tracks[c].rest) is not None
            and not self._pressed(rest, self._tracks[c].stop or 0.0, self._tracks[c].band)
        ]
        if free:
            return (
                ", ".join(free) + " rest at the free-travel stop: the robot is away from the "
                "fixture; bring it back to the taught point"
            )
        return "the robot is moving: waiting for it to come to rest at the fixture"


__all__ = ["MIN_REST_READINGS", "STOP_SIDES", "SlidingWindow", "StopSide", "TravelWatch"]
