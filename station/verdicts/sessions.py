"""Sessions as the analysis kinds read them: a session file's accepted readings, settings and
notes, its streamed strokes and fixture placements, and its report through the registry."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.strokes import (
    StrokeProfile,
    profiles_from_stream,
    profiles_from_table,
    trim_dwell,
)
from station.analysis.summary import Analysis, AnalysisConfig, analyze
from station.errors import StationError
from station.procedures import discover_procedures
from station.session.alarms import format_recorded_alarms, recorded_alarms
from station.session.header import analysis_config
from station.session.model import Session, load_session
from station.text import zero_taken
from station.verdicts.registry import (
    AccuracyInputs,
    KindInputs,
    SessionReport,
    judge,
    kinds,
)


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
    if recorded.get("analysis") in kinds():
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
