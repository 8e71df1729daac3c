"""Capability indices: definitions, one-sided limits, confidence bounds, and what is undefined."""

import math

import numpy as np
import pytest
from scipy import stats

from station.analysis.capability import (
    SpecLimits,
    bissell_interval,
    capability,
    cp_interval,
    cpk_lower_bound,
    cpk_upper_bound,
    readings_needed,
)
from station.analysis.charts import sigma_within
from station.errors import StationError

LIMITS = SpecLimits(lsl=-0.001, usl=0.001)


def test_nominal_defaults_to_the_mid_spec():
    assert SpecLimits(lsl=1.0, usl=3.0).nominal == 2.0
    assert SpecLimits(lsl=1.0, usl=3.0, nominal=1.5).nominal == 1.5
    assert SpecLimits(usl=3.0).nominal is None


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"lsl": 0.002, "usl": 0.001}, "upper limit 0.001 is not above lower limit 0.002"),
        ({"lsl": 0.001, "usl": 0.001}, "is not above lower limit"),
        ({}, "no specification limits"),
        ({"lsl": float("nan"), "usl": 1.0}, "lower limit nan is not a finite number"),
        ({"usl": float("inf")}, "upper limit inf is not a finite number"),
        ({"lsl": 0.0, "usl": 1.0, "nominal": float("nan")}, "nominal"),
        ({"lsl": "x"}, "lower limit 'x' is not a number"),
    ],
)
def test_impossible_limits_are_refused_with_a_sentence(kwargs, fragment):
    with pytest.raises(StationError, match=fragment):
        SpecLimits(**kwargs)


def test_indices_follow_the_report_definitions():
    values = np.array([0.1, 0.3, -0.2, 0.4, 0.0, 0.2, -0.1, 0.3])
    limits = SpecLimits(lsl=-1.0, usl=1.5)
    result = capability(values, limits)
    mean, s = values.mean(), values.std(ddof=1)
    assert result.sigma == pytest.approx(s)
    assert result.cp == pytest.approx(2.5 / (6 * s))
    assert result.cpu == pytest.approx((1.5 - mean) / (3 * s))
    assert result.cpl == pytest.approx((mean + 1.0) / (3 * s))
    assert result.cpk == pytest.approx(min(result.cpu, result.cpl))
    within = np.abs(np.diff(values)).mean() / (2 / math.sqrt(math.pi))
    assert result.sigma_within == pytest.approx(within)
    assert result.cp_within == pytest.approx(2.5 / (6 * within))
    assert result.cpk_within == pytest.approx(min(1.5 - mean, mean + 1.0) / (3 * within))
    assert (result.n, result.mean, result.message) == (8, pytest.approx(mean), None)


def test_capable_follows_the_threshold(table_2_1):
    assert capability(table_2_1, LIMITS).capable is True
    strict = capability(table_2_1, LIMITS, threshold=1.33)
    assert strict.capable is False and strict.threshold == 1.33
    assert capability(table_2_1, LIMITS, threshold=strict.cpk).capable is True


def test_upper_limit_only_gives_cpk_from_the_upper_side():
    values = [0.1, 0.3, -0.2, 0.4, 0.0]
    result = capability(values, SpecLimits(usl=1.0))
    assert result.cp is None and result.cpl is None and result.cp_within is None
    assert result.cpk == result.cpu is not None
    assert result.cpk_within is not None and result.capable is not None
    lower = capability(values, SpecLimits(lsl=-1.0))
    assert lower.cp is None and lower.cpu is None
    assert lower.cpk == lower.cpl is not None


def test_pieces_outside_are_counted_strictly():
    values = [0.001, 0.0011, -0.001, -0.0012, -0.0013, 0.0]
    result = capability(values, LIMITS)
    assert (result.above_usl, result.below_lsl) == (1, 2)


def test_zero_sigma_gives_a_message_and_no_indices():
    result = capability([0.0002] * 30, LIMITS)
    assert result.sigma == 0
    assert (result.cp, result.cpu, result.cpl, result.cpk, result.cpk_lower) == (None,) * 5
    assert (result.cp_within, result.cpk_within, result.capable) == (None, None, None)
    assert result.message.startswith("sigma is 0: every reading is the same (0.0002)")
    # Positional like every other figure, never "-4e-05".
    still = capability([-0.00004] * 30, LIMITS)
    assert "every reading is the same (-0.00004)" in still.message


@pytest.mark.parametrize("values", [[], [0.0004]])
def test_fewer_than_two_readings_give_a_message(values):
    result = capability(values, LIMITS)
    assert result.cpk is None and result.capable is None and result.sigma is None
    assert f"need at least 2 readings to estimate sigma (have {len(values)})" in result.message


def test_zero_within_sigma_is_reported_without_inf():
    # Subgroups that never vary inside but differ between each other: R-bar = 0.
    values = [0.0, 0.0, 0.0, 0.0005, 0.0005, 0.0005]
    result = capability(values, LIMITS, subgroup=3)
    assert result.cpk is not None
    assert result.sigma_within == 0 and result.cp_within is None and result.cpk_within is None
    assert "within sigma is 0" in result.message


def test_no_complete_subgroup_leaves_the_within_figures_undefined():
    result = capability([0.0, 0.0002, -0.0001], LIMITS, subgroup=5)
    assert result.cpk is not None and result.sigma_within is None and result.cp_within is None
    assert "no complete subgroup of 5" in result.message


def test_subgroups_select_the_range_estimator_and_a_known_sigma_overrides_it():
    rng = np.random.default_rng(3)
    values = rng.normal(0, 0.0002, 50)
    result = capability(values, LIMITS, subgroup=5)
    assert result.sigma_within == pytest.approx(sigma_within(values, 5))
    given = capability(values, LIMITS, subgroup=5, sigma_within=0.0002)
    assert given.sigma_within == 0.0002 and given.cp_within == pytest.approx(0.002 / 0.0012)


def test_cpk_lower_is_the_one_sided_bissell_bound(table_2_1):
    result = capability(table_2_1, LIMITS)
    z = stats.norm.ppf(0.95)
    expected = result.cpk - z * math.sqrt(1 / (9 * 30) + result.cpk**2 / (2 * 29))
    assert result.cpk_lower == pytest.approx(expected, rel=1e-12)
    assert result.cpk_lower == pytest.approx(0.897, abs=5e-4)
    looser = capability(table_2_1, LIMITS, confidence=0.9)
    assert result.cpk_lower < looser.cpk_lower < result.cpk


def test_table_2_1_carries_both_intervals_and_the_upper_bound(table_2_1):
    result = capability(table_2_1, LIMITS)
    assert result.cpk_upper == pytest.approx(cpk_upper_bound(result.cpk, 30), rel=1e-12)
    assert result.cpk_lower + result.cpk_upper == pytest.approx(2 * result.cpk, rel=1e-12)
    assert result.cpk_ci == pytest.approx(bissell_interval(result.cpk, 30, 0.95), rel=1e-12)
    assert result.cp_ci == pytest.approx(cp_interval(result.cp, 30, 0.95), rel=1e-12)
    # Two-sided at 95 % is wider than the one-sided 95 % bounds.
    assert result.cpk_ci[0] < result.cpk_lower and result.cpk_upper < result.cpk_ci[1]
    assert result.cpk_ci == pytest.approx((0.845, 1.491), abs=5e-4)
    assert result.cp_ci == pytest.approx((0.941, 1.588), abs=5e-4)


def test_an_upper_limit_only_has_no_cp_interval_but_a_cpk_interval(table_2_1):
    result = capability(table_2_1, SpecLimits(usl=0.001))
    assert result.cp_ci is None and result.cpk_ci is not None and result.cpk_upper is not None


def test_undefined_indices_have_no_bounds():
    result = capability([0.0001] * 30, LIMITS)
    assert (result.cpk_upper, result.cp_ci, result.cpk_ci) == (None, None, None)


def test_readings_needed_is_the_fewest_that_settle_the_bound(table_2_1):
    cpk = capability(table_2_1, LIMITS).cpk
    # The issue's figure: Table 2-1's bound reaches 1 at 77 readings, not at 76.
    assert readings_needed(cpk, 1.0) == 77
    assert cpk_lower_bound(cpk, 76) < 1.0 <= cpk_lower_bound(cpk, 77)
    # Below the threshold: the upper bound must fall below it.
    needed = readings_needed(0.9, 1.0)
    assert cpk_upper_bound(0.9, needed - 1) >= 1.0 > cpk_upper_bound(0.9, needed)
    assert readings_needed(1.0, 1.0) is None
    assert readings_needed(1.0 + 1e-9, 1.0) is None  # more than anyone will take
    assert readings_needed(1.5, 1.0, 0.99) > readings_needed(1.5, 1.0, 0.95)


def test_bissell_bound_moves_the_right_way_for_a_negative_cpk():
    assert cpk_lower_bound(-0.5, 30) < -0.5
    low, high = bissell_interval(-0.5, 30)
    assert low < -0.5 < high


def test_cp_interval_is_the_chi_square_interval():
    low, high = cp_interval(1.2, 30, 0.95)
    assert low == pytest.approx(1.2 * math.sqrt(stats.chi2.ppf(0.025, 29) / 29))
    assert high == pytest.approx(1.2 * math.sqrt(stats.chi2.ppf(0.975, 29) / 29))


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"confidence": 1.0}, "confidence"),
        ({"threshold": float("nan")}, "threshold"),
        ({"subgroup": 0}, "subgroup size 0"),
        ({"sigma_within": -1.0}, "within sigma"),
    ],
)
def test_bad_options_are_refused_with_a_sentence(kwargs, fragment):
    with pytest.raises(StationError, match=fragment):
        capability([0.0, 0.0001, 0.0002], LIMITS, **kwargs)


def test_nan_readings_name_the_position():
    with pytest.raises(StationError, match="reading 2 is not a number"):
        capability([0.0, float("nan")], LIMITS)


def test_indices_too_large_for_a_float_are_none_with_a_message():
    result = capability([0.0, 1e-320], LIMITS)
    assert (result.cp, result.cpk, result.capable) == (None, None, None)
    assert result.message.startswith("the indices are too large to represent")
