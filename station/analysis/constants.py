"""Control-chart constants, computed from their definitions rather than copied from a table.

``d2(n)`` and ``d3(n)`` are the mean and standard deviation of the range of ``n`` independent
standard normal values; ``c4(n)`` is the bias of the sample standard deviation. The chart
factors (A2, A3, B3, B4, D3, D4, E2) follow from them with k = 3 (SAS/QC "Deriving Control Chart
Constants"; see ``reference/standards.md`` §2.3).

Computing them avoids two kinds of drift: hand-typed tables with a slip, and tables built from
rounded constants (the textbook D4(3) = 2.574 is computed from rounded d2 and d3; the exact value
is 2.574591). The integrals are done once per ``n`` with a Gauss-Legendre rule that agrees with
the exact closed forms (d2(2) = 2/sqrt(pi), d2(3) = 3/sqrt(pi), ...) to about 1e-12.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

SIGMA_MULTIPLE = 3.0
"""The k of "k-sigma" control limits used throughout (the report's UCL = X-bar + 3 sigma)."""

# Standard normal values beyond +-10 contribute less than 1e-23 to either integral.
_HALF_WIDTH = 10.0
_NODES = 200
_C4_SERIES_FROM = 1000


def _check_size(n: int, smallest: int) -> int:
    if isinstance(n, bool) or int(n) != n or n < smallest:
        raise ValueError(f"subgroup size must be an integer >= {smallest}, got {n!r}")
    return int(n)


@cache
def _range_moments(n: int) -> tuple[float, float]:
    """(E[R], SD[R]) of the range of n iid N(0, 1) values, by 1-D and 2-D quadrature."""
    from scipy.special import ndtr  # on first use: see station/README.md

    nodes, weights = np.polynomial.legendre.leggauss(_NODES)
    x = _HALF_WIDTH * nodes
    wx = _HALF_WIDTH * weights
    # E[R] = integral of P(min < x < max) = 1 - P(all > x) - P(all < x).
    mean = float(np.sum(wx * (1.0 - ndtr(-x) ** n - ndtr(x) ** n)))
    # E[R^2] = 2 * double integral over x < y of P(min < x, max > y), written with y = x + r.
    r = _HALF_WIDTH * (nodes + 1.0)
    wr = _HALF_WIDTH * weights
    lower = x[:, None]
    upper = lower + r[None, :]
    cdf_lower = ndtr(lower)
    cdf_upper = ndtr(upper)
    tail = 1.0 - cdf_upper**n - ndtr(-lower) ** n + (cdf_upper - cdf_lower) ** n
    second_moment = 2.0 * float(np.einsum("i,ij,j->", wx, tail, wr))
    return mean, math.sqrt(max(second_moment - mean * mean, 0.0))


def d2(n: int) -> float:
    """Expected range of ``n`` >= 2 independent standard normal values (d2(2) = 2/sqrt(pi))."""
    if _check_size(n, 2) == 2:
        return 2.0 / math.sqrt(math.pi)  # closed form: the I-MR chart needs no quadrature
    return _range_moments(n)[0]


def d3(n: int) -> float:
    """Standard deviation of the range of ``n`` >= 2 independent standard normal values."""
    if _check_size(n, 2) == 2:
        return math.sqrt(2.0 - 4.0 / math.pi)  # |X1 - X2| with X1 - X2 ~ N(0, 2)
    return _range_moments(n)[1]


@cache
def c4(n: int) -> float:
    """E[s]/sigma for the sample standard deviation of ``n`` >= 2 normal values.

    c4(n) = sqrt(2/(n-1)) * Gamma(n/2) / Gamma((n-1)/2), with log-gamma so large ``n`` (pooled
    degrees of freedom in the hundreds) does not overflow.
    """
    n = _check_size(n, 2)
    if n >= _C4_SERIES_FROM:
        # The difference of two large log-gammas loses digits (1e-10 at n = 1e6); the
        # asymptotic series is exact to double precision here.
        return 1.0 - 1.0 / (4 * n) - 7.0 / (32 * n**2) - 19.0 / (128 * n**3)
    return math.sqrt(2.0 / (n - 1)) * math.exp(math.lgamma(n / 2) - math.lgamma((n - 1) / 2))


@dataclass(frozen=True)
class ChartFactors:
    """The constants of one subgroup size, with k = 3.

    For ``n == 1`` (individuals) the moving range of two consecutive points stands in for the
    subgroup range, so d2, d3, c4, B3, B4, D3 and D4 are those of n = 2 and
    A2 = A3 = E2 = 3/d2(2): the I-MR chart's limits are X-bar +- E2 * MR-bar.
    """

    n: int
    d2: float
    d3: float
    c4: float
    A2: float
    A3: float
    B3: float
    B4: float
    D3: float
    D4: float
    E2: float


@cache
def chart_factors(n: int) -> ChartFactors:
    """Chart factors for subgroup size ``n`` >= 1 (``n == 1``: the I-MR chart, see the class)."""
    n = _check_size(n, 1)
    size = max(n, 2)
    k = SIGMA_MULTIPLE
    d2_n, d3_n, c4_n = d2(size), d3(size), c4(size)
    root_n = math.sqrt(n)
    s_spread = (k / c4_n) * math.sqrt(1.0 - c4_n * c4_n)
    r_spread = k * d3_n / d2_n
    return ChartFactors(
        n=n,
        d2=d2_n,
        d3=d3_n,
        c4=c4_n,
        A2=k / (d2_n * root_n),
        A3=k / (c4_n * root_n) if n > 1 else k / d2_n,
        B3=max(0.0, 1.0 - s_spread),
        B4=1.0 + s_spread,
        D3=max(0.0, 1.0 - r_spread),
        D4=1.0 + r_spread,
        E2=k / d2_n,
    )
