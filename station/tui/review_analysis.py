"""The analysis of a saved session, as ``station analyze FILE`` and the live runner compute it.

Linearity and relative-accuracy sessions get their own analysis (:func:`procedure_report`),
made by the same calls ``station analyze FILE`` makes. The settings come from the session
header through the runner's ``analysis_config`` (the one place that turns a header into an
analysis configuration); rejected cycles are left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


def analyze_session(session: Any) -> Any:
    """The ``Analysis`` of a loaded session (``station.session.model.Session``), or None when
    it has no accepted cycle yet."""
    from station.analysis.summary import analyze
    from station.runner import analysis_config

    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    if not channels:
        return None
    return analyze(
        channels, analysis_config(session.header), excluded_cycles=session.excluded_cycles
    )


PROCEDURE_REPORTS = ("linearity", "relative_accuracy")
"""Procedures judged by their own analysis (straightness per stroke, accuracy per placement)
rather than by the repeatability analysis of the raw readings."""


@dataclass(frozen=True)
class ProcedureReport:
    """A linearity or relative-accuracy session's analysis, as ``station analyze FILE`` makes
    it: ``analysis`` is what the verdict judges (the per-stroke straightness of h and v, or the
    accuracy readings of x, y, z with their 3-D figures), ``result`` the procedure's own
    analysis, ``lines`` its report block (``format_linearity`` / ``format_accuracy``)."""

    kind: str
    analysis: Any
    result: Any
    lines: tuple[str, ...]
    title: str

    @property
    def count(self) -> str:
        """``7 strokes`` or ``3 placements``: what the session measured."""
        if self.kind == "linearity":
            return f"{len(self.result.strokes)} strokes"
        return f"{len(self.result.placements)} placements"


def procedure_report(path: Path, width: int = 80) -> ProcedureReport | None:
    """The procedure's own analysis of the session file at ``path`` (the same calls as
    ``station analyze FILE``, with the settings the file recorded), or None for a repeatability
    session. Raises StationError when the file has nothing to analyse yet."""
    from station.commands.analyze import accuracy_inputs, linearity_profiles, load_session_source

    source = load_session_source(path)
    kind = source.analysis  # the analysis the session's procedure declares
    if kind not in PROCEDURE_REPORTS:
        return None
    config = source.config
    if kind == "linearity":
        from station.analysis.linearity import (
            analyze_linearity,
            linearity_summary,
            tolerance_from_limits,
        )
        from station.analysis.report import format_linearity

        result = analyze_linearity(
            linearity_profiles(source, path), tolerance=tolerance_from_limits(config), config=config
        )
        analysis = linearity_summary(result)
        lines = format_linearity(result, analysis.config, width)
        title = f"LINEARITY REPORT ON {path.name}"
    else:
        from station.analysis.accuracy import analyze_accuracy
        from station.analysis.report import format_accuracy

        placements, errors, pendant = accuracy_inputs(source)
        result = analyze_accuracy(
            placements, errors, config, pendant=pendant, excluded_cycles=source.excluded_cycles
        )
        analysis = result.overall
        lines = format_accuracy(result, config, width)
        title = f"RELATIVE ACCURACY REPORT ON {path.name}"
    return ProcedureReport(str(kind), analysis, result, tuple(lines), title)
