"""Linearity along a parallel bar (the report's §2.9): straightness per stroke, path repeatability.

Two perpendicular indicators (horizontal ``h``, vertical ``v``) ride on the end effector while a
linear scale ``s`` tracks the position along the bar. Per stroke and per indicator:

* the **least-squares** reference line d = a + b·s and the peak-to-valley of its residuals
  (ISO 230-1's straightness error w.r.t. the LS line);
* the **minimum-zone** (Chebyshev) straightness: the narrowest strip between two parallel lines
  that holds every point (ISO 1101, ISO 12780). It is computed exactly: the strip's width as a
  function of the slope b, w(b) = max(d − b·s) − min(d − b·s), is convex and piecewise linear
  with its breaks at the slopes of the convex hull's edges, so a binary search over those slopes
  finds the minimum to float precision. MZ ≤ LS always.

Widths are measured **along the indicator axis** (the deviation an indicator shows), not
perpendicular to the reference line: the perpendicular width is the vertical one times
1/sqrt(1 + b²), which for the tiny slopes of a set-up (b ≈ 1e-4) is 1 − 5e-9: no difference
at any indicator's resolution.

Across strokes, the **path repeatability** along the bar: the bar is cut into bins of position;
per bin, the mean and 3·s (n − 1) over strokes of each stroke's mean reading in the bin; the
figure is the largest 3·s over the bar. The readings themselves are used (as zeroed), not each
stroke's residuals, because a stroke that runs offset or tilted is itself a path that does
not repeat.

Per-stroke MZ straightness is judged against a tolerance as a one-sided characteristic
(USL = tolerance, no LSL: straightness cannot be negative), with the same capability, control
chart and run rules as the repeatability readings
(:func:`~station.analysis.summary.analyze_channel`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.document import channel_to_json
from station.analysis.document import json_number as _number
from station.analysis.strokes import (
    DIRECTIONS,
    StrokeProfile,
)
from station.analysis.summary import (
    Analysis,
    AnalysisConfig,
    ChannelAnalysis,
    analyze_channel,
)
from station.errors import StationError
from station.text import format_figure

#: The indicator channels of the linearity set-up, and the scale.
INDICATORS = ("h", "v")
SCALE = "s"
NO_TOLERANCE_MESSAGE = (
    "no straightness tolerance: give a tolerance, or limits on h and v in the procedure"
)


@dataclass(frozen=True, eq=False)  # arrays: compare the fields, not the objects
class Straightness:
    """The straightness of one profile d(s), measured along the indicator axis.

    ``ls_line`` and ``mz_line`` are ``(a, b)`` of d = a + b·s (``mz_line`` is the centre line of
    the minimum zone); ``ls`` is the peak-to-valley of ``residuals_ls``; ``mz`` the zone's width.
    """

    ls: float
    mz: float
    ls_line: tuple[float, float]
    mz_line: tuple[float, float]
    residuals_ls: np.ndarray = field(repr=False)
    residuals_mz: np.ndarray = field(repr=False)
    n: int = 0


def _profile(s: Any, d: Any) -> tuple[np.ndarray, np.ndarray]:
    s = np.asarray(s, dtype=float).ravel()
    d = np.asarray(d, dtype=float).ravel()
    if s.shape != d.shape:
        raise StationError(
            f"a profile needs one position per deviation ({s.size} positions, {d.size} deviations)."
        )
    if s.size < 2:
        raise StationError(f"a straightness needs at least 2 points along the bar (have {s.size}).")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(d))):
        raise StationError("a profile holds a value that is not a finite number.")
    if np.ptp(s) == 0:
        raise StationError(
            "the scale did not move during the stroke (every position is the same): "
            "check that the linear scale is connected to the holder."
        )
    return s, d


def _hull_chain(points: np.ndarray) -> np.ndarray:
    """One monotone chain (Andrew): the lower hull of points sorted by x, then y."""
    chain: list[int] = []
    for i in range(len(points)):
        while len(chain) >= 2:
            o, a = points[chain[-2]], points[chain[-1]]
            b = points[i]
            cross = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
            if cross > 0:
                break
            chain.pop()
        chain.append(i)
    return np.asarray(chain)


def convex_hull(s: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The vertices of the convex hull of the points (s, d), as an (m, 2) array."""
    points = np.unique(np.column_stack([s, d]), axis=0)  # sorted by s, then d
    if len(points) <= 2:
        return points
    lower = points[_hull_chain(points)]
    upper = points[::-1][_hull_chain(points[::-1])]
    return np.concatenate([lower[:-1], upper[:-1]])


def _width(hull: np.ndarray, slope: float) -> float:
    intercepts = hull[:, 1] - slope * hull[:, 0]
    return float(intercepts.max() - intercepts.min())


def minimum_zone(s: Any, d: Any) -> tuple[float, tuple[float, float]]:
    """The minimum-zone width of d(s) along d, and the zone's centre line ``(a, b)``.

    Exact: the width w(b) is convex in b with breaks only at hull-edge slopes; the minimum is at
    one of them, found by binary search on the sorted slopes (w evaluated on the hull vertices).
    """
    s, d = _profile(s, d)
    hull = convex_hull(s, d)
    edges = np.diff(np.concatenate([hull, hull[:1]]), axis=0)
    edges = edges[edges[:, 0] != 0]  # vertical edges (same s) do not define a strip direction
    slopes = np.unique(edges[:, 1] / edges[:, 0])
    if slopes.size == 0:
        slopes = np.zeros(1)
    low, high = 0, slopes.size - 1
    while low < high:
        middle = (low + high) // 2
        # w is convex: once it stops falling, the minimum lies at or left of here.
        if _width(hull, slopes[middle]) <= _width(hull, slopes[middle + 1]):
            high = middle
        else:
            low = middle + 1
    slope = float(slopes[low])
    intercepts = hull[:, 1] - slope * hull[:, 0]
    centre = float(intercepts.max() + intercepts.min()) / 2
    return float(intercepts.max() - intercepts.min()), (centre, slope)


def least_squares_line(s: Any, d: Any) -> tuple[float, float]:
    """The least-squares line d = a + b·s, as ``(a, b)``."""
    s, d = _profile(s, d)
    s_mean, d_mean = float(s.mean()), float(d.mean())
    span = float(np.ptp(s))
    # Positions scaled to the travel: the sums of squares neither underflow nor overflow.
    scaled = (s - s_mean) / span
    slope = float(scaled @ (d - d_mean) / (scaled @ scaled)) / span
    return d_mean - slope * s_mean, slope


def straightness(s: Any, d: Any) -> Straightness:
    """The least-squares and minimum-zone straightness of the profile d(s) (see the module)."""
    s, d = _profile(s, d)
    ls_line = least_squares_line(s, d)
    residuals_ls = d - (ls_line[0] + ls_line[1] * s)
    mz, mz_line = minimum_zone(s, d)
    residuals_mz = d - (mz_line[0] + mz_line[1] * s)
    ls = float(residuals_ls.max() - residuals_ls.min())
    # The minimum is never above another line's width; equal up to rounding when LS is optimal.
    mz = min(mz, ls)
    return Straightness(
        ls=ls,
        mz=mz,
        ls_line=ls_line,
        mz_line=mz_line,
        residuals_ls=residuals_ls,
        residuals_mz=residuals_mz,
        n=int(s.size),
    )


# ----------------------------------------------------------------------------------------------
# Strokes


# ----------------------------------------------------------------------------------------------
# Path repeatability


@dataclass(frozen=True, eq=False)  # arrays: compare the fields, not the objects
class PathRepeatability:
    """Per position along the bar: the mean and 3·s over strokes; ``max_3s`` is the largest.

    ``positions`` are the bin centres; ``counts`` how many strokes had points in each bin
    (3·s is None-like NaN where fewer than 2 did). ``at`` is the position of ``max_3s``.
    """

    positions: np.ndarray = field(repr=False)
    mean: np.ndarray = field(repr=False)
    three_s: np.ndarray = field(repr=False)
    counts: np.ndarray = field(repr=False)
    max_3s: float | None
    at: float | None
    strokes: int


def path_repeatability(
    profiles: Sequence[tuple[Any, Any]], bins: int | Sequence[float] = 20
) -> PathRepeatability:
    """The path repeatability of profiles ``(s, d)`` (one per stroke) along the bar.

    ``bins`` is a number of equal bins over the stretch every stroke covers, or the bin edges.
    Each stroke contributes the mean of its points in a bin (so strokes sampled at different
    positions or rates weigh the same).
    """
    pairs = [(np.asarray(s, dtype=float), np.asarray(d, dtype=float)) for s, d in profiles]
    if isinstance(bins, int):
        if bins < 1:
            raise StationError(f"the number of bins must be 1 or more, not {bins}.")
        if not pairs:
            edges = np.zeros(0)
        else:
            low = max(float(s.min()) for s, _ in pairs)
            high = min(float(s.max()) for s, _ in pairs)
            if not high > low:
                low = min(float(s.min()) for s, _ in pairs)
                high = max(float(s.max()) for s, _ in pairs)
            edges = np.linspace(low, high, bins + 1)
    else:
        edges = np.asarray(bins, dtype=float)
    size = max(edges.size - 1, 0)
    table = np.full((len(pairs), size), np.nan)
    for row, (s, d) in enumerate(pairs):
        where = np.searchsorted(edges, s, side="right") - 1
        where[s == edges[-1]] = size - 1 if size else 0  # the last edge closes the last bin
        inside = (where >= 0) & (where < size) & (s >= edges[0]) & (s <= edges[-1])
        sums = np.bincount(where[inside], weights=d[inside], minlength=size)
        counts = np.bincount(where[inside], minlength=size)
        with np.errstate(invalid="ignore", divide="ignore"):
            table[row] = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    counts = np.sum(np.isfinite(table), axis=0)
    mean = np.full(size, np.nan)
    three_s = np.full(size, np.nan)
    for column in range(size):
        values = table[np.isfinite(table[:, column]), column]
        if values.size:
            mean[column] = values.mean()
        if values.size >= 2:
            three_s[column] = 3.0 * values.std(ddof=1)
    positions = (edges[:-1] + edges[1:]) / 2 if size else np.zeros(0)
    defined = np.isfinite(three_s)
    best = int(np.nanargmax(three_s)) if defined.any() else None
    return PathRepeatability(
        positions=positions,
        mean=mean,
        three_s=three_s,
        counts=counts,
        max_3s=None if best is None else float(three_s[best]),
        at=None if best is None else float(positions[best]),
        strokes=len(pairs),
    )


# ----------------------------------------------------------------------------------------------
# The whole analysis


@dataclass(frozen=True)
class StrokeResult:
    """One stroke's straightness per indicator channel (``recorded``: see StrokeProfile)."""

    number: int
    direction: str
    points: int
    travel: float
    straightness: Mapping[str, Straightness]
    recorded: int | None = None


@dataclass(frozen=True)
class DirectionSummary:
    """Per direction and channel: how many strokes, the largest and the mean LS and MZ."""

    direction: str
    strokes: int
    ls_max: Mapping[str, float]
    mz_max: Mapping[str, float]
    ls_mean: Mapping[str, float]
    mz_mean: Mapping[str, float]
    path: Mapping[str, PathRepeatability]


@dataclass(frozen=True)
class LinearityAnalysis:
    """Straightness per stroke, per direction and overall; path repeatability; the verdict.

    ``ls``/``mz`` hold the largest per-stroke straightness of each channel. ``judged`` holds,
    per channel, the analysis of the per-stroke MZ straightness as one reading per stroke
    (descriptive figures, control chart and alarms, one-sided capability against
    ``tolerance``).
    """

    channels: tuple[str, ...]
    strokes: tuple[StrokeResult, ...]
    directions: Mapping[str, DirectionSummary]
    ls: Mapping[str, float]
    mz: Mapping[str, float]
    path: Mapping[str, PathRepeatability]
    judged: Mapping[str, ChannelAnalysis]
    tolerance: float | None
    config: AnalysisConfig
    unit: str = ""


def _straightness_config(
    config: AnalysisConfig | None, channels: Sequence[str], tolerance: float | None
) -> AnalysisConfig:
    base = config or AnalysisConfig()
    limits = {} if tolerance is None else {c: SpecLimits(usl=tolerance) for c in channels}
    # The straightness is a width, never negative: its nominal (the ideal) is 0.
    return replace(
        base, limits=limits, default_limits=None, subgroup=1, nominal=dict.fromkeys(channels, 0.0)
    )


def analyze_linearity(
    profiles: Sequence[StrokeProfile],
    *,
    tolerance: float | None = None,
    config: AnalysisConfig | None = None,
    bins: int = 20,
) -> LinearityAnalysis:
    """Analyse strokes: LS and MZ straightness of every indicator channel against s per stroke
    and per direction, the largest over strokes, path repeatability along the bar (all strokes
    and per direction), and per channel the per-stroke MZ straightness judged against
    ``tolerance`` (one-sided, USL = tolerance) with a control chart and run rules.

    ``config`` supplies the resolution, unit, rule set and threshold (its limits are replaced
    by the tolerance).
    """
    if not profiles:
        raise StationError(
            "no complete stroke along the bar: the scale must travel from one end to the other."
        )
    if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
        raise StationError(
            f"the straightness tolerance must be a positive number, not {tolerance}."
        )
    channels = tuple(profiles[0].channels)
    if not channels:
        raise StationError("the strokes carry no indicator channel (h, v).")
    results = []
    for profile in profiles:
        missing = [c for c in channels if c not in profile.channels]
        if missing:
            raise StationError(f"stroke {profile.number} has no channel {missing[0]!r}.")
        results.append(
            StrokeResult(
                number=profile.number,
                direction=profile.direction,
                points=int(profile.s.size),
                travel=float(np.ptp(profile.s)),
                straightness={c: straightness(profile.s, profile.channels[c]) for c in channels},
                recorded=profile.recorded,
            )
        )

    def paths(selected: Sequence[StrokeProfile]) -> dict[str, PathRepeatability]:
        return {
            c: path_repeatability([(p.s, p.channels[c]) for p in selected], bins) for c in channels
        }

    directions = {}
    for direction in DIRECTIONS:
        chosen = [r for r in results if r.direction == direction]
        if not chosen:
            continue
        figures = {
            key: {c: [getattr(r.straightness[c], key) for r in chosen] for c in channels}
            for key in ("ls", "mz")
        }
        directions[direction] = DirectionSummary(
            direction=direction,
            strokes=len(chosen),
            ls_max={c: max(v) for c, v in figures["ls"].items()},
            mz_max={c: max(v) for c, v in figures["mz"].items()},
            ls_mean={c: float(np.mean(v)) for c, v in figures["ls"].items()},
            mz_mean={c: float(np.mean(v)) for c, v in figures["mz"].items()},
            path=paths([p for p in profiles if p.direction == direction]),
        )
    judge_config = _straightness_config(config, channels, tolerance)
    judged = {
        c: analyze_channel(c, np.asarray([r.straightness[c].mz for r in results]), judge_config)
        for c in channels
    }
    if tolerance is None:
        judged = {
            c: replace(a, capability=replace(a.capability, message=NO_TOLERANCE_MESSAGE))
            for c, a in judged.items()
        }
    return LinearityAnalysis(
        channels=channels,
        strokes=tuple(results),
        directions=directions,
        ls={c: max(r.straightness[c].ls for r in results) for c in channels},
        mz={c: max(r.straightness[c].mz for r in results) for c in channels},
        path=paths(profiles),
        judged=judged,
        tolerance=tolerance,
        config=judge_config,
        unit=judge_config.unit,
    )


def linearity_json(result: LinearityAnalysis) -> dict[str, Any]:
    """The ``"linearity"`` document of ``station analyze --json`` (straightness in the readings'
    unit; ``h.ls``/``h.mz`` at the top are the largest over strokes; ``path_repeatability`` per
    channel is the largest 3·s along the bar)."""
    channels = result.channels
    document: dict[str, Any] = {
        c: {"ls": _number(result.ls[c]), "mz": _number(result.mz[c])} for c in channels
    }
    document["strokes"] = [
        {
            "stroke": r.number,
            "recorded_stroke": r.recorded,
            "direction": r.direction,
            "points": r.points,
            "travel": _number(r.travel),
            **{
                c: {
                    "ls": _number(r.straightness[c].ls),
                    "mz": _number(r.straightness[c].mz),
                    "slope": _number(r.straightness[c].ls_line[1]),
                }
                for c in channels
            },
        }
        for r in result.strokes
    ]
    document["directions"] = {
        d.direction: {
            "strokes": d.strokes,
            **{
                c: {
                    "ls_max": _number(d.ls_max[c]),
                    "mz_max": _number(d.mz_max[c]),
                    "ls_mean": _number(d.ls_mean[c]),
                    "mz_mean": _number(d.mz_mean[c]),
                    "path_repeatability": _number(d.path[c].max_3s),
                }
                for c in channels
            },
        }
        for d in result.directions.values()
    }
    document["path_repeatability"] = {c: _number(result.path[c].max_3s) for c in channels}
    document["path_profile"] = {
        c: [
            {
                "s": _number(position),
                "mean": _number(mean),
                "three_s": _number(three_s),
                "strokes": int(count),
            }
            for position, mean, three_s, count in zip(
                p.positions, p.mean, p.three_s, p.counts, strict=True
            )
        ]
        for c, p in result.path.items()
    }
    document["tolerance"] = _number(result.tolerance)
    document["straightness"] = {c: channel_to_json(result.judged[c]) for c in channels}
    return document


def linearity_hints(result: LinearityAnalysis) -> tuple[str, ...]:
    """What stands out in a linearity analysis, in the report's manner of hints."""
    hints: list[str] = []
    unit = f" {result.unit}" if result.unit else ""
    resolution = result.config.resolution

    def figure(value: float) -> str:
        return format_figure(value, resolution, signed=False)

    for c in result.channels:
        values = [r.straightness[c].mz for r in result.strokes]
        if result.tolerance is not None:
            over = sum(v > result.tolerance for v in values)
            if over:
                hints.append(
                    f"{c}: {over} of {len(values)} strokes exceed the straightness tolerance "
                    f"{figure(result.tolerance)}{unit} (largest {figure(max(values))}{unit}): the "
                    "path "
                    "bends more than allowed; compare with the bar's own straightness."
                )
        if len(result.directions) == 2:
            forward, backward = (result.directions[d] for d in DIRECTIONS)
            low, high = sorted((forward.mz_mean[c], backward.mz_mean[c]))
            if low > 0 and high > 1.5 * low:
                hints.append(
                    f"{c}: the straightness differs by direction (mean MZ A→B "
                    f"{figure(forward.mz_mean[c])}, B→A {figure(backward.mz_mean[c])}{unit}): "
                    "look at "
                    "backlash or the controller's tracking in one direction."
                )
        alarms = result.judged[c].alarms
        if alarms:
            rules = ", ".join(sorted({a.rule for a in alarms}))
            hints.append(
                f"{c}: the straightness per stroke raises alarms ({rules}): look at the pattern "
                "(a trend suggests warm-up or a loosening set-up)."
            )
    return tuple(hints)


def linearity_summary(result: LinearityAnalysis) -> Analysis:
    """An :class:`~station.analysis.summary.Analysis` whose channels are the per-stroke MZ
    straightness of each indicator (what ``station analyze`` and a verdict judge), with the
    linearity hints instead of the repeatability ones (an offset from 0 is no fault here)."""
    named = {
        c: replace(judged, name=f"{c} straightness (MZ, one reading per stroke)")
        for c, judged in result.judged.items()
    }
    return Analysis(
        channels=named,
        spatial=None,
        config=result.config,
        given_hints=linearity_hints(result),
    )


def tolerance_from_limits(config: AnalysisConfig) -> float | None:
    """The straightness tolerance a procedure's limits imply: the width USL − LSL of the
    indicators' (h, v) limits, the smallest when they differ; None without two-sided limits.

    A procedure file states the tolerance as limits about the reference line (e.g. h within
    ±0.001 in): the zone the deviations must keep within is then 0.002 in wide.
    """
    widths = []
    for channel in INDICATORS:
        limits = config.limits_for(channel)
        if limits is not None and limits.lsl is not None and limits.usl is not None:
            widths.append(limits.usl - limits.lsl)
    return min(widths) if widths else None
