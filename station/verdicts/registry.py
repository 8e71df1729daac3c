"""What an analysis kind is made of, the registry of kinds, and the report of a judgement.

A kind is an :class:`AnalysisKind` given to :func:`register`; :func:`judge` runs one on a
session's or a CSV table's :class:`KindInputs` and gives a :class:`SessionReport`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from station.analysis.document import to_json
from station.analysis.report import format_report
from station.analysis.strokes import StrokeProfile
from station.analysis.summary import Analysis, AnalysisConfig
from station.errors import StationError
from station.procedures import AnalysisNeeds, register_analysis_needs
from station.session.alarms import recorded_alarms_json
from station.session.model import Session

AccuracyInputs = tuple[np.ndarray, dict[str, np.ndarray], dict[int, tuple[float, ...]]]
"""Placement of each reading, the errors x, y, z, and the pendant coordinates per placement."""


# -- what a kind is made of ----------------------------------------------------------------------


@dataclass(frozen=True)
class KindInputs:
    """What a batch analysis may read, from a session file or a CSV table; the kind takes the
    parts it needs (the others are never computed)."""

    config: AnalysisConfig
    channels: Mapping[str, Any]
    cycles: Mapping[str, Any] | None
    excluded_cycles: Sequence[int]
    profiles: Callable[[], Sequence[StrokeProfile]]
    accuracy_inputs: Callable[[], AccuracyInputs]
    tolerance: float | None = None
    width: int = 80
    options: Mapping[str, Any] = None  # type: ignore[assignment]
    """Kind-specific values (a reference size, a tolerance) from the command line or header."""
    times: Mapping[str, Any] | None = None
    """The time (s) of each reading per channel, for the drift's trend test."""
    header: Mapping[str, Any] | None = None
    """The session's header (None for a CSV table)."""
    input_events: Sequence[Mapping[str, Any]] = ()
    """The session's ``input`` events (values typed, with their placement); none for a CSV."""
    table: Any = None
    """The CSV table (``station.session.tables.ReadingTable``) a kind reads its own columns
    from (a joint number, a lever arm, a position q); None for a session."""


@dataclass(frozen=True)
class Judgement:
    """A kind's batch result: the :class:`Analysis` the verdict judges, the kind's own result
    (None for repeatability) and its report blocks."""

    analysis: Analysis | None
    result: Any
    sections: tuple[tuple[str, ...], ...]


class LiveVerdict(Protocol):
    """A kind's live analysis, fed by the engine as events reach the disk."""

    def add_cycle(
        self, values: Mapping[str, float], cycle: int, times: Mapping[str, float] | None = None
    ) -> Mapping[str, Any]:
        """Take one accepted cycle (``times``: each reading's time); per channel an update
        whose ``alarms`` are new."""
        ...

    def add_stroke(self, outcome: Any) -> None:
        """Take one whole streamed stroke (its ``profile`` and ``direction``)."""
        ...

    def snapshot(self) -> Analysis:
        """The analysis so far (StationError while there is nothing to analyse)."""
        ...

    def result(self) -> Any:
        """The kind's own result so far (per-stroke straightness...), or None."""
        ...

    def rebuilt(self, cycles: Sequence[tuple[Any, ...]], session: Session | None) -> LiveVerdict:
        """A fresh live analysis of ``cycles`` keeping what is not a cycle (strokes), or
        taking that from ``session`` when given (resume)."""
        ...

    def copy(self) -> LiveCopy:
        """What the analysis holds now, cheaply (no analysis: the engine takes it under its
        lock); its ``snapshot()`` and ``result()`` equal this object's now and are computed
        later, on another thread, while this one goes on taking cycles."""
        ...


class LiveCopy(Protocol):
    """A live analysis as it was at one moment (:meth:`LiveVerdict.copy`)."""

    def snapshot(self) -> Analysis:
        """The analysis (StationError while there is nothing to analyse)."""
        ...

    def result(self) -> Any:
        """The kind's own result, or None."""
        ...


@dataclass(frozen=True)
class AnalysisKind:
    """One way of judging a session."""

    name: str
    title: str
    """The report's title, before ``ON <file>``."""
    batch: Callable[[KindInputs], Judgement]
    live: Callable[[AnalysisConfig, Sequence[str], Mapping[str, Any]], LiveVerdict]
    needs: AnalysisNeeds = AnalysisNeeds()
    """What a procedure of this kind must hold (checked when the file loads)."""
    json_key: str | None = None
    """Where :attr:`json` goes in the JSON document (``linearity``, ``accuracy``)."""
    json: Callable[[Any], dict[str, Any]] | None = None
    count: Callable[[Any], str] | None = None
    """What a session measured, in words (``7 strokes``); None: its cycles."""
    export_layout: str = "tidy"
    """The CSV layout ``station export`` writes by default: ``tidy`` (a row per reading) or
    ``wide`` (the table this kind's analysis reads back: strokes, placements)."""
    header_fields: Callable[[Mapping[str, Any]], dict[str, Any]] | None = None
    """Fields a new session's header records for this kind, given the header's other fields
    (the gauge checks that cover a repeatability session's gauges)."""
    finished: Callable[[Path], Sequence[str]] | None = None
    """Called once a session of this kind is finished and closed, with its file; returns the
    operator messages to show (a gauge check filed in the gauge register). StationError: a
    warning, never a lost session."""


_KINDS: dict[str, AnalysisKind] = {}


def register(kind: AnalysisKind) -> AnalysisKind:
    """Add (or replace) an analysis kind; procedure files may then declare it."""
    register_analysis_needs(kind.name, kind.needs)
    _KINDS[kind.name] = kind
    return kind


def kind_of(name: str) -> AnalysisKind:
    """The analysis kind called ``name``; StationError naming the known ones."""
    try:
        return _KINDS[name]
    except KeyError:
        raise StationError(f"no analysis kind {name!r}; known kinds: {', '.join(_KINDS)}") from None


def kinds() -> tuple[str, ...]:
    """The registered analysis kinds."""
    return tuple(_KINDS)


# -- the report of a judgement -----------------------------------------------------------------


@dataclass(frozen=True)
class SessionReport:
    """The analysis of a session (or of a CSV table) and its report.

    ``analysis`` is what the verdict judges (None before there is anything); ``result`` is the
    kind's own analysis (None for repeatability), and ``sections`` its report blocks."""

    kind: str
    analysis: Analysis | None
    result: Any
    sections: tuple[tuple[str, ...], ...]
    title: str
    notes: tuple[str, ...] = ()
    excluded_cycles: tuple[int, ...] = ()
    recorded_alarms: tuple[Any, ...] | None = None
    """A session's alarm events with their acknowledgements (``station.session.alarms``);
    None for a CSV table."""
    alarm_lines: tuple[str, ...] = ()
    """The report block of those alarms and their causes (empty for a CSV table): print it
    after ``sections``."""

    @property
    def lines(self) -> tuple[str, ...]:
        """The report blocks as one run of lines."""
        return tuple(line for section in self.sections for line in section)

    @property
    def count(self) -> str | None:
        """What the session measured when the kind counts something else than cycles
        (``7 strokes``, ``3 placements``); None for a kind that counts cycles."""
        counter = kind_of(self.kind).count
        return counter(self.result) if counter is not None and self.result is not None else None

    def document(self) -> dict[str, Any]:
        """The JSON document of ``station analyze --json``: the analysis, the kind's own figures
        under its key (``linearity``, ``accuracy``...; at the top level for a kind without a
        key), and ``procedure`` (the kind). A kind that judges no readings (a gain schedule)
        has only its own figures."""
        kind = kind_of(self.kind)
        own = kind.json is not None and self.result is not None
        if self.analysis is None and not own:
            raise ValueError("a report without an analysis has no JSON document")
        document = {} if self.analysis is None else to_json(self.analysis)
        if own and kind.json_key:
            document[kind.json_key] = kind.json(self.result)  # type: ignore[misc]
        elif own:
            document.update(kind.json(self.result))  # type: ignore[misc]
        document["procedure"] = self.kind
        if self.recorded_alarms is not None:
            document["recorded_alarms"] = recorded_alarms_json(self.recorded_alarms)
        return document

    @property
    def empty(self) -> bool:
        """True when there is nothing to report: no analysis and no result of the kind's."""
        return self.analysis is None and self.result is None

    def text(self, notes: Sequence[str] | None = None, *, alarms: bool = True) -> str:
        """The text report as ``station analyze FILE`` prints it (``notes`` replace the
        report's own); a kind that judges no readings prints its title, notes and blocks."""
        shown = list(self.notes if notes is None else notes)
        sections = [list(section) for section in self.sections]
        if alarms and self.alarm_lines:
            sections.append(list(self.alarm_lines))
        if self.analysis is not None:
            return format_report(self.analysis, title=self.title, notes=shown, sections=sections)
        return "\n".join([self.title, *shown, *("\n" + "\n".join(s) for s in sections)]) + "\n"


def judge(kind: str, inputs: KindInputs, *, name: str, notes: Sequence[str] = ()) -> SessionReport:
    """Analyse ``inputs`` as analysis kind ``kind`` says; ``name`` (the file's) goes into the
    title."""
    chosen = kind_of(kind)
    judgement = chosen.batch(inputs)
    return SessionReport(
        kind=chosen.name,
        analysis=judgement.analysis,
        result=judgement.result,
        sections=judgement.sections,
        title=f"{chosen.title} ON {name}",
        notes=tuple(notes),
        excluded_cycles=tuple(inputs.excluded_cycles),
    )
