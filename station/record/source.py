"""The one adapter between the calibration record and the analysis of a session file.

Reports, history, comparison and baselines read a session's analysis only through
:func:`analyse_session`. It calls the domain function that turns a session into its analysis and
JSON document through the analysis-kind registry (:func:`station.verdicts.report_session`); if
that changes, only this function changes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.session.model import load_session
from station.verdicts import report_session, session_source, session_stroke_profiles

if TYPE_CHECKING:
    from station.analysis.strokes import StrokeProfile
    from station.session.model import Session
    from station.verdicts import SessionReport


@dataclass(frozen=True)
class AnalysedSession:
    """A session file with its analysis.

    ``report`` is the domain's analysis and report blocks, ``document`` its JSON document
    (``station analyze --json``); both None when the session has nothing to analyse yet, with
    the sentence in ``problem``. ``kind`` is the analysis kind (repeatability, linearity,
    relative_accuracy). ``profiles`` are the streamed strokes of a linearity session (for its
    charts), else empty.
    """

    path: Path
    session: Session
    kind: str
    report: SessionReport | None
    document: dict[str, Any] | None
    problem: str | None = None
    profiles: tuple[StrokeProfile, ...] = ()


def analyse_session(path: str | Path) -> AnalysedSession:
    """Load the session file at ``path`` read-only (a torn tail is noted, not repaired) and
    analyse it as its procedure declares, with the settings it recorded.

    Raises StationError when the file is not an intact session file; a session with nothing to
    analyse yet is returned with ``problem`` set instead.
    """
    path = Path(path)
    session = load_session(path, recover=False)
    source = session_source(session)
    try:
        report = report_session(source)
    except StationError as error:
        return AnalysedSession(path, session, source.analysis, None, None, error.message)
    if report.empty:
        return AnalysedSession(
            path, session, source.analysis, None, None, "the session has no accepted readings yet"
        )
    profiles: tuple[StrokeProfile, ...] = ()
    if report.kind == "linearity":
        profiles = tuple(session_stroke_profiles(session))
    return AnalysedSession(
        path=path,
        session=session,
        kind=report.kind,
        report=report,
        document=report.document(),
        profiles=profiles,
    )
