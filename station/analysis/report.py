"""The plain-text report, in the manner of the report's "BASIC STATISTICS COMPREHENSIVE REPORT".

Per channel: maximum, average, minimum, the spec limits and nominal, sigma, range, mode, the
pieces above and below spec, the numbered readings in three PIECE/MEASUREMENT columns, a text
histogram with the limits marked, the control chart's limits and alarms, the capability indices
(overall sigma as the report defines them, then the within-sigma ones and the lower confidence
bound on Cpk, each named), and the verdict as a word. Then the 3-D figures and the hints.

Plain text without colour codes so it can be filed and printed; no line is longer than
``width``. The pieces (:func:`format_channel`, :func:`format_histogram`, :func:`format_readings`,
:func:`verdict_word`) are public so the TUI can show them too.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING

from station.analysis.capability import Capability, SpecLimits
from station.analysis.descriptive import Histogram
from station.analysis.diagnostics import PERCENTILE_MIN_N, p_phrase
from station.analysis.rules import number_list, rule_name
from station.analysis.spatial import Spatial
from station.analysis.summary import Analysis, AnalysisConfig, ChannelAnalysis
from station.analysis.uncertainty import BudgetResult, ReadingDecisions, Rule
from station.analysis.verdict import Verdict, confidence_text, judge_verdict
from station.text import format_figure, format_spread, judged_count

if TYPE_CHECKING:
    from station.analysis.accuracy import AccuracyAnalysis
    from station.analysis.linearity import LinearityAnalysis


def index(value: float | None) -> str:
    """A capability index to two decimals (the report's precision), or "undefined"."""
    return "undefined" if value is None else f"{value:.2f}"


def _pairs(items: Sequence[tuple[str, str]], width: int) -> list[str]:
    """Lay "LABEL: value" items out in rows of three like the report's header block, each
    column as wide as its widest cell; one per line when three do not fit."""
    cells = [f"{label}: {value}" for label, value in items]
    rows = [cells[start : start + 3] for start in range(0, len(cells), 3)]
    widths = [max(len(row[j]) for row in rows if j < len(row)) + 3 for j in range(3)]
    if sum(widths) - 3 > width:
        return cells
    return ["".join(cell.ljust(widths[j]) for j, cell in enumerate(row)).rstrip() for row in rows]


def _wrap(text: str, width: int, indent: str = "") -> list[str]:
    return textwrap.wrap(
        text, width=width, initial_indent=indent, subsequent_indent=indent + "  "
    ) or [indent.rstrip()]


def format_readings(
    readings: Sequence[float],
    resolution: float | None,
    width: int = 80,
    cycles: Sequence[int] | None = None,
) -> list[str]:
    """The readings in three PIECE / MEASUREMENT column pairs, down then across; a piece is
    its cycle number (``cycles``; 1, 2, 3 ... when None), so a rejected cycle leaves a gap."""
    n = len(readings)
    pieces = list(range(1, n + 1)) if cycles is None else list(cycles)
    rows = math.ceil(n / 3)
    piece_width = max(5, max((len(str(p)) for p in pieces), default=1))
    measure_width = max(11, max((len(format_figure(v, resolution)) for v in readings), default=0))
    pair = piece_width + 2 + measure_width
    gap = max(2, min(6, (width - 3 * pair) // 2))
    header = gap * " "
    head = header.join(f"{'PIECE':>{piece_width}}  {'MEASUREMENT':>{measure_width}}" for _ in "abc")
    lines = [head]
    for row in range(rows):
        cells = []
        for column in range(3):
            i = column * rows + row
            if i < n:
                shown = format_figure(readings[i], resolution)
                cells.append(f"{pieces[i]:>{piece_width}}  {shown:>{measure_width}}")
        lines.append(header.join(cells))
    return lines


def format_histogram(
    hist: Histogram,
    limits: SpecLimits | None,
    resolution: float | None,
    width: int = 80,
    nominal: float | None = None,
) -> list[str]:
    """One row per bin: its centre, a bar of '#' and the count; LSL, NOM and USL marked."""
    counts = list(hist.counts)
    if not counts:
        return ["(no readings)"]
    centres = [(lo + hi) / 2 for lo, hi in zip(hist.edges[:-1], hist.edges[1:], strict=True)]
    label_width = max(len(format_figure(c, resolution)) for c in centres)
    count_width = len(str(max(counts)))
    marks: dict[int, list[str]] = {}
    last = len(counts) - 1
    for name, value in (
        ("LSL", None if limits is None else limits.lsl),
        ("NOM", nominal),
        ("USL", None if limits is None else limits.usl),
    ):
        if value is None:
            continue
        for i, (lo, hi) in enumerate(zip(hist.edges[:-1], hist.edges[1:], strict=True)):
            if lo <= value < hi or (i == last and value == hi):
                marks.setdefault(i, []).append(name)
                break
    mark_width = max((len(" <" + ",".join(m)) for m in marks.values()), default=0)
    bar_room = max(5, width - label_width - count_width - mark_width - 6)
    top = max(counts)
    lines = []
    for i, (centre, count) in enumerate(zip(centres, counts, strict=True)):
        bar = "#" * (0 if top == 0 else math.ceil(count * bar_room / top) if count else 0)
        mark = f" <{','.join(marks[i])}" if i in marks else ""
        lines.append(
            f"{format_figure(centre, resolution):>{label_width}} |{bar.ljust(bar_room)} "
            f"{count:>{count_width}}{mark}".rstrip()
        )
    if hist.below or hist.above:
        lines.append(f"out of spec: {hist.below} below LSL, {hist.above} above USL")
    return lines


WITHIN_SIGMA_SOURCE = {"I-MR": "MR-bar/d2", "Xbar-R": "R-bar/d2", "Xbar-S": "S-bar/c4"}


def _interval(pair: tuple[float, float] | None) -> str:
    return "-" if pair is None else f"{index(pair[0])} to {index(pair[1])}"


def _capability_lines(
    cap: Capability,
    chart_type: str,
    resolution: float | None,
    width: int,
    verdict: Verdict | None = None,
) -> list[str]:
    within_source = WITHIN_SIGMA_SOURCE.get(chart_type, "within subgroups")
    level = confidence_text(cap.confidence)
    lines = [
        f"CAPABILITY (overall sigma {format_spread(cap.sigma, resolution)}: report §2.7.3's "
        "Cp/Cpk, ISO 22514-2's Pp/Ppk)",
        f"  Cp {index(cap.cp)}   Cpu {index(cap.cpu)}   Cpl {index(cap.cpl)}   "
        f"Cpk {index(cap.cpk) if verdict is None or verdict.cpk is None else verdict.cpk_text}",
        f"  Cp (Pp)   {level} interval {_interval(cap.cp_ci)} (chi-square)",
        f"  Cpk (Ppk) {level} interval {_interval(cap.cpk_ci)}, one-sided bounds "
        f"{index(cap.cpk_lower)} and {index(cap.cpk_upper)} (Bissell)",
        f"  Within sigma {format_spread(cap.sigma_within, resolution)} ({within_source}):",
        f"    Cp within {index(cap.cp_within)}   Cpk within {index(cap.cpk_within)}",
    ]
    lines = [wrapped for line in lines for wrapped in _wrap(line, width)]
    judged = verdict if verdict is not None else judge_verdict(cap, 0)
    line = f"VERDICT: {judged.text}"
    if cap.capable is not None and cap.message:
        line += f"; {cap.message}"
    lines.extend(_wrap(line, width))
    return lines


def budget_rows(result: BudgetResult, resolution: float | None) -> list[tuple[str, ...]]:
    """The budget's table rows, figures in the one number format: input, u, |c|·u, dof,
    share of u_c². The filed report and the text report both lay these out."""
    return [
        (
            line.name,
            format_spread(line.u, resolution),
            format_spread(line.ui, resolution),
            "inf" if math.isinf(line.dof) else f"{line.dof:.0f}",
            f"{100 * line.share:.1f}%",
        )
        for line in result.lines
    ]


def budget_summary(result: BudgetResult, resolution: float | None, unit: str = "") -> str:
    """``u_c 0.00004 in, U = 0.00008 in at k = 2 (nu_eff inf)``: one decimal beyond the
    gauge step like every figure (a u of r/√12 reads 0.00003 at a 0.0001 in step)."""
    unit_text = f" {unit}" if unit else ""
    step = resolution
    nu = "inf" if math.isinf(result.nu_eff) else f"{result.nu_eff:.1f}"
    return (
        f"u_c {format_spread(result.u_c, step)}{unit_text}, "
        f"U = {format_spread(result.U, step)}{unit_text} at k = {result.k:g} (nu_eff {nu})"
    )


def budget_line(
    result: BudgetResult,
    decisions: ReadingDecisions | None,
    resolution: float | None,
    unit: str = "",
) -> str:
    """The budget in one short line, for a screen: ``measurement U 0.00006 in, k = 2: 29 PASS
    0 FAIL 1 INDETERMINATE`` (the rule named only when it is not the default guarded one)."""
    unit_text = f" {unit}" if unit else ""
    expanded = format_spread(result.U, resolution)
    text = f"measurement U {expanded}{unit_text}, k = {result.k:g}"
    if decisions is not None:
        text += (
            f": {decisions.passed} PASS {decisions.failed} FAIL "
            f"{decisions.indeterminate} INDETERMINATE"
        )
        if decisions.rule is not Rule.GUARDED:
            text += f" ({decisions.rule.value})"
    return text


def decisions_text(decisions: ReadingDecisions, resolution: float | None, unit: str = "") -> str:
    """The readings as the decision rule judged them with the budget's U, in a sentence."""
    unit_text = f" {unit}" if unit else ""
    if decisions.rule is Rule.GUARDED:
        rule = (
            f"guarded acceptance (ISO 14253-1: limits shrunk by U = "
            f"{format_spread(decisions.U, resolution)}{unit_text} to pass, widened by U "
            "to fail)"
        )
    else:
        rule = "simple acceptance (no guard band)"
    text = (
        f"Readings judged by {rule}: {decisions.passed} PASS, {decisions.failed} FAIL, "
        f"{decisions.indeterminate} INDETERMINATE"
    )
    if decisions.cycles_failed:
        text += f"; FAIL at cycles {number_list(decisions.cycles_failed)}"
    if decisions.cycles_indeterminate:
        text += (
            f"; INDETERMINATE (neither in nor out is proven) at cycles "
            f"{number_list(decisions.cycles_indeterminate)}"
        )
    if decisions.zone is None:
        text += "; the guard bands leave no acceptance zone: no reading can pass with this U"
    return text + "."


def format_budget(
    channel: ChannelAnalysis, resolution: float | None, unit: str = "", width: int = 80
) -> list[str]:
    """The channel's MEASUREMENT BUDGET block: the table, u_c and U at k, and the readings'
    decisions with that U; a line saying no budget is known when none is."""
    result = channel.budget
    if result is None:
        return _wrap(
            "MEASUREMENT BUDGET: none known (no gauge step, certificate, Type-1 check or zero "
            "recorded): the decisions below carry no measurement uncertainty.",
            width,
        )
    lines = ["MEASUREMENT BUDGET (GUM; one reading)"]
    lines += [
        f"  {row}"
        for row in _table(
            ("input", "u", "|c|*u", "dof", "share"), budget_rows(result, resolution), width - 2
        )
    ]
    lines += _wrap(budget_summary(result, resolution, unit), width, "  ")
    if channel.reading_decisions is not None:
        lines += _wrap(decisions_text(channel.reading_decisions, resolution, unit), width, "  ")
    return lines


def format_diagnostics(
    channel: ChannelAnalysis, resolution: float | None, width: int = 80
) -> list[str]:
    """Normality (and the percentile indices when it is rejected), lag-1 autocorrelation with
    the within- and overall-sigma indices side by side, and drift (trend and EWMA)."""
    lines: list[str] = []
    normal = channel.normality
    if normal is not None:
        if normal.rejected is None:
            lines += _wrap(f"NORMALITY ({normal.test}): not tested ({normal.message})", width)
        else:
            outcome = "rejected" if normal.rejected else "not rejected"
            lines += _wrap(
                f"NORMALITY ({normal.test}): statistic {normal.statistic:.4f}, "
                f"{p_phrase(normal.p_value or 0.0)}: normality {outcome} at "
                f"{normal.alpha:g}",
                width,
            )
            if normal.ties:
                lines += _wrap(f"  Note: {normal.ties}", width)
    percentile = channel.percentile
    if (
        percentile is None
        and normal is not None
        and normal.rejected
        and (normal.n < PERCENTILE_MIN_N)
    ):
        lines += _wrap(
            f"  The data are not normal: Cpk from sigma may mislead, and {normal.n} readings are "
            f"too few for percentile indices (at least {PERCENTILE_MIN_N}).",
            width,
        )
    if percentile is not None:
        lines += _wrap(
            f"  The data are not normal: Cpk from sigma may mislead. {percentile.method}, "
            f"quantiles 0.135% {format_figure(percentile.q_low, resolution)}, median "
            f"{format_figure(percentile.median, resolution)}, "
            f"99.865% {format_figure(percentile.q_high, resolution)}:",
            width,
        )
        word = (
            "undefined"
            if percentile.capable is None
            else ("capable" if percentile.capable else "not capable")
        )
        lines += _wrap(
            f"    Pp (percentile) {index(percentile.pp)}   Ppu {index(percentile.ppu)}   "
            f"Ppl {index(percentile.ppl)}   Ppk (percentile) {index(percentile.ppk)}: {word} "
            f"at {percentile.threshold:g}",
            width,
        )
    auto = channel.autocorrelation
    if auto is not None:
        if auto.significant is None:
            lines += _wrap(f"AUTOCORRELATION lag 1: not tested ({auto.message})", width)
        else:
            lines += _wrap(
                f"AUTOCORRELATION lag 1: r = {auto.r1:+.2f}, {p_phrase(auto.p_value or 0.0)}"
                f" ({'significant' if auto.significant else 'not significant'} at "
                f"{auto.alpha:g})",
                width,
            )
            if auto.significant and auto.message:
                cap = channel.capability
                lines += _wrap(f"  {auto.message}.", width)
                lines += _wrap(
                    f"  Side by side: Cpk (overall sigma {format_spread(cap.sigma, resolution)}) "
                    f"{index(cap.cpk)}   Cpk within (sigma "
                    f"{format_spread(cap.sigma_within, resolution)}) {index(cap.cpk_within)}",
                    width,
                )
    found = channel.drift
    if found is not None:
        trend = found.trend
        if trend.per_span is None:
            lines += _wrap("DRIFT: no trend test (too few readings or no spread)", width)
        else:
            basis = "reading times" if trend.basis == "time" else "cycle order"
            lines += _wrap(
                f"DRIFT: trend on {basis} {format_figure(trend.per_span, resolution)} per "
                f"{trend.span} cycles (95% CI {format_figure(trend.low, resolution)} to "
                f"{format_figure(trend.high, resolution)}), {p_phrase(trend.p_value or 0.0)}",
                width,
            )
        if found.ewma is not None:
            signals = found.ewma.signal_cycles
            lines += _wrap(
                f"  EWMA (lambda {found.ewma.lam:g}, {found.ewma.width:g} sigma within): "
                + (
                    f"beyond its limits at cycles {number_list(signals)}"
                    if signals
                    else "inside its limits"
                ),
                width,
            )
        if found.message:
            lines += _wrap(f"  {found.message}.", width)
    return lines


def channel_figures(
    channel: ChannelAnalysis, config: AnalysisConfig
) -> tuple[tuple[str, str], ...]:
    """A channel's figures as the text report labels them, label -> value: the extremes and
    average, the limits and nominal, the count, sigma, range, skewness, mode and the pieces
    beyond each limit. Every report format shows these same pairs."""
    d, cap = channel.descriptive, channel.capability
    resolution = config.resolution
    limits = channel.limits
    n = d.n
    figures = [
        ("MAXIMUM", format_figure(d.max, resolution)),
        ("AVERAGE", format_figure(d.mean, resolution)),
        ("MINIMUM", format_figure(d.min, resolution)),
        ("UPPER SPEC", format_figure(None if limits is None else limits.usl, resolution)),
        ("NOMINAL", format_figure(channel.nominal, resolution)),
        ("LOWER SPEC", format_figure(None if limits is None else limits.lsl, resolution)),
        ("TOTAL NUMBER OF PIECES", str(n)),
        ("SIGMA", format_spread(d.sd, resolution)),
        ("RANGE", format_spread(d.range, resolution)),
        ("SKEWNESS a1", "-" if d.skewness is None else f"{d.skewness:+.3f}"),
        ("MODE", " ".join(format_figure(m, resolution) for m in d.modes) or "-"),
    ]
    for side, count in (("ABOVE UPPER", cap.above_usl), ("BELOW LOWER", cap.below_lsl)):
        percent = 100.0 * count / n if n else 0.0
        figures += [(f"PIECES {side} SPEC", str(count)), (f"PERCENT {side} SPEC", f"{percent:.2f}")]
    return tuple(figures)


#: How many of :func:`channel_figures` the text report lays out in rows of three.
_PAIRED_FIGURES = 9


def format_figures(figures: Sequence[tuple[str, str]], width: int = 80) -> list[str]:
    """:func:`channel_figures` as the text report lays them out: the first nine in rows of
    three, then skewness and mode, then the pieces beyond each limit."""
    said = dict(figures)
    lines = _pairs(list(figures[:_PAIRED_FIGURES]), width)
    lines += _wrap(f"SKEWNESS a1: {said['SKEWNESS a1']}   MODE: {said['MODE']}", width)
    for side in ("ABOVE UPPER", "BELOW LOWER"):
        lines.append(
            f"PIECES {side} SPEC: {said[f'PIECES {side} SPEC']}   "
            f"PERCENT {side} SPEC: {said[f'PERCENT {side} SPEC']}"
        )
    return lines


def _out_of_spec_lines(channel: ChannelAnalysis, width: int) -> list[str]:
    found = channel.out_of_spec
    if found is None or not found.total:
        return []
    parts = []
    if found.cycles_below:
        parts.append(f"below LSL at cycles {number_list(found.cycles_below)}")
    if found.cycles_above:
        parts.append(f"above USL at cycles {number_list(found.cycles_above)}")
    return _wrap(f"OUT OF SPEC: {found.total} readings, " + "; ".join(parts), width)


def format_channel(
    channel: ChannelAnalysis, config: AnalysisConfig, width: int = 80, *, readings: bool = True
) -> list[str]:
    """The report block of one channel; without its numbered readings when ``readings`` is
    False (the filed report lists them in its own table)."""
    d = channel.descriptive
    resolution = config.resolution
    unit = f" ({config.unit})" if config.unit else ""
    lines = [f"FEATURE: {channel.name}{unit}   NO. PIECES: {d.n}", ""]
    lines += format_figures(channel_figures(channel, config), width)
    lines += _out_of_spec_lines(channel, width)
    if readings:
        lines.append("")
        lines += format_readings(channel.readings, resolution, width, channel.cycles or None)
    lines.append("")
    lines += format_judgement(channel, config, width)
    return lines


def format_out_of_spec(channel: ChannelAnalysis, width: int = 80) -> list[str]:
    """The cycles of a channel's readings beyond each limit (none when all are inside)."""
    return _out_of_spec_lines(channel, width)


def format_judgement(
    channel: ChannelAnalysis, config: AnalysisConfig, width: int = 80
) -> list[str]:
    """What the text report says of a channel after its figures and readings: the histogram,
    the control chart's limits and alarms (retrospective and live), the capability with its
    intervals and verdict, and the diagnostics (normality, autocorrelation, drift)."""
    cap, chart = channel.capability, channel.chart
    resolution = config.resolution
    limits = channel.limits
    lines = [f"HISTOGRAM (bin width {format_spread(channel.histogram.bin_width, resolution)})"]
    lines += format_histogram(channel.histogram, limits, resolution, width, channel.nominal)
    lines.append("")
    dispersion = {"I-MR": "MR", "Xbar-R": "R", "Xbar-S": "S"}.get(chart.type, "dispersion")
    location = "X" if chart.type == "I-MR" else "Xbar"
    lines.append(
        f"CONTROL CHART: {chart.type}, subgroup {chart.subgroup}, "
        f"sigma within {format_spread(chart.sigma_within, resolution)}"
    )
    for label, limits_of in ((location, chart), (dispersion, chart.dispersion)):
        lines.append(
            f"  {label + ' chart:':<11} UCL {format_figure(limits_of.ucl, resolution)}   "
            f"CENTER {format_figure(limits_of.center, resolution)}   "
            f"LCL {format_figure(limits_of.lcl, resolution)}"
        )
    if chart.floored and chart.limit_floor is not None:
        lines += _wrap(
            f"  Limits held {format_spread(chart.limit_floor, resolution)} from the centre "
            "(1.5 gauge steps; the within sigma would put them closer): a reading one step from "
            "the centre's nearest value is not a signal, and a reading counts beyond a zone "
            "line only by more than half a step.",
            width,
        )
    if chart.message:
        lines += _wrap(f"  {chart.message}", width)
    if channel.alarms:
        lines.append(f"ALARMS (rules: {config.rule_set}; retrospective chart):")
        for alarm in channel.alarms:
            when = "live and retrospective" if channel.alarm_is_live(alarm) else "retrospective"
            lines += _wrap(f"{rule_name(alarm.rule)} [{when}]: {alarm.text}", width, "  ")
    else:
        lines.append(f"ALARMS (rules: {config.rule_set}): none")
    if channel.false_alarm is not None:
        lines += _wrap(channel.false_alarm.text(), width, "  ")
    frozen = channel.frozen
    if frozen is not None:
        source = frozen.source
        if not source.startswith("frozen"):
            source = f"baseline: {source}" if source else "baseline"
        lines += _wrap(
            f"LIVE LIMITS (phase II, {source}): "
            f"UCL {format_figure(frozen.ucl, resolution)}   "
            f"CENTER {format_figure(frozen.center, resolution)}   "
            f"LCL {format_figure(frozen.lcl, resolution)}",
            width,
        )
        if channel.live_alarms:
            lines.append("LIVE ALARMS (against the frozen limits, as raised while capturing):")
            for alarm in channel.live_alarms:
                lines += _wrap(f"{rule_name(alarm.rule)} [live]: {alarm.text}", width, "  ")
        else:
            lines.append("LIVE ALARMS (against the frozen limits): none")
    lines.append("")
    lines += format_budget(channel, resolution, config.unit, width)
    lines.append("")
    lines += _capability_lines(cap, chart.type, resolution, width, channel.verdict)
    diagnostics = format_diagnostics(channel, resolution, width)
    if diagnostics:
        lines += ["", *diagnostics]
    return lines


def format_spatial(spatial: Spatial, config: AnalysisConfig, width: int = 80) -> list[str]:
    """The 3-D block: per-axis offsets, the report's total, ISO 9283 AP and RP."""
    resolution = config.resolution
    unit = f" {config.unit}" if config.unit else ""
    cells = [format_figure(v, resolution) for v in spatial.offset.values()]
    column = max(len(c) for c in cells) + 3
    lines = [
        f"3-D FIGURES (x, y, z; {spatial.n} cycles)",
        "  " + " " * 26 + "".join(axis.rjust(column) for axis in spatial.offset),
        "  " + "Offset (average - nominal)".ljust(26) + "".join(c.rjust(column) for c in cells),
        "  "
        + "Nominal".ljust(26)
        + "".join(format_figure(v, resolution).rjust(column) for v in spatial.nominal.values()),
        f"  Total offset sqrt(sum of squared offsets) = ISO 9283 APp: "
        f"{format_spread(spatial.total_offset, resolution)}{unit}",
        "  ISO 9283 pose accuracy APx, APy, APz: the offsets above",
        f"  ISO 9283 pose repeatability RP = l-bar + 3 S_l: "
        f"{format_spread(spatial.rp, resolution)}{unit} "
        f"(l-bar {format_spread(spatial.l_mean, resolution)}, "
        f"S_l {format_spread(spatial.l_sd, resolution)})",
    ]
    if spatial.message:
        lines.append(f"  {spatial.message}")
    return [wrapped for line in lines for wrapped in _wrap(line, width)]


def format_report(
    analysis: Analysis,
    title: str = "BASIC STATISTICS COMPREHENSIVE REPORT",
    width: int = 80,
    notes: Sequence[str] = (),
    sections: Sequence[Sequence[str]] = (),
) -> str:
    """The whole text report: every channel, the 3-D figures and the hints; ends with a newline.

    ``notes`` are printed under the title (robot, operator, the session's last hash, ...).
    ``sections`` are blocks of lines (e.g. :func:`format_linearity`, :func:`format_accuracy`)
    printed after the 3-D figures, before the hints.
    """
    config = analysis.config
    rule = "=" * width
    lines = _wrap(title, width) + [rule]
    # The gauge step in the one number format too (never 1e-05).
    step = (
        "not given"
        if not config.resolution
        else format_spread(config.resolution, config.resolution)
    )
    lines.append(
        f"Unit: {config.unit or 'not given'}   Resolution: {step}   Subgroup: {config.subgroup}"
    )
    lines += _wrap(
        f"Run rules: {config.rule_set}   Capable when Cpk >= {config.threshold:g}   "
        + judged_count(analysis).capitalize(),
        width,
    )
    for note in notes:
        lines += _wrap(note, width)
    if analysis.excluded_cycles:
        excluded = ", ".join(str(c) for c in analysis.excluded_cycles)
        lines += _wrap(f"Excluded (rejected) cycles: {excluded}", width)
    for channel in analysis.channels.values():
        lines += ["", "-" * width]
        lines += format_channel(channel, config, width)
    if analysis.spatial is not None:
        lines += ["", "-" * width]
        lines += format_spatial(analysis.spatial, config, width)
    for section in sections:
        lines += ["", "-" * width, *section]
    lines += ["", "-" * width, "HINTS"]
    if analysis.hints:
        for hint in analysis.hints:
            lines += _wrap(f"- {hint}", width)
    else:
        lines.append("- none: no skew, offset, shift, alarm or gauge problem stands out.")
    return "\n".join(line.rstrip() for line in lines) + "\n"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], width: int) -> list[str]:
    """Right-aligned columns, each as wide as its widest cell, two spaces apart (callers keep
    tables narrow enough for ``width``; a longer line is wrapped, never cut)."""
    widths = [max(len(str(row[j])) for row in [header, *rows]) for j in range(len(header))]
    lines = []
    for row in [header, *rows]:
        line = "  ".join(str(cell).rjust(widths[j]) for j, cell in enumerate(row))
        lines += _wrap(line.rstrip(), width)
    return lines


def format_linearity(
    result: LinearityAnalysis, config: AnalysisConfig, width: int = 80
) -> list[str]:
    """The linearity block (§2.9): straightness per stroke (LS and MZ of each indicator), per
    direction, the largest, and the path repeatability along the bar. The judged per-stroke
    straightness (chart, alarms, capability) is a channel block of its own
    (:func:`format_channel` of :func:`~station.analysis.linearity.linearity_summary`)."""
    channels = result.channels
    resolution = config.resolution
    unit = f" {config.unit}" if config.unit else ""
    tolerance = (
        "not given"
        if result.tolerance is None
        else f"{format_spread(result.tolerance, resolution)}{unit}"
    )
    lines = _wrap(
        f"LINEARITY (report §2.9; {len(result.strokes)} strokes; straightness tolerance "
        f"{tolerance})",
        width,
    )
    lines += _wrap(
        "LS: peak-to-valley about the least-squares line; MZ: minimum zone (ISO 1101); "
        "both measured along the indicator axis.",
        width,
        indent="  ",
    )
    lines.append("")
    header = ["STROKE", "DIR", "POINTS"] + [
        f"{c} {kind}" for c in channels for kind in ("LS", "MZ")
    ]
    rows = [
        [str(r.number), r.direction, str(r.points)]
        + [
            format_spread(getattr(r.straightness[c], kind), resolution)
            for c in channels
            for kind in ("ls", "mz")
        ]
        for r in result.strokes
    ]
    lines += _table(header, rows, width)
    lines.append("")
    rows = [
        [d.direction, str(d.strokes)]
        + [
            f"{format_spread(d.mz_max[c], resolution)} / {format_spread(d.mz_mean[c], resolution)}"
            for c in channels
        ]
        for d in result.directions.values()
    ]
    lines.append("PER DIRECTION: MZ straightness, largest / mean")
    lines += _table(["DIR", "STROKES"] + list(channels), rows, width)
    lines.append("")
    for c in channels:
        path = result.path[c]
        at = "" if path.at is None else f" at s = {format_spread(path.at, resolution)}"
        lines += _wrap(
            f"{c}: largest straightness LS {format_spread(result.ls[c], resolution)}, MZ "
            f"{format_spread(result.mz[c], resolution)}{unit}; path repeatability (largest 3s "
            f"along the bar over {path.strokes} strokes) "
            f"{format_spread(path.max_3s, resolution)}{unit}{at}",
            width,
        )
    lines += _wrap(
        "The straightness per stroke is judged above, one reading per stroke: its control "
        "chart, alarms and capability against the tolerance (one-sided: USL = tolerance).",
        width,
    )
    return lines


def format_accuracy(result: AccuracyAnalysis, config: AnalysisConfig, width: int = 80) -> list[str]:
    """The relative-accuracy block (§2.8): per placement the pendant coordinates, the distance
    moved and the mean error per axis and in 3-D; across placements the average accuracy per
    axis, its spread, and the error per unit moved."""
    resolution = config.resolution
    unit = f" {config.unit}" if config.unit else ""
    lines = _wrap(
        f"RELATIVE ACCURACY (report §2.8; {len(result.placements)} placements, "
        f"{result.error_3d.descriptive.n} readings)",
        width,
    ) + [
        "  Error: the first fixture's indicators after the inverse move.",
        "",
    ]
    # Two narrow tables rather than one wide one: pendant coordinates in mm run to 7 digits.
    rows = [
        [
            str(p.number),
            str(p.n),
            *(["-"] * 3 if p.pendant is None else [f"{v:.3f}" for v in p.pendant]),
            "-" if p.distance is None else f"{p.distance:.3f}",
        ]
        for p in result.placements
    ]
    lines.append("PENDANT (second fixture, home at the first) AND DISTANCE MOVED")
    lines += _table(["PLACE", "N", "X", "Y", "Z", "DISTANCE"], rows, width)
    rows = [
        [str(p.number)]
        + [format_figure(p.mean[axis], resolution) for axis in ("x", "y", "z")]
        + [format_spread(p.error_3d, resolution)]
        for p in result.placements
    ]
    lines += ["", "MEAN ERROR PER PLACEMENT (x, y, z and the 3-D error sqrt(x^2 + y^2 + z^2))"]
    lines += _table(["PLACE", "x", "y", "z", "3-D"], rows, width)
    lines += ["", "ACROSS PLACEMENTS (overall average accuracy in the direction of each axis)"]
    rows = [
        [
            axis,
            format_figure(result.average[axis], resolution),
            format_spread(result.spread[axis], resolution),
            format_spread(result.span[axis], resolution),
            # Parts per million of the distance moved: plain decimals, never 1e-05 notation.
            "-" if result.scale_error is None else f"{result.scale_error[axis] * 1e6:+.1f}",
        ]
        for axis in ("x", "y", "z")
    ]
    lines += _table(["AXIS", "AVERAGE", "SIGMA", "RANGE", "ERROR PER MOVE (ppm)"], rows, width)
    d = result.error_3d.descriptive
    lines += _wrap(
        f"3-D error sqrt(x^2 + y^2 + z^2) per reading: mean {format_spread(d.mean, resolution)}, "
        f"sigma {format_spread(d.sd, resolution)}, max {format_spread(d.max, resolution)}{unit}",
        width,
    )
    if result.per_unit is None:
        lines += _wrap(
            "Error per unit moved: needs the pendant coordinates of 3 or more placements.", width
        )
    return lines
