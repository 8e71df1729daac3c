"""A session's (or a CSV table's) judgement by its method, and its report: :func:`judge`,
:func:`report_session`, :func:`analyze_session_file` and the :class:`SessionReport` they give.

``station analyze``, the ``station capture`` summary, the TUI summary, the record and every
export come here; the method is the one a session's procedure declares
(:func:`~station.methods.catalog.session_method`) unless the caller names another.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from station.analysis.document import to_json
from station.analysis.report import format_report
from station.analysis.summary import Analysis, AnalysisConfig
from station.methods.catalog import method_of, session_method
from station.methods.contract import Method, MethodInputs, MethodVerdict
from station.methods.sessions import SessionSource, load_session_source, session_inputs
from station.session.alarms import format_recorded_alarms, recorded_alarms, recorded_alarms_json


@dataclass(frozen=True)
class SessionReport:
    """The judgement of a session (or of a CSV table) and its report.

    ``analysis`` is what the capability verdict judges (None when the method judges none);
    ``result`` is the method's own analysis (None for repeatability), ``sections`` its report
    blocks and ``verdict`` its own verdict, where it has one."""

    method: Method
    analysis: Analysis | None
    result: Any
    sections: tuple[tuple[str, ...], ...]
    title: str
    notes: tuple[str, ...] = ()
    excluded_cycles: tuple[int, ...] = ()
    verdict: MethodVerdict | None = None
    inputs: MethodInputs | None = None
    """What the method judged (for its charts)."""
    recorded_alarms: tuple[Any, ...] | None = None
    """A session's alarm events with their acknowledgements (``station.session.alarms``);
    None for a CSV table."""
    alarm_lines: tuple[str, ...] = ()
    """The report block of those alarms and their causes (empty for a CSV table): print it
    after ``sections``."""

    @property
    def kind(self) -> str:
        """The method's name (what the session's procedure declares)."""
        return self.method.name

    @property
    def lines(self) -> tuple[str, ...]:
        """The report blocks as one run of lines."""
        return tuple(line for section in self.sections for line in section)

    @property
    def count(self) -> str | None:
        """What the session measured when the method counts something else than cycles
        (``7 strokes``, ``3 placements``); None for a method that counts cycles."""
        return None if self.result is None else self.method.count(self.result)

    def document(self) -> dict[str, Any]:
        """The JSON document of ``station analyze --json``: the analysis, the method's own
        figures under its key (``linearity``, ``accuracy``...; at the top level for a method
        without a key), and ``procedure`` (the method). A method that judges no readings by
        capability (a gain schedule, a gauge linearity study) has only its own figures."""
        own = self.method.json(self.result) if self.result is not None else {}
        if self.analysis is None and not own:
            raise ValueError("a report without an analysis has no JSON document")
        document = {} if self.analysis is None else to_json(self.analysis)
        key = self.method.json_key
        if own and key:
            document[key] = own
        elif own:
            document.update(own)
        document["procedure"] = self.kind
        if self.recorded_alarms is not None:
            document["recorded_alarms"] = recorded_alarms_json(self.recorded_alarms)
        return document

    @property
    def empty(self) -> bool:
        """True when there is nothing to report: no analysis and no result of the method's."""
        return self.analysis is None and self.result is None

    def text(self, notes: Sequence[str] | None = None, *, alarms: bool = True) -> str:
        """The text report as ``station analyze FILE`` prints it (``notes`` replace the
        report's own); a method that judges no readings prints its title, notes and blocks."""
        shown = list(self.notes if notes is None else notes)
        sections = [list(section) for section in self.sections]
        if alarms and self.alarm_lines:
            sections.append(list(self.alarm_lines))
        if self.analysis is not None:
            return format_report(self.analysis, title=self.title, notes=shown, sections=sections)
        return "\n".join([self.title, *shown, *("\n" + "\n".join(s) for s in sections)]) + "\n"


def judge(
    method: str | Method, inputs: MethodInputs, *, name: str, notes: Sequence[str] = ()
) -> SessionReport:
    """Analyse ``inputs`` as ``method`` (or the method of that name) says; ``name`` (the
    file's) goes into the title."""
    chosen = method_of(method) if isinstance(method, str) else method
    judgement = chosen.batch(inputs)
    return SessionReport(
        method=chosen,
        analysis=judgement.analysis,
        result=judgement.result,
        sections=judgement.sections,
        title=f"{chosen.title} ON {name}",
        notes=tuple(notes),
        excluded_cycles=tuple(inputs.excluded_cycles),
        verdict=judgement.verdict,
        inputs=inputs,
    )


def report_session(
    source: SessionSource,
    *,
    config: AnalysisConfig | None = None,
    method: str | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> SessionReport:
    """The analysis and report of a loaded session: by the method its procedure declares
    unless ``method`` names another, with the settings it recorded unless ``config`` replaces
    them. Raises StationError when the session has nothing to analyse yet."""
    inputs = session_inputs(source, config=config, width=width, options=options)
    report = judge(
        method or session_method(source.session),
        inputs,
        name=Path(source.session.path).name,
        notes=source.notes,
    )
    alarms = recorded_alarms(source.session)
    return replace(
        report, recorded_alarms=alarms, alarm_lines=tuple(format_recorded_alarms(alarms, width))
    )


def analyze_session_file(
    path: Path,
    *,
    config: AnalysisConfig | None = None,
    method: str | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> SessionReport:
    """The analysis and report of the session file at ``path``, as ``station analyze FILE``
    prints it (see :func:`report_session`)."""
    return report_session(
        load_session_source(path), config=config, method=method, width=width, options=options
    )
