"""The live analyses the engine feeds while a session runs: :class:`LiveCycles` (repeatability,
relative accuracy: O(1) per cycle) and :class:`LiveStrokes` (linearity: each whole stroke)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from station.analysis.linearity import analyze_linearity, linearity_summary, tolerance_from_limits
from station.analysis.live import LiveAnalysis, LiveReadings
from station.analysis.monitor import LiveMonitor, Rejection
from station.analysis.strokes import StrokeProfile
from station.analysis.summary import Analysis, AnalysisConfig
from station.errors import StationError
from station.session.alarms import live_events
from station.session.model import Session
from station.verdicts.sessions import marked_profiles, session_stroke_profiles


class LiveCycles:
    """The live analysis of cycles (repeatability, relative accuracy): O(1) per cycle, equal
    to the batch analysis of the session's readings.

    Its alarms are phase II: judged against control limits frozen after the header's
    ``freeze_after`` points (or fixed by its ``baseline``), through the same
    :class:`~station.analysis.monitor.LiveMonitor` that
    :func:`~station.analysis.monitor.replay_live_alarms` runs over a recorded session, so a replay
    gives exactly the alarms the engine wrote. A rejected cycle leaves the analysis without
    moving the frozen limits; a resumed session is rebuilt from its journal in order.
    """

    def __init__(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> None:
        self.config, self.channels, self.header = config, tuple(channels), header
        self._monitor: LiveMonitor | None = None
        if config.freeze_after is None and config.baseline is None:
            # No phase II asked for: the limits move with every reading (phase I only).
            self._live = LiveAnalysis(config, self.channels)
        else:
            self._monitor = LiveMonitor(
                config,
                self.channels,
                freeze_after=config.freeze_after,
                baseline=config.baseline,
            )

    @property
    def live(self) -> LiveAnalysis:
        """The running analysis (the monitor's, when the limits freeze)."""
        return self._live if self._monitor is None else self._monitor.live

    def add_cycle(
        self, values: Mapping[str, float], cycle: int, times: Mapping[str, float] | None = None
    ) -> Mapping[str, Any]:
        if self._monitor is None:
            return self._live.add_set(values, cycle, times)
        updates, new = self._monitor.add_set(values, cycle, times)
        # Only the alarms that are new: a run growing by a point is the alarm already raised.
        return {
            channel: replace(update, alarms=tuple(a.alarm for a in new if a.channel == channel))
            for channel, update in updates.items()
        }

    def add_stroke(self, outcome: Any) -> None:
        return None

    def snapshot(self) -> Analysis:
        return self.live.snapshot()

    def result(self) -> Any:
        return None

    def copy(self) -> CyclesSoFar:
        return CyclesSoFar(self.live.readings())

    def rebuilt(self, cycles: Sequence[tuple[Any, ...]], session: Session | None) -> LiveCycles:
        fresh = type(self)(self.config, self.channels, self.header)
        if fresh._monitor is not None and session is not None:
            # Resume: the journal's readings and rejections in order, as they happened.
            for event in live_events(session):
                if isinstance(event, Rejection):
                    fresh._monitor.reject(event.cycle)
                else:
                    fresh._monitor.add_set(event.values, event.cycle, event.times)
            return fresh
        if fresh._monitor is not None and self._monitor is not None:
            # A reject: the frozen limits and the alarms already raised stay as they are.
            kept = {int(number) for _, number, *_ in cycles}
            for number in self._monitor.accepted_cycles:
                if number not in kept:
                    self._monitor.reject(number)
            fresh._monitor = self._monitor
            return fresh
        for values, number, *times in cycles:
            fresh.add_cycle(values, number, times[0] if times else None)
        return fresh


@dataclass(frozen=True)
class CyclesSoFar:
    """The cycles of a :class:`LiveCycles` at one moment (its :meth:`~LiveCycles.copy`)."""

    readings: LiveReadings

    def snapshot(self) -> Analysis:
        """The live analysis of these readings."""
        return self.readings.snapshot()

    def result(self) -> None:
        """A kind of cycles has no result of its own."""
        return None


@dataclass(frozen=True)
class StrokesSoFar:
    """The live result of a linearity session: the analysis of the whole strokes so far and
    their profiles (for the deviation plots)."""

    analysis: Any
    profiles: tuple[StrokeProfile, ...]


class LiveStrokes:
    """The live analysis of streamed strokes (linearity): each whole stroke the engine split
    is judged as the batch analysis judges it (the same profiles, the same function)."""

    def __init__(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> None:
        self.config, self.channels, self.header = config, tuple(channels), header
        self.profiles: list[StrokeProfile] = []
        self._result: Any = None

    def add_cycle(
        self, values: Mapping[str, float], cycle: int, times: Mapping[str, float] | None = None
    ) -> Mapping[str, Any]:
        return {}

    def add_stroke(self, outcome: Any) -> None:
        profile = {
            name: np.asarray(values, dtype=float) for name, values in outcome.profile.items()
        }
        if "s" not in profile:
            return
        numbers = np.full(len(profile["s"]), len(self.profiles) + 1)
        others = {name: values for name, values in profile.items() if name != "s"}
        added = marked_profiles(numbers, profile["s"], others, self.header.get("deadband"))
        for found in added:
            self.profiles.append(
                StrokeProfile(
                    number=len(self.profiles) + 1,
                    direction=outcome.direction or found.direction,
                    s=found.s,
                    channels=found.channels,
                    recorded=outcome.stroke,
                )
            )
        self._result = None

    def result(self) -> StrokesSoFar | None:
        if not self.profiles:
            return None
        if self._result is None:
            self._result = StrokesSoFar(
                analyze_linearity(
                    self.profiles, tolerance=tolerance_from_limits(self.config), config=self.config
                ),
                tuple(self.profiles),
            )
        return self._result

    def snapshot(self) -> Analysis:
        result = self.result()
        if result is None:
            raise StationError("no whole stroke yet: stream one first.")
        return linearity_summary(result.analysis)

    def copy(self) -> LiveStrokes:
        kept = type(self)(self.config, self.channels, self.header)
        kept.profiles = list(self.profiles)
        kept._result = self._result
        return kept

    def rebuilt(self, cycles: Sequence[tuple[Any, ...]], session: Session | None) -> LiveStrokes:
        fresh = type(self)(self.config, self.channels, self.header)
        if session is None:
            fresh.profiles = list(self.profiles)
        else:
            try:
                fresh.profiles = list(session_stroke_profiles(session))
            except StationError:
                fresh.profiles = []  # no whole stroke yet
        return fresh
