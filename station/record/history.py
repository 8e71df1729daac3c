"""A robot's history: every session of it in time order, the figures that follow it over the
months (RP, per-axis mean offset, σ, Cpk, verdict, anchor), and the wear trend.

The wear trend is, per channel, two least-squares lines against the date, each slope with its
confidence interval (Student's t on n − 2 degrees of freedom) and p (the report's periodic
testing, §1.3: a robot that wears drifts off its nominal and scatters more):

* **Cpk** of each session against the latest session's threshold. Only where its slope is
  significant (the interval excludes 0) is a date given: the day the line reaches the threshold,
  with the range of days at which the true line may reach it (Fieller's inverse-regression
  interval, :func:`threshold_crossing`, finite exactly when the slope is significant). Cpk is
  what a verdict turns on, so its date is the one that matters; otherwise the sentence says
  there is no significant trend and gives no date.
* the **mean**, described (per 30 days) but never dated: a mean that reaches a limit has half
  its returns out already.

Only sessions of the latest session's procedure and unit are trended together.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from datetime import datetime, timedelta
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.diagnostics import p_phrase
from station.errors import StationError
from station.record.baseline import baseline_for
from station.record.content import parse_time
from station.record.source import AnalysedSession, analyse_loaded
from station.record.text import plain
from station.session.model import load_session
from station.session.store import session_paths
from station.text import (
    UNDEFINED,
    format_figure,
    format_index,
    format_spread,
    overall_judgement,
)

if TYPE_CHECKING:
    from station.record.index import SessionIndex

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
    threshold: float | None = None
    """The Cpk the session's verdict holds the channel to."""


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
    """The wear trend of one channel over the sessions.

    The mean: its slope per day with the confidence interval and p-value (described, never
    dated: by the time the mean reaches a limit half the returns are already out). Cpk: its
    slope per day with interval and p; where that slope is significant, ``crossing`` is the date
    the line reaches ``threshold`` and ``crossing_low``/``crossing_high`` the range of dates
    at which the true line may reach it (:func:`threshold_crossing`); None otherwise (no
    significant trend, no Cpk, or a date beyond the calendar)."""

    channel: str
    procedure: str
    sessions: int
    slope_per_day: float
    ci_low: float
    ci_high: float
    p_value: float
    significant: bool
    cpk_sessions: int = 0
    cpk_slope_per_day: float | None = None
    cpk_ci_low: float | None = None
    cpk_ci_high: float | None = None
    cpk_p_value: float | None = None
    cpk_significant: bool = False
    threshold: float | None = None
    crossing: str | None = None
    crossing_low: str | None = None
    crossing_high: str | None = None
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


@dataclass(frozen=True)
class SessionFigures:
    """What one session file gives a history: whose it is, when, and its figures, or why it
    could not be read. What the session index keeps of a file (:mod:`station.record.index`)."""

    path: Path
    robot: str | None
    """None when the file does not load (then ``error`` says why)."""
    created: str = ""
    session_id: str = ""
    entry: HistoryEntry | None = None
    """None when the file could not be read or analysed (``error``), or was not analysed
    (another robot's, read for a single robot's history)."""
    error: str | None = None


def session_figures(path: Path, *, robot: str | None = None) -> SessionFigures:
    """The figures of the session file ``path``, read-only; a file that cannot be read or
    analysed gives its error, never raises it. With ``robot``, another robot's session is
    loaded (its chain checked: a damaged file is named in every history) but not analysed."""
    try:
        session = load_session(path, recover=False)
    except StationError as error:
        return SessionFigures(path, None, error=error.message)
    found = SessionFigures(path, session.robot, session.created, session.session_id)
    if robot is not None and session.robot != robot:
        return found
    try:
        return replace(found, entry=_entry(analyse_loaded(session)))
    except StationError as error:
        return replace(found, error=error.message)


def _entry(analysed: AnalysedSession) -> HistoryEntry:
    """A history's line of ``analysed`` (``baseline`` is marked when a history is built: the
    robot's baseline can change while the file does not)."""
    path = analysed.path
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
                threshold=cap.threshold,
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


def threshold_crossing(
    days: Sequence[float],
    values: Sequence[float],
    threshold: float,
    *,
    confidence: float = 0.95,
) -> tuple[float, float, float] | None:
    """When the least-squares line of ``values`` against ``days`` reaches ``threshold``:
    (day, low, high), the range being Fieller's interval (inverse regression): the days at
    which ``threshold`` lies inside the line's confidence band,
    (a + b·x − T)² ≤ t²·s²·(1/n + (x − x̄)²/Sxx), t on n − 2 degrees of freedom. The range is
    finite exactly when the slope is significant at ``confidence`` (its interval excludes 0);
    None otherwise, with fewer than three points or all on one day."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(days, dtype=float)
    y = np.asarray(values, dtype=float)
    if x.size < 3 or np.ptp(x) == 0:
        return None
    n = x.size
    mean_x, mean_y = float(x.mean()), float(y.mean())
    sxx = float(((x - mean_x) ** 2).sum())
    slope = float(((x - mean_x) * (y - mean_y)).sum() / sxx)
    residual = y - (mean_y + slope * (x - mean_x))
    s2 = float((residual**2).sum() / (n - 2))
    t2 = float(stats.t.ppf(0.5 + confidence / 2, n - 2)) ** 2
    a = slope * slope - t2 * s2 / sxx
    if slope == 0 or a <= 0:
        return None  # the band holds a flat line: any day, or none, could be the one
    gap = threshold - mean_y
    root = math.sqrt(max(0.0, slope * slope * gap * gap - a * (gap * gap - t2 * s2 / n)))
    low, high = sorted(((slope * gap - root) / a, (slope * gap + root) / a))
    return mean_x + gap / slope, mean_x + low, mean_x + high


def _date(first: datetime, day: float) -> str | None:
    """The calendar date ``day`` days after ``first``; None beyond the calendar."""
    try:
        return (first + timedelta(days=day)).strftime("%Y-%m-%d")
    except (OverflowError, ValueError):
        return None


def _cpk_sentence(
    channel: str,
    fit: tuple[float, float, float, float, float],
    threshold: float,
    crossing: tuple[str | None, str | None, str | None] | None,
    latest_day: float,
    day: float | None,
) -> str:
    slope, low, high, p_value, _ = fit
    interval = (
        f"(95% CI {format_index(low * 30)} to {format_index(high * 30)}, {p_phrase(p_value)})"
    )
    if crossing is None or day is None:
        return f"{channel}: Cpk shows no significant trend {interval}: no date is given."
    word = "falls" if slope < 0 else "rises"
    per_30 = f"Cpk {word} {format_index(abs(slope) * 30)} per 30 days {interval}"
    date, earliest, latest = (d or "beyond 9999" for d in crossing)
    span = f"(95% range {earliest} to {latest})"
    level = format_index(threshold)
    if day > latest_day:
        return (
            f"{channel}: {per_30}; at this rate it reaches the threshold {level} on {date} {span}."
        )
    side = "below" if slope < 0 else "above"
    return (
        f"{channel}: {per_30}; the trend line crossed the threshold {level} on {date} {span} "
        f"and is {side} it now."
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

    def day_of(entry: HistoryEntry) -> float:
        return (parse_time(entry.created) - first).total_seconds() / SECONDS_PER_DAY  # type: ignore[operator]

    trends = []
    for channel in same[-1].channels:
        rows = [e for e in same if channel in e.channels]
        days = [day_of(e) for e in rows]
        fit = wear_trend(days, [e.channels[channel].mean for e in rows])
        if fit is None:
            continue
        slope, low, high, p_value, _ = fit
        significant = low > 0 or high < 0
        interval = (
            f"(95% CI {format_figure(low * 30, resolution)} to "
            f"{format_figure(high * 30, resolution)}, {p_phrase(p_value)})"
        )
        if significant:
            per_30 = f"{format_figure(slope * 30, resolution, unit=unit)} per 30 days"
            mean_sentence = f"The mean moves {per_30} {interval}."
        else:
            mean_sentence = f"The mean shows no significant trend {interval}."
        # Cpk against the threshold of the latest session: the date a verdict would change.
        threshold = rows[-1].channels[channel].threshold
        judged = [e for e in rows if e.channels[channel].cpk is not None]
        cpk_days = [day_of(e) for e in judged]
        cpks = [float(e.channels[channel].cpk) for e in judged]  # type: ignore[arg-type]
        cpk_fit = wear_trend(cpk_days, cpks) if threshold is not None else None
        crossing = None
        day = None
        if cpk_fit is not None and threshold is not None:
            found = threshold_crossing(cpk_days, cpks, threshold)
            if found is not None:
                day = found[0]
                crossing = (_date(first, found[0]), _date(first, found[1]), _date(first, found[2]))
        if threshold is None or not judged:
            cpk_sentence = f"{channel}: no Cpk to trend (no session has limits for it)."
        elif cpk_fit is None:
            cpk_sentence = f"{channel}: too few sessions with a Cpk ({len(judged)}) for its trend."
        else:
            cpk_sentence = _cpk_sentence(channel, cpk_fit, threshold, crossing, cpk_days[-1], day)
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
                cpk_sessions=len(judged),
                cpk_slope_per_day=None if cpk_fit is None else cpk_fit[0],
                cpk_ci_low=None if cpk_fit is None else cpk_fit[1],
                cpk_ci_high=None if cpk_fit is None else cpk_fit[2],
                cpk_p_value=None if cpk_fit is None else cpk_fit[3],
                cpk_significant=crossing is not None,
                threshold=threshold,
                crossing=None if crossing is None else crossing[0],
                crossing_low=None if crossing is None else crossing[1],
                crossing_high=None if crossing is None else crossing[2],
                sentence=f"{cpk_sentence} {mean_sentence}",
            )
        )
    return tuple(trends)


def robot_history(
    folder: str | Path, robot: str, *, index: SessionIndex | None = None
) -> RobotHistory:
    """Every session of ``robot`` (exact name) in ``folder``, oldest first, with the trends.
    Files that do not load are left out and listed in ``skipped`` with why. StationError when
    the robot has no session there. With ``index`` the figures of the files that did not
    change since it last read them come from it (the same history, from a cache)."""
    folder = Path(folder)
    if index is None:
        files = [session_figures(path, robot=robot) for path in session_paths(folder)]
    else:
        files = index.figures(folder, robot=robot)
    if not any(f.robot == robot for f in files):
        raise StationError(f"no session of robot {robot!r} in {folder}; check the name.")
    return _history(folder, robot, files)


def _history(folder: Path, robot: str, files: Sequence[SessionFigures]) -> RobotHistory:
    """The history of ``robot`` from the figures of the folder's files."""
    try:
        baseline = baseline_for(robot)
    except StationError:
        baseline = None  # a damaged baseline must not hide the history; `baseline` says why
    baseline_session = None if baseline is None else str(baseline.get("session"))
    # Another robot's file is named only when it does not load at all (whose it is is unknown).
    skipped = [(f.path, f.error) for f in files if f.error is not None and f.robot in (None, robot)]
    mine = sorted((f for f in files if f.robot == robot), key=lambda f: (f.created, f.path.name))
    entries = [
        replace(f.entry, baseline=f.session_id == baseline_session)
        for f in mine
        if f.entry is not None
    ]
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


@dataclass(frozen=True)
class RobotLine:
    """One robot of ``station history --all``: its latest session and its trend in a word."""

    robot: str
    sessions: int
    latest: HistoryEntry
    trend: str
    """:func:`trend_word` of its trends."""
    unit: str


@dataclass(frozen=True)
class FleetHistory:
    """Every robot of a sessions folder, one line each, and the files that could not be read."""

    folder: Path
    robots: tuple[RobotLine, ...]
    skipped: tuple[tuple[Path, str], ...] = ()


def trend_word(trends: Sequence[Trend]) -> str:
    """A robot's trend in a word: ``falling`` when some channel's Cpk falls significantly
    (wear), ``rising`` when one rises and none falls, ``drifting`` when no Cpk moves
    significantly but a mean does, ``steady`` when nothing does, ``-`` when there are too
    few sessions for a trend."""

    def cpk_moves(t: Trend, down: bool) -> bool:
        if t.cpk_ci_low is None or t.cpk_ci_high is None:
            return False
        return t.cpk_ci_high < 0 if down else t.cpk_ci_low > 0

    if not trends:
        return "-"
    if any(cpk_moves(t, down=True) for t in trends):
        return "falling"
    if any(cpk_moves(t, down=False) for t in trends):
        return "rising"
    return "drifting" if any(t.significant for t in trends) else "steady"


def fleet_history(folder: str | Path, *, index: SessionIndex | None = None) -> FleetHistory:
    """One line per robot of ``folder`` (by name): its latest session's verdict and figures
    and its trend, robots in name order; the files that could not be read in ``skipped``.
    A robot none of whose files could be read has no line, only its files in ``skipped``."""
    folder = Path(folder)
    if index is None:
        files = [session_figures(path) for path in session_paths(folder)]
    else:
        files = index.figures(folder)
    lines = []
    for robot in sorted({f.robot for f in files if f.robot is not None}, key=str.casefold):
        history = _history(folder, robot, files)
        if history.entries:
            lines.append(
                RobotLine(
                    robot=robot,
                    sessions=len(history.entries),
                    latest=history.entries[-1],
                    trend=trend_word(history.trends),
                    unit=history.unit,
                )
            )
    skipped = sorted((f.path, f.error) for f in files if f.error is not None)
    return FleetHistory(folder=folder, robots=tuple(lines), skipped=tuple(skipped))


def lowest_cpk(entry: HistoryEntry) -> float | None:
    """The lowest Cpk of the session's channels (the one its verdict turns on); None when no
    channel has one."""
    cpks = [c.cpk for c in entry.channels.values() if c.cpk is not None and math.isfinite(c.cpk)]
    return min(cpks, default=None)


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
                "cpk_sessions": t.cpk_sessions,
                "cpk_slope_per_day": t.cpk_slope_per_day,
                "cpk_ci_low": t.cpk_ci_low,
                "cpk_ci_high": t.cpk_ci_high,
                "cpk_p_value": t.cpk_p_value,
                "cpk_significant": t.cpk_significant,
                "threshold": t.threshold,
                "crossing": t.crossing,
                "crossing_range": [t.crossing_low, t.crossing_high],
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


def fleet_json(fleet: FleetHistory) -> dict[str, Any]:
    """The JSON document of ``station history --all --json``."""

    def number(value: float | None) -> float | None:
        return None if value is None or not math.isfinite(value) else float(value)

    return {
        "folder": str(fleet.folder),
        "robots": [
            {
                "robot": line.robot,
                "sessions": line.sessions,
                "latest": line.latest.created,
                "file": line.latest.path.name,
                "procedure": line.latest.procedure,
                "verdict": line.latest.verdict,
                "rp": number(line.latest.rp),
                "cpk": number(lowest_cpk(line.latest)),
                "unit": line.unit,
                "trend": line.trend,
            }
            for line in fleet.robots
        ],
        "skipped": [{"file": path.name, "error": why} for path, why in fleet.skipped],
    }


def format_fleet(fleet: FleetHistory) -> list[str]:
    """The text of ``station history --all``: one line per robot (latest session's date,
    verdict, RP and lowest Cpk, the trend in a word), fitting 80 columns."""
    sessions = sum(line.sessions for line in fleet.robots)
    lines = [f"Robots in the sessions folder: {len(fleet.robots)} ({sessions} sessions)"]
    lines.append(f"Sessions folder: {plain(fleet.folder)}")
    lines.append("")
    lines.append(f"{'robot':<14}{'latest':<12}{'verdict':<22}{'RP':<14}{'Cpk':>5}  trend")
    for line in fleet.robots:
        entry = line.latest
        moment = parse_time(entry.created)
        when = moment.strftime("%Y-%m-%d") if isinstance(moment, datetime) else entry.created
        rp = "-" if entry.rp is None else f"{format_spread(entry.rp, entry.resolution)} {line.unit}"
        cpk = format_index(lowest_cpk(entry))
        lines.append(
            f"{plain(line.robot, limit=13):<14}{plain(when, limit=11):<12}"
            f"{plain(entry.verdict, limit=21):<22}{rp:<14}{cpk:>5}  {line.trend}"
        )
    lines += [
        "",
        "Cpk: the latest session's lowest; trend: of Cpk over the robot's sessions (falling,",
        "rising), else of the mean (drifting), else steady; - with fewer than three sessions.",
        "station history ROBOT shows one robot's sessions and the dates of its trend.",
    ]
    if fleet.skipped:
        lines += ["", f"Left out ({len(fleet.skipped)} files that could not be read):"]
        lines += [f"  {plain(path.name)}: {plain(why)}" for path, why in fleet.skipped]
    return lines
