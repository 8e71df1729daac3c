"""Straightness (least squares and minimum zone), stroke splitting, path repeatability and the
linearity analysis of a simulated parallel-bar run."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from station.analysis.capability import SpecLimits
from station.analysis.linearity import (
    analyze_linearity,
    convex_hull,
    linearity_json,
    linearity_summary,
    minimum_zone,
    path_repeatability,
    straightness,
    tolerance_from_limits,
)
from station.analysis.strokes import (
    A_TO_B,
    B_TO_A,
    profiles_from_stream,
    profiles_from_table,
    split_strokes,
)
from station.analysis.summary import AnalysisConfig
from station.errors import StationError
from station.instruments.simulator import BarModel, GaugeSpec
from tests.properties import examples


def brute_force_zone(s: np.ndarray, d: np.ndarray) -> float:
    """The narrowest vertical strip over every direction two points define (and level)."""
    best = float(np.ptp(d))
    for i, j in itertools.combinations(range(len(s)), 2):
        if s[i] == s[j]:
            continue
        with np.errstate(over="ignore"):
            slope = (d[j] - d[i]) / (s[j] - s[i])
        if np.isfinite(slope):  # two positions a hair apart define no usable direction
            best = min(best, float(np.ptp(d - slope * s)))
    return best


# -- straightness on hand-checkable profiles -------------------------------------------------


def test_a_straight_line_has_no_straightness_error():
    s = np.linspace(0.0, 20.0, 101)
    result = straightness(s, 0.003 + 2e-4 * s)
    assert result.ls == pytest.approx(0.0, abs=1e-15)
    assert result.mz == pytest.approx(0.0, abs=1e-15)
    assert result.ls_line == pytest.approx((0.003, 2e-4))
    assert result.mz_line == pytest.approx((0.003, 2e-4))


def test_standards_example_ex1():
    # standards.md §4.2 ex1: LS a 0.6, b 0.5, residuals (-0.6, 0.9, ...), p-v 1.5; MZ 1.5.
    result = straightness([0, 1, 2, 3, 4], [0, 2, 1, 3, 2])
    assert result.ls_line == pytest.approx((0.6, 0.5))
    assert result.residuals_ls == pytest.approx([-0.6, 0.9, -0.6, 0.9, -0.6])
    assert result.ls == pytest.approx(1.5)
    assert result.mz == pytest.approx(1.5)
    assert result.mz_line == pytest.approx((0.75, 0.5))
    assert result.n == 5


def test_a_circular_arc_gives_its_sagitta():
    radius, half_chord = 500.0, 10.0
    s = np.linspace(-half_chord, half_chord, 4001)
    d = np.sqrt(radius**2 - s**2)
    sagitta = radius - math.sqrt(radius**2 - half_chord**2)
    result = straightness(s, d + 0.01 * s)  # a tilt changes nothing
    assert result.mz == pytest.approx(sagitta, rel=1e-9)
    # A symmetric bow: the LS line is parallel to the chord, so its peak-to-valley is the same.
    assert result.ls == pytest.approx(sagitta, rel=1e-6)


def test_mz_is_below_ls_on_an_asymmetric_profile_and_equal_on_a_symmetric_one():
    s = np.arange(6.0)
    lopsided = straightness(s, [0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    # Zone of slope 0.2 (the hull edge from the first to the last point): width 0.8 by hand.
    assert lopsided.mz == pytest.approx(0.8)
    assert lopsided.mz_line == pytest.approx((-0.4, 0.2))
    assert lopsided.ls == pytest.approx(6 / 7)
    symmetric = straightness(s, [0.0, 1.0, 0.0, 0.0, 1.0, 0.0])
    assert symmetric.mz == pytest.approx(symmetric.ls)


def test_the_zone_holds_every_point():
    rng = np.random.default_rng(3)
    s = np.sort(rng.uniform(0, 10, 200))
    d = rng.normal(0, 1e-3, 200)
    result = straightness(s, d)
    assert np.ptp(result.residuals_mz) == pytest.approx(result.mz, rel=1e-12)
    assert np.max(np.abs(result.residuals_mz)) <= result.mz / 2 * (1 + 1e-12)


def test_convex_hull_of_a_square_with_inner_points():
    s = np.array([0, 1, 1, 0, 0.5, 0.2])
    d = np.array([0, 0, 1, 1, 0.5, 0.7])
    assert {tuple(p) for p in convex_hull(s, d)} == {(0, 0), (1, 0), (1, 1), (0, 1)}


@pytest.mark.parametrize(
    ("s", "d", "fault"),
    [
        ([1.0], [0.0], "at least 2 points"),
        ([1.0, 1.0, 1.0], [0.0, 1.0, 2.0], "did not move"),
        ([0.0, 1.0], [0.0], "one position per deviation"),
        ([0.0, 1.0], [0.0, math.nan], "finite"),
    ],
)
def test_bad_profiles_are_named(s, d, fault):
    with pytest.raises(StationError, match=fault):
        straightness(s, d)


profiles = st.integers(min_value=2, max_value=9).flatmap(
    lambda n: st.tuples(
        st.lists(st.floats(-50, 50, allow_nan=False), min_size=n, max_size=n, unique=True),
        st.lists(st.floats(-1, 1, allow_nan=False), min_size=n, max_size=n),
    )
)


@settings(max_examples=examples(150), deadline=None, derandomize=True)
@given(profiles)
def test_minimum_zone_matches_brute_force_and_never_exceeds_least_squares(profile):
    s, d = (np.asarray(v, dtype=float) for v in profile)
    width, (centre, slope) = minimum_zone(s, d)
    expected = brute_force_zone(s, d)
    assert width == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert np.ptp(d - slope * s) == pytest.approx(width, rel=1e-9, abs=1e-12)
    result = straightness(s, d)
    assert result.mz <= result.ls + 1e-12


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(-3, 3)), min_size=2, max_size=9))
def test_minimum_zone_with_repeated_positions_matches_brute_force(points):
    # Several readings at one position (a dwell): vertical hull edges define no strip.
    s = np.asarray([p[0] for p in points], dtype=float)
    d = np.asarray([p[1] for p in points], dtype=float) / 4
    assume(np.ptp(s) > 0)
    width, _ = minimum_zone(s, d)
    assert width == pytest.approx(brute_force_zone(s, d), rel=1e-9, abs=1e-12)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(st.floats(-1, 1, allow_nan=False), min_size=2, max_size=8))
def test_symmetric_profiles_have_mz_equal_to_ls(half):
    # A profile symmetric about its middle: the LS line is level, and so is a minimum zone.
    d = np.asarray(half + half[::-1])
    s = np.arange(d.size, dtype=float)
    result = straightness(s, d)
    assert result.mz == pytest.approx(result.ls, rel=1e-9, abs=1e-12)


# -- strokes ------------------------------------------------------------------------------


def shuttle(strokes: int, rng: np.random.Generator, *, dwell: int = 40, noise: float = 0.002):
    """A scale stream from A (0) to B (10) and back, dwelling at each end, with noise."""
    parts = [np.zeros(dwell)]
    for k in range(strokes):
        forward = np.linspace(0.0, 10.0, 300)
        parts.append(forward if k % 2 == 0 else forward[::-1])
        parts.append(np.full(dwell, 10.0 if k % 2 == 0 else 0.0))
    s = np.concatenate(parts)
    return s + rng.normal(0.0, noise, s.size)


@pytest.mark.parametrize("strokes", [1, 2, 7, 30])
def test_split_strokes_counts_strokes_and_directions_despite_noise_and_dwell(strokes):
    s = shuttle(strokes, np.random.default_rng(strokes))
    found = split_strokes(s)
    assert len(found) == strokes
    assert [f.direction for f in found] == [A_TO_B, B_TO_A] * (strokes // 2) + [A_TO_B] * (
        strokes % 2
    )
    assert [f.index for f in found] == list(range(1, strokes + 1))
    for stroke in found:
        travelled = s[stroke.start : stroke.stop]
        assert np.ptp(travelled) > 9.8  # end to end
        # The dwell is left out: at most a few points sit within the deadband of an end.
        assert stroke.stop - stroke.start < 300 + 10
    starts = [f.start for f in found]
    assert starts == sorted(starts)
    assert all(a.stop <= b.start + 1 for a, b in itertools.pairwise(found))


def test_split_strokes_drops_a_partial_pass_and_honours_the_direction_sign():
    rng = np.random.default_rng(5)
    s = np.concatenate([shuttle(2, rng), np.linspace(0.0, 3.0, 80)])  # stopped early
    assert len(split_strokes(s)) == 2
    reversed_scale = split_strokes(-s, a_to_b=-1)
    assert [f.direction for f in reversed_scale] == [A_TO_B, B_TO_A]


def test_split_strokes_of_a_still_scale_is_empty():
    assert split_strokes(np.zeros(50)) == []
    assert split_strokes([1.0]) == []


def test_noise_larger_than_the_deadband_is_not_a_stroke():
    rng = np.random.default_rng(9)
    s = shuttle(4, rng, noise=0.02)
    assert len(split_strokes(s, deadband=0.2)) == 4


# -- path repeatability -------------------------------------------------------------------


def test_path_repeatability_is_three_sigma_of_stroke_offsets():
    s = np.linspace(0, 10, 101)
    offsets = [0.0, 0.001, 0.002, 0.003]
    result = path_repeatability([(s, 0.0005 * np.sin(s) + o) for o in offsets], bins=10)
    assert result.strokes == 4
    assert result.positions.size == 10
    assert np.all(result.counts == 4)
    assert result.max_3s == pytest.approx(3 * np.std(offsets, ddof=1))
    assert np.nanmax(result.three_s) == pytest.approx(np.nanmin(result.three_s))


def test_path_repeatability_of_one_stroke_is_undefined():
    s = np.linspace(0, 10, 50)
    result = path_repeatability([(s, s * 0)], bins=5)
    assert result.max_3s is None
    assert result.at is None


# -- the whole analysis -------------------------------------------------------------------


def simulated(model: BarModel, strokes: int, seed: int = 1):
    stream = model.stream(strokes, seed)
    return profiles_from_stream(stream["s"], {"h": stream["h"], "v": stream["v"]})


def test_a_simulated_bar_recovers_bow_and_sag():
    model = BarModel(
        length=20.0,
        points=300,
        dwell=15,
        bow=0.0015,
        sag=0.0008,
        wobble=0.0,
        wobble_v=0.0,
        stroke_jitter=0.0,
        noise=0.00002,
    )
    profiles = simulated(model, 6)
    assert [p.direction for p in profiles] == [A_TO_B, B_TO_A] * 3
    result = analyze_linearity(profiles, tolerance=0.002)
    for stroke in result.strokes:
        # The indicators read at 0.0001 in: the bow comes back within about one step.
        assert stroke.straightness["h"].mz == pytest.approx(0.0015, abs=1.5e-4)
        assert stroke.straightness["v"].mz == pytest.approx(0.0008, abs=1.5e-4)
        # The tilt of the bar is removed by the reference line.
        assert stroke.straightness["h"].ls_line[1] == pytest.approx(model.tilt_h, abs=2e-5)


def test_a_simulated_wobble_gives_its_peak_to_peak_and_path_repeatability_its_jitter():
    model = BarModel(
        length=20.0,
        points=400,
        dwell=10,
        bow=0.0,
        sag=0.0,
        wobble=0.0005,
        wobble_v=0.0003,
        period=5.0,
        stroke_jitter=0.0002,
        noise=0.00001,
        indicator=GaugeSpec(0.00001, -0.5, 0.5, "in"),
    )
    result = analyze_linearity(simulated(model, 30, seed=4), tolerance=0.002)
    assert len(result.strokes) == 30
    assert result.mz["h"] == pytest.approx(2 * 0.0005, rel=0.1)
    assert result.mz["v"] == pytest.approx(2 * 0.0003, rel=0.1)
    for c in ("h", "v"):
        # Largest 3s over 20 positions of 30 strokes offset by N(0, 0.0002): about 0.0006.
        assert result.path[c].max_3s == pytest.approx(3 * 0.0002, rel=0.4)
    assert set(result.directions) == {A_TO_B, B_TO_A}
    assert result.directions[A_TO_B].strokes == 15


def test_capability_is_one_sided_against_the_tolerance_and_the_chart_is_per_stroke():
    model = BarModel(points=200, dwell=10, wobble=0.0, wobble_v=0.0, bow=0.001, sag=0.0005)
    profiles = simulated(model, 25)
    result = analyze_linearity(profiles, tolerance=0.002, config=AnalysisConfig(unit="in"))
    judged = result.judged["h"]
    assert judged.limits == SpecLimits(usl=0.002)
    assert judged.capability.cp is None  # one-sided: no Cp
    assert judged.capability.cpk == pytest.approx(judged.capability.cpu)
    assert judged.capability.capable is True
    assert len(judged.readings) == 25
    assert judged.readings == tuple(r.straightness["h"].mz for r in result.strokes)
    assert judged.chart.type == "I-MR"
    summary = linearity_summary(result)
    assert summary.config.unit == "in"
    assert set(summary.channels) == {"h", "v"}
    untoleranced = analyze_linearity(profiles).judged["h"].capability
    assert untoleranced.capable is None
    assert "give a tolerance" in untoleranced.message and "--" not in untoleranced.message
    tight = analyze_linearity(profiles, tolerance=0.0005)
    assert tight.judged["h"].capability.capable is False
    assert any("exceed the straightness tolerance" in h for h in linearity_summary(tight).hints)


def test_linearity_json_has_the_documented_keys():
    profiles = simulated(BarModel(points=100, dwell=5), 4)
    document = linearity_json(analyze_linearity(profiles, tolerance=0.002))
    assert {"h", "v", "strokes", "path_repeatability"} <= document.keys()
    assert set(document["h"]) == {"ls", "mz"}
    assert document["h"]["mz"] == max(s["h"]["mz"] for s in document["strokes"])
    stroke = document["strokes"][0]
    assert {"stroke", "direction", "h", "v"} <= stroke.keys()
    assert {"ls", "mz"} <= stroke["h"].keys()
    assert stroke["direction"] == A_TO_B
    assert set(document["path_repeatability"]) == {"h", "v"}


def test_profiles_from_table_groups_rows_by_stroke_and_trims_each():
    there = np.linspace(0, 5, 10)
    back = there[::-1]
    # Stroke 1 dwells at A first; stroke 2 was ended late (the way back began); stroke 3 has
    # no travel; stroke 4 holds two passes.
    s = np.concatenate([np.zeros(5), there, back, there[:4], [5.0, 5.0], there, back])
    numbers = np.concatenate([[1] * 15, [2] * 14, [3] * 2, [4] * 20])
    profiles = profiles_from_table(numbers, s, {"h": s * 0, "v": s * 0})
    assert [(p.number, p.recorded, p.direction) for p in profiles] == [
        (1, 1, A_TO_B),
        (2, 2, B_TO_A),
        (3, 4, A_TO_B),
        (4, 4, B_TO_A),
    ]
    assert profiles[0].s.size == 10  # the last dwell point and the pass
    assert profiles[1].s[-1] == 0.0 and profiles[1].s.size == 10
    with pytest.raises(StationError, match="whole numbers"):
        profiles_from_table([1.5, 1.5], [0.0, 1.0], {"h": [0, 0]})
    with pytest.raises(StationError, match="'h' has 1 values"):
        profiles_from_table([1, 1], [0.0, 1.0], {"h": [0]})


def test_no_stroke_and_bad_tolerance_are_errors():
    with pytest.raises(StationError, match="no complete stroke"):
        analyze_linearity([])
    profiles = simulated(BarModel(points=50, dwell=2), 2)
    with pytest.raises(StationError, match="tolerance"):
        analyze_linearity(profiles, tolerance=-1.0)


def test_the_tolerance_is_the_width_of_the_indicator_limits():
    config = AnalysisConfig(limits={"h": SpecLimits(-0.001, 0.001), "v": SpecLimits(-0.002, 0.002)})
    assert tolerance_from_limits(config) == pytest.approx(0.002)
    assert tolerance_from_limits(AnalysisConfig()) is None
