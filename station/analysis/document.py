"""The JSON document of an analysis (``station analyze --json``): every figure of
:class:`~station.analysis.summary.Analysis`, undefined values as null (never NaN or inf)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.rules import Alarm, rule_name

if TYPE_CHECKING:
    from station.analysis.diagnostics import (
        Autocorrelation,
        Drift,
        Normality,
        PercentileCapability,
    )
    from station.analysis.discrimination import Discrimination
    from station.analysis.false_alarms import FalseAlarmChance
    from station.analysis.spatial import Spatial
    from station.analysis.summary import Analysis, ChannelAnalysis
    from station.analysis.verdict import Verdict


def json_number(value: float | None) -> float | None:
    """A JSON number, or None for undefined (never NaN or inf)."""
    if value is None:
        return None
    value = float(value)
    return value if np.isfinite(value) else None


def channel_to_json(channel: ChannelAnalysis) -> dict[str, Any]:
    """One channel of the JSON document."""
    d, cap, chart = channel.descriptive, channel.capability, channel.chart
    verdict = channel.verdict
    return {
        "n": d.n,
        "mean": json_number(d.mean),
        "sd": json_number(d.sd),
        "skewness": json_number(d.skewness),
        "mode": [json_number(m) for m in d.modes],
        "min": json_number(d.min),
        "max": json_number(d.max),
        "range": json_number(d.range),
        "nominal": json_number(channel.nominal),
        # Absent when the readings are cycles 1 to n in order (a million-row CSV would
        # otherwise print a million numbers that say nothing).
        **({} if _numbered_in_order(channel.cycles) else {"cycles": list(channel.cycles)}),
        "capability": {
            "lsl": json_number(cap.lsl),
            "usl": json_number(cap.usl),
            "cp": json_number(cap.cp),
            "cpu": json_number(cap.cpu),
            "cpl": json_number(cap.cpl),
            "cpk": json_number(cap.cpk),
            "cpk_lower": json_number(cap.cpk_lower),
            "cpk_upper": json_number(cap.cpk_upper),
            "cp_ci": _json_pair(cap.cp_ci),
            "cpk_ci": _json_pair(cap.cpk_ci),
            "confidence": cap.confidence,
            "cp_within": json_number(cap.cp_within),
            "cpk_within": json_number(cap.cpk_within),
            "sigma": json_number(cap.sigma),
            "sigma_within": json_number(cap.sigma_within),
            "threshold": json_number(cap.threshold),
            "capable": cap.capable,
            "above_usl": cap.above_usl,
            "below_lsl": cap.below_lsl,
            "message": cap.message,
            "provisional": verdict.provisional if verdict else False,
            "min_n": verdict.min_n if verdict else None,
            "verdict": verdict.label if verdict else None,
            "verdict_text": verdict.text if verdict else None,
            "decision": _decision_json(verdict),
            "method": channel.capability_method,
            "percentile": _percentile_json(channel.percentile),
        },
        "out_of_spec": _out_of_spec_json(channel),
        "budget": _budget_json(channel),
        "normality": _normality_json(channel.normality),
        "autocorrelation": _autocorrelation_json(channel.autocorrelation),
        "drift": _drift_json(channel.drift),
        "phase_two": None
        if channel.frozen is None
        else {
            "center": json_number(channel.frozen.center),
            "ucl": json_number(channel.frozen.ucl),
            "lcl": json_number(channel.frozen.lcl),
            "source": channel.frozen.source,
        },
        "live_alarms": [_alarm_json(a, True) for a in channel.live_alarms],
        "chart": {
            "type": chart.type,
            "subgroup": chart.subgroup,
            "center": json_number(chart.center),
            "ucl": json_number(chart.ucl),
            "lcl": json_number(chart.lcl),
            "sigma_within": json_number(chart.sigma_within),
            "dispersion": {
                "center": json_number(chart.dispersion.center),
                "ucl": json_number(chart.dispersion.ucl),
                "lcl": json_number(chart.dispersion.lcl),
            },
            "message": chart.message,
            "limit_floor": json_number(chart.limit_floor),
            "floored": chart.floored,
            "false_alarm_chance": _false_alarm_json(channel.false_alarm),
        },
        "discrimination": _discrimination_json(channel.discrimination),
        "alarms": [_alarm_json(a, channel.alarm_is_live(a)) for a in channel.alarms],
    }


def _false_alarm_json(found: FalseAlarmChance | None) -> dict[str, Any] | None:
    """The rule set's simulated false-alarm chance on a chart of this length."""
    if found is None:
        return None
    return {
        "rule_set": found.rule_set,
        "points": found.points,
        "chance": found.chance,
        "standard_error": found.standard_error,
        "at_least": found.at_least,
        "sessions": found.sessions,
        "simulated_points": found.simulated_points,
        "seed": found.seed,
        "text": found.text(),
    }


def _discrimination_json(found: Discrimination | None) -> dict[str, Any] | None:
    """Whether the gauge step resolves the spread (null without a resolution)."""
    if found is None:
        return None
    return {
        "resolution": found.resolution,
        "distinct": found.distinct,
        "sigma_steps": json_number(found.sigma_steps),
        "possible_ranges": found.possible_ranges,
        "adequate": found.adequate,
    }


def _json_pair(pair: tuple[float, float] | None) -> list[float | None] | None:
    return None if pair is None else [json_number(pair[0]), json_number(pair[1])]


def _decision_json(verdict: Verdict | None) -> dict[str, Any] | None:
    """The verdict as the decision rule gave it: ``rule`` names the rule (one-sided Bissell
    bounds against the threshold), ``verdict`` its word, ``readings_needed`` the count that would
    settle an INCONCLUSIVE one at the observed Cpk. ``capable`` beside it is the report's rule."""
    if verdict is None:
        return None
    return {
        "rule": verdict.rule,
        "verdict": verdict.word,
        "confidence": verdict.confidence,
        "readings_needed": verdict.readings_needed,
    }


def _alarm_json(alarm: Alarm, live: bool) -> dict[str, Any]:
    return {
        "rule": alarm.rule,
        "rule_name": rule_name(alarm.rule),
        "points": list(alarm.points),
        "cycles": list(alarm.cycles),
        "text": alarm.text,
        "live": live,
    }


def _percentile_json(result: PercentileCapability | None) -> dict[str, Any] | None:
    if result is None:
        return None
    return {
        "method": result.method,
        "q_0_135": json_number(result.q_low),
        "median": json_number(result.median),
        "q_99_865": json_number(result.q_high),
        "pp": json_number(result.pp),
        "ppu": json_number(result.ppu),
        "ppl": json_number(result.ppl),
        "ppk": json_number(result.ppk),
        "capable": result.capable,
    }


def _budget_json(channel: ChannelAnalysis) -> dict[str, Any] | None:
    """The channel's measurement budget (u_c, U, k, contributions) and, with limits, its
    readings judged by the decision rule with that U (null when no budget is known)."""
    if channel.budget is None:
        return None
    decisions = channel.reading_decisions
    return {
        **channel.budget.as_json(),
        "readings": None if decisions is None else decisions.as_json(),
    }


def _out_of_spec_json(channel: ChannelAnalysis) -> dict[str, Any]:
    found = channel.out_of_spec
    if found is None:
        return {"below": 0, "above": 0, "cycles": []}
    return {
        "below": found.below,
        "above": found.above,
        "cycles": list(found.cycles),
        "cycles_below": list(found.cycles_below),
        "cycles_above": list(found.cycles_above),
    }


def _normality_json(result: Normality | None) -> dict[str, Any] | None:
    if result is None:
        return None
    return {
        "test": result.test,
        "statistic": json_number(result.statistic),
        "p": json_number(result.p_value),
        "alpha": result.alpha,
        "rejected": result.rejected,
        "ties": result.ties,
        "message": result.message,
    }


def _autocorrelation_json(result: Autocorrelation | None) -> dict[str, Any] | None:
    if result is None:
        return None
    return {
        "lag1": json_number(result.r1),
        "z": json_number(result.z),
        "p": json_number(result.p_value),
        "alpha": result.alpha,
        "significant": result.significant,
        "sigma_ratio": json_number(result.sigma_ratio),
        "message": result.message,
    }


def _drift_json(result: Drift | None) -> dict[str, Any] | None:
    if result is None:
        return None
    found = result.trend
    ewma = result.ewma
    return {
        "trend": {
            "basis": found.basis,
            "span_cycles": found.span,
            "per_span": json_number(found.per_span),
            "low": json_number(found.low),
            "high": json_number(found.high),
            "p": json_number(found.p_value),
            "significant": found.significant,
            "cycle_seconds": json_number(found.cycle_seconds),
        },
        "ewma": None
        if ewma is None
        else {
            "lambda": ewma.lam,
            "width": ewma.width,
            "center": json_number(ewma.center),
            "sigma": json_number(ewma.sigma),
            "signal_cycles": list(ewma.signal_cycles),
        },
        "message": result.message,
    }


def spatial_to_json(spatial: Spatial) -> dict[str, Any]:
    """The 3-D figures of the JSON document."""
    return {
        "n": spatial.n,
        "nominal": {axis: json_number(v) for axis, v in spatial.nominal.items()},
        "offset": {axis: json_number(v) for axis, v in spatial.offset.items()},
        "total_offset": json_number(spatial.total_offset),
        "ap": {key: json_number(v) for key, v in spatial.ap.items()},
        "rp": json_number(spatial.rp),
        "l_mean": json_number(spatial.l_mean),
        "l_sd": json_number(spatial.l_sd),
        "message": spatial.message,
    }


def to_json(analysis: Analysis) -> dict[str, Any]:
    """The JSON document of `station analyze --json` (undefined values are None → null).

    ``spatial`` is always present: an object when channels x, y, z exist, else null.
    """
    config = analysis.config
    return {
        "unit": config.unit,
        "resolution": json_number(config.resolution),
        "subgroup": config.subgroup,
        "rules": config.rule_set,
        "threshold": json_number(config.threshold),
        "excluded_cycles": list(analysis.excluded_cycles),
        "min_n": config.min_n,
        "freeze_after": config.freeze_after,
        "baseline": None if config.baseline is None else config.baseline.source or "baseline",
        "channels": {name: channel_to_json(c) for name, c in analysis.channels.items()},
        "spatial": None if analysis.spatial is None else spatial_to_json(analysis.spatial),
        "hints": list(analysis.hints),
    }


def _numbered_in_order(cycles: Any) -> bool:
    """True when ``cycles`` is exactly 1, 2, ..., n."""
    numbers = np.asarray(cycles)
    return bool(numbers.size == 0 or np.array_equal(numbers, np.arange(1, numbers.size + 1)))
