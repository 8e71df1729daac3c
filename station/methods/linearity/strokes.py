"""Linearity's streamed strokes: split and trimmed from a session's ``samples`` events
(:func:`session_stroke_profiles`) or a CSV's ``stroke,s,h,v`` rows, and judged live stroke by
stroke (:class:`LiveStrokes`) exactly as the batch analysis judges them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.analysis.linearity import analyze_linearity, linearity_summary, tolerance_from_limits
from station.analysis.strokes import (
    StrokeProfile,
    profiles_from_stream,
    profiles_from_table,
    trim_dwell,
)
from station.analysis.summary import Analysis, AnalysisConfig
from station.errors import StationError
from station.session.model import Session
from station.session.tables import ReadingTable, require_columns

TABLE_COLUMNS: tuple[str, ...] = ("stroke", "s", "h", "v")
"""The columns of a linearity table: one row per streamed point."""


def table_stroke_profiles(table: ReadingTable) -> list[StrokeProfile]:
    """The strokes of a linearity CSV (columns stroke, s, h, v)."""
    columns = require_columns(table, TABLE_COLUMNS, "a linearity table")
    return profiles_from_table(
        columns["stroke"], columns["s"], {"h": columns["h"], "v": columns["v"]}
    )


def session_stroke_profiles(session: Session) -> list[StrokeProfile]:
    """The whole strokes a session streamed (its ``samples`` events with s, h and v).

    Strokes the engine split live carry an end mark on their last event: they are taken as
    recorded (only the dwell at their ends trimmed, with the deadband the header records); a
    lead-in or a stroke cut short has no mark and is left out. Files without marks are split
    by the scale's travel here."""
    batches = [b for b in session.samples if {"s", "h", "v"} <= set(b.channels)]
    ended = {event["seq"] for event in session.events if event.get("end")}
    if ended:
        whole = {b.stroke for b in batches if b.seq in ended}
        batches = [b for b in batches if b.stroke in whole]
    if not batches:
        raise StationError(
            f"{session.path}: the session has no streamed strokes (samples events with h, v "
            "and s) to analyse yet."
        )
    arrays = [b.as_arrays() for b in batches]
    joined = {c: np.concatenate([a[c] for a in arrays]) for c in ("s", "h", "v")}
    deadband = session.header.get("deadband")
    if ended:
        numbers = np.concatenate(
            [np.full(len(a["s"]), b.stroke) for a, b in zip(arrays, batches, strict=True)]
        )
        return marked_profiles(numbers, joined["s"], {"h": joined["h"], "v": joined["v"]}, deadband)
    if all(b.stroke is not None for b in batches):
        numbers = np.concatenate(
            [np.full(len(a["s"]), b.stroke) for a, b in zip(arrays, batches, strict=True)]
        )
        return profiles_from_table(
            numbers, joined["s"], {"h": joined["h"], "v": joined["v"]}, deadband=deadband
        )
    # Batches without stroke numbers are one stream: split it by the scale's travel.
    return profiles_from_stream(
        joined["s"], {"h": joined["h"], "v": joined["v"]}, deadband=deadband
    )


def marked_profiles(
    numbers: np.ndarray,
    s: np.ndarray,
    channels: Mapping[str, np.ndarray],
    deadband: float | None,
) -> list[StrokeProfile]:
    """Strokes already split (one number per whole stroke), each with its dwell trimmed."""
    profiles: list[StrokeProfile] = []
    for number in dict.fromkeys(numbers.astype(int).tolist()):
        rows = np.flatnonzero(numbers == number)
        kept = rows[trim_dwell(s[rows], deadband)]
        if kept.size < 2 or float(np.ptp(s[kept])) == 0:
            continue
        direction = "A→B" if s[kept[-1]] > s[kept[0]] else "B→A"
        profiles.append(
            StrokeProfile(
                number=len(profiles) + 1,
                direction=direction,
                s=s[kept],
                channels={name: values[kept] for name, values in channels.items()},
                recorded=number,
            )
        )
    return profiles


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
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
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
