"""A crossed Gage R&R study (AIAG MSA, 4th ed., "Gage Repeatability and Reproducibility"): how
much of what a gauge shows over a set of parts is the gauge and its appraisers, and how much is
the parts?

k appraisers (2 or more; AIAG asks for 3) each measure the same n parts (2 or more; AIAG asks for
10 spanning the process range) r times (2 or more; AIAG asks for 3), in a fresh random order
each trial. With y_ijm the m-th reading of part i by appraiser j, it is analysed two ways.

**ANOVA** (parts and appraisers random, crossed, with their interaction). Sums of squares about
the part means ȳ_i, the appraiser means ȳ_j, the cell means ȳ_ij and the grand mean ȳ:

* SS_P = k·r·Σ(ȳ_i − ȳ)², df n − 1; SS_A = n·r·Σ(ȳ_j − ȳ)², df k − 1;
* SS_PA = r·Σ(ȳ_ij − ȳ_i − ȳ_j + ȳ)², df (n − 1)(k − 1); SS_E = Σ(y_ijm − ȳ_ij)², df n·k·(r − 1);
* MS = SS/df; the interaction is tested by F = MS_PA/MS_E, parts and appraisers against MS_PA.

When the interaction's p is above :data:`POOL_ABOVE` (0.25, AIAG's and Minitab's default) it is
pooled into repeatability, as AIAG does: MS_E' = (SS_PA + SS_E)/(df_PA + df_E), parts and
appraisers are tested against MS_E', and the interaction's variance is 0. The variance
components from the expected mean squares:

* repeatability σ²_E = MS_E (MS_E' pooled);
* interaction σ²_PA = (MS_PA − MS_E)/r (0 pooled);
* appraiser σ²_A = (MS_A − MS_PA)/(n·r) (MS_E' in place of MS_PA pooled);
* part σ²_P = (MS_P − MS_PA)/(k·r) (likewise);

a negative estimate is set to 0, and the report says so. Reproducibility σ²_R = σ²_A + σ²_PA,
GRR σ² = σ²_E + σ²_R, total σ²_T = GRR + σ²_P. EV, AV (reproducibility, the interaction in it),
GRR, PV and TV are stated as **6σ spreads** (the study variation, as Minitab's "6 × SD");
%study variation = 100·spread/TV, %tolerance = 100·spread/T, ndc = 1.41·PV/GRR truncated.

Why not statsmodels: its ``anova_lm`` fits the fixed-effects model and tests every term against
the residual, where the random crossed design tests parts and appraisers against the
interaction; and it gives no variance components (``MixedLM`` fits REML, a different estimator
from AIAG's). The sums of squares here are checked against ``anova_lm`` in the tests.

**Average and range** (AIAG's worksheet; σ figures, not spreads). R̄̄ = mean over appraisers of
their mean range of a part's r readings; X̄diff = the largest appraiser average less the
smallest; R_p = the largest part average less the smallest:

* EV = R̄̄·K1, K1 = 1/d2(r);
* AV = √((X̄diff·K2)² − EV²/(n·r)), K2 = 1/d2*(k) (0 when negative, said so);
* GRR = √(EV² + AV²); PV = R_p·K3, K3 = 1/d2*(n); TV = √(GRR² + PV²);
* %EV, %AV, %GRR, %PV = 100·x/TV, ndc = 1.41·PV/GRR truncated.

d2*(m) is Duncan's for one range, √(d2(m)² + d3(m)²) (the moment match that defines it), which
gives AIAG's tables (K1 0.8862, 0.5908; K2 0.7071, 0.5231; K3 0.7071 ... 0.3146) to every digit.
A part's range above D4·R̄̄ (the R chart's limit) is named: AIAG re-measures it.

**The verdict** (AIAG's bands), from the ANOVA: %GRR of the study variation, and with a
tolerance of the tolerance too, the larger judged: under 10 % ACCEPTABLE, 10 to 30 %
CONDITIONALLY ACCEPTABLE (by the importance of the application, the cost of the gauge...), over
30 % NOT ACCEPTABLE; ndc under 5 (the gauge cannot tell 5 groups of these parts apart) is NOT
ACCEPTABLE whatever the %GRR. Readings that never differ between trials or appraisers are
INCONCLUSIVE: the gauge's resolution hides its own variation.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from station.analysis.constants import chart_factors, d2, d3
from station.errors import StationError
from station.plain import plain

POOL_ABOVE = 0.25
"""The interaction's p above which it is pooled into repeatability (AIAG, Minitab)."""
SPREAD_SIGMAS = 6.0
"""The ANOVA's spreads are this many standard deviations (the study variation)."""
NDC_FACTOR = 1.41
"""ndc = 1.41·PV/GRR (AIAG: √2, rounded as AIAG prints it)."""
ACCEPTABLE_BELOW = 10.0
"""%GRR under which the gauge is acceptable (AIAG)."""
NOT_ACCEPTABLE_ABOVE = 30.0
"""%GRR over which it is not (AIAG); between the two it is conditionally acceptable."""
NDC_MIN = 5
"""The distinct categories AIAG asks the gauge to tell apart."""
APPRAISERS_AIAG, PARTS_AIAG, TRIALS_AIAG = 3, 10, 3
"""The study AIAG describes: 3 appraisers, 10 parts, 3 trials (fewer are analysed, noted)."""

ACCEPTABLE = "ACCEPTABLE"
CONDITIONAL = "CONDITIONALLY ACCEPTABLE"
NOT_ACCEPTABLE = "NOT ACCEPTABLE"
INCONCLUSIVE = "INCONCLUSIVE"


def k1(trials: int) -> float:
    """AIAG's K1 for ``trials`` readings of a part: 1/d2(r) (0.8862 for 2, 0.5908 for 3)."""
    return 1.0 / d2(trials)


def d2_star(size: int) -> float:
    """Duncan's d2* for one range of ``size`` values: √(d2² + d3²)."""
    return math.sqrt(d2(size) ** 2 + d3(size) ** 2)


def k2(appraisers: int) -> float:
    """AIAG's K2 for ``appraisers``: 1/d2*(k) (0.7071 for 2, 0.5231 for 3)."""
    return 1.0 / d2_star(appraisers)


def k3(parts: int) -> float:
    """AIAG's K3 for ``parts``: 1/d2*(n) (0.7071 for 2 ... 0.3146 for 10)."""
    return 1.0 / d2_star(parts)


@dataclass(frozen=True)
class AnovaRow:
    """One line of an ANOVA table (``f`` and ``p`` None for repeatability and the total)."""

    source: str
    df: int
    ss: float
    ms: float | None
    f: float | None = None
    p: float | None = None

    def as_json(self) -> dict[str, Any]:
        """The row's figures by name."""
        return {"source": self.source, "df": self.df, "ss": self.ss, "ms": self.ms,
                "f": self.f, "p": self.p}  # fmt: skip


@dataclass(frozen=True)
class AnovaStudy:
    """The ANOVA method's figures (see the module): variances, then 6σ spreads."""

    table: tuple[AnovaRow, ...]
    """With the interaction: part, appraiser, part × appraiser, repeatability, total."""
    pooled_table: tuple[AnovaRow, ...] | None
    """Without it (pooled into repeatability): part, appraiser, repeatability, total; None
    when the interaction stays."""
    interaction_p: float
    pooled: bool
    pool_above: float
    var_repeatability: float
    var_appraiser: float
    var_interaction: float
    var_part: float
    zeroed: tuple[str, ...]
    """The components whose estimate was negative, set to 0."""
    tolerance: float | None

    @property
    def var_reproducibility(self) -> float:
        """Appraiser and interaction."""
        return self.var_appraiser + self.var_interaction

    @property
    def var_grr(self) -> float:
        """Repeatability and reproducibility."""
        return self.var_repeatability + self.var_reproducibility

    @property
    def var_total(self) -> float:
        """GRR and part."""
        return self.var_grr + self.var_part

    @staticmethod
    def spread(variance: float) -> float:
        """A variance as a study variation: 6σ."""
        return SPREAD_SIGMAS * math.sqrt(variance)

    @property
    def ev(self) -> float:
        """Repeatability, 6σ."""
        return self.spread(self.var_repeatability)

    @property
    def av(self) -> float:
        """Reproducibility (appraiser and interaction), 6σ."""
        return self.spread(self.var_reproducibility)

    @property
    def grr(self) -> float:
        """Gage R&R, 6σ."""
        return self.spread(self.var_grr)

    @property
    def pv(self) -> float:
        """Part variation, 6σ."""
        return self.spread(self.var_part)

    @property
    def tv(self) -> float:
        """Total variation, 6σ."""
        return self.spread(self.var_total)

    def pct(self, spread: float) -> float | None:
        """``spread`` as a percentage of the total variation (None when there is none)."""
        return None if self.tv == 0 else 100.0 * spread / self.tv

    def pct_of_tolerance(self, spread: float) -> float | None:
        """``spread`` as a percentage of the tolerance (None without one)."""
        return None if self.tolerance is None else 100.0 * spread / self.tolerance

    @property
    def pct_grr(self) -> float | None:
        """%GRR of the study variation."""
        return self.pct(self.grr)

    @property
    def pct_tolerance(self) -> float | None:
        """%GRR of the tolerance."""
        return self.pct_of_tolerance(self.grr)

    @property
    def ndc(self) -> int | None:
        """1.41·PV/GRR truncated (None when GRR is 0)."""
        return _ndc(self.pv, self.grr)

    def as_json(self) -> dict[str, Any]:
        """The ANOVA's figures (``spread_sigmas``: EV...TV are that many σ)."""
        return {
            "var_repeatability": self.var_repeatability,
            "var_reproducibility": self.var_reproducibility,
            "var_part": self.var_part,
            "var_interaction": self.var_interaction,
            "interaction_p": self.interaction_p,
            "pooled": self.pooled,
            "ev": self.ev,
            "av": self.av,
            "grr": self.grr,
            "pv": self.pv,
            "tv": self.tv,
            "pct_grr": self.pct_grr,
            "pct_tolerance": self.pct_tolerance,
            "ndc": self.ndc,
            "var_appraiser": self.var_appraiser,
            "var_grr": self.var_grr,
            "var_total": self.var_total,
            "pct_ev": self.pct(self.ev),
            "pct_av": self.pct(self.av),
            "pct_pv": self.pct(self.pv),
            "spread_sigmas": SPREAD_SIGMAS,
            "pool_above": self.pool_above,
            "zeroed": list(self.zeroed),
            "table": [row.as_json() for row in self.table],
            "pooled_table": None
            if self.pooled_table is None
            else [row.as_json() for row in self.pooled_table],
        }


@dataclass(frozen=True)
class AverageRangeStudy:
    """The average and range method's figures (see the module): standard deviations."""

    rbarbar: float
    xdiff: float
    part_range: float
    """R_p: the largest part average less the smallest."""
    k1: float
    k2: float
    k3: float
    ev: float
    av: float
    av_zeroed: bool
    """(X̄diff·K2)² was below EV²/(n·r): AV is taken as 0."""
    pv: float
    appraiser_means: tuple[float, ...]
    appraiser_rbar: tuple[float, ...]
    ucl_r: float
    ranges_out: tuple[tuple[str, str, float], ...]
    """(part, appraiser, range) of each range above the R chart's limit."""

    @property
    def grr(self) -> float:
        """√(EV² + AV²)."""
        return math.hypot(self.ev, self.av)

    @property
    def tv(self) -> float:
        """√(GRR² + PV²)."""
        return math.hypot(self.grr, self.pv)

    def pct(self, value: float) -> float | None:
        """``value`` as a percentage of TV (None when TV is 0)."""
        return None if self.tv == 0 else 100.0 * value / self.tv

    @property
    def ndc(self) -> int | None:
        """1.41·PV/GRR truncated (None when GRR is 0)."""
        return _ndc(self.pv, self.grr)

    def as_json(self, appraisers: Sequence[str]) -> dict[str, Any]:
        """The worksheet's figures (σ, ``spread_sigmas`` 1)."""
        return {
            "rbarbar": self.rbarbar,
            "xdiff": self.xdiff,
            "ev": self.ev,
            "av": self.av,
            "grr": self.grr,
            "pv": self.pv,
            "tv": self.tv,
            "pct_ev": self.pct(self.ev),
            "pct_av": self.pct(self.av),
            "pct_grr": self.pct(self.grr),
            "pct_pv": self.pct(self.pv),
            "ndc": self.ndc,
            "part_range": self.part_range,
            "k1": self.k1,
            "k2": self.k2,
            "k3": self.k3,
            "av_zeroed": self.av_zeroed,
            "spread_sigmas": 1,
            "appraiser_means": dict(zip(appraisers, self.appraiser_means, strict=True)),
            "appraiser_rbar": dict(zip(appraisers, self.appraiser_rbar, strict=True)),
            "ucl_r": self.ucl_r,
            "ranges_out": [
                {"part": part, "appraiser": appraiser, "range": value}
                for part, appraiser, value in self.ranges_out
            ],
        }


@dataclass(frozen=True)
class GageRRStudy:
    """A crossed Gage R&R study: its design, both analyses and the verdict."""

    parts: tuple[str, ...]
    appraisers: tuple[str, ...]
    trials: int
    data: np.ndarray = field(repr=False)
    """The readings as an array [part, appraiser, trial] (trials in their numbers' order)."""
    anova: AnovaStudy
    xbar_r: AverageRangeStudy
    verdict: str
    sentence: str
    acceptable: bool | None
    tolerance: float | None = None
    resolution: float | None = None
    unit: str = ""
    names: Mapping[str, str] = field(default_factory=dict)
    """An appraiser's name where one was given (the report says ``A (Ann)``)."""

    @property
    def n(self) -> int:
        """The readings."""
        return int(self.data.size)

    def appraiser_label(self, appraiser: str) -> str:
        """``A`` or ``A (Ann)``."""
        name = self.names.get(appraiser, "").strip()
        shown = _shown(appraiser)
        return f"{shown} ({_shown(name)})" if name and name != appraiser else shown

    def as_json(self) -> dict[str, Any]:
        """``station analyze --procedure gage_rr --json``'s ``gage_rr``."""
        return {
            "anova": self.anova.as_json(),
            "xbar_r": self.xbar_r.as_json(self.appraisers),
            "verdict": self.verdict,
            "sentence": self.sentence,
            "acceptable": self.acceptable,
            "parts": list(self.parts),
            "appraisers": list(self.appraisers),
            "appraiser_names": {a: self.names[a] for a in self.appraisers if a in self.names},
            "trials": self.trials,
            "n": self.n,
            "tolerance": self.tolerance,
            "resolution": self.resolution,
            "unit": self.unit,
            "notes": self.notes(),
        }

    def lines(self) -> list[str]:
        """The study as plain report lines: the verdict, the ANOVA, the average and range."""
        unit = f" {self.unit}" if self.unit else ""
        anova, xr = self.anova, self.xbar_r
        lines = [
            f"GAGE R&R (CROSSED): {self.verdict}",
            f"  {self.sentence}",
            f"  {len(self.appraisers)} appraisers ("
            + ", ".join(self.appraiser_label(a) for a in self.appraisers)
            + f") x {len(self.parts)} parts x {self.trials} trials = {self.n} readings"
            + (f"; tolerance {_g(self.tolerance)}{unit}" if self.tolerance is not None else ""),
            "",
            "ANOVA METHOD (two-way crossed, parts and appraisers random; AIAG MSA 4th ed.)",
            *_table_lines(anova.table),
        ]
        if anova.pooled_table is not None:
            lines.append(
                f"  The interaction (p = {anova.interaction_p:.3f} > {anova.pool_above:g}) is "
                "pooled into repeatability:"
            )
            lines.extend(_table_lines(anova.pooled_table))
        else:
            lines.append(
                f"  The interaction (p = {anova.interaction_p:.3f} <= {anova.pool_above:g}) "
                "stays in the model."
            )
        tolerance = anova.tolerance is not None
        lines.append(
            f"  {'source':<22}{'variance':>11}{'%contrib':>9}{'6·SD':>11}{'%study':>8}"
            + (f"{'%tol':>7}" if tolerance else "")
        )
        rows = (
            ("Gage R&R (GRR)", anova.var_grr),
            ("  repeatability (EV)", anova.var_repeatability),
            ("  reproducibility (AV)", anova.var_reproducibility),
            ("    appraiser", anova.var_appraiser),
            ("    part x appraiser", anova.var_interaction),
            ("part-to-part (PV)", anova.var_part),
            ("total (TV)", anova.var_total),
        )
        for name, variance in rows:
            spread = anova.spread(variance)
            contribution = None if anova.var_total == 0 else 100 * variance / anova.var_total
            line = (
                f"  {name:<22}{_g(variance):>11}{_pct(contribution):>9}{_g(spread):>11}"
                f"{_pct(anova.pct(spread)):>8}"
            )
            if tolerance:
                line += f"{_pct(anova.pct_of_tolerance(spread)):>7}"
            lines.append(line)
        lines.append(
            f"  6·SD is the study variation{unit and ' (' + unit.strip() + ')'}; "
            f"ndc = 1.41·PV/GRR = {_ndc_text(anova.ndc)}"
        )
        lines += [
            "",
            "AVERAGE AND RANGE METHOD (AIAG MSA 4th ed. worksheet; figures are 1 SD)",
            f"  R̄̄ {_g(xr.rbarbar)}   X̄diff {_g(xr.xdiff)}   R_p {_g(xr.part_range)}   "
            f"UCL_R {_g(xr.ucl_r)}",
            f"  EV  = R̄̄·K1 = {_g(xr.rbarbar)}·{xr.k1:.4f} = {_g(xr.ev)}"
            f"   %EV  {_pct(xr.pct(xr.ev))}",
            f"  AV  = √((X̄diff·K2)² − EV²/(n·r)), K2 {xr.k2:.4f} = {_g(xr.av)}"
            f"   %AV  {_pct(xr.pct(xr.av))}",
            f"  GRR = √(EV² + AV²) = {_g(xr.grr)}   %GRR {_pct(xr.pct(xr.grr))}",
            f"  PV  = R_p·K3 = {_g(xr.part_range)}·{xr.k3:.4f} = {_g(xr.pv)}"
            f"   %PV  {_pct(xr.pct(xr.pv))}",
            f"  TV  = √(GRR² + PV²) = {_g(xr.tv)}   ndc = {_ndc_text(xr.ndc)}",
            "  appraiser    average       R̄",
        ]
        lines.extend(
            f"  {self.appraiser_label(a):<9}{mean:>11.6g}{_g(rbar):>9}"
            for a, mean, rbar in zip(
                self.appraisers, xr.appraiser_means, xr.appraiser_rbar, strict=True
            )
        )
        lines.extend(f"  note: {note}" for note in self.notes())
        return lines

    def notes(self) -> list[str]:
        """Sentences on what limits the study (its size, zeroed components, ranges out)."""
        notes: list[str] = []
        short = [
            f"{count} {what}"
            for count, least, what in (
                (len(self.appraisers), APPRAISERS_AIAG, "appraisers"),
                (len(self.parts), PARTS_AIAG, "parts"),
                (self.trials, TRIALS_AIAG, "trials"),
            )
            if count < least
        ]
        if short:
            notes.append(
                f"only {', '.join(short)}: AIAG asks for {APPRAISERS_AIAG} appraisers x "
                f"{PARTS_AIAG} parts x {TRIALS_AIAG} trials; the estimates are the rougher."
            )
        if self.anova.zeroed:
            notes.append(
                f"the ANOVA's {' and '.join(self.anova.zeroed)} variance came out negative "
                "and is taken as 0 (it is too small for these readings to show)."
            )
        if self.xbar_r.av_zeroed:
            notes.append("average and range: (X̄diff·K2)² is below EV²/(n·r), so AV is taken as 0.")
        for part, appraiser, value in self.xbar_r.ranges_out:
            notes.append(
                f"the range of part {_shown(part)} by appraiser {_shown(appraiser)} "
                f"({_g(value)}) is above "
                f"UCL_R {_g(self.xbar_r.ucl_r)}: AIAG has it measured again (or the cause found)."
            )
        if self.resolution is not None and 0 < self.anova.tv < 10 * self.resolution:
            notes.append(
                f"the gauge's resolution {self.resolution:g} is more than a tenth of the "
                f"study variation {_g(self.anova.tv)}: it cannot resolve these parts well."
            )
        return notes


def _shown(label: object) -> str:
    """A part's or an appraiser's name as the report shows it: text from outside, with its
    control characters made visible and a long one cut."""
    return plain(label, limit=40)


def _g(value: float | None) -> str:
    return "-" if value is None else f"{value:.4g}"


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def _ndc_text(ndc: int | None) -> str:
    return "- (GRR is 0)" if ndc is None else f"{ndc} (truncated)"


def _ndc(pv: float, grr: float) -> int | None:
    if grr <= 0:
        return None
    return int(math.floor(NDC_FACTOR * pv / grr))


def _table_lines(rows: Sequence[AnovaRow]) -> list[str]:
    lines = [f"  {'source':<18}{'df':>4}{'SS':>12}{'MS':>12}{'F':>9}{'p':>8}"]
    for row in rows:
        f = "" if row.f is None else (f"{row.f:.3f}" if math.isfinite(row.f) else "inf")
        p = "" if row.p is None else ("<0.001" if row.p < 0.001 else f"{row.p:.3f}")
        ms = "" if row.ms is None else _g(row.ms)
        line = f"  {row.source:<18}{row.df:>4}{_g(row.ss):>12}{ms:>12}{f:>9}{p:>8}"
        lines.append(line.rstrip())
    return lines


# -- the design --------------------------------------------------------------------------------

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def _ordered(labels: Sequence[str]) -> tuple[str, ...]:
    """The distinct labels: by number when every one is a number (parts 1, 2 ... 10), else in
    the order they first appear."""
    distinct = tuple(dict.fromkeys(labels))
    if all(_NUMBER.match(label) for label in distinct):
        return tuple(sorted(distinct, key=float))
    return distinct


def _design(
    parts: Sequence[Any], appraisers: Sequence[Any], trials: Sequence[Any], values: Sequence[Any]
) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray]:
    """The readings as an array [part, appraiser, trial], or a StationError naming what is
    missing: an appraiser or a part too few, a part some appraiser did not measure, a trial
    missing or read twice."""
    part_labels = [str(p).strip() for p in parts]
    appraiser_labels = [str(a).strip() for a in appraisers]
    trial_numbers = list(trials)
    y = np.asarray(values, dtype=float).ravel()
    if not len(part_labels) == len(appraiser_labels) == len(trial_numbers) == y.size:
        raise StationError("each reading needs its part, its appraiser and its trial.")
    if not y.size:
        raise StationError("there are no readings: measure each part by each appraiser.")
    for label in (*part_labels, *appraiser_labels):
        if not label:
            raise StationError("a reading names no part or no appraiser; name every one.")
    cells: dict[tuple[str, str], dict[Any, float]] = {}
    for part, appraiser, trial, value in zip(
        part_labels, appraiser_labels, trial_numbers, y.tolist(), strict=True
    ):
        if not math.isfinite(value):
            raise StationError(
                f"the reading of part {_shown(part)} by appraiser {_shown(appraiser)}, trial "
                f"{_shown(trial)} is not a "
                "finite number; fix or drop it."
            )
        cell = cells.setdefault((part, appraiser), {})
        if trial in cell:
            raise StationError(
                f"part {_shown(part)} by appraiser {_shown(appraiser)} has trial "
                f"{_shown(trial)} twice; each trial is "
                "one reading of each part by each appraiser."
            )
        cell[trial] = value
    part_order, appraiser_order = _ordered(part_labels), _ordered(appraiser_labels)
    if len(appraiser_order) < 2:
        raise StationError(
            f"a Gage R&R needs 2 or more appraisers; the readings name 1 "
            f"({_shown(appraiser_order[0])}):"
            f" AIAG asks for {APPRAISERS_AIAG}, each measuring every part."
        )
    if len(part_order) < 2:
        raise StationError(
            f"a Gage R&R needs 2 or more parts; the readings name 1 "
            f"({_shown(part_order[0])}): AIAG asks for {PARTS_AIAG} spanning the process range."
        )
    for part in part_order:
        missing = [a for a in appraiser_order if (part, a) not in cells]
        if missing:
            raise StationError(
                f"part {_shown(part)} was not measured by appraiser "
                f"{', '.join(map(_shown, missing))}: in a crossed "
                "study every appraiser measures every part (measure it, or leave the part out)."
            )
    every = sorted({t for cell in cells.values() for t in cell}, key=_trial_key)
    for part in part_order:
        for appraiser in appraiser_order:
            lacking = [t for t in every if t not in cells[(part, appraiser)]]
            if lacking:
                raise StationError(
                    f"part {_shown(part)} by appraiser {_shown(appraiser)} has no trial "
                    f"{', '.join(map(str, lacking))} (the others have trials "
                    f"{', '.join(map(str, every))}): measure it, or leave that trial out for "
                    "every part (the design must be balanced)."
                )
    if len(every) < 2:
        raise StationError(
            "each appraiser measured each part once: repeatability needs 2 or more trials "
            f"(AIAG asks for {TRIALS_AIAG})."
        )
    data = np.array(
        [
            [[cells[(part, appraiser)][t] for t in every] for appraiser in appraiser_order]
            for part in part_order
        ],
        dtype=float,
    )
    return part_order, appraiser_order, data


def _trial_key(trial: Any) -> tuple[int, float, str]:
    try:
        return (0, float(trial), "")
    except (TypeError, ValueError):
        return (1, 0.0, str(trial))


# -- the analyses ------------------------------------------------------------------------------


def _ratio(numerator: float, denominator: float) -> float:
    """An F ratio; infinite when only the denominator is 0, 0 when both are."""
    if denominator > 0:
        return numerator / denominator
    return math.inf if numerator > 0 else 0.0


def _f_row(source: str, df: int, ss: float, against: float, df_against: int) -> AnovaRow:
    from scipy import stats  # on first use: see station/README.md

    ms = ss / df
    f = _ratio(ms, against)
    p = 1.0 if f == 0 else (0.0 if math.isinf(f) else float(stats.f.sf(f, df, df_against)))
    return AnovaRow(source, df, ss, ms, f, p)


def anova_method(
    data: np.ndarray, *, pool_above: float = POOL_ABOVE, tolerance: float | None = None
) -> AnovaStudy:
    """The ANOVA method on ``data`` [part, appraiser, trial] (see the module)."""
    n, k, r = data.shape
    grand = float(data.mean())
    part_means = data.mean(axis=(1, 2))
    appraiser_means = data.mean(axis=(0, 2))
    cells = data.mean(axis=2)
    ss_part = k * r * float(np.sum((part_means - grand) ** 2))
    ss_appraiser = n * r * float(np.sum((appraiser_means - grand) ** 2))
    ss_interaction = r * float(
        np.sum((cells - part_means[:, None] - appraiser_means[None, :] + grand) ** 2)
    )
    ss_error = float(np.sum((data - cells[:, :, None]) ** 2))
    ss_total = float(np.sum((data - grand) ** 2))
    df_part, df_appraiser = n - 1, k - 1
    df_interaction, df_error = df_part * df_appraiser, n * k * (r - 1)
    ms_error = ss_error / df_error
    ms_interaction = ss_interaction / df_interaction
    interaction = _f_row("part x appraiser", df_interaction, ss_interaction, ms_error, df_error)
    table = (
        _f_row("part", df_part, ss_part, ms_interaction, df_interaction),
        _f_row("appraiser", df_appraiser, ss_appraiser, ms_interaction, df_interaction),
        interaction,
        AnovaRow("repeatability", df_error, ss_error, ms_error),
        AnovaRow("total", n * k * r - 1, ss_total, None),
    )
    assert interaction.p is not None
    pooled = interaction.p > pool_above
    pooled_table = None
    if pooled:
        df_pooled = df_interaction + df_error
        ms_pooled = (ss_interaction + ss_error) / df_pooled
        pooled_table = (
            _f_row("part", df_part, ss_part, ms_pooled, df_pooled),
            _f_row("appraiser", df_appraiser, ss_appraiser, ms_pooled, df_pooled),
            AnovaRow("repeatability", df_pooled, ss_interaction + ss_error, ms_pooled),
            AnovaRow("total", n * k * r - 1, ss_total, None),
        )
        estimates = {
            "repeatability": ms_pooled,
            "appraiser": (ss_appraiser / df_appraiser - ms_pooled) / (n * r),
            "part x appraiser": 0.0,
            "part": (ss_part / df_part - ms_pooled) / (k * r),
        }
    else:
        estimates = {
            "repeatability": ms_error,
            "appraiser": (ss_appraiser / df_appraiser - ms_interaction) / (n * r),
            "part x appraiser": (ms_interaction - ms_error) / r,
            "part": (ss_part / df_part - ms_interaction) / (k * r),
        }
    zeroed = tuple(name for name, value in estimates.items() if value < 0)
    kept = {name: max(value, 0.0) for name, value in estimates.items()}
    return AnovaStudy(
        table=table,
        pooled_table=pooled_table,
        interaction_p=interaction.p,
        pooled=pooled,
        pool_above=pool_above,
        var_repeatability=kept["repeatability"],
        var_appraiser=kept["appraiser"],
        var_interaction=kept["part x appraiser"],
        var_part=kept["part"],
        zeroed=zeroed,
        tolerance=tolerance,
    )


def average_range_method(
    data: np.ndarray, parts: Sequence[str], appraisers: Sequence[str]
) -> AverageRangeStudy:
    """AIAG's average and range worksheet on ``data`` [part, appraiser, trial]."""
    n, k, r = data.shape
    ranges = np.ptp(data, axis=2)  # [part, appraiser]
    appraiser_rbar = ranges.mean(axis=0)
    rbarbar = float(appraiser_rbar.mean())
    appraiser_means = data.mean(axis=(0, 2))
    xdiff = float(np.ptp(appraiser_means))
    part_range = float(np.ptp(data.mean(axis=(1, 2))))
    factor_1, factor_2, factor_3 = k1(r), k2(k), k3(n)
    ev = rbarbar * factor_1
    squared = (xdiff * factor_2) ** 2 - ev**2 / (n * r)
    ucl_r = chart_factors(r).D4 * rbarbar
    out = tuple(
        (parts[i], appraisers[j], float(ranges[i, j]))
        for j in range(k)
        for i in range(n)
        if ranges[i, j] > ucl_r * (1 + 1e-12)
    )
    return AverageRangeStudy(
        rbarbar=rbarbar,
        xdiff=xdiff,
        part_range=part_range,
        k1=factor_1,
        k2=factor_2,
        k3=factor_3,
        ev=ev,
        av=math.sqrt(squared) if squared > 0 else 0.0,
        av_zeroed=squared < 0,
        pv=part_range * factor_3,
        appraiser_means=tuple(float(m) for m in appraiser_means),
        appraiser_rbar=tuple(float(m) for m in appraiser_rbar),
        ucl_r=ucl_r,
        ranges_out=out,
    )


def _verdict(anova: AnovaStudy) -> tuple[str, str, bool | None]:
    """The word, the sentence and whether the gauge is accepted (see the module)."""
    if anova.grr == 0:
        return (
            INCONCLUSIVE,
            "the readings never differ between trials or appraisers: the gauge's resolution "
            "hides its own variation; study it with a finer gauge.",
            None,
        )
    judged = [("of the study variation", anova.pct_grr)]
    if anova.pct_tolerance is not None:
        judged.append(("of the tolerance", anova.pct_tolerance))
    figure = " and ".join(f"{value:.1f} % {what}" for what, value in judged if value is not None)
    worst = max(value for _, value in judged if value is not None)
    ndc = anova.ndc
    assert ndc is not None
    base = f"%GRR (ANOVA) is {figure}, ndc {ndc}"
    if worst > NOT_ACCEPTABLE_ABOVE:
        return (
            NOT_ACCEPTABLE,
            f"{base}: over {NOT_ACCEPTABLE_ABOVE:g} %, the gauge and its appraisers take too "
            "much of the variation; improve the gauge or the method before using it.",
            False,
        )
    if ndc < NDC_MIN:
        return (
            NOT_ACCEPTABLE,
            f"{base}: fewer than {NDC_MIN} distinct categories, the gauge cannot tell these "
            "parts apart well enough (or the parts do not span the process range).",
            False,
        )
    if worst >= ACCEPTABLE_BELOW:
        return (
            CONDITIONAL,
            f"{base}: between {ACCEPTABLE_BELOW:g} and {NOT_ACCEPTABLE_ABOVE:g} %, acceptable "
            "by the importance of the application and the cost of a better gauge (AIAG).",
            None,
        )
    return (
        ACCEPTABLE,
        f"{base}: under {ACCEPTABLE_BELOW:g} % with {NDC_MIN} or more distinct categories.",
        True,
    )


def gage_rr_study(
    parts: Sequence[Any],
    appraisers: Sequence[Any],
    trials: Sequence[Any],
    values: Sequence[float] | Any,
    *,
    tolerance: float | None = None,
    pool_above: float = POOL_ABOVE,
    resolution: float | None = None,
    unit: str = "",
    names: Mapping[str, str] | None = None,
) -> GageRRStudy:
    """The crossed Gage R&R study of ``values``, each a reading of the same row's part (a label)
    by its appraiser (a label) at its trial (a number), with the tolerance T where known; the
    interaction is pooled when its p is above ``pool_above``. ``names``: the appraisers' names
    by label, for the report.

    Raises StationError naming what is missing: fewer than 2 appraisers, parts or trials, a
    part some appraiser did not measure, a trial missing (or read twice) for a part and an
    appraiser, a reading that is not finite, a tolerance or resolution that is not positive.
    """
    for name, value in (("tolerance", tolerance), ("resolution", resolution)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise StationError(f"the {name} must be more than 0, not {value!r}.")
    if not 0 < pool_above < 1:
        raise StationError(f"the interaction's pooling level must be between 0 and 1, not "
                           f"{pool_above!r}.")  # fmt: skip
    part_order, appraiser_order, data = _design(parts, appraisers, trials, values)
    anova = anova_method(data, pool_above=pool_above, tolerance=tolerance)
    xbar_r = average_range_method(data, part_order, appraiser_order)
    verdict, sentence, acceptable = _verdict(anova)
    return GageRRStudy(
        parts=part_order,
        appraisers=appraiser_order,
        trials=data.shape[2],
        data=data,
        anova=anova,
        xbar_r=xbar_r,
        verdict=verdict,
        sentence=sentence,
        acceptable=acceptable,
        tolerance=tolerance,
        resolution=resolution,
        unit=unit,
        names=dict(names or {}),
    )
