"""Gain schedule fit (report §4.3): Chebyshev least squares, order by AICc / leave-one-out."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from station.analysis.gain_schedule import c_identifier, fit_gain, fit_schedule
from station.errors import StationError

POSITIONS = np.linspace(-30.0, 120.0, 9)
CUBIC = (2.0, -0.03, 4e-4, -1e-6)


def cubic(q):
    return np.polynomial.polynomial.polyval(q, CUBIC)


@pytest.mark.parametrize("criterion", ["aicc", "loo"])
def test_noiseless_cubic_is_recovered_exactly_by_auto(criterion):
    fit = fit_gain(POSITIONS, cubic(POSITIONS), "auto", criterion=criterion)
    assert fit.order == 3
    assert fit.coefficients == pytest.approx(CUBIC, rel=1e-9, abs=1e-15)
    assert max(abs(r) for r in fit.residuals) < 1e-12
    assert fit.warnings == ()
    # Between the positions too: the curve is the cubic.
    grid = np.linspace(-30, 120, 301)
    assert np.allclose(fit.evaluate(grid), cubic(grid), rtol=0, atol=1e-12)


def test_noisy_cubic_is_not_over_fitted():
    # 200 seeds of a cubic tuned at 9 positions with noise: AICc never chooses above order 4;
    # the leave-one-out rule (one-SE) does in a few seeds (measured: 13 of 200).
    aicc, loo = Counter(), Counter()
    for seed in range(200):
        noisy = cubic(POSITIONS) + np.random.default_rng(seed).normal(0, 0.02, POSITIONS.size)
        aicc[fit_gain(POSITIONS, noisy, "auto").order] += 1
        loo[fit_gain(POSITIONS, noisy, "auto", criterion="loo").order] += 1
    assert max(aicc) <= 4
    assert sum(count for order, count in loo.items() if order <= 4) >= 180
    assert aicc[3] >= 180  # and it finds the cubic, not a lower order


def test_high_order_warns_interpolation_and_few_degrees_of_freedom():
    noisy = cubic(POSITIONS) + np.random.default_rng(1).normal(0, 0.02, POSITIONS.size)
    eighth = fit_gain(POSITIONS, noisy, 8)
    assert eighth.loo_rmse is None
    assert any("interpolates" in w for w in eighth.warnings)
    seventh = fit_gain(POSITIONS, noisy, 7)
    assert any("1 degree(s) of freedom" in w for w in seventh.warnings)
    with pytest.raises(StationError, match="needs at least 10 positions"):
        fit_gain(POSITIONS, noisy, 9)


def test_runge_oscillation_between_positions_is_warned():
    # Runge's own function on 9 equally spaced points: the interpolating 8th-order polynomial
    # swings far beyond the data near the ends.
    q = np.linspace(-1, 1, 9)
    k = 1 / (1 + 25 * q**2)
    fit = fit_gain(q, k, 8)
    assert fit.overshoot > 0.5
    assert any("Runge" in w for w in fit.warnings)
    assert fit_gain(q, k, 2).overshoot < 0.1


def test_export_coefficients_match_the_chebyshev_form():
    rng = np.random.default_rng(3)
    gains = cubic(POSITIONS) + rng.normal(0, 0.05, POSITIONS.size)
    fit = fit_gain(POSITIONS, gains, 6)
    power = np.polynomial.polynomial.polyval(POSITIONS, fit.coefficients)
    assert np.allclose(power, fit.fitted, rtol=0, atol=1e-9)
    assert fit.export_error < 1e-9


def test_schedule_json_shape_and_bad_input():
    schedule = fit_schedule(POSITIONS, {"kp": cubic(POSITIONS), "ki": 0.5 + 0 * POSITIONS}, 2)
    document = schedule.as_json()
    assert set(document["gains"]) == {"kp", "ki"}
    kp = document["gains"]["kp"]
    assert {"order", "coefficients", "loo_rmse", "residuals"} <= set(kp)
    assert len(kp["coefficients"]) == 3 and len(kp["residuals"]) == 9
    with pytest.raises(StationError, match="given twice"):
        fit_gain([0, 1, 1, 2], [1, 2, 3, 4], 1)
    with pytest.raises(StationError, match="2 or more positions"):
        fit_gain([0], [1], 0)


def test_c_identifier():
    assert c_identifier("Kp") == "kp"
    assert c_identifier("K-d 2") == "k_d_2"
    assert c_identifier("2nd") == "g_2nd"
    assert c_identifier("ü*/") == "gain"
