"""The live analysis of a linearity and bias study: the readings about their own master's
mean, which is the gauge's repeatability across the masters.

The readings themselves jump from master to master by design, so a control chart of them would
alarm at every new block; about each master's mean they show what the capture can watch (a
seating that went wrong, a gauge that sticks). No live alarm is raised: the study's verdict is
its regression, at the finish.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from station.analysis.summary import Analysis, AnalysisConfig, analyze
from station.errors import StationError
from station.session.model import Session

Row = tuple[Mapping[str, float], int, Mapping[str, float] | None, int | None]
"""One accepted cycle: its values, number, reading times and placement (the master)."""


def about_masters(rows: Sequence[Row], config: AnalysisConfig, channels: Sequence[str]) -> Analysis:
    """The analysis of each channel's readings less their master's mean."""
    if not rows:
        raise StationError("no reading of a master yet: capture one first.")
    placements = np.asarray([-1 if r[3] is None else r[3] for r in rows])
    numbers = [r[1] for r in rows]
    residuals: dict[str, np.ndarray] = {}
    for channel in channels:
        values = np.asarray([r[0].get(channel, np.nan) for r in rows], dtype=float)
        if np.isnan(values).any():
            continue
        means = {p: values[placements == p].mean() for p in set(placements.tolist())}
        residuals[channel] = values - np.asarray([means[p] for p in placements.tolist()])
    if not residuals:
        raise StationError("no channel was read at every master yet.")
    return analyze(residuals, config, cycles=dict.fromkeys(residuals, numbers))


class LiveAboutMasters:
    """The live analysis of a linearity and bias study (see the module)."""

    def __init__(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> None:
        self.config, self.channels, self.header = config, tuple(channels), header
        self.rows: list[Row] = []

    def add_cycle(
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
    ) -> Mapping[str, Any]:
        """Keep the cycle; no live alarm (see the module)."""
        self.rows.append((dict(values), cycle, times, placement))
        return {}

    def add_stroke(self, outcome: Any) -> None:
        """A study streams no strokes."""
        return None

    def snapshot(self) -> Analysis:
        """The readings about their masters' means so far."""
        return about_masters(self.rows, self.config, self.channels)

    def result(self) -> None:
        """The study itself is judged at the finish."""
        return None

    def copy(self) -> LiveAboutMasters:
        """The cycles so far (the analysis is computed when asked)."""
        kept = type(self)(self.config, self.channels, self.header)
        kept.rows = list(self.rows)
        return kept

    def rebuilt(
        self, cycles: Sequence[tuple[Any, ...]], session: Session | None
    ) -> LiveAboutMasters:
        """A fresh analysis of the accepted ``cycles`` (values, number, times, placement)."""
        fresh = type(self)(self.config, self.channels, self.header)
        for values, number, *rest in cycles:
            times = rest[0] if rest else None
            placement = rest[1] if len(rest) > 1 else None
            fresh.add_cycle(values, number, times, placement)
        return fresh
