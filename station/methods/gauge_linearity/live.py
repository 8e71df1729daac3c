"""The live analysis of a linearity and bias study: the readings about their own master's
mean, which is the gauge's repeatability across the masters (a master is a placement of the
procedure's repeated block; :class:`~station.methods.live.LiveAboutGroups` says why no live
alarm is raised)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from station.analysis.summary import AnalysisConfig
from station.methods.live import LiveAboutGroups


def live_about_masters(
    config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
) -> LiveAboutGroups:
    """The readings about their master's mean, a master per placement."""
    return LiveAboutGroups(config, channels, header, by="placement", what="master")
