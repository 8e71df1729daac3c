"""The one adapter between the calibration record and the analysis of a session file.

Reports, history, comparison and baselines read a session's analysis only through
:func:`analyse_session`. It calls the domain function that turns a session into its analysis and
JSON document by its method (:func:`station.methods.report_session`); if that changes, only this
function changes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.methods import report_session, session_method, session_source
from station.session.model import load_session

if TYPE_CHECKING:
    from station.methods import SessionReport
    from station.session.model import Session


@dataclass(frozen=True)
class AnalysedSession:
    """A session file with its analysis.

    ``report`` is the domain's analysis and report blocks, ``document`` its JSON document
    (``station analyze --json``); both None when the session has nothing to analyse yet, with
    the sentence in ``problem``. ``kind`` is the name of its method (repeatability,
    linearity, ...).
    """

    path: Path
    session: Session
    kind: str
    report: SessionReport | None
    document: dict[str, Any] | None
    problem: str | None = None


def analyse_session(path: str | Path) -> AnalysedSession:
    """Load the session file at ``path`` read-only (a torn tail is noted, not repaired) and
    analyse it as its procedure declares, with the settings it recorded.

    Raises StationError when the file is not an intact session file; a session with nothing to
    analyse yet is returned with ``problem`` set instead.
    """
    return analyse_loaded(load_session(Path(path), recover=False))


def analyse_loaded(session: Session) -> AnalysedSession:
    """:func:`analyse_session` of a session already loaded (a caller that reads its header
    first, as the history does, loads the file once)."""
    path = session.path
    source = session_source(session)
    method = session_method(session)
    try:
        report = report_session(source, method=method)
    except StationError as error:
        return AnalysedSession(path, session, method, None, None, error.message)
    if report.empty:
        return AnalysedSession(
            path, session, method, None, None, "the session has no accepted readings yet"
        )
    return AnalysedSession(
        path=path, session=session, kind=report.kind, report=report, document=report.document()
    )
