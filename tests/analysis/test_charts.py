"""Control charts: type by subgroup size, limits from the within sigma, partial subgroups."""

import math

import numpy as np
import pytest

from station.analysis.charts import (
    chart_type,
    control_chart,
    moving_ranges,
    pooled_sigma,
    sigma_within,
    subgroups,
)
from station.analysis.constants import c4, chart_factors, d2
from station.errors import StationError


@pytest.mark.parametrize(
    ("size", "kind"), [(1, "I-MR"), (2, "Xbar-R"), (10, "Xbar-R"), (11, "Xbar-S"), (25, "Xbar-S")]
)
def test_chart_type_follows_the_subgroup_size(size, kind):
    assert chart_type(size) == kind
    assert control_chart(np.arange(2.0 * max(size, 2)), size).type == kind


def test_individuals_chart_of_table_2_1(table_2_1):
    chart = control_chart(table_2_1)
    values = np.array(table_2_1)
    mr_bar = np.abs(np.diff(values)).mean()
    sigma = mr_bar / d2(2)
    assert chart.center == pytest.approx(values.mean())
    assert chart.sigma_within == pytest.approx(sigma)
    assert chart.ucl == pytest.approx(values.mean() + 3 * sigma)
    assert chart.lcl == pytest.approx(values.mean() - 3 * sigma)
    assert chart.point_sigma == pytest.approx(sigma)
    assert chart.points == tuple(table_2_1)
    assert len(chart.dispersion_points) == 29
    assert chart.dispersion.center == pytest.approx(mr_bar)
    assert chart.dispersion.ucl == pytest.approx(chart_factors(1).D4 * mr_bar)
    assert chart.dispersion.lcl == 0
    assert chart.message is None
    # The report's Figure 2-6 shows no sign of trouble: every point is inside the limits.
    assert all(chart.lcl < p < chart.ucl for p in chart.points)


def test_xbar_r_limits_use_a2_and_d3_d4():
    values = [1.0, 2.0, 4.0, 2.0, 2.5, 3.0, 0.5, 1.5, 3.5]
    chart = control_chart(values, 3)
    groups = np.array(values).reshape(3, 3)
    r_bar = np.ptp(groups, axis=1).mean()
    f = chart_factors(3)
    assert chart.points == pytest.approx(tuple(groups.mean(axis=1)))
    assert chart.dispersion_points == pytest.approx(tuple(np.ptp(groups, axis=1)))
    assert chart.ucl == pytest.approx(groups.mean() + f.A2 * r_bar)
    assert chart.lcl == pytest.approx(groups.mean() - f.A2 * r_bar)
    assert chart.sigma_within == pytest.approx(r_bar / d2(3))
    assert chart.point_sigma == pytest.approx(r_bar / d2(3) / math.sqrt(3))
    assert (chart.dispersion.center, chart.dispersion.lcl) == (pytest.approx(r_bar), 0)
    assert chart.dispersion.ucl == pytest.approx(f.D4 * r_bar)


def test_xbar_s_limits_use_a3_and_b3_b4():
    rng = np.random.default_rng(11)
    values = rng.normal(10, 1, 12 * 6)
    chart = control_chart(values, 12)
    groups = values.reshape(6, 12)
    s_bar = groups.std(axis=1, ddof=1).mean()
    f = chart_factors(12)
    assert chart.type == "Xbar-S"
    assert chart.ucl == pytest.approx(groups.mean() + f.A3 * s_bar)
    assert chart.sigma_within == pytest.approx(s_bar / c4(12))
    assert chart.dispersion.lcl == pytest.approx(f.B3 * s_bar) and f.B3 > 0
    assert chart.dispersion.ucl == pytest.approx(f.B4 * s_bar)
    assert sigma_within(values, 12) == pytest.approx(chart.sigma_within)


def test_an_s_chart_can_be_asked_for_small_subgroups():
    values = np.arange(20.0) % 7
    chart = control_chart(values, 5, kind="Xbar-S")
    assert chart.type == "Xbar-S"
    assert chart.sigma_within == pytest.approx(sigma_within(values, 5, kind="Xbar-S"))
    with pytest.raises(StationError, match="does not fit subgroups of 1"):
        control_chart(values, 1, kind="Xbar-R")
    with pytest.raises(StationError, match="unknown chart type"):
        control_chart(values, 5, kind="p")


def test_a_trailing_partial_subgroup_is_left_out_and_said():
    chart = control_chart(np.arange(13.0), 5)
    assert len(chart.points) == 2
    assert chart.message == "the last 3 readings do not fill a subgroup of 5 and are left out"
    single = control_chart(np.arange(11.0), 5)
    assert single.message == "the last reading does not fill a subgroup of 5 and is left out"


@pytest.mark.parametrize(("values", "size"), [([], 1), ([1.0], 1), ([1.0, 2.0], 3)])
def test_too_few_readings_give_a_chart_without_limits(values, size):
    chart = control_chart(values, size)
    assert (chart.center, chart.ucl, chart.lcl, chart.sigma_within) == (None,) * 4
    assert chart.dispersion.center is None and chart.point_sigma is None
    assert "needs" in chart.message and f"(have {len(values)})" in chart.message
    assert sigma_within(values, size) is None


def test_constant_readings_give_collapsed_limits_not_nan():
    chart = control_chart([0.5] * 10)
    assert chart.sigma_within == 0 and chart.ucl == chart.lcl == chart.center == 0.5


@pytest.mark.parametrize("bad", [0, -2, 2.5, "5", None, True])
def test_bad_subgroup_sizes_are_refused(bad):
    with pytest.raises(StationError, match="subgroup size"):
        control_chart([1.0, 2.0, 3.0], bad)


def test_helpers_split_and_difference_in_order():
    assert subgroups([1, 2, 3, 4, 5], 2).tolist() == [[1, 2], [3, 4]]
    assert moving_ranges([1, 4, 2]).tolist() == [3, 2]


def test_pooled_sigma_is_the_root_mean_square_sd_over_c4():
    groups = np.array([[1.0, 2.0, 4.0], [2.0, 2.5, 3.0], [0.5, 1.5, 3.5]])
    pooled = math.sqrt(groups.var(axis=1, ddof=1).mean()) / c4(3 * 2 + 1)
    assert pooled_sigma(groups.ravel(), 3) == pytest.approx(pooled)
    assert pooled_sigma([1.0, 2.0], 1) is None


def test_numpy_and_whole_float_sizes_are_accepted():
    values = np.arange(10.0)
    assert control_chart(values, np.int64(5)).subgroup == 5
    assert control_chart(values, 5.0).type == "Xbar-R"
