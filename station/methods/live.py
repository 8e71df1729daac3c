"""The live analysis of cycles the engine feeds while a session runs (:class:`LiveCycles`:
O(1) per cycle), the one most methods take; the readings about their own group's mean
(:class:`LiveAboutGroups`), which the gauge studies take; a method with another (linearity's
strokes) keeps its own in its package."""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from station.analysis.live import LiveAnalysis, LiveReadings
from station.analysis.monitor import LiveMonitor, Rejection
from station.analysis.summary import Analysis, AnalysisConfig, analyze
from station.errors import StationError
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


GroupedRow = tuple[Mapping[str, float], int, Mapping[str, float] | None, Hashable]
"""One accepted cycle: its values, number, reading times and the group it belongs to."""


def about_groups(
    rows: Sequence[GroupedRow], config: AnalysisConfig, channels: Sequence[str], what: str
) -> Analysis:
    """The analysis of each channel's readings less their group's mean (``what``: the group
    in words, for the sentence when there is nothing yet)."""
    if not rows:
        raise StationError(f"no reading of a {what} yet: capture one first.")
    groups = [row[3] for row in rows]
    numbers = [row[1] for row in rows]
    residuals: dict[str, np.ndarray] = {}
    for channel in channels:
        values = np.asarray([row[0].get(channel, np.nan) for row in rows], dtype=float)
        if np.isnan(values).any():
            continue
        sums: dict[Hashable, list[float]] = {}
        for group, value in zip(groups, values.tolist(), strict=True):
            sums.setdefault(group, []).append(value)
        means = {group: float(np.mean(found)) for group, found in sums.items()}
        residuals[channel] = values - np.asarray([means[group] for group in groups])
    if not residuals:
        raise StationError(f"no channel was read at every {what} yet.")
    return analyze(residuals, config, cycles=dict.fromkeys(residuals, numbers))


class LiveAboutGroups:
    """The live analysis of a gauge study: the readings about their own group's mean, which
    is the gauge's variation without the differences the study makes on purpose (the masters of
    a linearity study, a placement each; the parts of a Gage R&R). The readings themselves jump
    from group to group by design, so a control chart of them would alarm at every new one;
    about each group's mean they show what the capture can watch (a seating that went wrong, a
    gauge that sticks). No live alarm is raised: the study's verdict is taken at the finish.

    ``by``: what groups the cycles, the ``placement`` of a repeated block or the ``part`` a
    parts step measured; ``what`` names one group in words."""

    def __init__(
        self,
        config: AnalysisConfig,
        channels: Sequence[str],
        header: Mapping[str, Any],
        *,
        by: Literal["placement", "part"] = "placement",
        what: str = "master",
    ) -> None:
        self.config, self.channels, self.header = config, tuple(channels), header
        self.by, self.what = by, what
        self.rows: list[GroupedRow] = []

    def add_cycle(
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
        *,
        part: int | None = None,
    ) -> Mapping[str, Any]:
        """Keep the cycle under its group; no live alarm (see the class)."""
        group = placement if self.by == "placement" else part
        self.rows.append((dict(values), cycle, times, -1 if group is None else group))
        return {}

    def add_stroke(self, outcome: Any) -> None:
        """A gauge study streams no strokes."""
        return None

    def snapshot(self) -> Analysis:
        """The readings about their groups' means so far."""
        return about_groups(self.rows, self.config, self.channels, self.what)

    def result(self) -> None:
        """The study itself is judged at the finish."""
        return None

    def _empty(self) -> LiveAboutGroups:
        return type(self)(self.config, self.channels, self.header, by=self.by, what=self.what)

    def copy(self) -> LiveAboutGroups:
        """The cycles so far (the analysis is computed when asked)."""
        kept = self._empty()
        kept.rows = list(self.rows)
        return kept

    def rebuilt(
        self, cycles: Sequence[tuple[Any, ...]], session: Session | None
    ) -> LiveAboutGroups:
        """A fresh analysis of the accepted ``cycles`` (values, number, times, placement,
        part)."""
        fresh = self._empty()
        for values, number, *rest in cycles:
            times = rest[0] if rest else None
            placement = rest[1] if len(rest) > 1 else None
            part = rest[2] if len(rest) > 2 else None
            fresh.add_cycle(values, number, times, placement, part=part)
        return fresh
