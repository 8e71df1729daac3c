"""The registry of analysis kinds: how a session (or a CSV table) is judged.

An analysis kind gives its live analysis (what the engine feeds while the session runs), its
batch analysis, its report sections (text), its JSON and its count. A procedure names its kind
with ``analysis =``; ``station analyze``, the ``station capture`` summary, the TUI summary and
every export call :func:`judge` (or :func:`analyze_session_file`), and nothing anywhere tests a
procedure id. A new kind is an :class:`AnalysisKind` given to :func:`register`.

Built-in kinds: ``repeatability`` (the readings of each channel, report §2.6), ``linearity``
(straightness per streamed stroke, §2.9) and ``relative_accuracy`` (the errors at each fixture
placement, §2.8).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from station.analysis.accuracy import accuracy_json, analyze_accuracy
from station.analysis.linearity import (
    analyze_linearity,
    linearity_json,
    linearity_summary,
    tolerance_from_limits,
)
from station.analysis.live import LiveAnalysis, LiveMonitor, LiveReadings, Rejection
from station.analysis.report import format_accuracy, format_linearity
from station.analysis.strokes import (
    StrokeProfile,
    profiles_from_stream,
    profiles_from_table,
    trim_dwell,
)
from station.analysis.summary import Analysis, AnalysisConfig, analyze, to_json
from station.errors import StationError
from station.procedures import AnalysisNeeds, discover_procedures, register_analysis_needs
from station.session.alarms import (
    format_recorded_alarms,
    live_events,
    recorded_alarms,
    recorded_alarms_json,
)
from station.session.gauge_register import coverage_fields, gauge_block
from station.session.header import analysis_config
from station.session.model import Session, load_session
from station.text import zero_taken

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
        from station.analysis.report import format_report

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


# -- sessions ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SessionSource:
    """What a session file gives the analysis: its accepted channels, the cycle number of each
    reading, its recorded settings and the notes a report prints about it."""

    session: Session
    channels: dict[str, np.ndarray]
    cycles: dict[str, np.ndarray]
    excluded_cycles: tuple[int, ...]
    config: AnalysisConfig
    notes: tuple[str, ...]
    analysis: str
    """The analysis kind the session's procedure declares (:func:`session_analysis`)."""
    times: dict[str, np.ndarray] | None = None
    """The time (s) of each reading, for the drift's trend test."""


def accepted_readings(session: Session) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The accepted readings of each channel that has any, and the cycle number of each."""
    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    cycles = session.channel_cycles()
    return channels, {name: cycles[name] for name in channels}


def session_source(session: Session) -> SessionSource:
    """The accepted channels (rejected cycles left out), settings and notes of a session."""
    notes = [
        f"Session {session.session_id}: robot {session.robot}, operator "
        f"{session.operator or 'not given'}, procedure {session.procedure_id}, "
        f"created {session.created}, {session.status}.",
        f"Last line hash (anchors the session file): {session.last_hash}",
    ]
    zero = zero_taken(session.zeroes, session.header.get("resolution"))
    if zero:
        notes.append(zero)
    if session.torn is not None:
        notes.append(f"Torn tail: {session.torn.message}")
    channels, cycles = accepted_readings(session)
    return SessionSource(
        session=session,
        channels=channels,
        cycles=cycles,
        excluded_cycles=tuple(session.excluded_cycles),
        # The same settings the live analysis of the running session used.
        config=analysis_config(session.header, session.zeroes),
        notes=tuple(notes),
        analysis=session_analysis(session),
        times={name: times for name, times in session.channel_times().items() if name in channels},
    )


def load_session_source(path: Path) -> SessionSource:
    """:func:`session_source` of the session file at ``path``, read-only (a torn tail is
    reported in the notes, not repaired)."""
    return session_source(load_session(path, recover=False))


def session_analysis(session: Session) -> str:
    """How to analyse a session: the analysis its header records for its procedure; else that
    of the same procedure file (id and sha256) where this machine has it; else what the
    session holds (streamed strokes: linearity; captures at fixture placements: relative
    accuracy; otherwise repeatability)."""
    recorded = session.header["procedure"]
    if recorded.get("analysis") in _KINDS:
        return str(recorded["analysis"])
    try:
        catalog = discover_procedures()
        procedure = next(
            (
                p
                for p in catalog.procedures
                if p.id == recorded.get("id") and p.sha256 == recorded.get("sha256")
            ),
            None,
        )
    except StationError:  # a STATION_PROCEDURES folder that is gone: judge by the content
        procedure = None
    if procedure is not None:
        return procedure.analysis
    if session.samples:
        return "linearity"
    if any(cycle.placement is not None for cycle in session.cycles.values()):
        return "relative_accuracy"
    return "repeatability"


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


def session_accuracy_inputs(session: Session) -> AccuracyInputs:
    """Placements, errors x, y, z and pendant coordinates of a relative-accuracy session."""
    numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
    if not numbers:
        raise StationError(
            f"{session.path}: the session has no accepted readings at a fixture placement yet."
        )
    errors = {
        axis: np.asarray([session.cycles[n].readings[axis].value for n in numbers])
        for axis in ("x", "y", "z")
        if all(axis in session.cycles[n].readings for n in numbers)
    }
    pendant: dict[int, tuple[float, ...]] = {}
    for event in session.input_events:
        values, placement = event.get("values") or {}, event.get("placement")
        if isinstance(placement, int) and all(
            isinstance(values.get(axis), int | float) for axis in ("x", "y", "z")
        ):
            pendant[placement] = tuple(float(values[axis]) for axis in ("x", "y", "z"))
    placements = np.asarray([session.cycles[n].placement for n in numbers])
    return placements, errors, pendant


def session_inputs(
    source: SessionSource,
    *,
    config: AnalysisConfig | None = None,
    tolerance: float | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> KindInputs:
    """A loaded session as the inputs of a batch analysis."""
    session = source.session
    return KindInputs(
        config=source.config if config is None else config,
        channels=source.channels,
        cycles=source.cycles,
        excluded_cycles=source.excluded_cycles,
        profiles=lambda: session_stroke_profiles(session),
        accuracy_inputs=lambda: session_accuracy_inputs(session),
        tolerance=tolerance,
        width=width,
        options=dict(options or {}),
        times=source.times,
        header=session.header,
        input_events=tuple(session.input_events),
    )


def report_session(
    source: SessionSource,
    *,
    config: AnalysisConfig | None = None,
    kind: str | None = None,
    tolerance: float | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> SessionReport:
    """The analysis and report of a loaded session: as its procedure declares unless ``kind``
    says otherwise, with the settings it recorded unless ``config`` replaces them. Raises
    StationError when a kind's session has nothing to analyse yet."""
    inputs = session_inputs(
        source, config=config, tolerance=tolerance, width=width, options=options
    )
    report = judge(
        kind or source.analysis, inputs, name=Path(source.session.path).name, notes=source.notes
    )
    alarms = recorded_alarms(source.session)
    return replace(
        report, recorded_alarms=alarms, alarm_lines=tuple(format_recorded_alarms(alarms, width))
    )


def analyze_session_file(
    path: Path,
    *,
    config: AnalysisConfig | None = None,
    kind: str | None = None,
    tolerance: float | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> SessionReport:
    """The analysis and report of the session file at ``path``, as ``station analyze FILE``
    prints it (see :func:`report_session`)."""
    return report_session(
        load_session_source(path),
        config=config,
        kind=kind,
        tolerance=tolerance,
        width=width,
        options=options,
    )


# -- the built-in kinds ------------------------------------------------------------------------


class LiveCycles:
    """The live analysis of cycles (repeatability, relative accuracy): O(1) per cycle, equal
    to the batch analysis of the session's readings.

    Its alarms are phase II: judged against control limits frozen after the header's
    ``freeze_after`` points (or fixed by its ``baseline``), through the same
    :class:`~station.analysis.live.LiveMonitor` that
    :func:`~station.analysis.live.replay_live_alarms` runs over a recorded session, so a replay
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


def _repeatability(inputs: KindInputs) -> Judgement:
    analysis = (
        analyze(
            dict(inputs.channels),
            inputs.config,
            excluded_cycles=inputs.excluded_cycles,
            cycles=inputs.cycles,
            times=inputs.times,
        )
        if inputs.channels
        else None
    )
    return Judgement(analysis, None, gauge_block(inputs.header, inputs.width))


def _linearity(inputs: KindInputs) -> Judgement:
    tolerance = inputs.tolerance
    if tolerance is None:
        tolerance = tolerance_from_limits(inputs.config)
    result = analyze_linearity(inputs.profiles(), tolerance=tolerance, config=inputs.config)
    analysis = linearity_summary(result)
    return Judgement(
        analysis, result, (tuple(format_linearity(result, analysis.config, inputs.width)),)
    )


def _relative_accuracy(inputs: KindInputs) -> Judgement:
    placements, errors, pendant = inputs.accuracy_inputs()
    result = analyze_accuracy(
        placements,
        errors,
        inputs.config,
        pendant=pendant,
        excluded_cycles=inputs.excluded_cycles,
    )
    return Judgement(
        result.overall, result, (tuple(format_accuracy(result, inputs.config, inputs.width)),)
    )


register(
    AnalysisKind(
        name="repeatability",
        title="BASIC STATISTICS COMPREHENSIVE REPORT",
        batch=_repeatability,
        live=LiveCycles,
        # The gauge checks that cover its gauges, from the gauge register at the start.
        header_fields=lambda fields: coverage_fields(fields),
    )
)
register(
    AnalysisKind(
        name="linearity",
        title="LINEARITY REPORT",
        batch=_linearity,
        live=LiveStrokes,
        needs=AnalysisNeeds(facet="direction", facet_words="a stroke step (streamed strokes)"),
        json_key="linearity",
        json=linearity_json,
        count=lambda result: f"{len(result.strokes)} strokes",
        export_layout="wide",
    )
)
register(
    AnalysisKind(
        name="relative_accuracy",
        title="RELATIVE ACCURACY REPORT",
        batch=_relative_accuracy,
        live=LiveCycles,
        needs=AnalysisNeeds(
            facet="block",
            facet_words="a repeat block (one per placement)",
            channels=("x", "y", "z"),
        ),
        json_key="accuracy",
        json=accuracy_json,
        count=lambda result: f"{len(result.placements)} placements",
        export_layout="wide",
    )
)


def analyze_session(session: Session) -> Analysis | None:
    """The repeatability ``Analysis`` of a loaded session's readings (cycle numbers included),
    or None when it has no accepted cycle yet."""
    channels, cycles = accepted_readings(session)
    if not channels:
        return None
    times = session.channel_times()
    return analyze(
        channels,
        analysis_config(session.header, session.zeroes),
        excluded_cycles=session.excluded_cycles,
        cycles=cycles,
        times={name: times[name] for name in channels},
    )


# The rest of the report's method (gauge check, per-joint troubleshooting, gain schedule): its
# module registers its kinds with the functions above, so it is imported last.
from station import method_kinds as _method_kinds  # noqa: E402, F401
