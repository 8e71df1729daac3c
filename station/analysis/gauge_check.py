"""Type-1 gauge study: is the indicator good enough to judge the robot? (Cg, Cgk, bias).

The report judges a robot to a few ten-thousandths of an inch with indicators of 0.0001 in, and
never checks them. A Type-1 study does: the indicator measures one reference of known size x_m
(a gauge block or a master) n times (25 to 50), re-seated each time, and its readings are judged
against T, the tolerance the gauge will be used to judge (USL − LSL of the feature):

* Cg  = (K/100 · T) / (L · s) = (0.2 · T) / (6 · s)
* Cgk = (K/200 · T − |x̄ − x_m|) / (L/2 · s) = (0.1 · T − |x̄ − x_m|) / (3 · s)

with K = 20 % and L = 6 (Bosch Booklet 10, VDA 5, Minitab's "Type 1 Gage Study" defaults) and s
the sample standard deviation (n − 1). The gauge is capable when Cg ≥ 1.33 and Cgk ≥ 1.33. The
bias x̄ − x_m is tested with a one-sample t-test (t = bias / (s/√n), n − 1 degrees of freedom;
:func:`scipy.stats.ttest_1samp`), and the resolution should be at most 5 % of T (VDA 5 / Bosch).
Minitab also prints %Var(Repeatability) = K/Cg and %Var(Repeatability and Bias) = K/Cgk.

Definitions and sources: ``reference/spc-extensions.md`` §1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.errors import StationError
from station.text import format_figure

#: K: the share of the tolerance (in %) the gauge's spread may take.
PERCENT_OF_TOLERANCE = 20.0
#: L: the number of standard deviations that span the gauge's spread.
SPREAD_SIGMAS = 6.0
#: Cg and Cgk at or above which the gauge is capable.
CAPABLE_AT = 1.33
#: The largest resolution, as a share of the tolerance, a gauge may have (VDA 5 / Bosch).
RESOLUTION_SHARE = 0.05
#: The number of readings a study wants (fewer is analysed, with a note).
READINGS_MIN = 25
#: The significance level at which a bias is called significant.
BIAS_ALPHA = 0.05


@dataclass(frozen=True)
class GaugeCheck:
    """A Type-1 study of one gauge on one reference (see the module for the formulas).

    ``cg``, ``cgk`` and ``capable`` are None when the readings do not vary (s = 0: the gauge's
    resolution hides its spread, so the study cannot judge it); ``bias_p`` is then None too.
    ``resolution_ratio`` is the resolution over T (None when no resolution is given).
    """

    n: int
    reference: float
    tolerance: float
    mean: float
    sd: float
    bias: float
    bias_t: float | None
    bias_p: float | None
    cg: float | None
    cgk: float | None
    resolution: float | None
    resolution_ratio: float | None
    capable: bool | None
    unit: str = ""

    @property
    def resolution_ok(self) -> bool | None:
        """True when the resolution is at most 5 % of the tolerance; None when not given."""
        if self.resolution_ratio is None:
            return None
        return self.resolution_ratio <= RESOLUTION_SHARE + 1e-12

    @property
    def bias_significant(self) -> bool | None:
        """True when the t-test rejects "no bias" at 5 %; None when it cannot be tested."""
        return None if self.bias_p is None else self.bias_p < BIAS_ALPHA

    @property
    def percent_repeatability(self) -> float | None:
        """Minitab's %Var(Repeatability) = K / Cg, in %."""
        return None if not self.cg else PERCENT_OF_TOLERANCE / self.cg

    @property
    def percent_repeatability_bias(self) -> float | None:
        """Minitab's %Var(Repeatability and Bias) = K / Cgk, in % (None when Cgk ≤ 0)."""
        return None if not self.cgk or self.cgk <= 0 else PERCENT_OF_TOLERANCE / self.cgk

    @property
    def verdict(self) -> str:
        """``capable``, ``not capable`` or ``no verdict`` (a word, never only a colour)."""
        if self.capable is None:
            return "no verdict"
        return "capable" if self.capable else "not capable"

    def as_json(self) -> dict[str, Any]:
        """The figures of ``station analyze --procedure gauge_check --json``: ``cg``, ``cgk``,
        ``bias``, ``bias_p``, ``resolution_ratio``, ``capable`` first, then the inputs."""
        return {
            "cg": self.cg,
            "cgk": self.cgk,
            "bias": self.bias,
            "bias_p": self.bias_p,
            "resolution_ratio": self.resolution_ratio,
            "capable": self.capable,
            "verdict": self.verdict,
            "n": self.n,
            "reference": self.reference,
            "tolerance": self.tolerance,
            "mean": self.mean,
            "sd": self.sd,
            "bias_t": self.bias_t,
            "resolution": self.resolution,
            "resolution_ok": self.resolution_ok,
            "percent_repeatability": self.percent_repeatability,
            "percent_repeatability_bias": self.percent_repeatability_bias,
            "capable_at": CAPABLE_AT,
        }

    def lines(self) -> list[str]:
        """The study as plain report lines (the verdict first, then the figures and notes)."""

        def figure(value: float, *, signed: bool = True) -> str:
            # The one number format: one decimal beyond the gauge step, never 1e-05.
            return format_figure(value, self.resolution, signed=signed, unit=self.unit)

        def index(value: float | None) -> str:
            return "undefined (no spread)" if value is None else f"{value:.2f}"

        lines = [
            f"GAUGE CHECK (TYPE-1 STUDY): {self.verdict.upper()}",
            f"  readings {self.n}   reference x_m {figure(self.reference)}   "
            f"tolerance T {figure(self.tolerance, signed=False)}",
            f"  mean {figure(self.mean)}   s {figure(self.sd, signed=False)}   "
            f"bias {figure(self.bias)}",
            f"  Cg  = 0.2·T / (6·s)           = {index(self.cg)}   (capable at {CAPABLE_AT})",
            f"  Cgk = (0.1·T − |bias|) / (3·s) = {index(self.cgk)}   (capable at {CAPABLE_AT})",
        ]
        if self.bias_p is None:
            lines.append("  bias t-test: not possible (the readings do not vary)")
        else:
            word = "significant" if self.bias_significant else "not significant"
            lines.append(
                f"  bias t-test: t = {self.bias_t:.3f}, df {self.n - 1}, p = {self.bias_p:.4f} "
                f"({word} at 5 %)"
            )
        if self.percent_repeatability is not None:
            both = self.percent_repeatability_bias
            lines.append(
                f"  %Var(repeatability) {self.percent_repeatability:.1f} %   "
                f"%Var(repeatability and bias) {'over 100' if both is None else f'{both:.1f}'} %"
            )
        if self.resolution_ratio is None or self.resolution is None:
            lines.append("  resolution: not given (cannot say whether it is fine enough)")
        else:
            ok = "fine enough" if self.resolution_ok else "TOO COARSE (over 5 % of T)"
            lines.append(
                f"  resolution {figure(self.resolution, signed=False)} = "
                f"{100 * self.resolution_ratio:.1f} % of T: {ok}"
            )
        lines.extend(f"  note: {note}" for note in self.notes())
        return lines

    def notes(self) -> list[str]:
        """Sentences on what limits the study (few readings, no spread, bias, resolution)."""
        notes: list[str] = []
        if self.n < READINGS_MIN:
            notes.append(
                f"only {self.n} readings: a Type-1 study wants {READINGS_MIN} to 50, re-seated "
                "each time."
            )
        if self.cg is None:
            notes.append(
                "the readings do not vary: the resolution hides the gauge's spread; use a finer "
                "gauge or more readings."
            )
        elif self.cg >= CAPABLE_AT and self.cgk is not None and self.cgk < CAPABLE_AT:
            notes.append(
                "Cg passes but Cgk fails: the gauge repeats but reads off the reference (bias); "
                "recalibrate it or check the reference's size."
            )
        if self.resolution_ok is False:
            notes.append("the resolution is over 5 % of the tolerance: the gauge is too coarse.")
        return notes


def gauge_check(
    values: Sequence[float] | Any,
    reference: float,
    tolerance: float,
    *,
    resolution: float | None = None,
    unit: str = "",
) -> GaugeCheck:
    """The Type-1 study of ``values`` (repeated readings of a reference of size ``reference``)
    for a gauge that will judge a tolerance ``tolerance`` (USL − LSL), with its ``resolution``.

    Raises StationError for fewer than 2 readings, a value that is not finite, or a tolerance or
    resolution that is not positive.
    """
    from scipy import stats  # on first use: see station/README.md

    readings = np.asarray(values, dtype=float).ravel()
    if readings.size < 2:
        raise StationError(
            f"a gauge check needs at least 2 readings of the reference ({readings.size} given); "
            f"take {READINGS_MIN} to 50."
        )
    if not np.all(np.isfinite(readings)):
        raise StationError("a gauge check reading is not a finite number; fix or drop it.")
    for name, value in (("reference", reference), ("tolerance", tolerance)):
        if not math.isfinite(value):
            raise StationError(f"the gauge check's {name} {value!r} is not a finite number.")
    if not tolerance > 0:
        raise StationError(f"the gauge check's tolerance must be more than 0, not {tolerance:g}.")
    if resolution is not None and not (math.isfinite(resolution) and resolution > 0):
        raise StationError(f"the gauge resolution must be more than 0, not {resolution!r}.")

    n = int(readings.size)
    mean = float(readings.mean())
    sd = float(readings.std(ddof=1))
    bias = mean - reference
    # The spread is zero when every reading is the same display value: no index is defined.
    # Readings that differ by float rounding only (0.1 read as 0.30000000000000004 − 0.2 after
    # a software zero) are the same value: their s of 1e-17 would give a Cg of 1e13.
    same = float(np.ptp(readings)) <= 1e-9 * max(1.0, float(np.max(np.abs(readings))))
    cg: float | None
    cgk: float | None
    bias_t: float | None
    bias_p: float | None
    capable: bool | None
    if sd > 0 and not same:
        k = PERCENT_OF_TOLERANCE / 100.0
        cg = (k * tolerance) / (SPREAD_SIGMAS * sd)
        cgk = (k / 2.0 * tolerance - abs(bias)) / (SPREAD_SIGMAS / 2.0 * sd)
        # The one-sample t-test of scipy.stats.ttest_1samp, written out: scipy warns of
        # "catastrophic cancellation" on readings that are nearly all one display value.
        bias_t = bias / (sd / math.sqrt(n))
        bias_p = float(2.0 * stats.t.sf(abs(bias_t), n - 1))
        capable = cg >= CAPABLE_AT and cgk >= CAPABLE_AT
    else:
        cg = cgk = bias_t = bias_p = None
        capable = None
    return GaugeCheck(
        n=n,
        reference=float(reference),
        tolerance=float(tolerance),
        mean=mean,
        sd=sd,
        bias=bias,
        bias_t=bias_t,
        bias_p=bias_p,
        cg=cg,
        cgk=cgk,
        resolution=None if resolution is None else float(resolution),
        resolution_ratio=None if resolution is None else float(resolution) / float(tolerance),
        capable=capable,
        unit=unit,
    )
