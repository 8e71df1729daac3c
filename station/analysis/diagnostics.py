"""What the capability figures assume, checked: out-of-spec readings, normality, independence and
stability (drift).

Definitions and sources: ``reference/spc-extensions.md`` §3–§5.

* :func:`out_of_spec`: the readings beyond a specification limit, per side, with their cycles.
* :func:`normality`: Shapiro–Wilk (``scipy.stats.shapiro``) for 3 ≤ n ≤ 5000; above that the
  Anderson–Darling statistic (``scipy.stats.anderson``) with D'Agostino & Stephens' p-value of
  the adjusted A*² = A²(1 + 0.75/n + 2.25/n²). Readings at a coarse gauge step tie often and
  these tests punish ties: the result says so when the step is over σ/4.
* :func:`percentile_capability`: the ISO 22514-2 percentile indices (Clements' method) from the
  0.135 %, 50 % and 99.865 % quantiles of a fitted Johnson SU distribution
  (``scipy.stats.johnsonsu.fit``; its four parameters follow skewed and long-tailed data), or
  the empirical quantiles from ``EMPIRICAL_QUANTILES_FROM`` readings on. Labelled Pp/Ppk
  (percentile), never Cpk.
* :func:`autocorrelation`: the lag-1 autocorrelation r₁ = Σ(x_t − x̄)(x_{t+1} − x̄)/Σ(x_t − x̄)²;
  under independence r₁ ≈ N(−1/n, 1/n) (Bartlett), so z = (r₁ + 1/n)√n and a two-sided p. With
  a positive r₁ the moving ranges understate σ: I-MR limits are too tight and alarms false.
* :func:`ewma_chart`: z_i = λx_i + (1 − λ)z_{i−1}, z_0 = the centre, limits
  centre ± Lσ√(λ/(2−λ)(1 − (1−λ)^{2i})), σ the within sigma (never the overall σ of drifting
  data); λ = 0.2, L = 3 (NIST/SEMATECH 6.3.2.4).
* :func:`trend`: the least-squares slope of value on reading time (``scipy.stats.linregress``,
  two-sided p and the t-interval of the slope), given per 10 cycles at the median time between
  cycles; on cycle numbers when no times are known.
"""

from __future__ import annotations

import math
import threading
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.descriptive import as_readings
from station.text import format_figure

#: Significance level of the normality, autocorrelation and trend tests.
ALPHA = 0.05
#: Shapiro–Wilk's p-value is accurate up to this many readings (scipy's documentation).
SHAPIRO_MAX_N = 5000
#: From this many readings on, the percentile method uses the empirical quantiles.
EMPIRICAL_QUANTILES_FROM = 2000
#: Fewer readings than this give no percentile indices: a four-parameter Johnson SU fit to a
#: handful of readings invents its tails (five placements once gave a Ppk of 114,618). The
#: report's own minimum sample (25 cycles).
PERCENTILE_MIN_N = 25
#: ISO 22514-2's quantiles: the normal ±3σ coverage.
LOWER_QUANTILE, UPPER_QUANTILE = 0.00135, 0.99865
#: EWMA weight and width (NIST/SEMATECH 6.3.2.4).
EWMA_LAMBDA, EWMA_WIDTH = 0.2, 3.0
#: Cycles a trend estimate is given over ("drifts +0.00004 in per 10 cycles").
TREND_SPAN = 10


@dataclass(frozen=True)
class OutOfSpec:
    """Readings strictly beyond a specification limit, per side, with their cycle numbers."""

    below: int
    above: int
    cycles_below: tuple[int, ...]
    cycles_above: tuple[int, ...]

    @property
    def cycles(self) -> tuple[int, ...]:
        """Every out-of-spec cycle, ascending."""
        return tuple(sorted(self.cycles_below + self.cycles_above))

    @property
    def total(self) -> int:
        """How many readings are out of specification."""
        return self.below + self.above


def out_of_spec(
    values: Iterable[float] | np.ndarray,
    limits: SpecLimits | None,
    cycles: Sequence[int] | np.ndarray | None = None,
) -> OutOfSpec:
    """The readings below the LSL and above the USL (strictly), named by ``cycles`` (1, 2, 3 ...
    when None). Without limits nothing is out of specification."""

    array = as_readings(values)
    labels = np.arange(1, array.size + 1) if cycles is None else np.asarray(cycles, dtype=int)
    if limits is None:
        return OutOfSpec(0, 0, (), ())
    below = array < limits.lsl if limits.lsl is not None else np.zeros(array.size, bool)
    above = array > limits.usl if limits.usl is not None else np.zeros(array.size, bool)
    return OutOfSpec(
        below=int(below.sum()),
        above=int(above.sum()),
        cycles_below=tuple(int(c) for c in labels[below]),
        cycles_above=tuple(int(c) for c in labels[above]),
    )


@dataclass(frozen=True)
class Normality:
    """A normality test of one channel. ``rejected`` when p < ``alpha``; undefined (None) with
    fewer than 3 readings or no spread, and ``message`` says why. ``ties`` notes a coarse gauge
    step (over σ/4), which makes the test reject more often than it should."""

    test: str
    statistic: float | None
    p_value: float | None
    alpha: float
    rejected: bool | None
    n: int
    ties: str | None = None
    message: str | None = None


def _anderson_darling_p(a2: float, n: int) -> float:
    """D'Agostino & Stephens (1986) p-value of the adjusted A*² for a normal with estimated
    mean and sigma (table 4.9)."""
    adjusted = a2 * (1 + 0.75 / n + 2.25 / n**2)
    if adjusted >= 153.0:
        # The fitted curve's minimum (≈ 1e-265); beyond it the quadratic turns up again.
        return 0.0
    if adjusted >= 0.6:
        p = math.exp(1.2937 - 5.709 * adjusted + 0.0186 * adjusted**2)
    elif adjusted >= 0.34:
        p = math.exp(0.9177 - 4.279 * adjusted - 1.38 * adjusted**2)
    elif adjusted >= 0.2:
        p = 1 - math.exp(-8.318 + 42.796 * adjusted - 59.938 * adjusted**2)
    else:
        p = 1 - math.exp(-13.436 + 101.14 * adjusted - 223.73 * adjusted**2)
    return min(1.0, max(0.0, p))


def normality(
    values: Iterable[float] | np.ndarray,
    resolution: float | None = None,
    alpha: float = ALPHA,
) -> Normality:
    """Shapiro–Wilk (n ≤ 5000) or Anderson–Darling (larger n) test of normality."""
    from scipy import stats

    array = as_readings(values)
    n = int(array.size)
    test = "Shapiro-Wilk" if n <= SHAPIRO_MAX_N else "Anderson-Darling"
    if n < 3:
        return Normality(test, None, None, alpha, None, n, message="needs 3 or more readings")
    sd = float(np.std(array, ddof=1))
    if not sd > 0:
        return Normality(
            test, None, None, alpha, None, n, message="every reading is the same: no spread"
        )
    ties = None
    if resolution and resolution > sd / 4:
        ties = (
            f"the gauge step {format_figure(resolution, resolution, signed=False)} is over a "
            "quarter of sigma "
            f"({format_figure(sd, resolution, signed=False)}): tied "
            "readings make the test reject normal data more often"
        )
    if n <= SHAPIRO_MAX_N:
        with warnings.catch_warnings():
            # A spread at the last digits of a float ("range zero") still has a p-value.
            warnings.simplefilter("ignore", UserWarning)
            result = stats.shapiro(array)
        statistic, p = float(result.statistic), float(result.pvalue)
    else:
        standardized = np.sort((array - array.mean()) / sd)
        cdf = stats.norm.cdf(standardized)
        logs = np.log(np.clip(cdf, 1e-300, None)) + np.log(np.clip(1 - cdf[::-1], 1e-300, None))
        i = np.arange(1, n + 1)
        statistic = float(-n - np.sum((2 * i - 1) * logs) / n)
        p = _anderson_darling_p(statistic, n)
    return Normality(test, statistic, p, alpha, p < alpha, n, ties=ties)


@dataclass(frozen=True)
class PercentileCapability:
    """ISO 22514-2 percentile indices (Clements): Pp = (USL − LSL)/(X₉₉.₈₆₅ − X₀.₁₃₅),
    Ppu = (USL − X₅₀)/(X₉₉.₈₆₅ − X₅₀), Ppl = (X₅₀ − LSL)/(X₅₀ − X₀.₁₃₅), Ppk = min.
    ``method`` names the quantiles' source; ``capable`` is Ppk ≥ ``threshold``."""

    method: str
    q_low: float
    median: float
    q_high: float
    pp: float | None
    ppu: float | None
    ppl: float | None
    ppk: float | None
    threshold: float
    capable: bool | None


def _quantiles(array: np.ndarray) -> tuple[str, tuple[float, float, float]]:
    from scipy import stats

    levels = [LOWER_QUANTILE, 0.5, UPPER_QUANTILE]
    if array.size >= EMPIRICAL_QUANTILES_FROM:
        return "percentile (ISO 22514-2), empirical quantiles", tuple(
            float(q) for q in np.quantile(array, levels)
        )  # type: ignore[return-value]
    # Fit on a standardised scale: the optimiser copes badly with readings of 1e-4.
    centre, scale = float(np.mean(array)), float(np.std(array, ddof=1))
    params = stats.johnsonsu.fit((array - centre) / scale)
    quantiles = stats.johnsonsu(*params).ppf(levels) * scale + centre
    return "percentile (ISO 22514-2), Johnson SU fit", tuple(float(q) for q in quantiles)  # type: ignore[return-value]


def percentile_capability(
    values: Iterable[float] | np.ndarray, limits: SpecLimits, threshold: float = 1.0
) -> PercentileCapability | None:
    """The percentile indices of the readings (None with fewer than ``PERCENTILE_MIN_N``
    readings or no spread)."""

    array = as_readings(values)
    if array.size < PERCENTILE_MIN_N or not float(np.ptp(array)) > 0:
        return None
    method, (low, median, high) = _quantiles(array)
    lsl, usl = limits.lsl, limits.usl

    def ratio(numerator: float, denominator: float) -> float | None:
        return numerator / denominator if denominator > 0 else None

    pp = ratio(usl - lsl, high - low) if usl is not None and lsl is not None else None
    ppu = ratio(usl - median, high - median) if usl is not None else None
    ppl = ratio(median - lsl, median - low) if lsl is not None else None
    sides = [v for v in (ppu, ppl) if v is not None]
    ppk = min(sides) if sides else None
    return PercentileCapability(
        method=method,
        q_low=low,
        median=median,
        q_high=high,
        pp=pp,
        ppu=ppu,
        ppl=ppl,
        ppk=ppk,
        threshold=float(threshold),
        capable=None if ppk is None else ppk >= threshold,
    )


@dataclass(frozen=True)
class Autocorrelation:
    """Lag-1 autocorrelation r₁ with its z-test under independence; ``significant`` when
    p < ``alpha`` (None with fewer than ``MIN_AUTOCORRELATION_N`` readings or no spread).
    ``sigma_ratio`` is overall σ / within σ: above 1 when positive correlation hides the spread
    from the moving ranges."""

    r1: float | None
    z: float | None
    p_value: float | None
    alpha: float
    significant: bool | None
    n: int
    sigma_ratio: float | None = None
    message: str | None = None


#: Fewer readings than this give no autocorrelation verdict.
MIN_AUTOCORRELATION_N = 8

AUTOCORRELATION_EXPLANATION = (
    "successive readings are correlated (lag-1 r = {r1:+.2f}, {p}): the moving ranges "
    "understate the spread, so the I-MR limits are too tight and alarms may be false; compare "
    "the within-sigma and overall-sigma indices, and judge by the overall ones"
)


def lag1(array: np.ndarray) -> float | None:
    """r₁ of an array (None without spread)."""

    deviations = array - array.mean()
    # Products summed by numpy rather than np.dot: BLAS threads on a shared, loaded machine
    # made the dot product 30x slower here.
    denominator = float(np.sum(deviations * deviations))
    if not denominator > 0:
        return None
    return float(np.sum(deviations[:-1] * deviations[1:]) / denominator)


def autocorrelation(
    values: Iterable[float] | np.ndarray,
    alpha: float = ALPHA,
    sigma_within: float | None = None,
) -> Autocorrelation:
    """Lag-1 autocorrelation and its significance (see the module docstring)."""
    from scipy.special import ndtr

    array = as_readings(values)
    n = int(array.size)
    if n < MIN_AUTOCORRELATION_N:
        return Autocorrelation(
            None, None, None, alpha, None, n, message=f"needs {MIN_AUTOCORRELATION_N} readings"
        )
    r1 = lag1(array)
    if r1 is None:
        return Autocorrelation(None, None, None, alpha, None, n, message="no spread")
    z = (r1 + 1 / n) * math.sqrt(n)
    p = float(2 * (1 - ndtr(abs(z))))
    ratio = None
    if sigma_within:
        ratio = float(np.std(array, ddof=1)) / sigma_within
    message = None
    if p < alpha and r1 > 0:
        message = AUTOCORRELATION_EXPLANATION.format(r1=r1, p=p_phrase(p))
    elif p < alpha:
        message = (
            f"successive readings alternate (lag-1 r = {r1:+.2f}, {p_phrase(p)}): the moving "
            "ranges overstate the spread; look for over-correction or two causes taking turns"
        )
    return Autocorrelation(r1, z, p, alpha, p < alpha, n, ratio, message)


def p_text(p: float) -> str:
    """A p-value as people write it: 0.003, 0.04, < 0.001."""
    if p < 0.001:
        return "< 0.001"
    return f"{p:.3f}" if p < 0.01 else f"{p:.2f}"


def two_digits(value: float) -> str:
    """A signed figure to two significant digits in plain decimals: +0.000082, -0.0013."""
    if value == 0 or not math.isfinite(value):
        return f"{value:+g}"
    places = max(0, 1 - math.floor(math.log10(abs(value))))
    return f"{value:+.{places}f}"


def p_phrase(p: float) -> str:
    """``p = 0.003`` or ``p < 0.001``."""
    text = p_text(p)
    return f"p {text}" if text.startswith("<") else f"p = {text}"


@dataclass(frozen=True)
class Ewma:
    """An EWMA chart's verdict: the centre and sigma it used, its last value, and the 1-based
    points (``signals``) beyond a limit, with their cycles. (The statistic per point is
    :func:`ewma_values`; its limits :func:`ewma_limit_half_width`: a chart plots them.)"""

    lam: float
    width: float
    center: float
    sigma: float
    last: float | None
    signals: tuple[int, ...]
    signal_cycles: tuple[int, ...]


def ewma_values(
    points: Iterable[float] | np.ndarray, center: float, lam: float = EWMA_LAMBDA
) -> np.ndarray:
    """z_i = λx_i + (1 − λ)z_{i−1} with z_0 = ``center``, in one pass of ``scipy.signal.lfilter``
    (direct form: y[n] = b₀x[n] − a₁y[n−1], initial state (1 − λ)·z₀)."""
    from scipy.signal import lfilter

    x = np.asarray(points, dtype=float)
    if not x.size:
        return x
    z, _ = lfilter([lam], [1.0, -(1.0 - lam)], x, zi=[(1.0 - lam) * center])
    return z


def ewma_limit_half_width(sigma: float, i: int, lam: float, width: float) -> float:
    """Half width of the EWMA limits at the i-th point (1-based)."""
    return width * sigma * math.sqrt(lam / (2 - lam) * (1 - (1 - lam) ** (2 * i)))


def ewma_limit_half_widths(sigma: float, n: int, lam: float, width: float) -> np.ndarray:
    """Half widths of the EWMA limits at points 1 to ``n``: :func:`ewma_limit_half_width` of
    each, as an array.

    The start-up term (1 − λ)^2i is computed only while it can still change ``1 − term``:
    beyond 2⁻⁶⁰ it rounds away and the difference is exactly 1. The power of a float over a
    million integer exponents cost a third of a second, more than the rest of the EWMA.
    """
    index = np.arange(1, n + 1)
    startup = np.ones(n)
    base = 1 - lam
    if base > 0:
        # The first i with base**(2i) below 2**-60; a few more for the rounding of log.
        needed = math.ceil(60 * math.log(2) / (-2 * math.log(base))) + 2 if base < 1 else n
        head = min(n, needed)
        startup[:head] = 1 - base ** (2 * index[:head])
    return width * sigma * np.sqrt(lam / (2 - lam) * startup)


def ewma_chart(
    values: Iterable[float] | np.ndarray,
    center: float,
    sigma: float,
    *,
    lam: float = EWMA_LAMBDA,
    width: float = EWMA_WIDTH,
    cycles: Sequence[int] | np.ndarray | None = None,
) -> Ewma:
    """The EWMA of the readings about ``center`` with limits from ``sigma`` (the within sigma)."""
    if not 0 < lam <= 1:
        raise ValueError("the EWMA weight must lie in (0, 1]")

    array = as_readings(values)
    labels = np.arange(1, array.size + 1) if cycles is None else np.asarray(cycles, dtype=int)
    z = ewma_values(array, center, lam)
    half = ewma_limit_half_widths(sigma, array.size, lam, width)
    beyond = np.abs(z - center) > half if sigma > 0 else np.zeros(array.size, bool)
    signals = (np.flatnonzero(beyond) + 1).tolist()
    return Ewma(
        lam=lam,
        width=width,
        center=float(center),
        sigma=float(sigma),
        last=float(z[-1]) if z.size else None,
        signals=tuple(signals),
        signal_cycles=tuple(int(c) for c in labels[beyond]),
    )


@dataclass(frozen=True)
class Trend:
    """The least-squares trend of the readings on their times (``basis`` "time") or cycle order
    (``basis`` "cycle"): ``per_span`` is the change over ``span`` cycles, with its
    ``confidence`` interval (``low``, ``high``) and two-sided ``p_value``; ``significant`` when
    p < alpha. None-valued with fewer than 3 readings or no spread in time."""

    basis: str
    span: int
    per_span: float | None
    low: float | None
    high: float | None
    p_value: float | None
    significant: bool | None
    n: int
    cycle_seconds: float | None = None


def trend(
    values: Iterable[float] | np.ndarray,
    times: Sequence[float] | np.ndarray | None = None,
    *,
    span: int = TREND_SPAN,
    alpha: float = ALPHA,
    confidence: float = 0.95,
) -> Trend:
    """The trend of the readings (see :class:`Trend`); ``times`` in seconds, one per reading."""
    from scipy import stats

    array = as_readings(values)
    n = int(array.size)
    basis = "cycle"
    x = np.arange(n, dtype=float)
    scale = 1.0  # cycles per unit of x
    cycle_seconds = None
    if times is not None:
        t = np.asarray(times, dtype=float)
        if t.size == n and np.all(np.isfinite(t)) and n >= 2 and float(np.ptp(t)) > 0:
            basis = "time"
            x = t - t[0]
            cycle_seconds = float(np.median(np.diff(t)))
            if not cycle_seconds > 0:
                cycle_seconds = float(np.ptp(t)) / (n - 1)
            scale = cycle_seconds
    if n < 3 or not float(np.ptp(x)) > 0 or not float(np.ptp(array)) > 0:
        return Trend(basis, span, None, None, None, None, None, n, cycle_seconds)
    fit = stats.linregress(x, array)
    t_quantile = float(stats.t.ppf(0.5 + confidence / 2, n - 2))
    per_span = float(fit.slope) * scale * span
    half = t_quantile * float(fit.stderr) * scale * span
    p = float(fit.pvalue)
    return Trend(
        basis, span, per_span, per_span - half, per_span + half, p, p < alpha, n, cycle_seconds
    )


@dataclass(frozen=True)
class Drift:
    """Drift of one channel: the retrospective EWMA chart and the trend test, and the sentence
    to show when either finds something (``message``; None when neither does)."""

    ewma: Ewma | None
    trend: Trend
    message: str | None


def drift(
    values: Iterable[float] | np.ndarray,
    sigma_within: float | None,
    *,
    times: Sequence[float] | np.ndarray | None = None,
    cycles: Sequence[int] | np.ndarray | None = None,
    name: str = "",
    unit: str = "",
    resolution: float | None = None,
) -> Drift:
    """EWMA about the mean (σ the within sigma) and the trend on reading times; the trend in
    the message is written at the gauge ``resolution``'s figure decimals when given."""

    array = as_readings(values)
    chart = None
    if sigma_within and sigma_within > 0 and array.size:
        chart = ewma_chart(array, float(np.mean(array)), sigma_within, cycles=cycles)
    found = trend(array, times)
    message = None
    subject = f"{name} " if name else ""
    if found.significant and found.per_span is not None and found.p_value is not None:
        per_span = (
            format_figure(found.per_span, resolution) if resolution else two_digits(found.per_span)
        )
        message = (
            f"{subject}drifts {per_span}{' ' + unit if unit else ''} per "
            f"{found.span} cycles, {p_phrase(found.p_value)}: let the robot warm up and repeat"
        )
    elif chart is not None and chart.signals:
        message = (
            f"{subject}EWMA leaves its limits at cycle {chart.signal_cycles[0]}: the mean moved "
            "during the session; look for warm-up, a loose fixture or gauge, and repeat"
        )
    return Drift(chart, found, message)


_SCIPY_IMPORT = threading.Lock()
"""One importer of scipy at a time: two threads importing its packages at once can deadlock
on Python's module locks (scipy.stats and scipy.special import each other's parts), which
under load ended ``station capture`` with exit 70."""


def import_scipy() -> None:
    """Import the parts of scipy the analysis loads where it uses them (a screen that imports
    the analysis does not wait for scipy), once: a second caller waits for the first.

    Call it before starting the threads that analyse (the engine does, as it starts), or early
    on one worker thread (the TUI's warm-up), so that no analysis imports scipy where waiting
    costs (an engine's intake, under its lock) or alongside another importer."""
    with _SCIPY_IMPORT:
        import scipy.signal  # noqa: F401 - the EWMA (diagnostics)
        import scipy.special  # noqa: F401 - the confidence bounds (capability, constants, hints)
        import scipy.stats  # noqa: F401 - the tests (diagnostics, gauge check, joints)
