"""Descriptive statistics and the histogram, as the report's §2.7 defines them.

* ``sd`` is the sample standard deviation (divisor n - 1).
* ``skewness`` is a1 = m3 / s**3 with m3 the third central moment (divisor n) and s the n - 1
  deviation: "type 3" in Joanes & Gill's naming, the MINITAB/BMDP form. It is the report's
  figure: -0.356 for Table 2-1 (scipy's ``skew`` would give -0.375, pandas' -0.395).
* ``modes`` are every most-frequent value after rounding to the gauge resolution. When no
  value occurs more than once there is no mode and ``modes`` is empty: with every value tied
  at one occurrence, "the most frequent value" says nothing about the process.
* Undefined figures are ``None``, never NaN or inf: mean, min, max and range need one reading,
  sd two, skewness three readings that are not all the same.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from station.errors import StationError


def as_readings(values: Iterable[float] | np.ndarray, what: str = "reading") -> np.ndarray:
    """The values as a 1-D float array; NaN, inf or text raise StationError naming the position.

    ``what`` names one value in the message ("reading", "subgroup mean", ...). Positions are
    1-based, as the operator numbers cycles. A 2-D array (one row per subgroup) is read row
    by row, which is the order the readings were taken in.
    """
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as error:
        raise StationError(f"the {what}s are not all numbers ({error}): check the input") from None
    if array.ndim != 1:
        array = array.reshape(-1)
    finite = np.isfinite(array)
    if not finite.all():
        position = int(np.flatnonzero(~finite)[0])
        bad = array[position]
        kind = "not a number (NaN)" if math.isnan(bad) else f"infinite ({bad})"
        raise StationError(f"{what} {position + 1} is {kind}: remove it or take that reading again")
    return array


@dataclass(frozen=True)
class Descriptive:
    """Summary of one channel's readings (report §2.7: mean, sigma, skewness, mode, range)."""

    n: int
    mean: float | None
    sd: float | None
    skewness: float | None
    modes: tuple[float, ...]
    min: float | None
    max: float | None
    range: float | None


def _scaled_moments(array: np.ndarray) -> tuple[float, float, float, float]:
    """(mean, scale, sum of (d/scale)**2, sum of (d/scale)**3) with d the deviations from the mean.

    Deviations are divided by their largest magnitude before they are raised to powers, so
    readings of 1e200 or 1e-200 neither overflow nor underflow.
    """
    lowest, highest = float(array.min()), float(array.max())
    if lowest == highest:
        return lowest, 0.0, 0.0, 0.0
    mean = min(max(float(np.mean(array)), lowest), highest)
    deviations = array - mean
    scale = float(np.max(np.abs(deviations)))
    unit = deviations / scale
    squares = unit * unit
    return mean, scale, float(np.sum(squares)), float(np.dot(squares, unit))


def mean_and_sd(values: Iterable[float] | np.ndarray) -> tuple[float | None, float | None]:
    """Mean and sample sd (n - 1) without the rest of :func:`describe`; ``None`` when undefined."""
    array = as_readings(values)
    if array.size == 0:
        return None, None
    mean, scale, sum_sq, _ = _scaled_moments(array)
    return mean, _sd(scale, sum_sq, array.size)


def _sd(scale: float, sum_sq: float, n: int) -> float | None:
    if n < 2:
        return None
    sd = scale * math.sqrt(sum_sq / (n - 1))
    return sd if math.isfinite(sd) else None


def modes_at_resolution(
    values: Iterable[float] | np.ndarray, resolution: float | None = None
) -> tuple[float, ...]:
    """Every most frequent value, after rounding to ``resolution`` (exact values when None).

    Empty when no value occurs more than once. Values are returned in ascending order as
    multiples of the resolution (so 0.00019999 read at 0.0001 counts as 0.0002).
    """
    array = as_readings(values)
    if array.size < 2:
        return ()
    if resolution is not None:
        step = _check_resolution(resolution)
        keys = np.floor(array / step + 0.5)
    else:
        keys = array
    distinct, counts = _counted_steps(keys) if resolution is not None else (None, None)
    if distinct is None or counts is None:
        distinct, counts = np.unique(keys, return_counts=True)
    highest = int(counts.max())
    if highest < 2:
        return ()
    tied = distinct[counts == highest]
    if resolution is None:
        return tuple(float(v) for v in tied)
    return tuple(step_multiple(int(k), step) for k in tied)


def _counted_steps(keys: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The distinct whole-step keys and their counts, ascending, by counting into one slot per
    step (O(n)) when the readings span few steps, as a gauge's do; (None, None) when they span
    too many (then sorting them is cheaper) or lie beyond exact integers."""
    lowest, highest = float(keys.min()), float(keys.max())
    span = highest - lowest
    if max(abs(lowest), abs(highest)) >= 2**52 or span > 4 * keys.size + 1024:
        return None, None
    counts = np.bincount((keys - lowest).astype(np.int64), minlength=int(span) + 1)
    present = np.flatnonzero(counts)
    return present + lowest, counts[present]


def step_multiple(k: int, step: float) -> float:
    """k * step without the binary noise (3 * 0.0001 is 0.00030000000000000003, not 0.0003)."""
    return float(f"{k * step:.12g}")


def _check_resolution(resolution: float) -> float:
    step = float(resolution)
    if not math.isfinite(step) or step <= 0:
        raise StationError(
            f"resolution {resolution} is not a positive number: give the gauge's smallest step, "
            "e.g. 0.0001"
        )
    return step


def describe(values: Iterable[float] | np.ndarray, resolution: float | None = None) -> Descriptive:
    """n, mean, sample sd, skewness a1 = m3/s**3, modes at the resolution, min, max and range.

    NaN or inf in ``values`` raise StationError naming the position; a bad ``resolution`` too.
    """
    array = as_readings(values)
    n = int(array.size)
    if resolution is not None:
        _check_resolution(resolution)
    if n == 0:
        return Descriptive(0, None, None, None, (), None, None, None)
    lowest, highest = float(array.min()), float(array.max())
    mean, scale, sum_sq, sum_cube = _scaled_moments(array)
    sd = _sd(scale, sum_sq, n)
    skewness = None
    if n >= 3 and sum_sq > 0:
        # a1 = m3 / s**3 = (sum d^3 / n) / (sum d^2 / (n - 1))**1.5; the scale cancels.
        skewness = (sum_cube / n) / (sum_sq / (n - 1)) ** 1.5
    spread = highest - lowest
    return Descriptive(
        n=n,
        mean=mean,
        sd=sd,
        skewness=skewness,
        modes=modes_at_resolution(array, resolution),
        min=lowest,
        max=highest,
        range=spread if math.isfinite(spread) else None,
    )


@dataclass(frozen=True)
class Histogram:
    """Counts in bins of equal width, each centred on a multiple of the bin width.

    ``edges`` has one more entry than ``counts``. ``below`` and ``above`` count the readings
    strictly below the lower / above the upper specification limit (0 when that limit is not
    given); the bins themselves always cover every reading and both limits.
    """

    edges: tuple[float, ...]
    counts: tuple[int, ...]
    bin_width: float
    below: int
    above: int


def _nice_width(span: float, bins: int) -> float:
    """The smallest 1, 2 or 5 times a power of ten that splits ``span`` into <= ``bins`` bins."""
    if span <= 0:
        return 1.0
    raw = span / bins
    power = 10.0 ** math.floor(math.log10(raw))
    for factor in (1.0, 2.0, 5.0, 10.0):
        if factor * power >= raw:
            return factor * power
    return 10.0 * power


def histogram(
    values: Iterable[float] | np.ndarray,
    resolution: float | None = None,
    *,
    lsl: float | None = None,
    usl: float | None = None,
    max_bins: int = 40,
) -> Histogram:
    """Bin the readings at the gauge resolution, like the report's Figure 2-5.

    Bins are one resolution step wide, centred on multiples of it, so each quantised reading
    falls in the middle of a bin. When that would give more than ``max_bins`` bins the width is
    widened by the smallest integer factor that fits. The bins cover the data and the
    specification limits when given. Without a resolution the width is a 1-2-5 step giving
    about sqrt(n) bins (at most ``max_bins``).
    """
    array = as_readings(values)
    if int(max_bins) != max_bins or max_bins < 1:
        raise StationError(f"max_bins must be a whole number of at least 1, got {max_bins}")
    limits = [float(v) for v in (lsl, usl) if v is not None]
    for limit in limits:
        if not math.isfinite(limit):
            raise StationError(f"specification limit {limit} is not a finite number")
    below = int(np.count_nonzero(array < lsl)) if lsl is not None else 0
    above = int(np.count_nonzero(array > usl)) if usl is not None else 0
    if array.size == 0 and not limits:
        width = _check_resolution(resolution) if resolution is not None else 0.0
        return Histogram((), (), width, below, above)
    extremes = [*limits, float(array.min()), float(array.max())] if array.size else limits
    low, high = min(extremes), max(extremes)
    if resolution is not None:
        step = _check_resolution(resolution)
    else:
        target = max(1, min(int(max_bins), math.ceil(math.sqrt(max(array.size, 1)))))
        step = _nice_width(high - low, target)
    factor = 1
    while True:
        width = step * factor
        first, last = math.floor(low / width + 0.5), math.floor(high / width + 0.5)
        bins = last - first + 1
        if bins <= max_bins:
            break
        # Jump straight to a factor that can fit, then step up to absorb rounding at the ends.
        factor = max(factor + 1, math.ceil(factor * bins / max_bins))
    index = np.floor(array / width + 0.5).astype(np.int64) - first
    counts = np.bincount(index, minlength=bins) if array.size else np.zeros(bins, dtype=int)
    edges = tuple(float(f"{(first + j - 0.5) * width:.12g}") for j in range(bins + 1))
    return Histogram(
        edges=edges,
        counts=tuple(int(c) for c in counts[:bins]),
        bin_width=width,
        below=below,
        above=above,
    )
