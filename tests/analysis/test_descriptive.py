"""Descriptive statistics and the histogram."""

import math

import numpy as np
import pytest
from scipy import stats

from station.analysis.descriptive import as_readings, describe, histogram, modes_at_resolution
from station.errors import StationError


def test_skewness_is_m3_over_s_cubed():
    rng = np.random.default_rng(7)
    values = rng.gamma(2.0, size=50)
    n = values.size
    expected = stats.skew(values, bias=True) * ((n - 1) / n) ** 1.5
    assert describe(values).skewness == pytest.approx(expected, rel=1e-12)
    assert describe(values).sd == pytest.approx(np.std(values, ddof=1), rel=1e-12)


def test_all_tied_modes_are_returned_in_order():
    assert describe([3, 1, 2, 2, 3]).modes == (2.0, 3.0)
    assert describe([5, 5, 5, 1]).modes == (5.0,)


def test_no_mode_when_no_value_repeats():
    assert describe([1.0, 2.0, 3.0]).modes == ()
    assert describe([4.2]).modes == ()


def test_modes_count_values_at_the_gauge_resolution():
    # 0.00019999 and 0.00020001 are both the reading 0.0002 on a 0.0001 in gauge.
    values = [0.00019999, 0.00020001, 0.0001, 0.0003]
    assert describe(values, resolution=0.0001).modes == (0.0002,)
    assert describe(values).modes == ()
    # Multiples come back clean, without binary noise.
    assert modes_at_resolution([0.0003, 0.0003], 0.0001) == (0.0003,)


def test_empty_single_and_pair_leave_undefined_figures_as_none():
    empty = describe([])
    assert (empty.n, empty.mean, empty.sd, empty.skewness, empty.min, empty.range) == (
        0,
        None,
        None,
        None,
        None,
        None,
    )
    one = describe([0.5])
    assert (one.n, one.mean, one.sd, one.skewness, one.range) == (1, 0.5, None, None, 0.0)
    two = describe([0.5, 1.5])
    assert two.sd == pytest.approx(math.sqrt(0.5)) and two.skewness is None


def test_constant_readings_have_zero_sigma_and_no_skewness():
    result = describe([0.1] * 30)
    assert result.sd == 0.0
    assert result.mean == 0.1
    assert result.skewness is None
    assert result.range == 0.0


@pytest.mark.parametrize("scale", [1e-200, 1e-6, 1.0, 1e150])
def test_extreme_magnitudes_stay_finite_and_scale_exactly(scale):
    base = np.array([2.0, 1.0, -1.0, -4.0, 4.0, 3.0, 1.0, -5.0, 7.0])
    reference = describe(base)
    scaled = describe(base * scale)
    assert scaled.sd == pytest.approx(reference.sd * scale, rel=1e-12)
    assert scaled.skewness == pytest.approx(reference.skewness, rel=1e-12)
    assert math.isfinite(scaled.mean)


@pytest.mark.parametrize(
    ("values", "fragment"),
    [
        ([0.1, 0.2, float("nan")], "reading 3 is not a number"),
        ([float("inf"), 0.0], "reading 1 is infinite"),
        (["0.1", "abc"], "not all numbers"),
    ],
)
def test_bad_readings_name_the_position(values, fragment):
    with pytest.raises(StationError, match=fragment):
        describe(values)


def test_a_bad_resolution_is_refused_with_a_sentence():
    for bad in (0, -0.001, float("nan")):
        with pytest.raises(StationError, match="resolution"):
            describe([1.0, 2.0], resolution=bad)


def test_as_readings_names_what_it_reads():
    with pytest.raises(StationError, match="point 2 is not a number"):
        as_readings([1.0, float("nan")], what="point")


def test_histogram_bins_are_centred_on_multiples_of_the_resolution(table_2_1):
    result = histogram(table_2_1, 0.0001)
    assert result.bin_width == 0.0001
    assert result.edges[0] == pytest.approx(-0.00055)
    assert result.edges[-1] == pytest.approx(0.00075)
    centres = [(a + b) / 2 for a, b in zip(result.edges, result.edges[1:], strict=False)]
    counts = dict(zip((round(c / 0.0001) for c in centres), result.counts, strict=True))
    # Table 2-1 in tenths of a thousandth: the readings counted by hand.
    assert counts == {
        -5: 2,
        -4: 1,
        -3: 0,
        -2: 2,
        -1: 3,
        0: 3,
        1: 6,
        2: 7,
        3: 3,
        4: 2,
        5: 0,
        6: 0,
        7: 1,
    }


def test_histogram_covers_the_specification_limits_and_counts_pieces_outside():
    result = histogram([0.0, 0.0002, 0.0012, -0.0011], 0.0001, lsl=-0.001, usl=0.001)
    assert result.edges[0] <= -0.0011 and result.edges[-1] >= 0.0012
    assert (result.below, result.above) == (1, 1)
    assert sum(result.counts) == 4
    inside = histogram([0.0, 0.0001], 0.0001, lsl=-0.001, usl=0.001)
    assert inside.edges[0] == pytest.approx(-0.00105) and inside.edges[-1] == pytest.approx(0.00105)
    assert len(inside.counts) == 21


def test_histogram_widens_bins_by_an_integer_factor_when_there_are_too_many():
    values = np.arange(0, 100) * 0.001  # 100 distinct multiples of the resolution
    result = histogram(values, 0.001, max_bins=40)
    assert len(result.counts) <= 40
    factor = result.bin_width / 0.001
    assert factor == pytest.approx(round(factor)) and round(factor) == 3
    assert sum(result.counts) == 100
    # Every bin centre is still a multiple of the resolution.
    for left in result.edges[:-1]:
        centre = (left + result.bin_width / 2) / 0.001
        assert centre == pytest.approx(round(centre), abs=1e-6)


def test_histogram_without_resolution_uses_a_round_width():
    result = histogram([1.3, 2.7, 3.1, 4.4, 5.9, 2.2, 3.3, 4.8, 1.1], max_bins=40)
    mantissa = result.bin_width / 10 ** math.floor(math.log10(result.bin_width))
    assert round(mantissa, 9) in (1.0, 2.0, 5.0)
    assert sum(result.counts) == 9
    assert len(result.counts) <= 6


def test_histogram_of_nothing_is_empty():
    result = histogram([], 0.001)
    assert (result.edges, result.counts, result.bin_width) == ((), (), 0.001)
    assert histogram([5.0] * 4).counts == (4,)
