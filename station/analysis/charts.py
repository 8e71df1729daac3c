"""Shewhart control charts: I-MR for single readings, X-bar-R for subgroups of 2..10, X-bar-S above.

Readings are split into consecutive subgroups of ``subgroup`` values in the order taken; a
trailing subgroup that is not full is left out of the chart (and the message says so). The
limits use the within-subgroup sigma, with constants computed in :mod:`constants`
(``reference/standards.md`` §2.3-2.4):

* I-MR: sigma = MR-bar / d2(2); limits X-bar +- 3 sigma; MR chart MR-bar, D3(2)/D4(2) * MR-bar.
* X-bar-R: sigma = R-bar / d2(n); limits X-double-bar +- A2 * R-bar; R chart D3/D4 * R-bar.
* X-bar-S: sigma = S-bar / c4(n); limits X-double-bar +- A3 * S-bar; S chart B3/B4 * S-bar.

The location chart's limits are never narrower than the gauge can tell apart: with a gauge
``resolution`` their half-width is at least 1.5 steps
(:func:`~station.analysis.discrimination.limit_half_width`), and ``limit_floor`` says so.

These are qcc's defaults (UWAVE-R for X-bar-R, UWAVE-SD for X-bar-S, "MR" for individuals),
except that qcc takes d2 from a 3-decimal table (d2(2) = 1.128) where we use the exact value
(1.1283792), so qcc's sigma differs from ours in the 4th-5th significant digit.
"""

from __future__ import annotations

import contextlib
import math
import operator
from collections.abc import Iterable
from dataclasses import dataclass
from typing import SupportsIndex

import numpy as np

from station.analysis.column import Column
from station.analysis.constants import SIGMA_MULTIPLE, c4, chart_factors, d2
from station.analysis.descriptive import as_readings
from station.analysis.discrimination import limit_half_width
from station.errors import StationError

LARGEST_RANGE_SUBGROUP = 10
"""Subgroups up to this size get an X-bar-R chart; larger ones an X-bar-S chart."""


@dataclass(frozen=True)
class Limits:
    """Centre line and control limits of one chart; ``None`` where they cannot be computed."""

    center: float | None
    ucl: float | None
    lcl: float | None


@dataclass(frozen=True)
class ControlChart:
    """A location chart (individuals or subgroup means) with its dispersion chart (MR, R or S)."""

    type: str
    subgroup: int
    center: float | None
    ucl: float | None
    lcl: float | None
    sigma_within: float | None
    points: Column
    """The plotted points in order: one array, read as a sequence of floats."""
    dispersion: Limits
    dispersion_points: Column
    message: str | None
    limit_floor: float | None = None
    """The least half-width the gauge step allows (1.5 steps), when a resolution was given:
    the limits are at least this far from the centre line."""

    @property
    def floored(self) -> bool:
        """True when the gauge step, not the within sigma, set the limits' half-width."""
        if self.limit_floor is None or self.sigma_within is None or self.ucl is None:
            return False
        return SIGMA_MULTIPLE * self.sigma_within / math.sqrt(self.subgroup) < self.limit_floor

    @property
    def point_sigma(self) -> float | None:
        """Sigma of the plotted statistic, (UCL - centre) / 3: what the run rules need."""
        if self.ucl is None or self.center is None:
            return None
        return (self.ucl - self.center) / SIGMA_MULTIPLE


CHART_TYPES: tuple[str, ...] = ("I-MR", "Xbar-R", "Xbar-S")


def chart_type(subgroup: int, kind: str | None = None) -> str:
    """``"I-MR"``, ``"Xbar-R"`` or ``"Xbar-S"``: the default for the subgroup size, or ``kind``.

    ``kind`` asks for a chart other than the default (an X-bar-S chart for subgroups of 5, say);
    single readings only have the I-MR chart and subgroups cannot have it.
    """
    size = check_subgroup(subgroup)
    default = "I-MR" if size == 1 else "Xbar-R" if size <= LARGEST_RANGE_SUBGROUP else "Xbar-S"
    if kind is None or kind == default:
        return default
    if kind not in CHART_TYPES:
        raise StationError(f"unknown chart type {kind!r}: use one of {', '.join(CHART_TYPES)}")
    if (kind == "I-MR") != (size == 1):
        raise StationError(
            f"a {kind} chart does not fit subgroups of {size}: I-MR is for single readings, "
            "Xbar-R and Xbar-S for subgroups of 2 or more"
        )
    return kind


def check_subgroup(subgroup: SupportsIndex | float) -> int:
    """The subgroup size as an int; StationError unless it is a whole number >= 1."""
    size = None
    if isinstance(subgroup, float):
        if subgroup.is_integer():
            size = int(subgroup)
    elif not isinstance(subgroup, bool):
        with contextlib.suppress(TypeError):
            size = operator.index(subgroup)
    if size is None or size < 1:
        raise StationError(
            f"subgroup size {subgroup!r} is not a whole number of at least 1: use 1 for single "
            "readings per cycle, or the number of readings taken together"
        )
    return size


def subgroups(values: Iterable[float] | np.ndarray, subgroup: int) -> np.ndarray:
    """The complete consecutive subgroups as an (m, subgroup) array; a partial tail is dropped."""
    array = as_readings(values)
    size = check_subgroup(subgroup)
    complete = array.size // size
    return array[: complete * size].reshape(complete, size)


def moving_ranges(values: Iterable[float] | np.ndarray) -> np.ndarray:
    """|x_i - x_(i-1)| for i = 2..n (n - 1 values)."""
    return np.abs(np.diff(as_readings(values)))


def _spread(array: np.ndarray, size: int, kind: str) -> tuple[np.ndarray, float, float] | None:
    """(dispersion points, their mean, the within sigma) of a chart; ``None`` without data.

    Moving ranges and MR-bar / d2(2) for I-MR, subgroup ranges and R-bar / d2(n) for X-bar-R,
    subgroup SDs and S-bar / c4(n) for X-bar-S.
    """
    if size == 1:
        if array.size < 2:
            return None
        spreads, divisor = np.abs(np.diff(array)), d2(2)
    else:
        groups = subgroups(array, size)
        if groups.shape[0] == 0:
            return None
        if kind == "Xbar-R":
            spreads, divisor = groups.max(axis=1) - groups.min(axis=1), d2(size)
        else:
            spreads, divisor = groups.std(axis=1, ddof=1), c4(size)
    spread = float(spreads.mean())
    return spreads, spread, spread / divisor


def sigma_within(
    values: Iterable[float] | np.ndarray, subgroup: int = 1, kind: str | None = None
) -> float | None:
    """The within-subgroup sigma the chart of this subgroup size (or ``kind``) uses.

    MR-bar / d2(2) for single readings, R-bar / d2(n) for 2..10, S-bar / c4(n) above 10.
    ``None`` when there is not enough data: fewer than 2 readings, or no complete subgroup.
    """
    size = check_subgroup(subgroup)
    found = _spread(as_readings(values), size, chart_type(size, kind))
    return None if found is None else found[2]


def pooled_sigma(values: Iterable[float] | np.ndarray, subgroup: int) -> float | None:
    """Pooled within sigma sqrt(sum (n_i-1) S_i^2 / sum (n_i-1)) / c4(sum (n_i-1) + 1).

    qcc's "RMSDF" and Minitab's default for capability with subgroups; the sigma printed in the
    qcc paper for the piston rings (0.009887547). ``None`` without a complete subgroup of >= 2.
    """
    size = check_subgroup(subgroup)
    groups = subgroups(values, size)
    if size < 2 or groups.shape[0] == 0:
        return None
    degrees = groups.shape[0] * (size - 1)
    variances = groups.var(axis=1, ddof=1)
    return math.sqrt(float(variances.sum()) * (size - 1) / degrees) / c4(degrees + 1)


def _left_out(left_over: int, size: int) -> str | None:
    if left_over == 1:
        return f"the last reading does not fill a subgroup of {size} and is left out"
    if left_over:
        return f"the last {left_over} readings do not fill a subgroup of {size} and are left out"
    return None


def control_chart(
    values: Iterable[float] | np.ndarray,
    subgroup: int = 1,
    kind: str | None = None,
    resolution: float | None = None,
) -> ControlChart:
    """The control chart of the readings for this subgroup size (see the module docstring).

    ``kind`` overrides the default chart type for the size (see :func:`chart_type`). With the
    gauge ``resolution`` the location limits are at least 1.5 steps from the centre line.
    """
    array = as_readings(values)
    size = check_subgroup(subgroup)
    kind = chart_type(size, kind)
    found = _spread(array, size, kind)
    if found is None:
        needed = (
            "an I-MR chart needs at least 2" if size == 1 else f"a subgroup of {size} needs {size}"
        )
        message = f"{needed} readings (have {array.size})"
        return ControlChart(
            type=kind,
            subgroup=size,
            center=None,
            ucl=None,
            lcl=None,
            sigma_within=None,
            points=Column(()),
            dispersion=Limits(None, None, None),
            dispersion_points=Column(()),
            message=message,
        )
    spreads, spread, sigma = found
    means = array if size == 1 else subgroups(array, size).mean(axis=1)
    center = float(means.mean())
    # X-bar +- 3 sigma / sqrt(n) is X-bar +- E2 * MR-bar, A2 * R-bar or A3 * S-bar; never
    # narrower than the gauge can tell apart.
    half_width = limit_half_width(sigma, size, resolution, SIGMA_MULTIPLE)
    factors = chart_factors(size)
    lower, upper = (factors.B3, factors.B4) if kind == "Xbar-S" else (factors.D3, factors.D4)
    return ControlChart(
        type=kind,
        subgroup=size,
        center=center,
        ucl=center + half_width,
        lcl=center - half_width,
        sigma_within=sigma,
        points=Column(means),
        dispersion=Limits(spread, upper * spread, lower * spread),
        dispersion_points=Column(spreads),
        message=_left_out(array.size % size, size),
        limit_floor=limit_half_width(0.0, size, resolution) if resolution else None,
    )
