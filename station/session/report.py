"""The analysis and report of a session file: the one place that turns a session into them.

``station analyze FILE`` (session files) and the TUI's summary and review both call
:func:`analyze_session_file` (or :func:`report_session` on a session already loaded), so the
verdict, the procedure's own report block and the title are the same wherever they are shown.
The settings come from the session header through the runner's ``analysis_config`` (the one
place that turns a header into an analysis configuration); rejected cycles are left out.

A session is judged as its procedure declares (:func:`session_analysis`): repeatability (the
readings of each channel), linearity (straightness per streamed stroke) or relative accuracy
(the errors at each fixture placement). :func:`judge` is that dispatch, shared with the CSV
tables of ``station analyze``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.procedures import ANALYSIS_KINDS

if TYPE_CHECKING:
    import numpy as np

    from station.analysis.linearity import StrokeProfile
    from station.analysis.summary import Analysis, AnalysisConfig
    from station.session.model import Session

PROCEDURE_REPORTS = ("linearity", "relative_accuracy")
"""Analysis kinds judged by their own analysis (straightness per stroke, accuracy per placement)
rather than by the repeatability analysis of the raw readings."""

AccuracyInputs = tuple["np.ndarray", dict[str, "np.ndarray"], dict[int, tuple[float, ...]]]
"""Placement of each reading, the errors x, y, z, and the pendant coordinates per placement."""


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


@dataclass(frozen=True)
class SessionReport:
    """The analysis of a session (or of a CSV table, through :func:`judge`) and its report.

    ``analysis`` is what the verdict judges: the readings per channel (repeatability), the
    per-stroke straightness of h and v (linearity), or the accuracy readings of x, y, z with
    their 3-D figures (relative accuracy); None for a repeatability session without an accepted
    cycle yet. ``result`` is the procedure's own analysis (None for repeatability), and
    ``sections`` its report blocks (``format_linearity`` / ``format_accuracy`` lines)."""

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
    def count(self) -> str:
        """``7 strokes`` or ``3 placements``: what a procedure's session measured."""
        if self.kind == "linearity":
            return f"{len(self.result.strokes)} strokes"
        if self.kind == "relative_accuracy":
            return f"{len(self.result.placements)} placements"
        raise ValueError(f"a {self.kind} report has no count of strokes or placements")

    def document(self) -> dict[str, Any]:
        """The JSON document of ``station analyze --json``: the analysis, the procedure's own
        figures under ``linearity`` or ``accuracy``, and ``procedure`` (the kind)."""
        from station.analysis.summary import to_json

        if self.analysis is None:
            raise ValueError("a report without an analysis has no JSON document")
        document = to_json(self.analysis)
        if self.kind == "linearity":
            from station.analysis.linearity import linearity_json

            document["linearity"] = linearity_json(self.result)
        elif self.kind == "relative_accuracy":
            from station.analysis.accuracy import accuracy_json

            document["accuracy"] = accuracy_json(self.result)
        document["procedure"] = self.kind
        if self.recorded_alarms is not None:
            from station.session.alarms import recorded_alarms_json

            document["recorded_alarms"] = recorded_alarms_json(self.recorded_alarms)
        return document


def accepted_readings(
    session: Session,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The accepted readings of each channel that has any, and the cycle number of each."""
    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    cycles = session.channel_cycles()
    return channels, {name: cycles[name] for name in channels}


def session_source(session: Session) -> SessionSource:
    """The accepted channels (rejected cycles left out), settings and notes of a session."""
    from station.runner import analysis_config

    notes = [
        f"Session {session.session_id}: robot {session.robot}, operator "
        f"{session.operator or 'not given'}, procedure {session.procedure_id}, "
        f"created {session.created}, {session.status}.",
        f"Last line hash (anchors the session file): {session.last_hash}",
    ]
    if session.torn is not None:
        notes.append(f"Torn tail: {session.torn.message}")
    channels, cycles = accepted_readings(session)
    return SessionSource(
        session=session,
        channels=channels,
        cycles=cycles,
        excluded_cycles=tuple(session.excluded_cycles),
        # The same settings the live analysis of the running session used.
        config=analysis_config(session.header),
        notes=tuple(notes),
        analysis=session_analysis(session),
        times={name: times for name, times in session.channel_times().items() if name in channels},
    )


def load_session_source(path: Path) -> SessionSource:
    """:func:`session_source` of the session file at ``path``, read-only (a torn tail is
    reported in the notes, not repaired)."""
    from station.session.model import load_session

    return session_source(load_session(path, recover=False))


def session_analysis(session: Session) -> str:
    """How to analyse a session: the analysis its header records for its procedure; else that
    of the same procedure file (id and sha256) where this machine has it; else what the
    session holds, as a procedure's default follows its steps (streamed strokes: linearity;
    captures at fixture placements: relative accuracy; otherwise repeatability)."""
    from station.procedures import discover_procedures

    recorded = session.header["procedure"]
    if recorded.get("analysis") in ANALYSIS_KINDS:
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


def session_linearity_profiles(session: Session) -> list[StrokeProfile]:
    """The whole strokes a session streamed (its ``samples`` events with s, h and v)."""
    import numpy as np

    from station.analysis.linearity import profiles_from_stream, profiles_from_table

    batches = [b for b in session.samples if {"s", "h", "v"} <= set(b.channels)]
    # A runner marks the last event of each whole stroke (`end`); a lead-in or a stroke cut
    # short by an interruption has no mark and is left out. Files without marks: every stroke.
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
    if all(b.stroke is not None for b in batches):
        numbers = np.concatenate(
            [np.full(len(a["s"]), b.stroke) for a, b in zip(arrays, batches, strict=True)]
        )
        return profiles_from_table(numbers, joined["s"], {"h": joined["h"], "v": joined["v"]})
    # Batches without stroke numbers are one stream: split it by the scale's travel.
    return profiles_from_stream(joined["s"], {"h": joined["h"], "v": joined["v"]})


def session_accuracy_inputs(session: Session) -> AccuracyInputs:
    """Placements, errors x, y, z and pendant coordinates of a relative-accuracy session."""
    import numpy as np

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


def judge(
    kind: str,
    config: AnalysisConfig,
    *,
    name: str,
    channels: Mapping[str, Any],
    cycles: Mapping[str, Any] | None,
    excluded_cycles: Sequence[int],
    profiles: Callable[[], Sequence[StrokeProfile]],
    accuracy_inputs: Callable[[], AccuracyInputs],
    tolerance: float | None = None,
    width: int = 80,
    notes: Sequence[str] = (),
    times: Mapping[str, Any] | None = None,
) -> SessionReport:
    """Analyse readings as ``kind`` says: repeatability (``channels``), linearity (the strokes
    ``profiles()`` gives, straightness against ``tolerance``, by default the one the limits of h
    and v imply) or relative accuracy (``accuracy_inputs()``). ``name`` (the file's) goes into
    the title; ``width`` is that of the report blocks. A repeatability analysis without
    channels is None."""
    title = f"BASIC STATISTICS COMPREHENSIVE REPORT ON {name}"
    if kind == "linearity":
        from station.analysis.linearity import (
            analyze_linearity,
            linearity_summary,
            tolerance_from_limits,
        )
        from station.analysis.report import format_linearity

        if tolerance is None:
            tolerance = tolerance_from_limits(config)
        result = analyze_linearity(profiles(), tolerance=tolerance, config=config)
        analysis = linearity_summary(result)
        sections = (tuple(format_linearity(result, analysis.config, width)),)
        title = f"LINEARITY REPORT ON {name}"
    elif kind == "relative_accuracy":
        from station.analysis.accuracy import analyze_accuracy
        from station.analysis.report import format_accuracy

        placements, errors, pendant = accuracy_inputs()
        result = analyze_accuracy(
            placements, errors, config, pendant=pendant, excluded_cycles=excluded_cycles
        )
        analysis = result.overall
        sections = (tuple(format_accuracy(result, config, width)),)
        title = f"RELATIVE ACCURACY REPORT ON {name}"
    else:
        from station.analysis.summary import analyze

        result = None
        sections = ()
        analysis = (
            analyze(
                dict(channels),
                config,
                excluded_cycles=excluded_cycles,
                cycles=cycles,
                times=times,
            )
            if channels
            else None
        )
    return SessionReport(
        kind=kind,
        analysis=analysis,
        result=result,
        sections=sections,
        title=title,
        notes=tuple(notes),
        excluded_cycles=tuple(excluded_cycles),
    )


def report_session(
    source: SessionSource,
    *,
    config: AnalysisConfig | None = None,
    kind: str | None = None,
    tolerance: float | None = None,
    width: int = 80,
) -> SessionReport:
    """The analysis and report of a loaded session: as its procedure declares unless ``kind``
    says otherwise, with the settings it recorded unless ``config`` replaces them. Raises
    StationError when a linearity or relative-accuracy session has nothing to analyse yet."""
    from dataclasses import replace as replaced

    from station.session.alarms import format_recorded_alarms, recorded_alarms

    session = source.session
    report = judge(
        kind or source.analysis,
        source.config if config is None else config,
        name=Path(session.path).name,
        channels=source.channels,
        cycles=source.cycles,
        excluded_cycles=source.excluded_cycles,
        profiles=lambda: session_linearity_profiles(session),
        accuracy_inputs=lambda: session_accuracy_inputs(session),
        tolerance=tolerance,
        width=width,
        notes=source.notes,
        times=source.times,
    )
    alarms = recorded_alarms(session)
    return replaced(
        report,
        recorded_alarms=alarms,
        alarm_lines=tuple(format_recorded_alarms(alarms, width)),
    )


def analyze_session_file(
    path: Path,
    *,
    config: AnalysisConfig | None = None,
    kind: str | None = None,
    tolerance: float | None = None,
    width: int = 80,
) -> SessionReport:
    """The analysis and report of the session file at ``path``, as ``station analyze FILE``
    prints it (see :func:`report_session`)."""
    return report_session(
        load_session_source(path), config=config, kind=kind, tolerance=tolerance, width=width
    )


def analyze_session(session: Session) -> Analysis | None:
    """The repeatability ``Analysis`` of a loaded session (readings per channel, cycle numbers
    included), or None when it has no accepted cycle yet."""
    from station.analysis.summary import analyze
    from station.runner import analysis_config

    channels, cycles = accepted_readings(session)
    if not channels:
        return None
    times = session.channel_times()
    return analyze(
        channels,
        analysis_config(session.header),
        excluded_cycles=session.excluded_cycles,
        cycles=cycles,
        times={name: times[name] for name in channels},
    )
