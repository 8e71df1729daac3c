"""The live analysis of cycles the engine feeds while a session runs (:class:`LiveCycles`:
O(1) per cycle), the one most methods take; a method with another (linearity's strokes) keeps
its own in its package."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from station.analysis.live import LiveAnalysis, LiveReadings
from station.analysis.monitor import LiveMonitor, Rejection
from station.analysis.summary import Analysis, AnalysisConfig
from station.session.alarms import live_events
from station.session.model import Session


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
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
    ) -> Mapping[str, Any]:
        """Take one accepted cycle (the placement it was taken at is not this analysis'
        business); per channel an update whose ``alarms`` are new."""
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
        for values, number, *rest in cycles:
            fresh.add_cycle(values, number, rest[0] if rest else None)
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
