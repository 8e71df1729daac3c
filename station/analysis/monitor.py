"""The live alarms of a running session: phase II monitoring of its cycles.

:class:`LiveMonitor` is a :class:`~station.analysis.live.LiveAnalysis` with phase II limits
(frozen after ``freeze_after`` points, or a baseline's) and an :class:`AlarmLedger`: the engine
calls :meth:`LiveMonitor.add_set` for every recorded cycle and journals the alarms it returns,
and :func:`replay_live_alarms` runs the same steps over a recorded session, so a replay gives
exactly the recorded live alarms.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from station.analysis.live import LiveAnalysis, LiveUpdate
from station.analysis.phases import DEFAULT_FREEZE_AFTER, ControlBaseline, FrozenLimits
from station.analysis.rules import Alarm, rule_name
from station.analysis.summary import AnalysisConfig


@dataclass(frozen=True)
class LiveAlarm:
    """An alarm the live analysis raised: its channel, the cycle whose reading raised it, and
    the alarm (rule, points, cycles, sentence)."""

    channel: str
    cycle: int
    alarm: Alarm

    def event_fields(self) -> dict[str, object]:
        """The fields of the journal's ``alarm`` event for it (``live`` marks a phase II alarm;
        ``rule_name`` says the rule in words)."""
        return {
            "channel": self.channel,
            "rule": self.alarm.rule,
            "rule_name": rule_name(self.alarm.rule),
            "points": list(self.alarm.points),
            "cycles": list(self.alarm.cycles),
            "text": self.alarm.text,
            "raised_at": self.cycle,
            "live": True,
        }


class AlarmLedger:
    """Which alarms were already raised: an alarm is new unless an alarm of the same channel
    and rule already flagged one of its cycles (a run growing by a point is one alarm)."""

    def __init__(self) -> None:
        self._flagged: dict[tuple[str, str], set[int]] = {}

    def admit(self, channel: str, alarm: Alarm) -> bool:
        """Record the alarm's cycles; True when it is new."""
        cycles = set(alarm.cycles or ())
        flagged = self._flagged.setdefault((channel, alarm.rule), set())
        known = not flagged.isdisjoint(cycles)
        flagged.update(cycles)
        return not known


@dataclass(frozen=True)
class ReadingSet:
    """One accepted cycle's readings (channel → value), as the journal recorded them."""

    cycle: int
    values: Mapping[str, float]
    times: Mapping[str, float] | None = None


@dataclass(frozen=True)
class Rejection:
    """The operator rejected cycle ``cycle`` (its readings leave the analysis)."""

    cycle: int


class LiveMonitor:
    """The live alarms of a running session: a :class:`LiveAnalysis` with phase II limits and
    an :class:`AlarmLedger`. The engine calls :meth:`add_set` for every recorded cycle and
    journals the alarms it returns; :func:`replay_live_alarms` runs the same steps over a
    recorded session, so a replay gives exactly the recorded live alarms.

    A rejected cycle (:meth:`reject`) leaves the analysis; limits already frozen stay frozen
    (phase II limits never move) and alarms already raised stay raised.
    """

    def __init__(
        self,
        config: AnalysisConfig,
        channels: Sequence[str] = (),
        *,
        freeze_after: int | None = DEFAULT_FREEZE_AFTER,
        baseline: ControlBaseline | None = None,
    ) -> None:
        if freeze_after is None and baseline is None:
            raise ValueError("a live monitor needs a freeze count or a baseline")
        self.config = config
        self.channel_names = tuple(channels)
        self.freeze_after = freeze_after
        self.baseline = baseline
        self.ledger = AlarmLedger()
        self._accepted: list[ReadingSet] = []
        self.live = LiveAnalysis(
            config, self.channel_names, freeze_after=freeze_after, baseline=baseline
        )

    def add_set(
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
    ) -> tuple[dict[str, LiveUpdate], list[LiveAlarm]]:
        """Add one recorded cycle (with its readings' times, when known); the updates per
        channel and the alarms that are new."""
        self._accepted.append(ReadingSet(cycle, dict(values), times))
        updates = self.live.add_set(values, cycle, times)
        new = [
            LiveAlarm(channel, cycle, alarm)
            for channel, update in updates.items()
            for alarm in update.alarms
            if self.ledger.admit(channel, alarm)
        ]
        return updates, new

    def reject(self, cycle: int) -> None:
        """Take cycle ``cycle`` out: the analysis is rebuilt from the other cycles, with the
        limits already frozen kept as they were."""
        self._accepted = [s for s in self._accepted if s.cycle != cycle]
        frozen = {
            name: channel.frozen
            for name, channel in self.live.channels.items()
            if channel.frozen is not None
        }
        baseline = ControlBaseline(
            {**({} if self.baseline is None else dict(self.baseline.limits)), **frozen},
            "" if self.baseline is None else self.baseline.source,
        )
        self.live = LiveAnalysis(
            self.config, self.channel_names, freeze_after=self.freeze_after, baseline=baseline
        )
        for reading_set in self._accepted:
            self.live.add_set(reading_set.values, reading_set.cycle, reading_set.times)

    @property
    def accepted_cycles(self) -> tuple[int, ...]:
        """The cycle numbers the analysis holds now (added and not rejected), in order."""
        return tuple(reading_set.cycle for reading_set in self._accepted)

    def frozen_limits(self) -> dict[str, FrozenLimits]:
        """The phase II limits of each channel that has them."""
        return {
            name: channel.frozen
            for name, channel in self.live.channels.items()
            if channel.frozen is not None
        }


def replay_live_alarms(
    events: Iterable[ReadingSet | Rejection],
    config: AnalysisConfig,
    channels: Sequence[str] = (),
    *,
    freeze_after: int | None = DEFAULT_FREEZE_AFTER,
    baseline: ControlBaseline | None = None,
) -> list[LiveAlarm]:
    """The live alarms a session raised, from its recorded cycles and rejections in journal
    order: what :class:`LiveMonitor` gave the engine, in the same order."""
    monitor = LiveMonitor(config, channels, freeze_after=freeze_after, baseline=baseline)
    raised: list[LiveAlarm] = []
    for event in events:
        if isinstance(event, Rejection):
            monitor.reject(event.cycle)
        else:
            raised.extend(monitor.add_set(event.values, event.cycle, event.times)[1])
    return raised
