"""The gain schedule of the report's Part IV (§4.3): each PID gain as a polynomial of position.

The report tunes the PID gains of a joint at a few positions along the robot's path (both ends
included) and fits each gain as a polynomial of the joint position q,
K(q) = a0 + a1·q + a2·q² + ... + an·qⁿ, "of the 8th order or more". This module fits that
polynomial honestly:

* **A well-conditioned basis.** The fit is least squares in the Chebyshev basis on q scaled to
  [−1, 1] (:class:`numpy.polynomial.Chebyshev`), whose design matrix stays well-conditioned at any
  order; the plain power coefficients a0, a1, ... on the original q are computed only for export
  (``Chebyshev.convert(kind=Polynomial, domain=window)``), and the export says when re-evaluating
  them loses precision.
* **The order from the data.** ``order="auto"`` picks the order with the smallest
  AICc = n ln(RSS/n) + 2k + 2k(k+1)/(n−k−1), k = order + 1 coefficients (the default), or by
  the leave-one-out error (the prediction error at each tuned position when it is left out of
  the fit), computed without refitting as e_i / (1 − h_ii) with h the diagonal of the hat
  matrix, with the one-standard-error rule. Both are reported for every order. AICc is the
  default because on few positions it over-fits less: on a noisy cubic tuned at 9 positions
  (200 seeds, tests/analysis/test_gain_schedule.py) AICc chose an order above 4 in none, the
  leave-one-out rule in about 6 %.
* **Warnings** when the order approaches the number of positions (n positions fix at most an
  order n − 1 polynomial, which interpolates them and predicts nothing), and when the curve
  oscillates between the positions (Runge's phenomenon): the curve is checked on a fine grid
  between the tuned points, not only at them.

Definitions and sources: ``reference/spc-extensions.md`` §7.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.polynomial import Chebyshev, Polynomial, chebyshev

from station.errors import StationError

Criterion = Literal["loo", "aicc"]
CRITERIA: tuple[str, ...] = ("loo", "aicc")
#: The highest order ``auto`` tries (the report's "8th order or more", plus room).
AUTO_ORDER_MAX = 10
#: Scores within this fraction of the gains' size of the best are numerical ties.
_NOISE_FLOOR = 1e-9
#: The curve may swing between two positions beyond its values there by this share of its range.
OVERSHOOT_SHARE = 0.10
#: Points of the fine grid per interval between positions, for the oscillation check.
_GRID_PER_INTERVAL = 40


@dataclass(frozen=True)
class OrderScore:
    """One candidate order: its leave-one-out RMSE and AICc (None where undefined)."""

    order: int
    loo_rmse: float | None
    aicc: float | None
    rss: float
    loo_se: float | None = None
    """The standard error of the mean squared leave-one-out error (for the one-SE rule)."""


@dataclass(frozen=True)
class GainFit:
    """The fitted schedule of one gain.

    ``chebyshev`` holds the coefficients in the Chebyshev basis on q scaled from ``domain`` to
    [−1, 1] (what the evaluation uses); ``coefficients`` the power coefficients a0, a1, ... an
    on the original q (for export). ``loo_rmse`` is None when the fit interpolates (order
    n − 1). ``scores`` lists every order tried by ``auto`` (only the chosen one otherwise).
    ``overshoot`` is the largest swing of the curve between two neighbouring positions beyond
    its own values at them, as a share of the fitted gains' range (Runge oscillation).
    """

    name: str
    order: int
    chosen_by: str
    positions: tuple[float, ...]
    gains: tuple[float, ...]
    domain: tuple[float, float]
    chebyshev: tuple[float, ...]
    coefficients: tuple[float, ...]
    fitted: tuple[float, ...]
    residuals: tuple[float, ...]
    rmse: float
    loo_rmse: float | None
    aicc: float | None
    scores: tuple[OrderScore, ...]
    overshoot: float
    export_error: float
    """Largest |power-form − Chebyshev-form| at the positions, relative to the gains' size."""
    warnings: tuple[str, ...]

    def evaluate(self, q: Any) -> Any:
        """K(q) from the Chebyshev form (well-conditioned), for a number or an array."""
        series = Chebyshev(np.asarray(self.chebyshev), domain=list(self.domain))
        return series(np.asarray(q, dtype=float))

    def as_json(self) -> dict[str, Any]:
        """``{order, coefficients: [a0, a1, ...], loo_rmse, residuals, ...}`` for the export."""
        return {
            "order": self.order,
            "coefficients": list(self.coefficients),
            "loo_rmse": self.loo_rmse,
            "residuals": list(self.residuals),
            "rmse": self.rmse,
            "aicc": self.aicc,
            "chosen_by": self.chosen_by,
            "chebyshev": list(self.chebyshev),
            "domain": list(self.domain),
            "overshoot": self.overshoot,
            "export_error": self.export_error,
            "scores": [
                {"order": s.order, "loo_rmse": s.loo_rmse, "aicc": s.aicc, "rss": s.rss}
                for s in self.scores
            ],
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class GainSchedule:
    """The fits of every gain over the same tuned positions."""

    positions: tuple[float, ...]
    fits: Mapping[str, GainFit]

    def as_json(self) -> dict[str, Any]:
        """``{positions, domain, gains: {NAME: {...}}}``."""
        first = next(iter(self.fits.values()))
        return {
            "positions": list(self.positions),
            "domain": list(first.domain),
            "gains": {name: fit.as_json() for name, fit in self.fits.items()},
        }


def _design(x: Any, order: int) -> Any:
    return chebyshev.chebvander(x, order)


def _score(x: Any, k: Any, order: int, scale: float) -> tuple[OrderScore, Any, Any]:
    """Least squares of ``k`` on the Chebyshev basis of order ``order`` at scaled ``x``: the
    score, the coefficients and the residuals."""
    n = len(x)
    design = _design(x, order)
    q_factor, r_factor = np.linalg.qr(design)
    coefficients = np.linalg.solve(r_factor, q_factor.T @ k)
    residuals = k - design @ coefficients
    rss = float(residuals @ residuals)
    parameters = order + 1
    leverage = np.sum(q_factor**2, axis=1)
    loo: float | None = None
    loo_se: float | None = None
    if parameters < n and np.all(leverage < 1 - 1e-9):
        squared = (residuals / (1 - leverage)) ** 2
        loo = float(np.sqrt(np.mean(squared)))
        loo_se = float(np.std(squared, ddof=1) / math.sqrt(n))
    aicc: float | None = None
    if n - parameters - 1 > 0:
        # A perfect fit has RSS 0 and ln 0 = −∞: floor the RSS at numerical noise.
        floor = (_NOISE_FLOOR * scale) ** 2 * n
        aicc = (
            n * math.log(max(rss, floor) / n)
            + 2 * parameters
            + 2 * parameters * (parameters + 1) / (n - parameters - 1)
        )
    return OrderScore(order, loo, aicc, rss, loo_se), coefficients, residuals


def _choose(scores: Sequence[OrderScore], criterion: Criterion, scale: float) -> OrderScore:
    """The lowest order whose score ties the best.

    Leave-one-out: the one-standard-error rule (Hastie, Tibshirani & Friedman, *The Elements of
    Statistical Learning*, §7.10): the lowest order whose mean squared LOO error is within one
    standard error of the smallest (on 9 positions the LOO error itself is noisy, and its
    minimum alone over-fits now and then). AICc: the smallest, ties within 1e-9.
    """
    if criterion == "loo":
        rated = [(s, s.loo_rmse) for s in scores if s.loo_rmse is not None]
        if not rated:
            raise StationError("no order leaves a position out: give more tuned positions.")
        best, best_rmse = min(rated, key=lambda pair: pair[1])
        allowed = best_rmse**2 + (best.loo_se or 0.0) + (_NOISE_FLOOR * scale) ** 2
        return next(s for s, rmse in rated if rmse**2 <= allowed)
    ranked = [(s, s.aicc) for s in scores if s.aicc is not None]
    if not ranked:
        raise StationError("AICc needs 3 or more tuned positions to choose an order: give --order.")
    best_aicc = min(aicc for _, aicc in ranked)
    return next(s for s, aicc in ranked if aicc <= best_aicc + 1e-9)


def _overshoot(series: Any, q: Any) -> float:
    """The largest swing of the curve between two neighbouring positions beyond its own values
    at them, relative to the range of the fitted gains (0 for a curve monotone between each
    pair). A smooth schedule with a peak between two positions swings a little (about the
    square of the spacing over the span); Runge oscillation swings a lot."""
    at_positions = series(q)
    span = float(np.ptp(at_positions))
    if span == 0:
        span = max(float(np.max(np.abs(at_positions))), 1e-300)
    worst = 0.0
    for left, right, k_left, k_right in zip(
        q[:-1], q[1:], at_positions[:-1], at_positions[1:], strict=True
    ):
        grid = np.linspace(left, right, _GRID_PER_INTERVAL + 2)[1:-1]
        curve = series(grid)
        above = float(np.max(curve)) - max(k_left, k_right)
        below = min(k_left, k_right) - float(np.min(curve))
        worst = max(worst, above, below)
    return worst / span


def fit_gain(
    positions: Sequence[float] | Any,
    gains: Sequence[float] | Any,
    order: int | Literal["auto"] = "auto",
    *,
    criterion: Criterion = "aicc",
    name: str = "K",
    max_order: int = AUTO_ORDER_MAX,
) -> GainFit:
    """Fit ``gains`` (tuned at ``positions``) as a polynomial of the position.

    ``order`` is a whole number, or ``"auto"``: the order up to ``max_order`` (and at most
    n − 2, so that one position is always left to predict; n − 3 for AICc) with the smallest
    AICc (``criterion="aicc"``) or leave-one-out RMSE by the one-SE rule (``"loo"``). Raises
    StationError for fewer than 2 positions, repeated positions, values that are not finite, or
    an order the positions cannot fix (order ≥ n).
    """
    q = np.asarray(positions, dtype=float).ravel()
    k = np.asarray(gains, dtype=float).ravel()
    if q.size != k.size:
        raise StationError(f"gain {name!r}: {k.size} gains for {q.size} positions.")
    if q.size < 2:
        raise StationError(f"gain {name!r}: a schedule needs gains tuned at 2 or more positions.")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(k))):
        raise StationError(f"gain {name!r}: a position or gain is not a finite number.")
    if criterion not in CRITERIA:
        raise StationError(f"unknown order criterion {criterion!r}: use loo or aicc.")
    sort = np.argsort(q, kind="stable")
    q, k = q[sort], k[sort]
    if np.any(np.diff(q) == 0):
        repeated = q[np.flatnonzero(np.diff(q) == 0)[0]]
        raise StationError(
            f"position {repeated:g} is given twice: tune each position once (or average the "
            "gains tuned there)."
        )
    n = int(q.size)
    domain = (float(q[0]), float(q[-1]))
    x = (2 * q - (domain[0] + domain[1])) / (domain[1] - domain[0])
    scale = max(float(np.max(np.abs(k))), 1e-300)

    if order == "auto":
        top = min(max_order, n - 2)
        if top < 0:
            raise StationError(f"gain {name!r}: 'auto' needs 2 or more positions to leave one out.")
        scored = [_score(x, k, m, scale) for m in range(top + 1)]
        scores = tuple(s for s, _, _ in scored)
        chosen = _choose(scores, criterion, scale)
        score, cheb, residuals = scored[chosen.order]
        chosen_by = "leave-one-out RMSE" if criterion == "loo" else "AICc"
    else:
        if isinstance(order, bool) or not isinstance(order, int) or order < 0:
            raise StationError(f"gain {name!r}: the order must be a whole number 0 or more.")
        if order >= n:
            raise StationError(
                f"gain {name!r}: an order-{order} polynomial needs at least {order + 1} "
                f"positions; {n} were tuned (use --order {n - 2} or less, or --order auto)."
            )
        score, cheb, residuals = _score(x, k, order, scale)
        scores = (score,)
        chosen_by = "given"

    series = Chebyshev(cheb, domain=list(domain))
    # A series maps its domain onto its window; with domain = window the map is the identity,
    # so these coefficients are in powers of the original q.
    power = series.convert(kind=Polynomial, domain=[-1, 1], window=[-1, 1])
    coefficients = np.zeros(score.order + 1)
    coefficients[: len(power.coef)] = power.coef
    fitted = series(q)
    by_power = np.polynomial.polynomial.polyval(q, coefficients)
    export_error = float(np.max(np.abs(by_power - fitted))) / scale
    overshoot = _overshoot(series, q)

    warnings: list[str] = []
    if score.order >= n - 1:
        warnings.append(
            f"order {score.order} on {n} positions interpolates them: the residuals are zero "
            "by construction and nothing is left to check the curve between the positions."
        )
    elif score.order >= n - 2 and n > 3:
        warnings.append(
            f"order {score.order} on {n} positions leaves {n - score.order - 1} degree(s) of "
            "freedom: the fit follows the tuning noise; tune more positions or lower the order."
        )
    if overshoot > OVERSHOOT_SHARE:
        warnings.append(
            f"the curve swings {100 * overshoot:.0f} % of the gains' range between positions "
            "beyond its values at them (Runge oscillation): lower the order or tune more positions "
            "where it swings."
        )
    if export_error > 1e-9:
        warnings.append(
            f"the power coefficients a0..a{score.order} lose precision (they differ from the "
            f"fit by {export_error:.1e} of the gains' size): a controller should evaluate with "
            "double precision and the exported domain."
        )
    return GainFit(
        name=name,
        order=score.order,
        chosen_by=chosen_by,
        positions=tuple(float(v) for v in q),
        gains=tuple(float(v) for v in k),
        domain=domain,
        chebyshev=tuple(float(c) for c in cheb),
        coefficients=tuple(float(c) for c in coefficients),
        fitted=tuple(float(v) for v in fitted),
        residuals=tuple(float(v) for v in residuals),
        rmse=math.sqrt(score.rss / n),
        loo_rmse=score.loo_rmse,
        aicc=score.aicc,
        scores=scores,
        overshoot=overshoot,
        export_error=export_error,
        warnings=tuple(warnings),
    )


def fit_schedule(
    positions: Sequence[float] | Any,
    gains: Mapping[str, Sequence[float] | Any],
    order: int | Literal["auto"] = "auto",
    *,
    criterion: Criterion = "aicc",
) -> GainSchedule:
    """:func:`fit_gain` for every gain (e.g. ``{"kp": ..., "ki": ..., "kd": ...}``)."""
    if not gains:
        raise StationError("no gains to fit: give one column per gain beside the position q.")
    fits = {
        name: fit_gain(positions, values, order, criterion=criterion, name=name)
        for name, values in gains.items()
    }
    first = next(iter(fits.values()))
    return GainSchedule(positions=first.positions, fits=fits)


def c_identifier(name: str) -> str:
    """A C identifier from a gain's name: letters, digits and ``_`` only, not starting with a
    digit (``Kp`` → ``kp``, ``K-d 2`` → ``k_d_2``)."""
    cleaned = "".join(ch if ch.isascii() and ch.isalnum() else "_" for ch in name.lower())
    cleaned = "_".join(part for part in cleaned.split("_") if part) or "gain"
    return f"g_{cleaned}" if cleaned[0].isdigit() else cleaned


def c_header(schedule: GainSchedule, *, source: str = "", prefix: str = "gain_schedule") -> str:
    """The schedule as a C header a controller can load: per gain a ``static const double``
    array of the power coefficients a0..an (``K(q) = a0 + a1 q + ...`` on the original q), its
    order, the valid range of q, and an inline Horner evaluation."""
    prefix = c_identifier(prefix)
    guard = prefix.upper() + "_H"
    first = next(iter(schedule.fits.values()))
    # Text from outside (the file name) goes into a comment: keep it printable ASCII without
    # the comment's closing sequence.
    safe_source = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in source).replace("*/", "*?")
    lines = [
        "/* Gain schedule K(q) = a0 + a1*q + ... + an*q^n, fitted by `station gains fit`"
        + (f" from {safe_source}" if safe_source else "")
        + ".",
        f"   Valid for q in [{first.domain[0]!r}, {first.domain[1]!r}] (the tuned positions);",
        "   outside it the polynomial extrapolates. */",
        f"#ifndef {guard}",
        f"#define {guard}",
        "",
        f"#define {prefix.upper()}_Q_MIN ({first.domain[0]!r})",
        f"#define {prefix.upper()}_Q_MAX ({first.domain[1]!r})",
        "",
    ]
    used: set[str] = set()
    for name, fit in schedule.fits.items():
        ident = c_identifier(name)
        while ident in used:
            ident += "_"
        used.add(ident)
        values = ", ".join(repr(c) for c in fit.coefficients)
        loo = "n/a" if fit.loo_rmse is None else f"{fit.loo_rmse:.6g}"
        safe_name = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in name).replace("*/", "*?")
        lines += [
            f"/* {safe_name}: order {fit.order}, leave-one-out RMSE {loo} */",
            f"#define {prefix.upper()}_{ident.upper()}_ORDER {fit.order}",
            f"static const double {prefix}_{ident}[{fit.order + 1}] = {{{values}}};",
            "",
        ]
    lines += [
        "/* K(q) by Horner's rule: coefficients a0..an, n = order. */",
        f"static inline double {prefix}_eval(const double *a, int order, double q)",
        "{",
        "    double k = a[order];",
        "    for (int i = order - 1; i >= 0; --i)",
        "        k = k * q + a[i];",
        "    return k;",
        "}",
        "",
        f"#endif /* {guard} */",
        "",
    ]
    return "\n".join(lines)
