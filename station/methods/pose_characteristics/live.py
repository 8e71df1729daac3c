"""The live analysis of a pose test: the readings of the pose being measured, each pose on its
own.

Every pose has a bias of its own by design (it is what AP measures), so one control chart of
all the readings would alarm at every new pose; each pose's readings are a repeatability run of
their own, charted and judged as one (:class:`~station.methods.live.LiveCycles`, its phase II
alarms included), and the dashboard shows the pose being measured.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from station.analysis.summary import Analysis, AnalysisConfig
from station.errors import StationError
from station.methods.live import LiveCycles
from station.session.model import Session


class LivePerPose:
    """The live analysis of each pose (a placement of the repeated block) on its own; its
    snapshot is the latest pose's."""

    def __init__(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> None:
        self.config, self.channels, self.header = config, tuple(channels), header
        self.poses: dict[int | None, LiveCycles] = {}
        self.current: int | None = None

    def _pose(self, placement: int | None) -> LiveCycles:
        if placement not in self.poses:
            self.poses[placement] = LiveCycles(self.config, self.channels, self.header)
        return self.poses[placement]

    def add_cycle(
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
    ) -> Mapping[str, Any]:
        """Take one cycle into its pose's analysis."""
        self.current = placement
        return self._pose(placement).add_cycle(values, cycle, times, placement)

    def add_stroke(self, outcome: Any) -> None:
        """A pose test streams no strokes."""
        return None

    def snapshot(self) -> Analysis:
        """The analysis of the pose measured last (StationError before its first cycle)."""
        return self.copy().snapshot()

    def result(self) -> None:
        """The pose characteristics are computed at the finish."""
        return None

    def copy(self) -> Any:
        """The pose measured last, as it is now."""
        if self.current not in self.poses:
            return _Nothing()
        return self.poses[self.current].copy()

    def rebuilt(self, cycles: Sequence[tuple[Any, ...]], session: Session | None) -> LivePerPose:
        """A fresh analysis of the accepted ``cycles`` (values, number, times, placement), each
        pose's from its own (a pose that had a cycle rejected keeps its frozen limits)."""
        fresh = type(self)(self.config, self.channels, self.header)
        by_pose: dict[int | None, list[tuple[Any, ...]]] = {}
        for values, number, *rest in cycles:
            placement = rest[1] if len(rest) > 1 else None
            by_pose.setdefault(placement, []).append((values, number, *rest))
            fresh.current = placement
        for placement, kept in by_pose.items():
            earlier = None if session is not None else self.poses.get(placement)
            if earlier is not None:
                fresh.poses[placement] = earlier.rebuilt(kept, None)
                continue
            live = fresh._pose(placement)
            for values, number, *rest in kept:
                live.add_cycle(values, number, rest[0] if rest else None, placement)
        return fresh


class _Nothing:
    """No pose measured yet."""

    def snapshot(self) -> Analysis:
        raise StationError("no cycle at a pose yet: capture one first.")

    def result(self) -> None:
        return None
