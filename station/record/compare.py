"""Before and after: two sessions of one procedure compared axis by axis and in 3-D.

Per channel (``reference/spc-extensions.md`` §6):

* the **mean shift** B − A with its t test and the confidence interval of the difference on the
  Welch–Satterthwaite degrees of freedom. Where the two sessions were zeroed separately (each
  records its own ``zero``), each session's mean is read from a zero taken at one rest of the
  robot, which carries one draw of the robot's own repeatability
  (:mod:`station.analysis.zeros`): the variance of the shift is then
  s_A²/n_A + Var(z_A) + s_B²/n_B + Var(z_B), each session's part on its n − 1 degrees of
  freedom (its spread s is what both terms are estimated from). Where neither session zeroed
  the channel (both read the gauge's own reference, one zero for both) the zero terms are 0 and
  this is exactly Welch's t (``scipy.stats.ttest_ind(equal_var=False)``). When the zeros make
  up most of the shift's variance the sentence says the shift measures the zeros;
* the **spread**: the ratio σ_B/σ_A with the F test's confidence interval, and the
  Brown–Forsythe test (``scipy.stats.levene(center="median")``, robust to non-normal data) as
  the one that decides (a zero moves every reading alike: spreads need no correction);
* a plain sentence, which says when Holm's correction made the call.

The error rate is held over the channels with Holm's step-down procedure, separately for the
shifts and for the spreads: the chance that any unchanged axis is reported as changed is at most
1 − confidence (5 % by default). The 3-D shift of the mean of x, y, z is the two-sample
Hotelling T² with its F test (pooled covariance, when no zero is in it), or, for separately
zeroed sessions, the unequal-covariance T² with the zeros' covariance added and Nel and
Van der Merwe's degrees of freedom (Krishnamoorthy and Yu 2004, eq. 2.3); the change of ISO 9283
RP is given as it is (no test).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.summary import Analysis
from station.analysis.zeros import ZeroDraw, zeros_variance
from station.errors import StationError
from station.record.source import AnalysedSession, analyse_session
from station.session.header import zero_draws
from station.text import format_figure, format_index, format_spread


@dataclass(frozen=True)
class HolmCall:
    """Holm's step-down decision on one of ``tests`` p-values: ``threshold`` is α/(tests − rank),
    the level its p was held to; ``stopped`` says the procedure stopped at a smaller p (so this
    one was not rejected whatever its own threshold)."""

    rejected: bool
    threshold: float
    tests: int
    stopped: bool = False


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
    zero_a: float | None = None
    """The standard uncertainty session A's zeros add to its mean (None: not zeroed by it)."""
    zero_b: float | None = None
    zero_share: float = 0.0
    """The zeros' share of the shift's variance (0 when neither session zeroed the channel)."""
    shift_holm: HolmCall | None = None
    spread_holm: HolmCall | None = None

    @property
    def separately_zeroed(self) -> bool:
        """True when a session's own zero is in the shift (its uncertainty counted)."""
        return self.zero_a is not None or self.zero_b is not None


ZEROS_DOMINATE = 0.5
"""The zeros' share of the shift's variance above which the sentence says the shift measures
the zeros more than the robot."""


@dataclass(frozen=True)
class Hotelling:
    """The two-sample Hotelling T² of the 3-D mean (x, y, z)."""

    t2: float
    f: float
    df1: int
    df2: float
    p: float
    shift: tuple[float, float, float]
    length: float
    """The length of the 3-D shift of the mean, √(Δx² + Δy² + Δz²)."""
    zeroed: bool = False
    """True when the zeros' covariance is in the test (separately zeroed sessions)."""
    zero_share: float = 0.0
    """The zeros' share of the trace of the shift's covariance."""


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
    return [call.rejected for call in holm_calls(p_values, alpha)]


def holm_calls(p_values: Sequence[float], alpha: float) -> list[HolmCall]:
    """Holm's step-down procedure at family-wise level ``alpha``, one :class:`HolmCall` per
    p-value in the given order: the smallest p is held to α/m, the next to α/(m − 1), ...,
    and the procedure stops at the first p above its threshold."""
    m = len(p_values)
    order = sorted(range(m), key=lambda i: p_values[i])
    calls: list[HolmCall | None] = [None] * m
    stopped = False
    for rank, index in enumerate(order):
        threshold = alpha / (m - rank)
        if stopped:
            calls[index] = HolmCall(False, threshold, m, stopped=True)
        elif p_values[index] <= threshold:
            calls[index] = HolmCall(True, threshold, m)
        else:
            stopped = True
            calls[index] = HolmCall(False, threshold, m)
    return [call for call in calls if call is not None]


def _holm_clause(p: float, alpha: float, call: HolmCall | None) -> str:
    """The words that say Holm's correction decided: a p at or below α that was not called."""
    if call is None or call.rejected or p > alpha or call.tests < 2:
        return ""
    if call.stopped:
        return (
            f", at or below its Holm threshold {call.threshold:.3f} but Holm's procedure for "
            f"{call.tests} channels stopped at a smaller p above its own threshold"
        )
    return f", above Holm's threshold {call.threshold:.3f} for {call.tests} channels"


def _zero_clause(zero_share: float, moved: bool, separately: bool) -> str:
    """The words on the zeros in a shift between sessions each zeroed at its own rest."""
    if not separately:
        return ""
    if moved:
        return "; the zeros' rest-to-rest uncertainty is counted in it"
    if zero_share > ZEROS_DOMINATE:
        return (
            "; the sessions were zeroed separately, each at one rest of the robot, and the two "
            f"zeros make up {zero_share:.0%} of this shift's variance: the shift measures the "
            "zeros more than the robot"
        )
    return "; the zeros' rest-to-rest uncertainty is counted in it"


def compare_axis(
    channel: str,
    a: Sequence[float],
    b: Sequence[float],
    *,
    confidence: float = 0.95,
    unit: str = "",
    shifted: bool | HolmCall | None = None,
    spread_changed: bool | HolmCall | None = None,
    resolution: float | None = None,
    zeros_a: Sequence[ZeroDraw] = (),
    zeros_b: Sequence[ZeroDraw] = (),
) -> AxisComparison:
    """Compare one channel's readings ``a`` (before) and ``b`` (after). ``shifted`` and
    ``spread_changed`` are the decisions (Holm's calls, from :func:`compare_channels`); None
    decides on this axis alone at 1 − ``confidence``. ``resolution``: the gauge step the
    sentence writes the shifts at (:func:`~station.text.format_figure`). ``zeros_a`` and
    ``zeros_b``: the zeros each session's readings were taken under
    (:func:`station.session.header.zero_draws`); none in either is one shared reference, and
    the test is Welch's."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    if x.size < 2 or y.size < 2:
        raise StationError(f"channel {channel!r} needs two readings or more in each session.")
    alpha = 1 - confidence
    va, vb = x.var(ddof=1), y.var(ddof=1)
    sd_a, sd_b = math.sqrt(va), math.sqrt(vb)
    za = zeros_variance(sd_a, zeros_a)
    zb = zeros_variance(sd_b, zeros_b)
    # Each session's part of the shift's variance, its mean's and its zero's, both estimated
    # from its own spread: n − 1 degrees of freedom each (Welch–Satterthwaite over the two).
    part_a, part_b = va / x.size + za, vb / y.size + zb
    se2 = part_a + part_b
    shift = float(y.mean() - x.mean())
    if se2 > 0:
        df = se2**2 / (part_a**2 / (x.size - 1) + part_b**2 / (y.size - 1))
        t = shift / math.sqrt(se2)
        p = float(2 * stats.t.sf(abs(t), df))
        margin = float(stats.t.ppf(1 - alpha / 2, df)) * math.sqrt(se2)
    else:  # both sessions read one value each: any difference is certain, none is none
        t, df, margin = (math.inf if shift else 0.0), float(x.size + y.size - 2), 0.0
        p = 0.0 if shift else 1.0
    zero_share = (za + zb) / se2 if se2 > 0 else 0.0
    separately = bool(zeros_a) or bool(zeros_b)
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
    shift_call = shifted if isinstance(shifted, HolmCall) else None
    spread_call = spread_changed if isinstance(spread_changed, HolmCall) else None
    moved = p <= alpha if shifted is None else bool(getattr(shifted, "rejected", shifted))
    spread = (
        levene_p <= alpha
        if spread_changed is None
        else bool(getattr(spread_changed, "rejected", spread_changed))
    )
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
            f"{from_text} to {to_text}, {_p_text(p)}{_holm_clause(p, alpha, shift_call)})"
        )
    first += _zero_clause(zero_share, moved, separately)
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
            f"Brown–Forsythe {_p_text(levene_p)}{_holm_clause(levene_p, alpha, spread_call)})"
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
        zero_a=math.sqrt(za) if zeros_a else None,
        zero_b=math.sqrt(zb) if zeros_b else None,
        zero_share=zero_share,
        shift_holm=shift_call,
        spread_holm=spread_call,
    )


def hotelling_t2(
    a: Any,
    b: Any,
    zeros_a: Sequence[Sequence[ZeroDraw]] | None = None,
    zeros_b: Sequence[Sequence[ZeroDraw]] | None = None,
) -> Hotelling | None:
    """The two-sample Hotelling T² of the means of ``a`` and ``b`` (rows: readings, columns:
    x, y, z); None when there are too few readings or the covariance is singular.

    Without zeros (``zeros_a``/``zeros_b``: per column, the zeros of that session's channel) it
    is the pooled-covariance T² with its exact F. With zeros, each session's covariance of its
    mean is S/n plus its zeros' covariance D·S·D (D diagonal, D_ii² = Var(z_i)/s_i²: a rest draw
    in 3-D correlates across the axes as the rests do), T² = d̄ᵀ (V_A + V_B)⁻¹ d̄, and
    F = T²·(ν − p + 1)/(p·ν) on (p, ν − p + 1) degrees of freedom with Nel and Van der Merwe's
    ν = (tr V² + (tr V)²) / Σ_i (tr V_i² + (tr V_i)²)/(n_i − 1)."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    n1, n2, p = x.shape[0], y.shape[0], x.shape[1]
    if n1 + n2 - p - 1 < 1 or n1 < 2 or n2 < 2:
        return None
    d = y.mean(axis=0) - x.mean(axis=0)
    zeroed = any(zeros_a or ()) or any(zeros_b or ())
    share = 0.0
    if not zeroed:
        pooled = ((n1 - 1) * np.cov(x, rowvar=False) + (n2 - 1) * np.cov(y, rowvar=False)) / (
            n1 + n2 - 2
        )
        if np.linalg.matrix_rank(pooled) < p:
            return None
        t2 = float(n1 * n2 / (n1 + n2) * d @ np.linalg.solve(pooled, d))
        df1, df2 = p, float(n1 + n2 - p - 1)
        f = t2 * df2 / (p * (n1 + n2 - 2))
    else:
        parts, zero_trace = [], 0.0
        for data, n, zeros in ((x, n1, zeros_a), (y, n2, zeros_b)):
            cov = np.cov(data, rowvar=False)
            sds = np.sqrt(np.diag(cov))
            scale = np.array(
                [
                    math.sqrt(zeros_variance(float(s), (zeros or [()] * p)[i])) / s if s > 0 else 0
                    for i, s in enumerate(sds)
                ]
            )
            zero_cov = cov * np.outer(scale, scale)
            zero_trace += float(np.trace(zero_cov))
            parts.append((cov / n + zero_cov, n))
        total = parts[0][0] + parts[1][0]
        if np.linalg.matrix_rank(total) < p:
            return None
        t2 = float(d @ np.linalg.solve(total, d))

        def spread(v: Any) -> float:
            return float(np.trace(v @ v) + np.trace(v) ** 2)

        nu = spread(total) / sum(spread(v) / (n - 1) for v, n in parts)
        if nu - p + 1 <= 0:
            return None
        df1, df2 = p, float(nu - p + 1)
        f = t2 * df2 / (p * nu)
        share = zero_trace / float(np.trace(total))
    return Hotelling(
        t2=t2,
        f=float(f),
        df1=df1,
        df2=df2,
        p=float(stats.f.sf(f, df1, df2)),
        shift=tuple(float(v) for v in d),  # type: ignore[arg-type]
        length=float(np.linalg.norm(d)),
        zeroed=bool(zeroed),
        zero_share=share,
    )


def compare_channels(
    a: Mapping[str, Sequence[float]],
    b: Mapping[str, Sequence[float]],
    *,
    confidence: float = 0.95,
    unit: str = "",
    resolution: float | None = None,
    zeros_a: Mapping[str, Sequence[ZeroDraw]] | None = None,
    zeros_b: Mapping[str, Sequence[ZeroDraw]] | None = None,
) -> tuple[AxisComparison, ...]:
    """Compare every channel ``a`` and ``b`` share (in ``a``'s order), Holm's procedure holding
    the family-wise error rate at 1 − ``confidence`` for the shifts and for the spreads.
    ``zeros_a``/``zeros_b``: per channel, the zeros each session's readings were taken under
    (a channel without any in both: one shared reference, Welch's test)."""
    channels = [c for c in a if c in b]
    za, zb = zeros_a or {}, zeros_b or {}

    def one(c: str, **calls: Any) -> AxisComparison:
        return compare_axis(
            c,
            a[c],
            b[c],
            confidence=confidence,
            unit=unit,
            resolution=resolution,
            zeros_a=za.get(c, ()),
            zeros_b=zb.get(c, ()),
            **calls,
        )

    first = [one(c) for c in channels]
    alpha = 1 - confidence
    shifted = holm_calls([r.shift_p for r in first], alpha)
    spread = holm_calls([r.levene_p for r in first], alpha)
    return tuple(
        one(c, shifted=shifted[i], spread_changed=spread[i]) for i, c in enumerate(channels)
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
    zeros_a, zeros_b = zero_draws(sa.events), zero_draws(sb.events)
    axes = compare_channels(
        readings_a,
        readings_b,
        confidence=confidence,
        unit=sa.unit,
        resolution=resolution,
        zeros_a=zeros_a,
        zeros_b=zeros_b,
    )
    hotelling = None
    names = [n for n in ("x", "y", "z") if n in readings_a and n in readings_b]
    lengths = {len(readings_a[n]) for n in names}
    if len(names) == 3 and len(lengths) == 1 and len({len(readings_b[n]) for n in names}) == 1:
        hotelling = hotelling_t2(
            np.column_stack([readings_a[n] for n in names]),
            np.column_stack([readings_b[n] for n in names]),
            [zeros_a.get(n, ()) for n in names],
            [zeros_b.get(n, ()) for n in names],
        )
    spatial_a, spatial_b = analysis_a.spatial, analysis_b.spatial
    rp_a = None if spatial_a is None else spatial_a.rp
    rp_b = None if spatial_b is None else spatial_b.rp
    sentences = [axis.sentence for axis in axes]
    unit = sa.unit
    if hotelling is not None:
        verdict = "moved" if hotelling.p <= 1 - confidence else "did not move detectably"
        length = format_spread(hotelling.length, resolution, unit=unit)
        zeros = ""
        if hotelling.zeroed:
            zeros = "; the zeros' rest-to-rest uncertainty is counted in it"
            if verdict != "moved" and hotelling.zero_share > ZEROS_DOMINATE:
                zeros = (
                    f"; the two zeros make up {hotelling.zero_share:.0%} of its variance: the "
                    "shift measures the zeros more than the robot"
                )
        sentences.append(
            f"The 3-D mean {verdict}: shift {length}, Hotelling T² {format_index(hotelling.t2)} "
            f"(F {format_index(hotelling.f)} on {hotelling.df1} and "
            f"{hotelling.df2:.3g} degrees of freedom), {_p_text(hotelling.p)}{zeros}."
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
                "zeroed": "separately" if r.separately_zeroed else "one reference",
                "zero_u": [number(r.zero_a), number(r.zero_b)],
                "zero_share": number(r.zero_share),
                "shift_holm_threshold": None
                if r.shift_holm is None
                else number(r.shift_holm.threshold),
                "spread_holm_threshold": None
                if r.spread_holm is None
                else number(r.spread_holm.threshold),
                "sentence": r.sentence,
            }
            for r in comparison.axes
        },
        "hotelling": None
        if h is None
        else {
            "t2": number(h.t2),
            "f": number(h.f),
            "df": [h.df1, number(h.df2)],
            "p": number(h.p),
            "shift": list(h.shift),
            "length": number(h.length),
            "zeroed": h.zeroed,
            "zero_share": number(h.zero_share),
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
