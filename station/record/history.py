"""A robot's history: every session of it in time order, the figures that follow it over the
months (RP, per-axis mean offset, σ, Cpk, verdict, anchor), and the wear trend.

The wear trend is, per channel, the least-squares line of the session means against the date
(the report's periodic testing, §1.3: a robot that wears drifts off its nominal). Its slope is
given with a confidence interval (Student's t on n − 2 degrees of freedom); where the slope is
significant (the interval excludes 0) and heads for a limit, the date at which the line would
reach that limit is given too. Only sessions of the latest session's procedure and unit are
trended together.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.diagnostics import p_phrase
from station.errors import StationError
from station.record.baseline import baseline_for
from station.record.content import parse_time
from station.record.source import analyse_session
from station.record.text import plain
from station.session.store import list_sessions
from station.text import (
    UNDEFINED,
    format_figure,
    format_index,
    format_spread,
    overall_judgement,
)

SECONDS_PER_DAY = 86400.0


@dataclass(frozen=True)
class ChannelFigures:
    """One channel of one session: mean, its offset from nominal, σ and Cpk."""

    mean: float
    offset: float
    sd: float | None
    cpk: float | None
    capable: bool | None
    usl: float | None
    lsl: float | None


@dataclass(frozen=True)
class HistoryEntry:
    """One session in a robot's history (``problem`` says why a figure is missing)."""

    path: Path
    created: str
    procedure: str
    kind: str
    status: str
    rp: float | None
    channels: dict[str, ChannelFigures]
    verdict: str
    anchor: str
    baseline: bool = False
    problem: str | None = None
    unit: str = ""
    resolution: float | None = None
    """The session's gauge step: its figures are written one decimal beyond it."""


@dataclass(frozen=True)
class Trend:
    """The wear trend of one channel's session means: slope per day with its confidence
    interval and p-value; ``crossing`` is the date the line reaches ``limit`` (None when the
    slope is not significant or heads for no limit)."""

    channel: str
    procedure: str
    sessions: int
    slope_per_day: float
    ci_low: float
    ci_high: float
    p_value: float
    significant: bool
    limit: float | None = None
    limit_name: str | None = None
    crossing: str | None = None
    sentence: str = ""


@dataclass(frozen=True)
class RobotHistory:
    """A robot's sessions in time order, its trends and the baseline's session id."""

    robot: str
    folder: Path
    entries: tuple[HistoryEntry, ...]
    trends: tuple[Trend, ...] = field(default_factory=tuple)
    baseline_session: str | None = None
    unit: str = ""
    skipped: tuple[tuple[Path, str], ...] = ()
    """The session files of the folder that could not be read, each with why (whose robot
    they are is unknown, or their analysis failed): left out, and said so one line each."""
    resolution: float | None = None
    """The latest session's gauge step, which the charts and trends are written at."""


def _entry(path: Path, baseline_session: str | None) -> HistoryEntry:
    analysed = analyse_session(path)
    session = analysed.session
    channels: dict[str, ChannelFigures] = {}
    rp = None
    verdict = UNDEFINED
    if analysed.report is not None and analysed.report.analysis is not None:
        analysis = analysed.report.analysis
        for name, channel in analysis.channels.items():
            cap = channel.capability
            mean = channel.descriptive.mean
            if mean is None:
                # No reading, no figures (an analysed channel has readings: this does not
                # happen, and a history line without the channel is what it would mean).
                continue
            channels[name] = ChannelFigures(
                mean=mean,
                offset=mean - channel.nominal,
                sd=channel.descriptive.sd,
                cpk=cap.cpk,
                capable=cap.capable,
                usl=None if channel.limits is None else channel.limits.usl,
                lsl=None if channel.limits is None else channel.limits.lsl,
            )
        if analysis.spatial is not None:
            rp = analysis.spatial.rp
        verdict = overall_judgement(analysis.channels.values())
    recorded = session.header.get("resolution")
    return HistoryEntry(
        path=path,
        created=session.created,
        procedure=session.procedure_id,
        kind=analysed.kind,
        status=session.status,
        rp=rp,
        channels=channels,
        verdict=verdict,
        anchor=session.last_hash,
        baseline=baseline_session is not None and session.session_id == baseline_session,
        problem=analysed.problem,
        unit=session.unit,
        resolution=float(recorded) if isinstance(recorded, int | float) and recorded > 0 else None,
    )


def wear_trend(
    days: Sequence[float],
    means: Sequence[float],
    *,
    confidence: float = 0.95,
) -> tuple[float, float, float, float, float] | None:
    """The least-squares slope of ``means`` against ``days``: (slope, ci_low, ci_high,
    p_value, intercept); None with fewer than three sessions or all on one day."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(days, dtype=float)
    y = np.asarray(means, dtype=float)
    if x.size < 3 or np.ptp(x) == 0:
        return None
    fit = stats.linregress(x, y)
    dof = x.size - 2
    margin = stats.t.ppf(0.5 + confidence / 2, dof) * fit.stderr
    p_value = float(fit.pvalue) if math.isfinite(fit.pvalue) else 0.0
    return (
        float(fit.slope),
        float(fit.slope - margin),
        float(fit.slope + margin),
        p_value,
        float(fit.intercept),
    )


def _trends(
    entries: Sequence[HistoryEntry], unit: str, resolution: float | None
) -> tuple[Trend, ...]:
    analysed = [e for e in entries if e.channels and parse_time(e.created) is not None]
    if not analysed:
        return ()
    procedure, unit_of_latest = analysed[-1].procedure, analysed[-1].unit
    # Means in different units (or of different procedures) cannot share one line.
    same = [e for e in analysed if e.procedure == procedure and e.unit == unit_of_latest]
    first = parse_time(same[0].created)
    assert first is not None
    trends = []
    for channel in same[-1].channels:
        rows = [e for e in same if channel in e.channels]
        days = [(parse_time(e.created) - first).total_seconds() / SECONDS_PER_DAY for e in rows]  # type: ignore[operator]
        fit = wear_trend(days, [e.channels[channel].mean for e in rows])
        if fit is None:
            continue
        slope, low, high, p_value, intercept = fit
        significant = low > 0 or high < 0
        latest = rows[-1].channels[channel]
        limit, limit_name = (latest.usl, "USL") if slope > 0 else (latest.lsl, "LSL")
        crossing = None
        per_30 = f"{format_figure(slope * 30, resolution, unit=unit)} per 30 days"
        interval = (
            f"(95% CI {format_figure(low * 30, resolution)} to "
            f"{format_figure(high * 30, resolution)}, {p_phrase(p_value)})"
        )
        if significant and limit is not None and slope != 0:
            day = (limit - intercept) / slope
            if day > days[-1]:
                crossing = (first + timedelta(days=day)).strftime("%Y-%m-%d")
                sentence = (
                    f"{channel}: the mean moves {per_30} {interval}; at this rate it reaches "
                    f"the {limit_name} {format_figure(limit, resolution)} on {crossing}."
                )
            else:
                sentence = (
                    f"{channel}: the mean moves {per_30} {interval} and the trend line is "
                    f"already past the {limit_name} {format_figure(limit, resolution)}."
                )
        elif significant:
            sentence = f"{channel}: the mean moves {per_30} {interval}; no limit to reach."
        else:
            sentence = f"{channel}: no significant trend {interval}."
        trends.append(
            Trend(
                channel=channel,
                procedure=procedure,
                sessions=len(rows),
                slope_per_day=slope,
                ci_low=low,
                ci_high=high,
                p_value=p_value,
                significant=significant,
                limit=limit if crossing else None,
                limit_name=limit_name if crossing else None,
                crossing=crossing,
                sentence=sentence,
            )
        )
    return tuple(trends)


def robot_history(folder: str | Path, robot: str) -> RobotHistory:
    """Every session of ``robot`` (exact name) in ``folder``, oldest first, with the trends.
    Files that do not load are left out and listed in ``skipped`` with why. StationError when
    the robot has no session there."""
    folder = Path(folder)
    listed = list_sessions(folder)
    skipped = [(s.path, s.error) for s in listed if s.error is not None]
    summaries = [s for s in listed if s.error is None and s.robot == robot]
    if not summaries:
        raise StationError(f"no session of robot {robot!r} in {folder}; check the name.")
    try:
        baseline = baseline_for(robot)
    except StationError:
        baseline = None  # a damaged baseline must not hide the history; `baseline` says why
    baseline_session = None if baseline is None else str(baseline.get("session"))
    summaries.sort(key=lambda s: (s.created, s.path.name))
    entries = []
    for summary in summaries:
        try:
            entries.append(_entry(summary.path, baseline_session))
        except StationError as error:
            skipped.append((summary.path, error.message))
    unit = entries[-1].unit if entries else ""
    resolution = entries[-1].resolution if entries else None
    return RobotHistory(
        robot=robot,
        folder=folder,
        entries=tuple(entries),
        trends=_trends(entries, unit, resolution),
        baseline_session=baseline_session,
        unit=unit,
        skipped=tuple(sorted(skipped)),
        resolution=resolution,
    )


def text_chart(
    values: Sequence[float | None],
    *,
    height: int = 8,
    width: int = 60,
    label: Callable[[float], str] = format_index,
) -> list[str]:
    """A plain-text chart of ``values`` in order (one column per value, spread over ``width``;
    None leaves a gap): ``*`` marks, the top and bottom values labelled at the left as
    ``label`` writes them (an index at two decimals; a figure in the unit by
    :func:`~station.text.format_figure`)."""
    known = [v for v in values if v is not None and math.isfinite(v)]
    if not known:
        return ["(no values)"]
    low, high = min(known), max(known)
    span = high - low or 1.0
    step = max(1, min(width // max(1, len(values)), 6))
    grid = [[" "] * (step * len(values)) for _ in range(height)]
    for column, value in enumerate(values):
        if value is None or not math.isfinite(value):
            continue
        row = height - 1 - round((value - low) / span * (height - 1))
        grid[row][column * step] = "*"
    labels = [f"{label(high):>11} |", *[" " * 11 + " |"] * (height - 2), f"{label(low):>11} |"]
    if height == 1:
        labels = [f"{label(high):>11} |"]
    lines = [label + "".join(row).rstrip() for label, row in zip(labels, grid, strict=True)]
    lines.append(" " * 12 + "+" + "-" * (step * len(values)))
    return lines


def history_json(history: RobotHistory) -> dict[str, Any]:
    """The JSON document of ``station history --json``."""

    def number(value: float | None) -> float | None:
        return None if value is None or not math.isfinite(value) else float(value)

    return {
        "robot": history.robot,
        "folder": str(history.folder),
        "unit": history.unit,
        "baseline_session": history.baseline_session,
        "skipped": [{"file": path.name, "error": why} for path, why in history.skipped],
        "sessions": [
            {
                "file": e.path.name,
                "created": e.created,
                "procedure": e.procedure,
                "analysis": e.kind,
                "status": e.status,
                "rp": number(e.rp),
                "verdict": e.verdict,
                "anchor": e.anchor,
                "baseline": e.baseline,
                "problem": e.problem,
                "channels": {
                    name: {
                        "mean": number(c.mean),
                        "offset": number(c.offset),
                        "sd": number(c.sd),
                        "cpk": number(c.cpk),
                        "capable": c.capable,
                    }
                    for name, c in e.channels.items()
                },
            }
            for e in history.entries
        ],
        "trends": [
            {
                "channel": t.channel,
                "procedure": t.procedure,
                "sessions": t.sessions,
                "slope_per_day": t.slope_per_day,
                "ci_low": t.ci_low,
                "ci_high": t.ci_high,
                "p_value": t.p_value,
                "significant": t.significant,
                "limit": t.limit,
                "limit_name": t.limit_name,
                "crossing": t.crossing,
                "sentence": t.sentence,
            }
            for t in history.trends
        ],
    }


def format_history(history: RobotHistory) -> list[str]:
    """The text of ``station history``: the table, charts of RP and Cpk, the trends."""
    unit, resolution = history.unit, history.resolution
    lines = [f"History of robot {plain(history.robot)} ({len(history.entries)} sessions)"]
    lines.append(f"Sessions folder: {plain(history.folder)}")
    lines.append("")
    for number, entry in enumerate(history.entries, start=1):
        mark = "  [baseline]" if entry.baseline else ""
        moment = parse_time(entry.created)
        when = moment.strftime("%Y-%m-%d %H:%M") if isinstance(moment, datetime) else entry.created
        rp = "—" if entry.rp is None else format_spread(entry.rp, entry.resolution)
        lines.append(
            f"{number:>3}. {when}  {plain(entry.procedure)}  {entry.verdict}  RP {rp} {unit}{mark}"
        )
        for name, c in entry.channels.items():
            sd = "—" if c.sd is None else format_spread(c.sd, entry.resolution)
            cpk = "—" if c.cpk is None else format_index(c.cpk)
            offset = format_figure(c.offset, entry.resolution)
            lines.append(f"       {plain(name):<10} offset {offset}  σ {sd}  Cpk {cpk}")
        if entry.problem:
            lines.append(f"       {plain(entry.problem)}")
        lines.append(f"       anchor {entry.anchor}  ({plain(entry.path.name)})")
    rps = [e.rp for e in history.entries]
    if any(v is not None for v in rps):

        def rp_label(value: float) -> str:
            return format_spread(value, resolution)

        lines += ["", f"RP over the sessions ({unit}):", *text_chart(rps, label=rp_label)]
    channels = list(dict.fromkeys(n for e in history.entries for n in e.channels))
    for name in channels:
        cpks = [e.channels[name].cpk if name in e.channels else None for e in history.entries]
        if any(v is not None for v in cpks):
            lines += ["", f"Cpk of {plain(name)} over the sessions:", *text_chart(cpks, height=5)]
    if history.trends:
        lines += ["", f"Wear trend ({history.trends[0].procedure} sessions):"]
        lines += [f"  {plain(t.sentence)}" for t in history.trends]
    if history.skipped:
        lines += ["", f"Left out ({len(history.skipped)} files that could not be read):"]
        lines += [f"  {plain(path.name)}: {plain(why)}" for path, why in history.skipped]
    return lines
