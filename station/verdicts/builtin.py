"""The built-in analysis kinds: ``repeatability`` (report §2.6), ``linearity`` (§2.9) and
``relative_accuracy`` (§2.8), registered when the package loads."""

from __future__ import annotations

from station.analysis.accuracy import accuracy_json, analyze_accuracy
from station.analysis.linearity import (
    analyze_linearity,
    linearity_json,
    linearity_summary,
    tolerance_from_limits,
)
from station.analysis.report import format_accuracy, format_linearity
from station.analysis.summary import analyze
from station.procedures import AnalysisNeeds
from station.session.gauge_register import coverage_fields, gauge_block
from station.verdicts.live import LiveCycles, LiveStrokes
from station.verdicts.registry import AnalysisKind, Judgement, KindInputs, register


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
