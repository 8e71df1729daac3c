"""The gauge linearity and bias study (AIAG MSA, 4th ed., "Gage Linearity and Bias Study"): is
the indicator right over its whole travel, not only near its zero?

Five or more reference masters (gauge blocks) spanning the range used, of known sizes x_i, are
each measured m_i times (10 to 12, re-seated each time). With z_ij the j-th reading of master i:

* bias per reading y_ij = z_ij − x_i; per master the bias b_i = mean(y_ij), the repeatability
  s_i (sample SD, n − 1) and the t-test of b_i = 0: t = b_i / (s_i/√m_i), m_i − 1 degrees of
  freedom (Minitab's "sample standard deviation" method);
* the least-squares line of every y_ij on its x_i (N = Σm_i points): y = a + b·x with slope b,
  intercept a, R², s = √(Σ(y − ŷ)²/(N − 2)); the t-tests of the slope (t = b / (s/√Sxx)) and of
  the intercept (t = a / (s·√(1/N + x̄²/Sxx))), N − 2 degrees of freedom;
* linearity = |b|·PV (PV: the process variation, 6σ of the process, or the tolerance when no PV
  is known, said so) and %linearity = 100·|b|;
* the average bias b̄ = mean of every y_ij, its test t = b̄ / (s_r/√N) with s_r the pooled
  repeatability √(Σ(m_i − 1)s_i² / Σ(m_i − 1)), and %bias = 100·|b̄|/PV.

Checked against AIAG's own example (five parts of reference 2 to 10, twelve readings each: bias
= 0.7367 − 0.1317·x, R² 71.4 %, s 0.2396; average bias −0.0533, t 1.729; tests/methods).

The verdict (a word and a sentence, never more than the readings show), at 95 %:

* the 95 % confidence band of the fitted bias over the range of the masters is AIAG's criterion:
  bias and linearity are *not detected* when the line bias = 0 lies inside the band over the
  whole range. When the bias is not a straight line in the size (the lack-of-fit F-test of the
  masters' means against the line, p < 5 %), the line's band is not trusted and each master's
  own interval stands in for it (Bonferroni over the masters);
* without a tolerance: ACCEPTABLE when nothing is detected (the sentence gives the largest
  bias the readings cannot exclude), else NOT ACCEPTABLE;
* with a tolerance T: ACCEPTABLE when the largest bias the readings cannot exclude over the
  range is within :data:`BIAS_SHARE` of T (a bias may be detected and still be harmless), NOT
  ACCEPTABLE when a bias beyond it is proven somewhere in the range, else INCONCLUSIVE with the
  readings per master that would settle it.

A spread hidden by the gauge's rounding (every reading of a master the same display value) is
taken as the rounding's own, r/√12, so no test divides by a zero; the report says so.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.errors import StationError
from station.text import format_figure

ALPHA = 0.05
"""The significance level of every test, and 1 − the confidence of every band."""
BIAS_SHARE = 0.05
"""With a tolerance T, the bias (anywhere over the range, at 95 % confidence) the gauge may
have and still be acceptable: 5 % of T, the share VDA 5 and Bosch allow a gauge's resolution
(the station's rule, stated in the report)."""
MASTERS_MIN = 5
"""The reference masters AIAG asks for (fewer are analysed, with a note)."""
READINGS_MIN = 10
"""The readings per master AIAG asks for (fewer are analysed, with a note)."""
BAND_POINTS = 201
"""Points of the range the confidence band is evaluated at."""

ACCEPTABLE, NOT_ACCEPTABLE, INCONCLUSIVE = "ACCEPTABLE", "NOT ACCEPTABLE", "INCONCLUSIVE"


@dataclass(frozen=True)
class MasterBias:
    """One reference master: its size, its readings' count, mean, bias and repeatability, and
    the t-test of its bias (``t``, ``p`` None when it cannot be tested: one reading)."""

    reference: float
    n: int
    mean: float
    bias: float
    sd: float
    t: float | None
    p: float | None
    rounded: bool = False
    """True when its readings did not vary: ``sd`` is the rounding's r/√12."""

    @property
    def half_width(self) -> float | None:
        """The 95 % confidence half-width of its bias (None with one reading)."""
        from scipy import stats  # on first use: see station/README.md

        if self.n < 2:
            return None
        return float(stats.t.ppf(1 - ALPHA / 2, self.n - 1)) * self.sd / math.sqrt(self.n)

    def as_json(self) -> dict[str, Any]:
        """``reference``, ``n``, ``bias``, ``t``, ``p``, then the rest."""
        return {
            "reference": self.reference,
            "n": self.n,
            "bias": self.bias,
            "t": self.t,
            "p": self.p,
            "mean": self.mean,
            "sd": self.sd,
            "rounded": self.rounded,
        }


@dataclass(frozen=True)
class LinearityStudy:
    """A gauge linearity and bias study (see the module for every formula)."""

    masters: tuple[MasterBias, ...]
    n: int
    slope: float
    intercept: float
    r2: float | None
    s: float
    slope_se: float
    intercept_se: float
    slope_t: float
    intercept_t: float
    slope_p: float
    intercept_p: float
    average_bias: float
    repeatability: float
    """The pooled repeatability s_r of the masters."""
    average_bias_t: float
    average_bias_p: float
    lack_of_fit_p: float | None
    """The lack-of-fit F-test of the straight line (None with fewer than 3 masters)."""
    process_variation: float | None
    pv_source: str | None
    """``given`` (a PV), ``tolerance`` (T stands in for it) or None (neither)."""
    tolerance: float | None
    share: float
    """The share of the tolerance the verdict allows as bias."""
    bias_bound: float
    """The largest |bias| over the range the readings cannot exclude (95 %)."""
    bias_proven: float
    """The largest |bias| over the range the readings prove (95 %; ≤ 0: none proven)."""
    bias_proven_at: float
    """The reference size where that bias is proven (or nearest to it)."""
    verdict: str
    sentence: str
    acceptable: bool | None
    resolution: float | None = None
    unit: str = ""

    @property
    def linearity(self) -> float | None:
        """|slope| · PV (None without a process variation or a tolerance)."""
        return None if self.process_variation is None else abs(self.slope) * self.process_variation

    @property
    def pct_linearity(self) -> float:
        """100 · |slope|: the linearity as a percentage of the process variation."""
        return 100.0 * abs(self.slope)

    @property
    def pct_bias(self) -> float | None:
        """100 · |average bias| / PV (None without one)."""
        if not self.process_variation:
            return None
        return 100.0 * abs(self.average_bias) / self.process_variation

    @property
    def allowed_bias(self) -> float | None:
        """The bias the verdict allows: :data:`BIAS_SHARE` of the tolerance (None without)."""
        return None if self.tolerance is None else self.share * self.tolerance

    def as_json(self) -> dict[str, Any]:
        """``station analyze --procedure gauge_linearity --json``'s ``gauge_linearity``."""
        return {
            "slope": self.slope,
            "intercept": self.intercept,
            "r2": self.r2,
            "s": self.s,
            "slope_p": self.slope_p,
            "intercept_p": self.intercept_p,
            "average_bias": self.average_bias,
            "average_bias_p": self.average_bias_p,
            "linearity": self.linearity,
            "pct_linearity": self.pct_linearity,
            "biases": [master.as_json() for master in self.masters],
            "acceptable": self.acceptable,
            "verdict": self.verdict,
            "sentence": self.sentence,
            "n": self.n,
            "slope_t": self.slope_t,
            "intercept_t": self.intercept_t,
            "slope_se": self.slope_se,
            "intercept_se": self.intercept_se,
            "df": self.n - 2,
            "average_bias_t": self.average_bias_t,
            "repeatability": self.repeatability,
            "pct_bias": self.pct_bias,
            "lack_of_fit_p": self.lack_of_fit_p,
            "process_variation": self.process_variation,
            "pv_source": self.pv_source,
            "tolerance": self.tolerance,
            "allowed_bias": self.allowed_bias,
            "share": self.share,
            "bias_bound": self.bias_bound,
            "bias_proven": max(self.bias_proven, 0.0),
            "alpha": ALPHA,
            "resolution": self.resolution,
            "unit": self.unit,
        }

    def lines(self) -> list[str]:
        """The study as plain report lines (the verdict first, then the figures and notes)."""
        unit = f" {self.unit}" if self.unit else ""

        def g(value: float | None, *, signed: bool = True) -> str:
            return _figure(value, self.resolution, signed=signed)

        lines = [
            f"GAUGE LINEARITY AND BIAS STUDY: {self.verdict}",
            f"  {self.sentence}",
            f"  {len(self.masters)} reference masters, {self.n} readings",
            f"  bias = {g(self.intercept)} {self.slope:+.5g}·reference{unit}   "
            f"R² {_percent(self.r2)}   s {g(self.s, signed=False)}{unit}",
            f"  slope     {self.slope:+.5g} (se {self.slope_se:.3g}), t = {self.slope_t:.3f}, "
            f"{_p(self.slope_p)}",
            f"  intercept {g(self.intercept)}{unit} (se {g(self.intercept_se, signed=False)}), "
            f"t = {self.intercept_t:.3f}, {_p(self.intercept_p)}   (df {self.n - 2})",
        ]
        pv = self.process_variation
        if pv is None:
            lines.append(
                f"  %linearity = 100·|slope| = {self.pct_linearity:.3g} %   linearity: no "
                "process variation or tolerance given"
            )
        else:
            source = "the tolerance T" if self.pv_source == "tolerance" else "PV"
            lines.append(
                f"  linearity = |slope|·{source} ({g(pv, signed=False)}{unit}) = "
                f"{g(self.linearity, signed=False)}{unit}   %linearity {self.pct_linearity:.3g} %"
            )
        bias_line = (
            f"  average bias {g(self.average_bias)}{unit}, t = {self.average_bias_t:.3f}, "
            f"{_p(self.average_bias_p)} (pooled repeatability "
            f"{g(self.repeatability, signed=False)}{unit})"
        )
        if self.pct_bias is not None:
            bias_line += f", %bias {self.pct_bias:.3g} %"
        lines.append(bias_line)
        lines.append(f"  {'reference':>12}  {'n':>3}  {'bias':>11}  {'s':>10}  {'t':>8}  p-value")
        for master in self.masters:
            t = "-" if master.t is None else f"{master.t:.3f}"
            p = "-" if master.p is None else _p(master.p).removeprefix("p = ").replace("p ", "")
            mark = " (rounded)" if master.rounded else ""
            lines.append(
                f"  {master.reference:>12.6g}  {master.n:>3}  {g(master.bias):>11}  "
                f"{g(master.sd, signed=False):>10}  {t:>8}  {p}{mark}"
            )
        lines.extend(f"  note: {note}" for note in self.notes())
        return lines

    def notes(self) -> list[str]:
        """Sentences on what limits the study (few masters or readings, rounding, the rule)."""
        notes: list[str] = []
        if len(self.masters) < MASTERS_MIN:
            notes.append(
                f"only {len(self.masters)} reference masters: AIAG asks for {MASTERS_MIN} or "
                "more spanning the range the gauge is used over."
            )
        few = [m for m in self.masters if m.n < READINGS_MIN]
        if few:
            notes.append(
                f"{len(few)} master(s) measured fewer than {READINGS_MIN} times: AIAG asks for "
                "10 to 12 readings each, re-seated every time."
            )
        if any(m.rounded for m in self.masters):
            notes.append(
                "a master's readings did not vary: its spread is taken as the gauge's rounding "
                "(resolution/√12); a finer gauge would show the real one."
            )
        if self.lack_of_fit_p is not None and self.lack_of_fit_p < ALPHA:
            notes.append(
                f"the bias is not a straight line in the size (lack of fit, "
                f"{_p(self.lack_of_fit_p)}): each master's own bias is judged, not the line."
            )
        if self.allowed_bias is not None:
            unit = f" {self.unit}" if self.unit else ""
            notes.append(
                f"the verdict allows a bias within {self.share:.0%} of the tolerance "
                f"(±{_figure(self.allowed_bias, self.resolution, signed=False)}{unit}) anywhere "
                "over the range, "
                "at 95 % confidence."
            )
        return notes


def _figure(value: float | None, resolution: float | None, *, signed: bool = True) -> str:
    """A figure in the unit as every report writes it (:func:`~station.text.format_figure`)."""
    return format_figure(value, resolution, signed=signed)


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def _p(value: float) -> str:
    """``p = 0.0894`` or ``p < 0.0001``."""
    return "p < 0.0001" if value < 1e-4 else f"p = {value:.4f}"


def _two_sided_p(t: float, df: int) -> float:
    from scipy import stats  # on first use: see station/README.md

    return float(2.0 * stats.t.sf(abs(t), df))


def linearity_study(
    references: Sequence[float] | Any,
    values: Sequence[float] | Any,
    *,
    process_variation: float | None = None,
    tolerance: float | None = None,
    share: float = BIAS_SHARE,
    resolution: float | None = None,
    unit: str = "",
) -> LinearityStudy:
    """The study of ``values`` (each a reading of the master whose size is the same row's
    ``references``), with the process variation (6σ) and the tolerance where known and the
    gauge's ``resolution``; with a tolerance the verdict allows a bias of ``share`` of it.

    Raises StationError for fewer than 2 masters, a master read once, a value that is not
    finite, or a PV, tolerance or resolution that is not positive.
    """
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(references, dtype=float).ravel()
    z = np.asarray(values, dtype=float).ravel()
    if x.size != z.size:
        raise StationError("each reading needs the size of the master it was read on.")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        raise StationError("a reference size or a reading is not a finite number; fix or drop it.")
    for name, value in (
        ("process variation", process_variation),
        ("tolerance", tolerance),
        ("resolution", resolution),
        ("share of the tolerance", share),
    ):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise StationError(f"the {name} must be more than 0, not {value!r}.")
    sizes = sorted(set(x.tolist()))
    if len(sizes) < 2:
        raise StationError(
            f"a linearity study needs 2 or more reference masters of different sizes "
            f"({len(sizes)} given); AIAG asks for {MASTERS_MIN} spanning the range."
        )
    rounding = None if resolution is None else resolution / math.sqrt(12.0)
    y = z - x
    masters = []
    for size in sizes:
        rows = y[x == size]
        if rows.size < 2:
            raise StationError(
                f"the master of size {size:g} was read {rows.size} time; read each master "
                f"{READINGS_MIN} to 12 times."
            )
        sd, rounded = _spread(rows, rounding)
        bias = float(rows.mean())
        t = None if sd == 0 else bias / (sd / math.sqrt(rows.size))
        masters.append(
            MasterBias(
                reference=float(size),
                n=int(rows.size),
                mean=float(z[x == size].mean()),
                bias=bias,
                sd=sd,
                t=t,
                p=None if t is None else _two_sided_p(t, rows.size - 1),
                rounded=rounded,
            )
        )

    n = int(y.size)
    x_bar, y_bar = float(x.mean()), float(y.mean())
    sxx = float(np.sum((x - x_bar) ** 2))
    slope = float(np.sum((x - x_bar) * (y - y_bar)) / sxx)
    intercept = y_bar - slope * x_bar
    residuals = y - (intercept + slope * x)
    sse = float(np.sum(residuals**2))
    syy = float(np.sum((y - y_bar) ** 2))
    df = n - 2
    s = math.sqrt(sse / df)
    if rounding is not None and s < rounding:
        s = rounding  # the readings cannot tell a spread below the gauge's rounding
    r2 = None if syy == 0 else 1.0 - sse / syy
    slope_se = s / math.sqrt(sxx)
    intercept_se = s * math.sqrt(1.0 / n + x_bar**2 / sxx)
    slope_t, intercept_t = _ratio(slope, slope_se), _ratio(intercept, intercept_se)

    pooled_df = sum(m.n - 1 for m in masters)
    repeatability = math.sqrt(sum((m.n - 1) * m.sd**2 for m in masters) / pooled_df)
    average_t = _ratio(y_bar, repeatability / math.sqrt(n))

    lack_of_fit_p = None
    if len(masters) > 2 and n > len(masters):
        # Pure error: the readings about their master's mean; lack of fit: the means about the
        # line. F = (SS_LOF / (g − 2)) / (SS_PE / (N − g)).
        ss_pe = sum(float(np.sum((y[x == m.reference] - m.bias) ** 2)) for m in masters)
        ss_lof = max(sse - ss_pe, 0.0)
        pure = max(ss_pe / (n - len(masters)), (rounding or 0.0) ** 2)
        if pure > 0:
            f = (ss_lof / (len(masters) - 2)) / pure
            lack_of_fit_p = float(stats.f.sf(f, len(masters) - 2, n - len(masters)))

    pv, pv_source = process_variation, "given" if process_variation is not None else None
    if pv is None and tolerance is not None:
        pv, pv_source = tolerance, "tolerance"

    line_trusted = lack_of_fit_p is None or lack_of_fit_p >= ALPHA
    if line_trusted:
        grid = np.linspace(sizes[0], sizes[-1], BAND_POINTS)
        t_band = float(stats.t.ppf(1 - ALPHA / 2, df))
        fitted = intercept + slope * grid
        half = t_band * s * np.sqrt(1.0 / n + (grid - x_bar) ** 2 / sxx)
        bound = float(np.max(np.abs(fitted) + half))
        proof = np.abs(fitted) - half
        worst = int(np.argmax(proof))
        proven, proven_at = float(proof[worst]), float(grid[worst])
    else:
        # Each master's own 95 % interval, Bonferroni over the masters.
        widths = [
            float(stats.t.ppf(1 - ALPHA / (2 * len(masters)), m.n - 1)) * m.sd / math.sqrt(m.n)
            for m in masters
        ]
        bound = max(abs(m.bias) + w for m, w in zip(masters, widths, strict=True))
        proofs = [abs(m.bias) - w for m, w in zip(masters, widths, strict=True)]
        worst = int(np.argmax(proofs))
        proven, proven_at = proofs[worst], masters[worst].reference
    verdict, sentence, acceptable = _verdict(
        None if tolerance is None else share * tolerance,
        f"{share:.0%} of T",
        bound,
        proven,
        proven_at,
        masters,
        line_trusted,
        unit,
    )
    return LinearityStudy(
        masters=tuple(masters),
        n=n,
        slope=slope,
        intercept=intercept,
        r2=r2,
        s=s,
        slope_se=slope_se,
        intercept_se=intercept_se,
        slope_t=slope_t,
        intercept_t=intercept_t,
        slope_p=_two_sided_p(slope_t, df),
        intercept_p=_two_sided_p(intercept_t, df),
        average_bias=y_bar,
        repeatability=repeatability,
        average_bias_t=average_t,
        average_bias_p=_two_sided_p(average_t, pooled_df),
        lack_of_fit_p=lack_of_fit_p,
        process_variation=pv,
        pv_source=pv_source,
        tolerance=tolerance,
        share=share,
        bias_bound=bound,
        bias_proven=proven,
        bias_proven_at=proven_at,
        verdict=verdict,
        sentence=sentence,
        acceptable=acceptable,
        resolution=resolution,
        unit=unit,
    )


def _spread(rows: np.ndarray, rounding: float | None) -> tuple[float, bool]:
    """The sample SD of a master's biases, and whether the gauge's rounding stands in for it
    (readings that do not vary, or vary by float noise only, show no spread of their own)."""
    sd = float(rows.std(ddof=1))
    same = float(np.ptp(rows)) <= 1e-9 * max(1.0, float(np.max(np.abs(rows))))
    if rounding is not None and (same or sd < rounding):
        return rounding, True
    return (0.0 if same else sd), False


def _ratio(value: float, error: float) -> float:
    """A t statistic; infinite (signed) when the error is 0 and the value is not."""
    if error > 0:
        return value / error
    return 0.0 if value == 0 else math.copysign(math.inf, value)


def _verdict(
    allowed: float | None,
    share: str,
    bound: float,
    proven: float,
    proven_at: float,
    masters: Sequence[MasterBias],
    line_trusted: bool,
    unit: str,
) -> tuple[str, str, bool | None]:
    """The word, the sentence and whether the gauge is accepted (see the module)."""
    u = f" {unit}" if unit else ""
    where = "over the range" if line_trusted else "at the masters"
    cannot = f"the readings cannot exclude a bias of up to ±{bound:.3g}{u} {where}"
    if allowed is None:
        if proven <= 0:
            return (
                ACCEPTABLE,
                f"no bias or linearity detected (AIAG: bias = 0 lies within the 95 % "
                f"confidence band {where}); {cannot}: give the tolerance to judge whether "
                "that matters.",
                True,
            )
        return (
            NOT_ACCEPTABLE,
            f"a bias of at least {proven:.3g}{u} is proven at {proven_at:g}{u} (95 %): "
            "recalibrate or correct the gauge, or give the tolerance to judge whether it "
            "matters.",
            False,
        )
    if bound <= allowed:
        detected = "a bias is detected but" if proven > 0 else "no bias detected, and"
        return (
            ACCEPTABLE,
            f"{detected} any bias {where} is within ±{bound:.3g}{u}, inside the "
            f"±{allowed:.3g}{u} ({share}) allowed (95 %).",
            True,
        )
    if proven > allowed:
        return (
            NOT_ACCEPTABLE,
            f"a bias of at least {proven:.3g}{u} is proven at {proven_at:g}{u}, beyond the "
            f"±{allowed:.3g}{u} ({share}) allowed (95 %): recalibrate or "
            "correct the gauge.",
            False,
        )
    readings = _readings_to_settle(masters, bound, max(proven, 0.0), allowed)
    settle = (
        f"about {readings} readings per master would settle it"
        if readings is not None
        else "the bias lies at the allowed limit: more readings will not settle it, a finer "
        "gauge or a decision on the tolerance will"
    )
    return (
        INCONCLUSIVE,
        f"{cannot}, more than the ±{allowed:.3g}{u} ({share}) allowed, and no "
        f"bias beyond it is proven: {settle}.",
        None,
    )


def _readings_to_settle(
    masters: Sequence[MasterBias], bound: float, proven: float, allowed: float
) -> int | None:
    """Readings per master at which the band (its half-width falling as 1/√m) would lie on one
    side of the allowed bias, at the bias estimated now; None when the estimate sits on it."""
    estimate = (bound + proven) / 2.0  # the largest |bias| the line estimates, about
    half = (bound - proven) / 2.0
    gap = abs(allowed - estimate)
    if gap <= 1e-12 * max(allowed, 1e-300) or half <= 0:
        return None
    per_master = max(m.n for m in masters)
    return max(per_master + 1, math.ceil(per_master * (half / gap) ** 2))
