"""Process capability as the report defines it (§2.7.3), with the within-sigma figures beside it.

The report's indices use the overall sample sigma s (n - 1) of every reading:

    Cp = (USL - LSL) / 6s     Cpu = (USL - mean) / 3s     Cpl = (mean - LSL) / 3s
    Cpk = min(Cpu, Cpl)       capable when Cpk >= threshold (1.0 unless set)

(qcc, Minitab and JMP call these Pp, Ppu, Ppl, Ppk.) Beside them, ``cp_within`` and
``cpk_within`` use the within sigma of the control chart (MR-bar/d2 for single readings,
R-bar/d2 or S-bar/c4 for subgroups; qcc's and Minitab's Cp/Cpk). With one limit only, Cp is
undefined and Cpk is the index of the side that exists.

``cpk_lower`` and ``cpk_upper`` are the one-sided confidence bounds on the (overall) Cpk by
Bissell's (1990) normal approximation, Cpk -+ z * sqrt(1/(9n) + Cpk^2/(2(n-1))) with z the
``confidence`` quantile: with 30 readings Table 2-1's Cpk of 1.17 is only known to be above 0.90
with 95 % confidence. ``cpk_ci`` is Bissell's two-sided interval and ``cp_ci`` the chi-square
interval on Cp, both at ``confidence``. :func:`readings_needed` says how many readings the bound
needs to settle a verdict at the observed Cpk. The capability verdict built on these bounds is
in :mod:`station.analysis.verdict`.

Nothing here returns inf or NaN: with fewer than 2 readings or a sigma of 0 the indices are
``None`` and ``message`` says why.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from decimal import Decimal
from statistics import NormalDist

import numpy as np

from station.analysis.charts import check_subgroup
from station.analysis.charts import sigma_within as estimate_sigma_within
from station.analysis.descriptive import as_readings, mean_and_sd
from station.errors import StationError


def _check_limit(name: str, value: float | None) -> None:
    if value is None:
        return
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise StationError(f"{name} {value!r} is not a number") from None
    if not math.isfinite(number):
        raise StationError(f"{name} {value} is not a finite number: give a value such as 0.001")


@dataclass(frozen=True)
class SpecLimits:
    """Specification limits of one channel; at least one of ``lsl``/``usl`` is required.

    ``nominal`` defaults to the mid-spec when both limits are given. Impossible limits raise
    StationError with a sentence the user can act on.
    """

    lsl: float | None = None
    usl: float | None = None
    nominal: float | None = None

    def __post_init__(self) -> None:
        _check_limit("lower limit", self.lsl)
        _check_limit("upper limit", self.usl)
        _check_limit("nominal", self.nominal)
        if self.lsl is None and self.usl is None:
            raise StationError(
                "no specification limits: give a lower limit, an upper limit or both"
            )
        for name in ("lsl", "usl", "nominal"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, float(value))
        if self.lsl is not None and self.usl is not None:
            if self.usl <= self.lsl:
                raise StationError(
                    f"upper limit {self.usl:g} is not above lower limit {self.lsl:g}: "
                    "swap them or correct the limits"
                )
            if self.nominal is None:
                object.__setattr__(self, "nominal", (self.lsl + self.usl) / 2)


@dataclass(frozen=True)
class Capability:
    """Capability indices of one channel; see the module docstring for the definitions.

    ``cp`` .. ``cpk`` and their bounds use ``sigma`` (overall, n - 1); ``cp_within`` and
    ``cpk_within`` use ``sigma_within``. ``capable`` is the report's point-estimate rule
    ``cpk >= threshold`` (``None`` when Cpk is undefined, and then ``message`` says why); the
    verdict that weighs the bounds is :func:`station.analysis.verdict.judge_verdict`'s.
    ``above_usl``/``below_lsl`` count readings strictly outside the limits. ``n`` and ``mean``
    are the readings' count and mean; ``confidence`` is the level of ``cpk_lower`` and
    ``cpk_upper`` (each one-sided) and of ``cp_ci`` and ``cpk_ci`` (two-sided, Bissell's for Cpk).
    """

    lsl: float | None
    usl: float | None
    cp: float | None
    cpu: float | None
    cpl: float | None
    cpk: float | None
    cpk_lower: float | None
    cp_within: float | None
    cpk_within: float | None
    sigma: float | None
    sigma_within: float | None
    threshold: float
    capable: bool | None
    above_usl: int
    below_lsl: int
    message: str | None
    n: int = 0
    mean: float | None = None
    confidence: float = 0.95
    cpk_upper: float | None = None
    cp_ci: tuple[float, float] | None = None
    cpk_ci: tuple[float, float] | None = None


def _finite_or_none(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def _finite_pair(pair: tuple[float, float]) -> tuple[float, float] | None:
    return pair if all(math.isfinite(v) for v in pair) else None


def capability_indices(
    mean: float, sigma: float | None, lsl: float | None, usl: float | None
) -> tuple[float | None, float | None, float | None, float | None]:
    """(Cp, Cpu, Cpl, Cpk) of a mean and one sigma; None where undefined (no sigma, sigma 0)."""
    if sigma is None or sigma <= 0:
        return None, None, None, None
    cp = (usl - lsl) / (6 * sigma) if usl is not None and lsl is not None else None
    cpu = (usl - mean) / (3 * sigma) if usl is not None else None
    cpl = (mean - lsl) / (3 * sigma) if lsl is not None else None
    sides = [index for index in (cpu, cpl) if index is not None]
    cpk = min(sides) if sides else None
    return tuple(_finite_or_none(v) for v in (cp, cpu, cpl, cpk))  # type: ignore[return-value]


def _check_confidence(confidence: float) -> float:
    if not 0 < confidence < 1:
        raise StationError(f"confidence {confidence} must be between 0 and 1, e.g. 0.95")
    return float(confidence)


def cp_interval(cp: float, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided chi-square confidence interval on Cp from ``n`` readings (qcc, SAS)."""
    from scipy.special import chdtri  # on first use: see station/README.md

    alpha = 1 - _check_confidence(confidence)
    if n < 2:
        raise ValueError("a confidence interval needs at least 2 readings")
    degrees = n - 1
    # chdtri(df, p) is the chi-square quantile of upper-tail probability p.
    return (
        cp * math.sqrt(chdtri(degrees, 1 - alpha / 2) / degrees),
        cp * math.sqrt(chdtri(degrees, alpha / 2) / degrees),
    )


def _bissell_half_width(index: float, n: int, z: float) -> float:
    if n < 2:
        raise ValueError("a confidence bound needs at least 2 readings")
    # hypot: the same root, without overflow for the huge indices of a tiny sigma.
    return z * math.hypot(1 / math.sqrt(9 * n), index / math.sqrt(2 * (n - 1)))


def bissell_interval(index: float, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided interval on Cpk (or Cpu, Cpl) by Bissell's (1990) normal approximation.

    index +- z * sqrt(1/(9n) + index^2/(2(n-1))), z the (1 + confidence)/2 normal quantile.
    """
    alpha = 1 - _check_confidence(confidence)
    half_width = _bissell_half_width(index, n, normal_quantile(1 - alpha / 2))
    return index - half_width, index + half_width


def cpk_lower_bound(cpk: float, n: int, confidence: float = 0.95) -> float:
    """One-sided lower confidence bound on Cpk (Bissell), z the ``confidence`` normal quantile."""
    return cpk - _bissell_half_width(cpk, n, normal_quantile(_check_confidence(confidence)))


def cpk_upper_bound(cpk: float, n: int, confidence: float = 0.95) -> float:
    """One-sided upper confidence bound on Cpk (Bissell), z the ``confidence`` normal quantile."""
    return cpk + _bissell_half_width(cpk, n, normal_quantile(_check_confidence(confidence)))


#: Beyond this many readings :func:`readings_needed` gives up (a Cpk a hair off the threshold).
MOST_READINGS_NEEDED = 10**9


def readings_needed(cpk: float, threshold: float, confidence: float = 0.95) -> int | None:
    """The fewest readings at which Bissell's one-sided bound at ``confidence`` settles the
    verdict if the Cpk stays at ``cpk``: the lower bound reaching ``threshold`` (``cpk`` above
    it), or the upper bound falling below it (``cpk`` below). ``None`` when ``cpk`` equals the
    threshold or more than ``MOST_READINGS_NEEDED`` would be needed.

    Table 2-1 (Cpk 1.167 from 30 readings, threshold 1, 95 %) needs 77.
    """
    z = normal_quantile(_check_confidence(confidence))
    margin = abs(cpk - threshold)
    if not margin > 0:
        return None

    def settles(n: int) -> bool:
        # The lower bound must reach the threshold (>=); the upper must fall below it (<).
        half_width = _bissell_half_width(cpk, n, z)
        return half_width <= margin if cpk > threshold else half_width < margin

    # The half-width shrinks as n grows: double to an n that settles, then bisect.
    low, high = 1, 2
    while not settles(high):
        low, high = high, high * 2
        if low > MOST_READINGS_NEEDED:
            return None
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if settles(middle) else (middle, high)
    return high if high <= MOST_READINGS_NEEDED else None


def normal_quantile(p: float) -> float:
    """The standard normal quantile (the standard library's, Wichura's AS 241 to double
    precision: the same figure as scipy's ndtri, without loading scipy.special)."""
    return NormalDist().inv_cdf(p)


def capability(
    values: Iterable[float] | np.ndarray,
    limits: SpecLimits,
    *,
    threshold: float = 1.0,
    subgroup: int = 1,
    confidence: float = 0.95,
    sigma_within: float | None = None,
) -> Capability:
    """Capability of the readings against ``limits`` (see the module docstring).

    ``subgroup`` picks the within-sigma estimator (as the control chart does). ``sigma_within``
    overrides it with a known value, e.g. the sigma of a phase-I chart or a pooled sigma.
    ``confidence`` is the level of the one-sided bounds and of the two-sided intervals.
    """
    if not isinstance(limits, SpecLimits):
        raise TypeError("limits must be a SpecLimits")
    array = as_readings(values)
    size = check_subgroup(subgroup)
    _check_confidence(confidence)
    if not math.isfinite(threshold):
        raise StationError(f"capability threshold {threshold} is not a finite number, e.g. 1.33")
    if sigma_within is not None and not (math.isfinite(sigma_within) and sigma_within >= 0):
        raise StationError(f"within sigma {sigma_within} must be a finite number >= 0")
    lsl, usl = limits.lsl, limits.usl
    n = int(array.size)
    above = int(np.count_nonzero(array > usl)) if usl is not None else 0
    below = int(np.count_nonzero(array < lsl)) if lsl is not None else 0
    reasons: list[str] = []
    mean: float | None = None
    sigma: float | None = None
    within: float | None = None
    if n < 2:
        reasons.append(f"need at least 2 readings to estimate sigma (have {n})")
        if n == 1:
            mean = float(array[0])
    else:
        mean, sigma = mean_and_sd(array)
        if sigma == 0 and mean is not None:
            reasons.append(
                # Positional, as every other figure on the screens ("-4e-05" read as a code).
                f"sigma is 0: every reading is the same ({format(Decimal(repr(float(mean))), 'f')})"
                ", so the indices are undefined; check that the gauge is reading and its "
                "resolution is fine enough"
            )
        within = sigma_within if sigma_within is not None else estimate_sigma_within(array, size)
        if within is None and sigma:
            reasons.append(f"no complete subgroup of {size} for the within sigma")
        elif within == 0 and sigma:
            reasons.append(
                "within sigma is 0: consecutive readings do not vary, so the within indices "
                "are undefined"
            )
    cp, cpu, cpl, cpk = (
        capability_indices(mean, sigma, lsl, usl) if mean is not None else (None,) * 4
    )
    cp_within, _, _, cpk_within = (
        capability_indices(mean, within, lsl, usl) if mean is not None else (None,) * 4
    )
    if cpk is None and not reasons:
        reasons.append(f"the indices are too large to represent (sigma {sigma:g})")
    cpk_lower = cpk_upper = cp_ci = cpk_ci = None
    if cpk is not None:
        cpk_lower = _finite_or_none(cpk_lower_bound(cpk, n, confidence))
        cpk_upper = _finite_or_none(cpk_upper_bound(cpk, n, confidence))
        cpk_ci = _finite_pair(bissell_interval(cpk, n, confidence))
    if cp is not None:
        cp_ci = _finite_pair(cp_interval(cp, n, confidence))
    return Capability(
        lsl=lsl,
        usl=usl,
        cp=cp,
        cpu=cpu,
        cpl=cpl,
        cpk=cpk,
        cpk_lower=cpk_lower,
        cp_within=cp_within,
        cpk_within=cpk_within,
        sigma=sigma,
        sigma_within=within,
        threshold=float(threshold),
        capable=None if cpk is None else cpk >= threshold,
        above_usl=above,
        below_lsl=below,
        message="; ".join(reasons) if reasons else None,
        n=n,
        mean=mean,
        confidence=float(confidence),
        cpk_upper=cpk_upper,
        cp_ci=cp_ci,
        cpk_ci=cpk_ci,
    )
