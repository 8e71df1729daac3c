"""Properties that hold for any readings (hypothesis, seeded through the derandomize profile)."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from station.analysis.capability import SpecLimits, capability
from station.analysis.charts import control_chart
from station.analysis.descriptive import describe, histogram
from station.analysis.rules import RULE_SETS, check_rules
from tests.properties import examples

# Deterministic and lean: the whole file runs in a few seconds.
lean = settings(max_examples=examples(150), deadline=None, derandomize=True, database=None)

# Gauge readings: quantised to a resolution, within a realistic span.
resolutions = st.sampled_from([0.0001, 0.001, 0.01, 0.5])
counts = st.lists(st.integers(-2000, 2000), min_size=0, max_size=60)
plain_floats = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


def _finite_or_none(value):
    return value is None or math.isfinite(value)


@lean
@given(
    st.lists(st.floats(-1e12, 1e12, allow_nan=False, allow_infinity=False), max_size=50),
    st.one_of(st.none(), resolutions),
)
def test_describe_never_returns_nan_or_inf(values, resolution):
    result = describe(values, resolution)
    for figure in (result.mean, result.sd, result.skewness, result.min, result.max, result.range):
        assert _finite_or_none(figure)
    assert all(math.isfinite(m) for m in result.modes)
    if values:
        assert result.min <= result.mean <= result.max


@lean
@given(counts, resolutions, st.integers(1, 40))
def test_histogram_counts_sum_to_n(steps, resolution, max_bins):
    values = np.array(steps) * resolution
    result = histogram(values, resolution, lsl=-0.5, usl=0.7, max_bins=max_bins)
    assert sum(result.counts) == len(values)
    assert len(result.counts) <= max_bins
    assert len(result.edges) == len(result.counts) + 1
    assert result.edges[0] <= -0.5 and result.edges[-1] >= 0.7
    if len(values):
        assert result.edges[0] <= values.min() and result.edges[-1] >= values.max()


@st.composite
def readings_and_limits(draw):
    values = draw(st.lists(plain_floats, min_size=2, max_size=40))
    centre = draw(plain_floats)
    half = draw(st.floats(1e-3, 1e6))
    return np.array(values), SpecLimits(lsl=centre - half, usl=centre + half)


@lean
@given(readings_and_limits(), st.integers(1, 12))
def test_cpk_never_exceeds_cp(data, subgroup):
    values, limits = data
    result = capability(values, limits, subgroup=subgroup)
    for figure in (
        result.cp,
        result.cpu,
        result.cpl,
        result.cpk,
        result.cpk_lower,
        result.cp_within,
        result.cpk_within,
    ):
        assert _finite_or_none(figure)
    if result.cp is not None:
        assert result.cpk <= result.cp * (1 + 1e-12)
        assert result.cpk_lower <= result.cpk
    if result.cp_within is not None:
        assert result.cpk_within <= result.cp_within * (1 + 1e-12)


@lean
@given(
    st.lists(st.integers(-50, 50), min_size=2, max_size=40),
    st.integers(-(10**6), 10**6),
    st.integers(1, 5),
)
def test_capability_is_invariant_under_shifting_data_and_limits_together(steps, shift, subgroup):
    # Readings on a 0.001 grid shifted by a whole number of units: exact in floating point
    # apart from the mean's last bits, so the indices agree to a relative 1e-9.
    values = np.array(steps) * 0.001
    limits = SpecLimits(lsl=-0.04, usl=0.06)
    moved = SpecLimits(lsl=-0.04 + shift, usl=0.06 + shift)
    before = capability(values, limits, subgroup=subgroup)
    after = capability(values + shift, moved, subgroup=subgroup)
    for name in ("cp", "cpu", "cpl", "cpk", "cpk_lower", "cp_within", "cpk_within"):
        a, b = getattr(before, name), getattr(after, name)
        assert (a is None) == (b is None), name
        if a is not None:
            assert math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-6), name
    assert before.capable == after.capable or abs(before.cpk - 1.0) < 1e-6
    assert (before.above_usl, before.below_lsl) == (after.above_usl, after.below_lsl)


@lean
@given(st.lists(st.integers(-40, 40), min_size=0, max_size=60), st.sampled_from(RULE_SETS))
def test_alarms_name_real_points_in_order(steps, rule_set):
    values = np.array(steps, dtype=float) * 0.1
    chart = control_chart(values)
    alarms = check_rules(chart.points, chart.center, chart.point_sigma, rule_set)
    for alarm in alarms:
        assert list(alarm.points) == sorted(alarm.points)
        assert all(1 <= p <= len(values) for p in alarm.points)
        assert alarm.points == tuple(range(alarm.points[0], alarm.points[-1] + 1))
        assert alarm.rule.split("-")[0] in {"report", "we", "nelson"}
    firsts = [a.points[0] for a in alarms]
    assert firsts == sorted(firsts)
