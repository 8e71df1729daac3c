"""The live analysis of an axis positioning test: each reading about the mean of its own
approach (the same stop of the test cycle, run after run), which is the axis's repeatability.

The readings themselves step from target to target and turn with the direction by design, so a
control chart of them would alarm at every stop; about their approach's mean they show what the
capture can watch (a stop that went wrong, a scale that slips). No live alarm is raised: the
figures of ISO 230-2 come at the finish, once the targets typed give the deviations.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from station.analysis.summary import Analysis, AnalysisConfig, analyze
from station.errors import StationError
from station.session.model import Session

Row = tuple[Mapping[str, float], int, Mapping[str, float] | None, int | None]
"""One accepted cycle: its values, number, reading times and placement (the run)."""


def stops(placements: Sequence[int | None]) -> list[tuple[int | None, int]]:
    """Each cycle's run and its place in that run (0-based), in the order taken: the k-th
    stop of every run is the same target approached the same way."""
    seen: dict[int | None, int] = {}
    found = []
    for placement in placements:
        found.append((placement, seen.get(placement, 0)))
        seen[placement] = seen.get(placement, 0) + 1
    return found


def about_approaches(
    rows: Sequence[Row], config: AnalysisConfig, channels: Sequence[str]
) -> Analysis:
    """The analysis of each channel's readings less the mean of their approach."""
    if not rows:
        raise StationError("no stop of the test cycle captured yet: capture the first one.")
    approach = np.asarray([k for _, k in stops([r[3] for r in rows])])
    numbers = [r[1] for r in rows]
    residuals: dict[str, np.ndarray] = {}
    for channel in channels:
        values = np.asarray([r[0].get(channel, np.nan) for r in rows], dtype=float)
        if np.isnan(values).any():
            continue
        means = {k: values[approach == k].mean() for k in set(approach.tolist())}
        residuals[channel] = values - np.asarray([means[k] for k in approach.tolist()])
    if not residuals:
        raise StationError("no channel was read at every stop yet.")
    return analyze(residuals, config, cycles=dict.fromkeys(residuals, numbers))


class LiveAboutApproaches:
    """The live analysis of a positioning test (see the module)."""

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
        """A positioning test streams no strokes."""
        return None

    def snapshot(self) -> Analysis:
        """The readings about their approaches' means so far."""
        return about_approaches(self.rows, self.config, self.channels)

    def result(self) -> None:
        """The ISO 230-2 figures are computed at the finish."""
        return None

    def copy(self) -> LiveAboutApproaches:
        """The cycles so far (the analysis is computed when asked)."""
        kept = type(self)(self.config, self.channels, self.header)
        kept.rows = list(self.rows)
        return kept

    def rebuilt(
        self, cycles: Sequence[tuple[Any, ...]], session: Session | None
    ) -> LiveAboutApproaches:
        """A fresh analysis of the accepted ``cycles`` (values, number, times, placement)."""
        fresh = type(self)(self.config, self.channels, self.header)
        for values, number, *rest in cycles:
            times = rest[0] if rest else None
            placement = rest[1] if len(rest) > 1 else None
            fresh.add_cycle(values, number, times, placement)
        return fresh
