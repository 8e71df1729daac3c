"""Before and after: two sessions of one procedure compared axis by axis and in 3-D.

Per channel (``reference/spc-extensions.md`` §6):

* the **mean shift** B − A with Welch's t (``scipy.stats.ttest_ind(equal_var=False)``) and the
  confidence interval of the difference on the Welch–Satterthwaite degrees of freedom;
* the **spread**: the ratio σ_B/σ_A with the F test's confidence interval, and the
  Brown–Forsythe test (``scipy.stats.levene(center="median")``, robust to non-normal data) as
  the one that decides;
* a plain sentence.

The error rate is held over the channels with Holm's step-down procedure, separately for the
shifts and for the spreads: the chance that any unchanged axis is reported as changed is at most
1 − confidence (5 % by default). The 3-D shift of the mean of x, y, z is the two-sample
Hotelling T² with its F test, and the change of ISO 9283 RP is given as it is (no test).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.summary import Analysis
from station.errors import StationError
from station.record.source import AnalysedSession, analyse_session
from station.text import format_figure, format_index, format_spread


@dataclass(frozen=True)
class AxisComparison:
    """One channel before (A) and after (B)."""

    channel: str
    n_a: int
    n_b: int
    mean_a: float
    mean_b: float
    shift: float
    shift_low: float
    shift_high: float
    welch_t: float
    welch_df: float
    shift_p: float
    shifted: bool
    sd_a: float
    sd_b: float
    ratio: float
    """σ_B / σ_A."""
    ratio_low: float
    ratio_high: float
    f_p: float
    levene_p: float
    spread_changed: bool
    sentence: str


@dataclass(frozen=True)
class Hotelling:
    """The two-sample Hotelling T² of the 3-D mean (x, y, z)."""

    t2: float
    f: float
    df1: int
    df2: int
    p: float
    shift: tuple[float, float, float]
    length: float
    """The length of the 3-D shift of the mean, √(Δx² + Δy² + Δz²)."""


@dataclass(frozen=True)
class Comparison:
    """Two sessions compared (A before, B after)."""

    a: str
    b: str
    procedure: str
    unit: str
    confidence: float
    axes: tuple[AxisComparison, ...]
    hotelling: Hotelling | None
    rp_a: float | None
    rp_b: float | None
    sentences: tuple[str, ...]


def _p_text(p: float) -> str:
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}"


def holm(p_values: Sequence[float], alpha: float) -> list[bool]:
    """Holm's step-down rejections at family-wise level ``alpha``, in the given order."""
    order = sorted(range(len(p_values)), key=lambda i: p_values[i])
    rejected = [False] * len(p_values)
    for rank, index in enumerate(order):
        if p_values[index] <= alpha / (len(p_values) - rank):
            rejected[index] = True
        else:
            break
    return rejected


def compare_axis(
    channel: str,
    a: Sequence[float],
    b: Sequence[float],
    *,
    confidence: float = 0.95,
    unit: str = "",
    shifted: bool | None = None,
    spread_changed: bool | None = None,
    resolution: float | None = None,
) -> AxisComparison:
    """Compare one channel's readings ``a`` (before) and ``b`` (after). ``shifted`` and
    ``spread_changed`` are the decisions (Holm's, from :func:`compare_sessions`); None decides
    on this axis alone at 1 − ``confidence``. ``resolution``: the gauge step the sentence
    writes the shifts at (:func:`~station.text.format_figure`)."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    if x.size < 2 or y.size < 2:
        raise StationError(f"channel {channel!r} needs two readings or more in each session.")
    alpha = 1 - confidence
    va, vb = x.var(ddof=1), y.var(ddof=1)
    se2 = va / x.size + vb / y.size
    shift = float(y.mean() - x.mean())
    if se2 > 0:
        welch = stats.ttest_ind(y, x, equal_var=False)
        t, p = float(welch.statistic), float(welch.pvalue)
        df = se2**2 / ((va / x.size) ** 2 / (x.size - 1) + (vb / y.size) ** 2 / (y.size - 1))
        margin = float(stats.t.ppf(1 - alpha / 2, df)) * math.sqrt(se2)
    else:  # both sessions read one value each: any difference is certain, none is none
        t, df, margin = (math.inf if shift else 0.0), float(x.size + y.size - 2), 0.0
        p = 0.0 if shift else 1.0
    sd_a, sd_b = math.sqrt(va), math.sqrt(vb)
    if va > 0 and vb > 0:
        f = vb / va
        d1, d2 = y.size - 1, x.size - 1
        f_p = float(2 * min(stats.f.cdf(f, d1, d2), stats.f.sf(f, d1, d2)))
        low = math.sqrt(f / stats.f.ppf(1 - alpha / 2, d1, d2))
        high = math.sqrt(f / stats.f.ppf(alpha / 2, d1, d2))
        levene_p = float(stats.levene(x, y, center="median").pvalue)
        ratio = sd_b / sd_a
    else:
        ratio, low, high, f_p, levene_p = math.nan, math.nan, math.nan, 1.0, 1.0
    if not math.isfinite(levene_p):
        levene_p = 1.0
    moved = p <= alpha if shifted is None else shifted
    spread = levene_p <= alpha if spread_changed is None else spread_changed
    level = f"{confidence:.0%}"
    moved_by = format_figure(shift, resolution, unit=unit)
    from_text = format_figure(shift - margin, resolution)
    to_text = format_figure(shift + margin, resolution)
    if moved:
        first = (
            f"{channel} moved {moved_by} ({level} CI {from_text} to {to_text}), "
            f"{_p_text(p)}: the change between the sessions moved {channel}"
        )
    else:
        first = (
            f"{channel} did not move detectably ({moved_by}, {level} CI "
            f"{from_text} to {to_text}, {_p_text(p)})"
        )
    if not math.isfinite(ratio):
        second = "spread not comparable (a session without spread)"
    elif spread:
        word = "grew" if ratio > 1 else "shrank"
        second = (
            f"spread {word}: σ ratio {ratio:.2f} ({level} CI {low:.2f} to {high:.2f}), "
            f"Brown–Forsythe {_p_text(levene_p)}"
        )
    else:
        second = (
            f"spread unchanged (σ ratio {ratio:.2f}, {level} CI {low:.2f} to {high:.2f}, "
            f"Brown–Forsythe {_p_text(levene_p)})"
        )
    return AxisComparison(
        channel=channel,
        n_a=int(x.size),
        n_b=int(y.size),
        mean_a=float(x.mean()),
        mean_b=float(y.mean()),
        shift=shift,
        shift_low=shift - margin,
        shift_high=shift + margin,
        welch_t=t,
        welch_df=float(df),
        shift_p=p,
        shifted=moved,
        sd_a=sd_a,
        sd_b=sd_b,
        ratio=ratio,
        ratio_low=low,
        ratio_high=high,
        f_p=f_p,
        levene_p=levene_p,
        spread_changed=spread,
        sentence=f"{first}; {second}.",
    )


def hotelling_t2(a: Any, b: Any) -> Hotelling | None:
    """The two-sample Hotelling T² of the means of ``a`` and ``b`` (rows: readings, columns:
    x, y, z); None when there are too few readings or the pooled covariance is singular."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    n1, n2, p = x.shape[0], y.shape[0], x.shape[1]
    if n1 + n2 - p - 1 < 1 or n1 < 2 or n2 < 2:
        return None
    d = y.mean(axis=0) - x.mean(axis=0)
    pooled = ((n1 - 1) * np.cov(x, rowvar=False) + (n2 - 1) * np.cov(y, rowvar=False)) / (
        n1 + n2 - 2
    )
    if np.linalg.matrix_rank(pooled) < p:
        return None
    t2 = float(n1 * n2 / (n1 + n2) * d @ np.linalg.solve(pooled, d))
    df1, df2 = p, n1 + n2 - p - 1
    f = t2 * df2 / (p * (n1 + n2 - 2))
    return Hotelling(
        t2=t2,
        f=float(f),
        df1=df1,
        df2=df2,
        p=float(stats.f.sf(f, df1, df2)),
        shift=tuple(float(v) for v in d),  # type: ignore[arg-type]
        length=float(np.linalg.norm(d)),
    )


def compare_channels(
    a: Mapping[str, Sequence[float]],
    b: Mapping[str, Sequence[float]],
    *,
    confidence: float = 0.95,
    unit: str = "",
    resolution: float | None = None,
) -> tuple[AxisComparison, ...]:
    """Compare every channel ``a`` and ``b`` share (in ``a``'s order), Holm's procedure holding
    the family-wise error rate at 1 − ``confidence`` for the shifts and for the spreads."""
    channels = [c for c in a if c in b]
    first = [
        compare_axis(c, a[c], b[c], confidence=confidence, unit=unit, resolution=resolution)
        for c in channels
    ]
    alpha = 1 - confidence
    shifted = holm([r.shift_p for r in first], alpha)
    spread = holm([r.levene_p for r in first], alpha)
    return tuple(
        compare_axis(
            c,
            a[c],
            b[c],
            confidence=confidence,
            unit=unit,
            shifted=shifted[i],
            spread_changed=spread[i],
            resolution=resolution,
        )
        for i, c in enumerate(channels)
    )


def _analysis_of(analysed: AnalysedSession) -> Analysis:
    """The session's analysis; StationError saying why there is none."""
    if analysed.report is None or analysed.report.analysis is None:
        raise StationError(f"{analysed.path.name}: {analysed.problem}; nothing to compare.")
    return analysed.report.analysis


def compare_sessions(
    path_a: str | Path, path_b: str | Path, *, confidence: float = 0.95
) -> Comparison:
    """Compare the session files ``path_a`` (before) and ``path_b`` (after): refused with a
    sentence when they follow different procedures, record different units, or one has
    nothing to analyse."""
    first, second = analyse_session(path_a), analyse_session(path_b)
    sa, sb = first.session, second.session
    if sa.procedure_id != sb.procedure_id:
        raise StationError(
            f"{sa.path.name} follows procedure {sa.procedure_id!r} and {sb.path.name} "
            f"{sb.procedure_id!r}: only sessions of one procedure can be compared."
        )
    if sa.unit != sb.unit:
        raise StationError(
            f"{sa.path.name} is in {sa.unit} and {sb.path.name} in {sb.unit}: only sessions in "
            "one unit can be compared."
        )
    analysis_a, analysis_b = _analysis_of(first), _analysis_of(second)
    readings_a = {name: c.readings for name, c in analysis_a.channels.items()}
    readings_b = {name: c.readings for name, c in analysis_b.channels.items()}
    if not set(readings_a) & set(readings_b):
        raise StationError(f"{sa.path.name} and {sb.path.name} share no channel to compare.")
    recorded = sa.header.get("resolution")
    resolution = float(recorded) if isinstance(recorded, int | float) else None
    axes = compare_channels(
        readings_a, readings_b, confidence=confidence, unit=sa.unit, resolution=resolution
    )
    hotelling = None
    names = [n for n in ("x", "y", "z") if n in readings_a and n in readings_b]
    lengths = {len(readings_a[n]) for n in names}
    if len(names) == 3 and len(lengths) == 1 and len({len(readings_b[n]) for n in names}) == 1:
        hotelling = hotelling_t2(
            np.column_stack([readings_a[n] for n in names]),
            np.column_stack([readings_b[n] for n in names]),
        )
    spatial_a, spatial_b = analysis_a.spatial, analysis_b.spatial
    rp_a = None if spatial_a is None else spatial_a.rp
    rp_b = None if spatial_b is None else spatial_b.rp
    sentences = [axis.sentence for axis in axes]
    unit = sa.unit
    if hotelling is not None:
        verdict = "moved" if hotelling.p <= 1 - confidence else "did not move detectably"
        length = format_spread(hotelling.length, resolution, unit=unit)
        sentences.append(
            f"The 3-D mean {verdict}: shift {length}, Hotelling T² {format_index(hotelling.t2)} "
            f"(F {format_index(hotelling.f)} on {hotelling.df1} and {hotelling.df2} "
            f"degrees of freedom), {_p_text(hotelling.p)}."
        )
    if rp_a is not None and rp_b is not None:
        sentences.append(
            f"RP went from {format_spread(rp_a, resolution)} to "
            f"{format_spread(rp_b, resolution, unit=unit)} "
            f"({format_figure(rp_b - rp_a, resolution)}; RP has no test "
            "of its own: read the spreads above)."
        )
    return Comparison(
        a=sa.path.name,
        b=sb.path.name,
        procedure=sa.procedure_id,
        unit=unit,
        confidence=confidence,
        axes=axes,
        hotelling=hotelling,
        rp_a=rp_a,
        rp_b=rp_b,
        sentences=tuple(sentences),
    )


def comparison_json(comparison: Comparison) -> dict[str, Any]:
    """The JSON document of ``station compare --json`` (undefined numbers are null)."""

    def number(value: float | None) -> float | None:
        return None if value is None or not math.isfinite(value) else float(value)

    h = comparison.hotelling
    return {
        "a": comparison.a,
        "b": comparison.b,
        "procedure": comparison.procedure,
        "unit": comparison.unit,
        "confidence": comparison.confidence,
        "error_rate": "family-wise, Holm over the channels (shifts and spreads separately)",
        "channels": {
            r.channel: {
                "n_a": r.n_a,
                "n_b": r.n_b,
                "mean_a": number(r.mean_a),
                "mean_b": number(r.mean_b),
                "shift": number(r.shift),
                "shift_ci": [number(r.shift_low), number(r.shift_high)],
                "welch_t": number(r.welch_t),
                "welch_df": number(r.welch_df),
                "shift_p": number(r.shift_p),
                "shifted": r.shifted,
                "sd_a": number(r.sd_a),
                "sd_b": number(r.sd_b),
                "sd_ratio": number(r.ratio),
                "sd_ratio_ci": [number(r.ratio_low), number(r.ratio_high)],
                "f_p": number(r.f_p),
                "brown_forsythe_p": number(r.levene_p),
                "spread_changed": r.spread_changed,
                "sentence": r.sentence,
            }
            for r in comparison.axes
        },
        "hotelling": None
        if h is None
        else {
            "t2": number(h.t2),
            "f": number(h.f),
            "df": [h.df1, h.df2],
            "p": number(h.p),
            "shift": list(h.shift),
            "length": number(h.length),
        },
        "rp": {
            "a": number(comparison.rp_a),
            "b": number(comparison.rp_b),
            "change": None
            if comparison.rp_a is None or comparison.rp_b is None
            else number(comparison.rp_b - comparison.rp_a),
        },
        "sentences": list(comparison.sentences),
    }
