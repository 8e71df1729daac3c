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

from station.verdicts.live import CyclesSoFar, LiveCycles, LiveStrokes, StrokesSoFar
from station.verdicts.registry import (
    AccuracyInputs,
    AnalysisKind,
    Judgement,
    KindInputs,
    LiveCopy,
    LiveVerdict,
    SessionReport,
    judge,
    kind_of,
    kinds,
    register,
)
from station.verdicts.sessions import (
    SessionSource,
    accepted_readings,
    analyze_session,
    analyze_session_file,
    load_session_source,
    marked_profiles,
    report_session,
    session_accuracy_inputs,
    session_analysis,
    session_inputs,
    session_source,
    session_stroke_profiles,
)

__all__ = [
    "AccuracyInputs",
    "AnalysisKind",
    "CyclesSoFar",
    "Judgement",
    "KindInputs",
    "LiveCopy",
    "LiveCycles",
    "LiveStrokes",
    "LiveVerdict",
    "SessionReport",
    "SessionSource",
    "StrokesSoFar",
    "accepted_readings",
    "analyze_session",
    "analyze_session_file",
    "judge",
    "kind_of",
    "kinds",
    "load_session_source",
    "marked_profiles",
    "register",
    "report_session",
    "session_accuracy_inputs",
    "session_analysis",
    "session_inputs",
    "session_source",
    "session_stroke_profiles",
]

# The built-in kinds, then the rest of the report's method (gauge check, per-joint
# troubleshooting, gain schedule): their modules register their kinds with the registry above
# (through this package's names), so they are imported last.
# isort: off
from station.verdicts import builtin as _builtin  # noqa: E402, F401
from station import method_kinds as _method_kinds  # noqa: E402, F401
# isort: on
