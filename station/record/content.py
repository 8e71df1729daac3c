"""What a filed report says: one content model built from a session file, shown in txt, md or
html by :mod:`station.record.render`.

Everything is formatted here, once, so the three formats cannot disagree: the robot, operator,
procedure (id, version, sha256), date and duration, gauges, zeroes, limits, every reading with
the rejects and their reasons, notes, alarms with their acknowledgements, the overall verdict
(the session's word and each channel's, with Cpk and its one-sided Bissell bounds), every judged
channel's statistics as the text report (``station analyze``) gives them, each channel's
measurement budget, hints, the
procedure's own blocks, the anchor (the last line's hash) and the signature id, and the sign-off
lines. Text from outside stays raw here; each
format escapes it (see :mod:`station.record.text`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from station.analysis.report import (
    budget_rows,
    budget_summary,
    channel_figures,
    decisions_text,
    format_figures,
    format_judgement,
    format_out_of_spec,
)
from station.analysis.rules import rule_name
from station.analysis.verdict import confidence_text
from station.record.source import AnalysedSession
from station.text import (
    NOT_AVAILABLE,
    format_figure,
    format_index,
    format_spread,
    judged_count,
    judged_cpk,
    judged_label,
    overall_judgement,
)

MISSING = NOT_AVAILABLE
"""What an absent or undefined figure shows (the same ``-`` as every screen and command)."""
SIGN_OFF = ("Tested by", "Reviewed by")


@dataclass(frozen=True)
class Gauge:
    """One serial line of the session: where, what protocol, which channels, serials."""

    port: str
    protocol: str
    channels: str
    serials: str
    settings: str


@dataclass(frozen=True)
class ZeroLine:
    """One channel of one zero event: how the indicator was zeroed and the offset taken."""

    time: str
    step: str
    channel: str
    method: str
    offset: str
    detail: str = ""
    """`` (mean of 5 readings, spread 0.00010)`` for a zero from several readings, else ''."""


@dataclass(frozen=True)
class LimitLine:
    """The specification limits of one channel."""

    channel: str
    lsl: str
    usl: str
    nominal: str


@dataclass(frozen=True)
class ReadingRow:
    """One recorded cycle: its values per channel (in ``ReportContent.channels`` order) and its
    status, ``ok``, ``out of spec`` or ``rejected: <reason>`` (readings are never deleted).

    A value the verdict judged beyond a limit carries the mark (``+0.00103 >USL``): the value
    is written in the one number format, so the value listed is the value judged."""

    cycle: str
    time: str
    placement: str
    values: tuple[str, ...]
    status: str


@dataclass(frozen=True)
class NoteLine:
    """One note the operator (or the engine) wrote."""

    time: str
    by: str
    text: str


@dataclass(frozen=True)
class AlarmLine:
    """One recorded alarm and its acknowledgement (``acknowledged`` is MISSING without one)."""

    time: str
    channel: str
    rule: str
    cycles: str
    text: str
    acknowledged: str


@dataclass(frozen=True)
class Verdict:
    """One judged channel: n, mean, σ, Cp, Cpk with its one-sided confidence bounds (Bissell),
    the word, and the decision in a sentence (why the word, and the report's own rule)."""

    channel: str
    name: str
    n: str
    mean: str
    sd: str
    cp: str
    cpk: str
    cpk_lower: str
    cpk_upper: str
    """Bissell's one-sided upper bound on Cpk: with the lower one, what the verdict weighed."""
    confidence: str
    """The one-sided confidence level of each of ``cpk_lower`` and ``cpk_upper`` (``95%``)."""
    word: str
    message: str
    decision: str = ""
    """The verdict line without ``VERDICT:`` (``CAPABLE (Cpk 1.80; Bissell 95% lower bound
    1.39 >= 1; by the report's rule: capable, Cpk 1.80 >= 1)``)."""


@dataclass(frozen=True)
class ChannelStatistics:
    """Everything the text report (``station analyze``) says of one judged channel but its
    numbered readings, which the filed report lists in its own table: the labelled figures
    (maximum ... skewness, mode, pieces beyond each limit) and the lines that follow them
    (out-of-spec cycles, histogram, control chart and alarms, capability with its intervals,
    normality, autocorrelation, drift)."""

    channel: str
    heading: str
    figures: tuple[tuple[str, str], ...]
    figure_lines: tuple[str, ...]
    """``figures`` laid out as the text report lays them out (the txt format prints these)."""
    lines: tuple[str, ...]


@dataclass(frozen=True)
class BudgetBlock:
    """One channel's measurement budget: the table rows (input, u, |c|·u, dof, share), u_c and
    U at k in a line, and the readings as the decision rule judged them with that U."""

    name: str
    rows: tuple[tuple[str, ...], ...]
    summary: str
    decisions: str


BUDGET_HEADER = ("input", "u", "|c|·u", "dof", "share")
"""The columns of a budget table."""


@dataclass(frozen=True)
class ReportContent:
    """The facts of one filed report, every value already formatted as text."""

    title: str
    file_name: str
    kind: str
    session_id: str
    robot: str
    operator: str
    host: str
    procedure_id: str
    procedure_version: str
    procedure_sha256: str
    created: str
    ended: str
    duration: str
    status: str
    unit: str
    resolution: str
    rules: str
    threshold: str
    trigger: str
    gauges: tuple[Gauge, ...]
    zeroes: tuple[ZeroLine, ...]
    limits: tuple[LimitLine, ...]
    channels: tuple[str, ...]
    readings: tuple[ReadingRow, ...]
    rejected: tuple[tuple[str, str], ...]
    streamed: str
    """How many points a session streamed ("" when it streamed none)."""
    notes: tuple[NoteLine, ...]
    alarms: tuple[AlarmLine, ...]
    verdicts: tuple[Verdict, ...]
    overall: str
    """The session's verdict word (``CAPABLE``, ``PROVISIONAL: 9 of 25``, a method's own word),
    MISSING when nothing was judged."""
    overall_basis: str
    """What the overall word rests on: the count judged and the decision rule, or the method's
    own sentence."""
    statistics: tuple[ChannelStatistics, ...]
    figures: tuple[tuple[str, str], ...]
    """Label → value of the 3-D figures (offsets, RP, AP), empty without x, y, z."""
    sections: tuple[tuple[str, ...], ...]
    """The procedure's own report blocks (linearity, relative accuracy), preformatted lines."""
    hints: tuple[str, ...]
    anchor: str
    signature: str
    problem: str
    """Why there is no analysis ("" when there is one)."""
    torn: str
    """The torn tail's message ("" for an intact file)."""
    budgets: tuple[BudgetBlock, ...] = ()
    """Each judged channel's measurement budget (none when nothing of it is known)."""
    budget_header: tuple[str, ...] = BUDGET_HEADER
    sign_off: tuple[str, ...] = SIGN_OFF


ABOVE_MARK, BELOW_MARK = ">USL", "<LSL"
"""The mark beside a reading the verdict judged above the upper / below the lower limit."""


def parse_time(text: str) -> datetime | None:
    """An event time (ISO-8601, ``Z``) as an aware datetime, None when it is not one."""
    try:
        return datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        return None


def duration_text(seconds: float) -> str:
    """``1 h 02 min 05 s``, ``4 min 10 s`` or ``12 s``."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours} h {minutes:02d} min {secs:02d} s"
    if minutes:
        return f"{minutes} min {secs:02d} s"
    return f"{secs} s"


def short_time(text: str) -> str:
    """An event time to the second, ``2026-11-23 12:00:05Z``."""
    moment = parse_time(text)
    return MISSING if moment is None else moment.strftime("%Y-%m-%d %H:%M:%SZ")


def signature_id(session: Any) -> str:
    """The id of the key that signed the session's ``finish`` event, where one did: the
    finish event's ``signature`` (its ``key_id``/``key``, or the text itself), else the header's
    ``key_id`` / ``signing_key``. MISSING for an unsigned session."""
    for event in reversed(session.events):
        if event.get("type") == "finish":
            signature = event.get("signature")
            if isinstance(signature, Mapping):
                key = signature.get("key_id") or signature.get("key")
                if key:
                    return str(key)
            elif isinstance(signature, str) and signature:
                return signature
            break
    for key in ("key_id", "signing_key", "public_key_id"):
        if session.header.get(key):
            return str(session.header[key])
    return MISSING


def _acknowledgements(session: Any) -> list[Mapping[str, Any]]:
    return [e for e in session.events if e.get("type") in ("ack", "acknowledge")]


def acknowledgement_of(alarm: Mapping[str, Any], acks: Sequence[Mapping[str, Any]]) -> str:
    """The acknowledgement of ``alarm`` (an ``ack`` event naming its seq in ``alarm``, or its
    channel and rule and one of its cycles), as ``cause; action (by, time)``; MISSING when
    none. Sessions written before acknowledgements existed simply have none."""
    cycles = set(alarm.get("cycles") or ())
    for ack in acks:
        named = ack.get("alarm")
        matches = (
            named == alarm.get("seq")
            if named is not None
            else (
                ack.get("channel") == alarm.get("channel")
                and ack.get("rule") == alarm.get("rule")
                and bool(cycles & set(ack.get("cycles") or ()))
            )
        )
        if matches:
            parts = [str(ack.get(k)) for k in ("cause", "action", "text") if ack.get(k)]
            who = ", ".join(x for x in (str(ack.get("by") or ""), short_time(ack["t"])) if x)
            return f"{'; '.join(parts) or 'acknowledged'} ({who})"
    return MISSING


def _gauges(header: Mapping[str, Any], events: Sequence[Mapping[str, Any]]) -> tuple[Gauge, ...]:
    instruments = header.get("instruments") or {}
    serials_seen: dict[str, set[str]] = {}
    for event in events:
        if event.get("type") == "instrument":
            for key in ("serial", "serial_number"):
                if event.get(key):
                    port = str(event.get("port") or "")
                    serials_seen.setdefault(port, set()).add(str(event[key]))
    gauges = []
    for port in instruments.get("ports") or ():
        if not isinstance(port, Mapping):
            continue
        url = str(port.get("url") or "")
        mapping = port.get("map") or {}
        serials = set(serials_seen.get(url, set()))
        recorded = port.get("serials") or port.get("serial") or port.get("serial_number")
        if isinstance(recorded, Mapping):
            serials.update(f"{k}: {v}" for k, v in recorded.items())
        elif recorded:
            serials.add(str(recorded))
        settings = port.get("settings") or {}
        gauges.append(
            Gauge(
                port=url,
                protocol=str(port.get("protocol") or ""),
                channels=", ".join(f"{k}→{v}" for k, v in mapping.items()) or MISSING,
                serials=", ".join(sorted(serials)) or "not reported by the gauge",
                settings=" ".join(f"{k}={v}" for k, v in settings.items()) or MISSING,
            )
        )
    return tuple(gauges)


def _figure(value: Any, resolution: float | None) -> str:
    """A reading, zero offset or limit from the file in the one number format (``+0.00103``),
    ``-`` when absent or not a number."""
    if value is None or isinstance(value, bool) or not isinstance(value, int | float):
        return MISSING
    return format_figure(float(value), resolution)


def _limits(header: Mapping[str, Any], resolution: float | None) -> tuple[LimitLine, ...]:
    lines = []
    for channel, spec in (header.get("limits") or {}).items():
        if isinstance(spec, Mapping):
            lines.append(
                LimitLine(
                    channel=str(channel),
                    lsl=_figure(spec.get("lsl"), resolution),
                    usl=_figure(spec.get("usl"), resolution),
                    nominal=_figure(spec.get("nominal"), resolution),
                )
            )
    return tuple(lines)


def _zero_detail(spec: Mapping[str, Any], resolution: float | None) -> str:
    """How a zero from several readings was taken: `` (mean of 5 readings, spread 0.00010)``."""
    n, spread = spec.get("n"), spec.get("spread")
    if not isinstance(n, int) or n < 2 or not isinstance(spread, int | float):
        return ""
    return f" (mean of {n} readings, spread {format_spread(float(spread), resolution)})"


def _zeroes(session: Any, resolution: float | None) -> tuple[ZeroLine, ...]:
    lines = []
    for event in session.zeroes:
        for channel, spec in (event.get("channels") or {}).items():
            spec = spec if isinstance(spec, Mapping) else {}
            offset = spec.get("offset")
            lines.append(
                ZeroLine(
                    time=short_time(event["t"]),
                    step=str(event.get("step") or "")
                    + (
                        f" (placement {event['placement']})"
                        if event.get("placement") is not None
                        else ""
                    ),
                    channel=str(channel),
                    method=str(spec.get("method") or MISSING),
                    offset=_figure(offset, resolution),
                    detail=_zero_detail(spec, resolution),
                )
            )
    return tuple(lines)


def out_of_spec_marks(analysed: AnalysedSession) -> dict[tuple[str, int], tuple[float, str]]:
    """(channel, cycle) -> (the value judged, its mark) of every reading the verdict judged
    beyond a limit: the analysis' own out-of-spec cycles of each channel whose judged values
    are the readings themselves (a linearity stroke's straightness is not a reading)."""
    report = analysed.report
    if report is None or report.analysis is None:
        return {}
    marks: dict[tuple[str, int], tuple[float, str]] = {}
    for key, channel in report.analysis.channels.items():
        found = channel.out_of_spec
        if found is None or not found.total:
            continue
        cycles = channel.cycles or tuple(range(1, len(channel.readings) + 1))
        judged = dict(zip(cycles, channel.readings, strict=True))
        for mark, numbers in ((ABOVE_MARK, found.cycles_above), (BELOW_MARK, found.cycles_below)):
            for number in numbers:
                marks[(str(key), int(number))] = (float(judged[number]), mark)
    return marks


def _readings(analysed: AnalysedSession, resolution: float | None) -> tuple[ReadingRow, ...]:
    session = analysed.session
    marks = out_of_spec_marks(analysed)
    rows = []
    for cycle_number in sorted(session.cycles):
        cycle = session.cycles[cycle_number]
        reason = session.rejected.get(cycle_number)
        values, beyond = [], False
        for channel in session.channels:
            reading = cycle.readings.get(channel)
            if reading is None:
                values.append(MISSING)
                continue
            text = _figure(reading.value, resolution)
            judged = marks.get((channel, cycle_number))
            if judged is not None and judged[0] == reading.value:
                text, beyond = f"{text} {judged[1]}", True
            values.append(text)
        status = "ok" if not beyond else "out of spec"
        rows.append(
            ReadingRow(
                cycle=str(cycle_number),
                time=short_time(cycle.t),
                placement=MISSING if cycle.placement is None else str(cycle.placement),
                values=tuple(values),
                status=status if reason is None else f"rejected: {reason}",
            )
        )
    return tuple(rows)


def _verdicts(analysed: AnalysedSession, resolution: float | None) -> tuple[Verdict, ...]:
    if analysed.report is None or analysed.report.analysis is None:
        return ()
    verdicts = []
    for key, channel in analysed.report.analysis.channels.items():
        cap = channel.capability
        verdicts.append(
            Verdict(
                channel=str(key),
                name=str(channel.name),
                n=str(channel.descriptive.n),
                mean=format_figure(channel.descriptive.mean, resolution),
                sd=format_spread(channel.descriptive.sd, resolution),
                cp=format_index(cap.cp),
                cpk=judged_cpk(channel),
                cpk_lower=format_index(cap.cpk_lower),
                cpk_upper=format_index(cap.cpk_upper),
                confidence=confidence_text(cap.confidence),
                word=judged_label(channel),
                message=str(cap.message or ""),
                decision=channel.verdict.text if channel.verdict is not None else "",
            )
        )
    return tuple(verdicts)


def _overall(analysed: AnalysedSession) -> tuple[str, str]:
    """The session's word and what it rests on (see ``ReportContent.overall``): the channels'
    judgement (:func:`~station.text.overall_judgement`, the summary's and history's too), else a
    method's own verdict, else MISSING with why."""
    report = analysed.report
    if report is None:
        return MISSING, f"no verdict: {analysed.problem or 'nothing to judge'}"
    analysis = report.analysis
    if analysis is not None and analysis.channels:
        config = analysis.config
        level = confidence_text(config.confidence)
        count = judged_count(analysis)
        # The rule in lower case: the words in capitals are verdicts, and this is none.
        basis = (
            f"{count[:1].upper()}{count[1:]}; capable when Cpk's one-sided {level} lower bound "
            f"(Bissell) reaches {config.threshold:g}, not capable when its upper bound is below "
            f"{config.threshold:g}, inconclusive between; the session is capable only when "
            "every channel is, not capable when any is"
        )
        return overall_judgement(analysis.channels.values()), basis
    if report.verdict is not None:
        return str(report.verdict.word), str(report.verdict.sentence)
    return MISSING, "this procedure judges no readings by capability: its results are below"


def _statistics(analysed: AnalysedSession) -> tuple[ChannelStatistics, ...]:
    """Each judged channel's block of the text report, without the numbered readings."""
    if analysed.report is None or analysed.report.analysis is None:
        return ()
    analysis = analysed.report.analysis
    config = analysis.config
    unit = f" ({config.unit})" if config.unit else ""
    return tuple(
        ChannelStatistics(
            channel=str(channel.name),
            heading=f"{channel.name}{unit}, {channel.descriptive.n} pieces",
            figures=channel_figures(channel, config),
            figure_lines=tuple(format_figures(channel_figures(channel, config))),
            lines=(*format_out_of_spec(channel), *format_judgement(channel, config)),
        )
        for channel in analysis.channels.values()
    )


def _budgets(analysed: AnalysedSession, resolution: float | None) -> tuple[BudgetBlock, ...]:
    if analysed.report is None or analysed.report.analysis is None:
        return ()
    unit = analysed.report.analysis.config.unit
    blocks = []
    for channel in analysed.report.analysis.channels.values():
        if channel.budget is None:
            continue
        decisions = channel.reading_decisions
        blocks.append(
            BudgetBlock(
                name=str(channel.name),
                rows=tuple(budget_rows(channel.budget, resolution)),
                summary=budget_summary(channel.budget, resolution, unit),
                decisions="" if decisions is None else decisions_text(decisions, resolution, unit),
            )
        )
    return tuple(blocks)


def _figures(analysed: AnalysedSession, resolution: float | None) -> tuple[tuple[str, str], ...]:
    if analysed.report is None or analysed.report.analysis is None:
        return ()
    spatial = analysed.report.analysis.spatial
    if spatial is None:
        return ()
    figures = [
        (f"Offset {axis} (mean − nominal)", format_figure(value, resolution))
        for axis, value in spatial.offset.items()
    ]
    figures.append(("Total offset (APp)", format_spread(spatial.total_offset, resolution)))
    figures.append(("Pose repeatability RP = l̄ + 3·S_l", format_spread(spatial.rp, resolution)))
    figures.append(
        ("l̄ (mean distance from the mean pose)", format_spread(spatial.l_mean, resolution))
    )
    figures.append(("S_l (its standard deviation)", format_spread(spatial.l_sd, resolution)))
    return tuple(figures)


def build_content(analysed: AnalysedSession) -> ReportContent:
    """The report's content for an analysed session (see the module)."""
    session = analysed.session
    header = session.header
    recorded = header.get("resolution")
    resolution = float(recorded) if isinstance(recorded, int | float) and recorded > 0 else None
    times = [t for t in (parse_time(e["t"]) for e in session.events) if t is not None]
    duration = duration_text((times[-1] - times[0]).total_seconds()) if times else MISSING
    procedure = header.get("procedure") or {}
    acks = _acknowledgements(session)
    report = analysed.report
    overall, overall_basis = _overall(analysed)
    streamed = ""
    if session.samples:
        points = sum(len(batch.values) for batch in session.samples)
        strokes = len({batch.stroke for batch in session.samples})
        streamed = (
            f"{points} streamed points in {strokes} recorded strokes (every point is in the "
            "session file; station export --csv writes them as stroke,s,h,v)"
        )
    alarms = tuple(
        AlarmLine(
            time=short_time(alarm["t"]),
            channel=str(alarm.get("channel") or ""),
            # The rule in words, and whether it was raised live (all alarm events are, since
            # the live limits froze; a file may still mark one retrospective).
            rule=f"{rule_name(str(alarm.get('rule') or ''))} "
            f"[{'live' if alarm.get('live', True) else 'retrospective'}]",
            cycles=", ".join(str(c) for c in alarm.get("cycles") or ()) or MISSING,
            text=str(alarm.get("text") or ""),
            acknowledged=acknowledgement_of(alarm, acks),
        )
        for alarm in session.alarms
    )
    return ReportContent(
        title=report.title if report is not None else f"REPORT ON {session.path.name}",
        file_name=session.path.name,
        kind=analysed.kind,
        session_id=session.session_id,
        robot=session.robot,
        operator=session.operator or "not given",
        host=str(header.get("host") or MISSING),
        procedure_id=session.procedure_id,
        procedure_version=str(procedure.get("version") or MISSING),
        procedure_sha256=str(procedure.get("sha256") or MISSING),
        created=short_time(session.created),
        ended=short_time(session.events[-1]["t"]) if session.events else MISSING,
        duration=duration,
        status=session.status,
        unit=session.unit,
        # The gauge step in the one number format too (never 1e-05).
        resolution=MISSING if resolution is None else format_spread(resolution, resolution),
        rules=str(header.get("rules") or "report"),
        threshold=f"{float(header.get('threshold') or 1.0):g}",
        trigger=str((header.get("instruments") or {}).get("trigger") or MISSING),
        gauges=_gauges(header, session.events),
        zeroes=_zeroes(session, resolution),
        limits=_limits(header, resolution),
        channels=session.channels,
        readings=_readings(analysed, resolution),
        rejected=tuple((str(c), str(r)) for c, r in sorted(session.rejected.items())),
        streamed=streamed,
        notes=tuple(
            NoteLine(
                time=short_time(note["t"]),
                by=str(note.get("by") or MISSING),
                text=str(note.get("text") or ""),
            )
            for note in session.notes
        ),
        alarms=alarms,
        verdicts=_verdicts(analysed, resolution),
        overall=overall,
        overall_basis=overall_basis,
        statistics=_statistics(analysed),
        budgets=_budgets(analysed, resolution),
        figures=_figures(analysed, resolution),
        sections=report.sections if report is not None else (),
        hints=tuple(report.analysis.hints) if report is not None and report.analysis else (),
        anchor=session.last_hash,
        signature=signature_id(session),
        problem=analysed.problem or "",
        torn=session.torn.message if session.torn is not None else "",
    )
