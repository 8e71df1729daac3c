"""Splitting a stream along the bar into strokes: the one point-by-point hysteresis the live
split (:class:`TravelTracker`, in the engine) and the batch split (:func:`split_strokes`, for
files without stroke marks and CSV tables) share, the deadband rule a session records, and the
dwell trimmed at a stroke's ends.

A stroke runs from rest or a reversal to a reversal or rest; a reversal is a return from the
running extreme of more than the deadband, so scale noise and a dwell at an end never split a
stroke (report §2.9: the robot moves the indicators along the parallel bar and back).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from station.errors import StationError

A_TO_B = "A→B"
B_TO_A = "B→A"
DIRECTIONS = (A_TO_B, B_TO_A)


@dataclass(frozen=True)
class Stroke:
    """One pass along the bar in a stream: points ``start`` to ``stop`` (exclusive), 1-based
    ``index``, and its direction (A→B is the direction in which the scale counts up, unless
    told otherwise)."""

    index: int
    direction: str
    start: int
    stop: int


def _direction(sign: float, a_to_b: int) -> str:
    return A_TO_B if sign * a_to_b > 0 else B_TO_A


DEADBAND_RESOLUTIONS = 100
"""The stroke split's deadband, in gauge resolutions: a reversal smaller than this is scale
noise or a dwell at an end, never a turn."""


def stroke_deadband(resolution: float) -> float:
    """The one deadband rule of a session's stroke split (live and batch): 100 resolutions of
    the scale. The engine records it in the session header; a table without one falls back to
    2 % of its whole travel (:func:`split_strokes`)."""
    return DEADBAND_RESOLUTIONS * float(resolution)


class Hysteresis:
    """The point-by-point step of the stroke split, shared by the batch split
    (:func:`turning_points`) and the live one (:class:`TravelTracker`): a direction of travel
    changes only when the scale comes back from its running extreme by more than ``deadband``.

    :meth:`step` answers ``rest`` (not moving yet), ``start`` (the first move beyond the
    deadband: :attr:`start_index` is where it began), ``beyond`` (a new extreme), ``back`` (within
    the deadband of the extreme) or ``turn`` (a reversal: :attr:`turned_at` is the extreme's
    index, the direction has flipped)."""

    def __init__(self, deadband: float) -> None:
        self.deadband = float(deadband)
        self.direction = 0
        self.extreme = math.nan
        self.extreme_index = -1
        self.start_index = -1
        self.turned_at = -1
        self._low = self._high = math.nan
        self._low_index = self._high_index = -1

    def step(self, value: float, index: int) -> str:
        """Take the scale reading ``value`` of point ``index``."""
        if self.direction == 0:
            if math.isnan(self._low) or value < self._low:
                self._low, self._low_index = value, index
            if math.isnan(self._high) or value > self._high:
                self._high, self._high_index = value, index
            if value - self._low > self.deadband:
                self.direction, self.start_index = 1, self._low_index
            elif self._high - value > self.deadband:
                self.direction, self.start_index = -1, self._high_index
            else:
                return "rest"
            self.extreme, self.extreme_index = value, index
            return "start"
        if (value >= self.extreme) if self.direction > 0 else (value <= self.extreme):
            self.extreme, self.extreme_index = value, index
            return "beyond"
        if abs(value - self.extreme) > self.deadband:
            self.turned_at = self.extreme_index
            self.direction = -self.direction
            self.extreme, self.extreme_index = value, index
            return "turn"
        return "back"

    def rest(self, values: Sequence[float], first_index: int) -> None:
        """Start over at rest with ``values`` (the points that waited at an end)."""
        self.direction = 0
        self._low = self._high = math.nan
        for offset, value in enumerate(values):
            self.step(value, first_index + offset)


def turning_points(s: Any, deadband: float) -> list[int]:
    """Indices of the ends of travel of s: the extremes between reversals larger than
    ``deadband`` (:class:`Hysteresis`, so noise and dwell at an end do not make false
    reversals). The first and last entries are where the travel starts and where it last
    ends."""
    s = np.asarray(s, dtype=float)
    if s.size == 0:
        return []
    points = [0]
    hysteresis = Hysteresis(deadband)
    for index, value in enumerate(s.tolist()):
        event = hysteresis.step(value, index)
        if event == "start":
            points[0] = hysteresis.start_index
        elif event == "turn":
            points.append(hysteresis.turned_at)
    if hysteresis.direction != 0:
        points.append(hysteresis.extreme_index)
    return points


def _end_level(s: np.ndarray, index: int, deadband: float) -> float:
    """The scale's level at an end of travel: the median of the run of points around the
    extreme ``index`` within half the deadband of it (the dwell). The extreme itself is
    biased by noise; the dwell's median is not."""
    near = np.abs(s - s[index]) <= deadband / 2
    first = last = index
    while first > 0 and near[first - 1]:
        first -= 1
    while last + 1 < s.size and near[last + 1]:
        last += 1
    return float(np.median(s[first : last + 1]))


def split_strokes(
    s: Any,
    *,
    min_travel: float | None = None,
    deadband: float | None = None,
    a_to_b: int = 1,
    dwell_band: float | None = None,
) -> list[Stroke]:
    """Split a stream by the scale's direction of travel into strokes.

    ``deadband`` (default 2 % of the whole travel) is the reversal a turn must exceed, so scale
    noise and a dwell at an end never split a stroke. The dwell itself (points within
    ``dwell_band`` of an end, default a tenth of the deadband) is left out of the strokes but
    for its last point. A stroke must cover ``min_travel`` (default
    half the whole travel): a partial pass at the start or the end is dropped. ``a_to_b`` is
    the sign of the scale's count from A to B (+1: it counts up from A).
    """
    s = np.asarray(s, dtype=float).ravel()
    if s.size < 2:
        return []
    if not np.all(np.isfinite(s)):
        raise StationError("the scale readings hold a value that is not a finite number.")
    travel = float(np.ptp(s))
    if travel == 0:
        return []
    deadband = 0.02 * travel if deadband is None else float(deadband)
    dwell_band = deadband / 10 if dwell_band is None else float(dwell_band)
    min_travel = 0.5 * travel if min_travel is None else float(min_travel)
    if deadband < 0 or min_travel < 0:
        raise StationError("the deadband and the minimum travel must not be negative.")
    ends = turning_points(s, deadband)
    strokes: list[Stroke] = []
    for begin, end in zip(ends[:-1], ends[1:], strict=False):
        start_value, end_value = s[begin], s[end]
        if abs(end_value - start_value) < max(min_travel, 1e-300):
            continue
        segment = s[begin : end + 1]
        start_level, end_level = _end_level(s, begin, deadband), _end_level(s, end, deadband)
        left = np.flatnonzero(np.abs(segment - start_level) > dwell_band)
        arrived = np.flatnonzero(np.abs(segment - end_level) <= dwell_band)
        first = begin + max(int(left[0]) - 1, 0) if left.size else begin
        last = begin + int(arrived[0]) if arrived.size else end
        strokes.append(
            Stroke(
                index=len(strokes) + 1,
                direction=_direction(end_value - start_value, a_to_b),
                start=first,
                stop=last + 1,
            )
        )
    return strokes


def trim_dwell(s: Any, deadband: float | None = None) -> np.ndarray:
    """The indices of one whole stroke's points without the dwell at its ends (as
    :func:`split_strokes` leaves it out: points within a tenth of the ``deadband`` of an end's
    level, but for the last point before leaving and the first on arriving). A stroke split
    live is trimmed, never split again."""
    s = np.asarray(s, dtype=float).ravel()
    everything = np.arange(s.size)
    if s.size < 2 or not np.all(np.isfinite(s)) or float(np.ptp(s)) == 0:
        return everything
    deadband = 0.02 * float(np.ptp(s)) if deadband is None else float(deadband)
    dwell_band = deadband / 10
    end = int(np.argmax(np.abs(s - s[0])))
    start_level, end_level = _end_level(s, 0, deadband), _end_level(s, end, deadband)
    left = np.flatnonzero(np.abs(s - start_level) > dwell_band)
    arrived = np.flatnonzero(np.abs(s - end_level) <= dwell_band)
    first = max(int(left[0]) - 1, 0) if left.size else 0
    last = int(arrived[0]) if arrived.size else s.size - 1
    return everything[first : last + 1] if last > first else everything


@dataclass(frozen=True)
class TravelEvent:
    """What :class:`TravelTracker` learnt from a point: ``points`` (tokens, in order) now
    definitely belong to the segment under way; ``close`` ends that segment first (with its
    ``direction`` and whether it is a whole ``stroke``: it began at rest or at a reversal, and
    it ended at a reversal or at rest)."""

    kind: Literal["points", "close"]
    points: tuple[Any, ...] = ()
    direction: str = ""
    stroke: bool = False


class TravelTracker:
    """Split a live stream by the scale's direction of travel, point by point (the live twin
    of :func:`turning_points`: the same hysteresis, so noise and a dwell within ``deadband``
    never make a reversal).

    Each point is given with an opaque token. A point is *definite* once it is known which
    segment of travel it belongs to: every point up to the running extreme is; the points past
    it wait until the scale either goes further (they join the segment) or comes back by more
    than the deadband (the segment closes at the extreme and they start the next one). A
    segment also closes when the scale has stayed within the deadband of its extreme for
    ``still_seconds`` (the robot stopped at an end). A segment is a whole stroke when it
    began at rest (``rest_points`` points within the deadband first) or at a reversal, and
    ended at a reversal or at rest. The points waiting are at most the deadband's worth of
    travel plus a dwell: memory stays bounded however long the stream.
    """

    def __init__(
        self,
        deadband: float,
        *,
        still_seconds: float = 2.0,
        rest_points: int = 5,
        a_to_b: int = 1,
    ) -> None:
        if not deadband > 0:
            raise StationError(f"the deadband must be positive, not {deadband}.")
        self.deadband = float(deadband)
        self.still_seconds = float(still_seconds)
        self.rest_points = int(rest_points)
        self.a_to_b = a_to_b
        self._hysteresis = Hysteresis(deadband)
        self._count = 0
        self._extreme_t = 0.0
        self._resting = 0
        self._from_rest_or_turn = False
        self._waiting: list[Any] = []
        self._waiting_values: list[float] = []

    @property
    def moving(self) -> bool:
        """True once the segment under way has left its start by more than the deadband."""
        return self._hysteresis.direction != 0

    def add(self, token: Any, s: float, t: float) -> list[TravelEvent]:
        """Take one point (scale reading ``s`` at monotonic time ``t``)."""
        index, self._count = self._count, self._count + 1
        was_moving = self._hysteresis.direction
        event = self._hysteresis.step(s, index)
        if not was_moving:
            if event == "start":
                self._from_rest_or_turn = self._from_rest_or_turn or (
                    self._resting >= self.rest_points
                )
                self._extreme_t = t
            else:
                self._resting += 1
            return [TravelEvent("points", (token,))]
        events: list[TravelEvent] = []
        if event == "beyond":
            self._extreme_t = t
            events.append(TravelEvent("points", (*self._waiting, token)))
            self._waiting, self._waiting_values = [], []
            return events
        if event == "turn":
            events.append(self._close(was_moving))
            self._from_rest_or_turn = True
            self._extreme_t = t
            events.append(TravelEvent("points", (*self._waiting, token)))
            self._waiting, self._waiting_values = [], []
            return events
        self._waiting.append(token)
        self._waiting_values.append(s)
        if t - self._extreme_t >= self.still_seconds:
            events.append(self._close(was_moving))
            # Still at an end: the next segment starts at rest with the points that waited.
            self._from_rest_or_turn = True
            self._resting = len(self._waiting)
            self._hysteresis.rest(self._waiting_values, index - len(self._waiting) + 1)
            events.append(TravelEvent("points", tuple(self._waiting)))
            self._waiting, self._waiting_values = [], []
        return events

    def flush(self) -> list[Any]:
        """The points still waiting (the stream ended): they belong to the segment under way,
        which stays open."""
        waiting, self._waiting, self._waiting_values = self._waiting, [], []
        return waiting

    def _close(self, direction: int) -> TravelEvent:
        return TravelEvent(
            "close",
            direction=_direction(float(direction), self.a_to_b),
            stroke=self._from_rest_or_turn,
        )


@dataclass(frozen=True, eq=False)  # arrays: compare the fields, not the objects
class StrokeProfile:
    """The points of one stroke: positions ``s`` and one array per indicator channel."""

    number: int
    direction: str
    s: np.ndarray = field(repr=False)
    channels: Mapping[str, np.ndarray] = field(repr=False)
    recorded: int | None = None
    """The stroke number the points were recorded under, when they were (a CSV, a session)."""


def profiles_from_stream(
    s: Any,
    channels: Mapping[str, Any],
    *,
    min_travel: float | None = None,
    deadband: float | None = None,
    a_to_b: int = 1,
    dwell_band: float | None = None,
) -> list[StrokeProfile]:
    """Split a stream (the scale ``s`` and the indicators, point by point) into strokes."""
    s = np.asarray(s, dtype=float).ravel()
    arrays = {name: np.asarray(values, dtype=float).ravel() for name, values in channels.items()}
    for name, values in arrays.items():
        if values.size != s.size:
            raise StationError(
                f"channel {name!r} has {values.size} points but the scale has {s.size}."
            )
    strokes = split_strokes(
        s, min_travel=min_travel, deadband=deadband, a_to_b=a_to_b, dwell_band=dwell_band
    )
    return [
        StrokeProfile(
            number=stroke.index,
            direction=stroke.direction,
            s=s[stroke.start : stroke.stop],
            channels={name: values[stroke.start : stroke.stop] for name, values in arrays.items()},
        )
        for stroke in strokes
    ]


def profiles_from_table(
    stroke: Any,
    s: Any,
    channels: Mapping[str, Any],
    *,
    a_to_b: int = 1,
    min_travel: float | None = None,
    deadband: float | None = None,
) -> list[StrokeProfile]:
    """Strokes from rows numbered by stroke (a CSV's ``stroke`` column, a session's ``samples``
    events), in the order the numbers first appear.

    A recorded stroke may hold a dwell at its ends, or the start of the way back when it was
    ended late: each is split by the scale like a stream (:func:`split_strokes`, with the
    deadband and minimum travel taken from the whole bar's travel), and its complete passes
    are kept, numbered 1, 2, 3, ... in order; ``recorded`` keeps the number they came under.
    A recorded stroke without a complete pass is left out.
    """
    numbers = np.asarray(stroke, dtype=float).ravel()
    s = np.asarray(s, dtype=float).ravel()
    arrays = {name: np.asarray(values, dtype=float).ravel() for name, values in channels.items()}
    for name, values in {"stroke": numbers, **arrays}.items():
        if values.size != s.size:
            raise StationError(
                f"column {name!r} has {values.size} values but the scale has {s.size}."
            )
    if not np.all(np.isfinite(s)):
        raise StationError("the scale readings hold a value that is not a finite number.")
    if np.any(numbers != np.round(numbers)):
        raise StationError("the stroke column must hold whole numbers (1, 2, 3, ...).")
    travel = float(np.ptp(s)) if s.size else 0.0
    deadband = 0.02 * travel if deadband is None else deadband
    min_travel = 0.5 * travel if min_travel is None else min_travel
    profiles: list[StrokeProfile] = []
    for number in dict.fromkeys(numbers.astype(int).tolist()):
        rows = np.flatnonzero(numbers == number)
        passes = split_strokes(s[rows], min_travel=min_travel, deadband=deadband, a_to_b=a_to_b)
        for found in passes:
            chosen = rows[found.start : found.stop]
            profiles.append(
                StrokeProfile(
                    number=len(profiles) + 1,
                    direction=found.direction,
                    s=s[chosen],
                    channels={name: values[chosen] for name, values in arrays.items()},
                    recorded=number,
                )
            )
    return profiles
