"""The live form equals the batch analysis: every reading's figures, alarms, and the snapshot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from station.analysis.capability import SpecLimits
from station.analysis.live import RULE_WINDOW, LiveAnalysis, LiveChannel
from station.analysis.summary import AnalysisConfig, analyze, analyze_channel
from station.errors import StationError

RELATIVE = 1e-12
EPSILON = np.finfo(float).eps


def close(live: float | None, batch: float | None, scale: float, relative: float) -> bool:
    """Equal to ``relative``; figures that are zero in exact arithmetic (a symmetric sample's
    skewness, a centred mean) are compared at ``relative`` of the data's own scale instead."""
    if live is None or batch is None:
        return live is batch
    return math.isclose(live, batch, rel_tol=relative, abs_tol=relative * scale)


def tolerance(values: list[float]) -> float:
    """1e-12, or the rounding of the batch's own two-pass sums when that is larger.

    The batch subtracts a rounded mean, so its third moment carries an error of about
    eps * max|x| / sd relative: negligible for zeroed readings (|x| ~ sd), visible for an
    indicator read far from zero with a fine spread. The live form shifts by the first reading
    and is the more exact of the two there.
    """
    spread = float(np.std(values)) if len(values) > 1 else 0.0
    if spread == 0.0:
        return RELATIVE
    return max(RELATIVE, 16 * EPSILON * max(abs(v) for v in values) / spread)


def assert_update_matches_batch(update, batch, scale: float, relative: float) -> None:
    d, cap, chart = batch.descriptive, batch.capability, batch.chart
    assert update.n == d.n
    for live, exact in [
        (update.mean, d.mean),
        (update.sd, d.sd),
        (update.min, d.min),
        (update.max, d.max),
        (update.range, d.range),
        (update.sigma_within, chart.sigma_within),
        (update.center, chart.center),
        (update.ucl, chart.ucl),
        (update.lcl, chart.lcl),
    ]:
        assert close(live, exact, scale, relative), (live, exact)
    for live, exact in [
        (update.skewness, d.skewness),
        (update.cp, cap.cp),
        (update.cpu, cap.cpu),
        (update.cpl, cap.cpl),
        (update.cpk, cap.cpk),
        (update.cpk_lower, cap.cpk_lower),
        (update.cp_within, cap.cp_within),
        (update.cpk_within, cap.cpk_within),
    ]:
        # Dimensionless figures: their natural scale is 1.
        assert close(live, exact, 1.0, relative), (live, exact)
    assert update.modes == d.modes
    assert (update.above_usl, update.below_lsl) == (cap.above_usl, cap.below_lsl)
    assert update.capable == cap.capable


def newest_point_alarms(batch) -> set[str]:
    """Rules whose batch alarms flag the chart's last point."""
    last = len(batch.chart.points)
    return {alarm.rule for alarm in batch.alarms if last in alarm.points}


def run_live_against_batch(values: list[float], config: AnalysisConfig) -> LiveChannel:
    """Feed the readings one by one; after each, compare with the batch analysis of the prefix."""
    live = LiveChannel("x", config)
    scale = max(abs(v) for v in values) or 1.0
    points_before = 0
    for k, value in enumerate(values, start=1):
        update = live.add(value)
        batch = analyze_channel("x", np.array(values[:k]), config)
        assert_update_matches_batch(update, batch, scale, tolerance(values[:k]))
        new_point = len(batch.chart.points) > points_before
        points_before = len(batch.chart.points)
        expected = newest_point_alarms(batch) if new_point else set()
        assert {alarm.rule for alarm in update.alarms} == expected
        last = len(batch.chart.points)
        for alarm in update.alarms:
            (match,) = [a for a in batch.alarms if a.rule == alarm.rule and last in a.points]
            # The live alarm sees the last RULE_WINDOW points; the batch run may start earlier.
            assert set(alarm.points) <= set(match.points)
            assert alarm.points[-1] == last
            assert alarm.text.split(" ")[1] == str(alarm.points[0])  # "Point(s) <first> ..."
    assert live.snapshot() == analyze_channel("x", np.array(values), config)
    return live


# Quantised readings in gauge steps: a level, noise, and optionally a drift, an oscillation
# or a jump, so that every rule set has alarms to raise and to withhold.
steps = st.integers(min_value=-12, max_value=12)


@st.composite
def readings(draw) -> list[float]:
    n = draw(st.integers(min_value=1, max_value=45))
    noise = draw(st.lists(steps, min_size=n, max_size=n))
    shape = draw(st.sampled_from(["flat", "drift", "zigzag", "jump"]))
    if shape == "drift":
        noise = [v + i // 2 for i, v in enumerate(noise)]
    elif shape == "zigzag":
        noise = [v // 4 + (8 if i % 2 else -8) for i, v in enumerate(noise)]
    elif shape == "jump":
        at = draw(st.integers(min_value=0, max_value=n))
        noise = [v + (40 if i >= at else 0) for i, v in enumerate(noise)]
    return [float(v) for v in noise]


configs = st.builds(
    AnalysisConfig,
    default_limits=st.sampled_from(
        [None, SpecLimits(-20.0, 20.0), SpecLimits(usl=15.0), SpecLimits(lsl=-9.0)]
    ),
    resolution=st.sampled_from([None, 1.0, 2.0]),
    subgroup=st.sampled_from([1, 1, 2, 3, 5, 11]),
    rule_set=st.sampled_from(["report", "western-electric", "nelson"]),
    threshold=st.sampled_from([1.0, 1.33]),
)


@settings(
    max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(values=readings(), config=configs)
def test_live_equals_batch_on_quantised_readings_with_alarms(values, config):
    run_live_against_batch(values, config)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    steps=st.lists(st.integers(min_value=-1000, max_value=1000), min_size=2, max_size=40),
    origin=st.sampled_from([0.0, 0.05, -12.5]),
    subgroup=st.sampled_from([1, 4]),
)
def test_live_equals_batch_on_fine_readings_near_and_far_from_zero(steps, origin, subgroup):
    # Readings of a 1e-6 gauge, zeroed at the taught pose or not (origin).
    values = [origin + k * 1e-6 for k in steps]
    config = AnalysisConfig(
        default_limits=SpecLimits(origin - 2e-3, origin + 2e-3), subgroup=subgroup
    )
    run_live_against_batch(values, config)


def test_a_seeded_run_raises_every_report_rule_live_as_in_batch():
    rng = np.random.default_rng(12)
    noise = np.round(rng.normal(0, 1.0, 40))
    trend = np.arange(8.0) * 2.0  # seven rises in a row: report-2
    zigzag = np.tile([-1.5, 1.5], 8)  # sixteen alternating points: report-3
    spike = [0.0, 9.0, 9.5, 0.0, 30.0]  # two of three beyond 2 sigma, then beyond 3 sigma
    values = [*noise, *trend, *zigzag, *spike]
    live = run_live_against_batch(values, AnalysisConfig(resolution=0.5))
    rules = {alarm.rule for alarm in live.snapshot().alarms}
    assert rules == {"report-1", "report-2", "report-3", "report-4"}


def test_live_alarms_name_the_point_in_the_whole_chart():
    values = [0.0, 1.0, -1.0, 0.5, -0.5] * 6 + [25.0]
    live = LiveChannel("x", AnalysisConfig())
    for value in values:
        update = live.add(value)
    assert len(values) > RULE_WINDOW
    (alarm,) = update.alarms
    assert alarm.rule == "report-1" and alarm.points == (31,)
    assert alarm.text.startswith("Cycle 31 is above the upper control limit")


def test_live_alarms_name_cycle_numbers_as_the_batch_does():
    """Review finding 9: after a rejected cycle, the 6th reading is cycle 7, not "point 6"."""
    values = [0.0, 1.0, -1.0, 0.5, -0.5] * 6 + [25.0]
    cycles = [n for n in range(1, len(values) + 2) if n != 3]
    live = LiveAnalysis(AnalysisConfig(), channels=("x",))
    for value, cycle in zip(values, cycles, strict=True):
        update = live.add_set({"x": value}, cycle=cycle)["x"]
    (alarm,) = update.alarms
    assert alarm.points == (31,) and alarm.cycles == (32,)
    assert alarm.text.startswith("Cycle 32 is above the upper control limit")
    assert live.snapshot() == analyze(
        {"x": np.array(values)}, AnalysisConfig(), cycles={"x": cycles}
    )
    (batch,) = live.snapshot().channels["x"].alarms
    assert batch.cycles == (32,) and batch.text == alarm.text


def test_live_subgroup_alarms_list_the_cycles_of_their_subgroups():
    values = [0.0, 1.0, -1.0, 0.5, -0.5, 0.2] * 5 + [25.0, 25.0, 25.0]
    cycles = list(range(101, 101 + len(values)))
    config = AnalysisConfig(subgroup=3)
    live = LiveChannel("x", config)
    for value, cycle in zip(values, cycles, strict=True):
        update = live.add(value, cycle)
    (alarm,) = [a for a in update.alarms if a.rule == "report-1"]
    assert alarm.points == (11,) and alarm.cycles == (131, 132, 133)
    assert live.snapshot() == analyze_channel("x", np.array(values), config, cycles)


def test_the_snapshot_is_cached_until_the_next_reading():
    live = LiveChannel("x", AnalysisConfig())
    for value in (1.0, 2.0, 4.0):
        live.add(value)
    first = live.snapshot()
    assert live.snapshot() is first
    live.add(3.0)
    assert live.snapshot() is not first and live.snapshot().descriptive.n == 4


def test_live_analysis_over_channels_equals_analyze():
    rng = np.random.default_rng(21)
    data = {axis: np.round(rng.normal(0, 2.0, 30)) for axis in "xyz"}
    config = AnalysisConfig(default_limits=SpecLimits(-8.0, 8.0), resolution=1.0)
    live = LiveAnalysis(config, channels=("x", "y", "z"))
    for cycle in range(30):
        updates = live.add_set({axis: data[axis][cycle] for axis in "xyz"})
    assert set(updates) == {"x", "y", "z"}
    assert live.snapshot() == analyze(data, config)


def test_bad_readings_and_empty_snapshots_are_sentences():
    live = LiveChannel("x", AnalysisConfig())
    with pytest.raises(StationError, match="no readings yet"):
        live.snapshot()
    with pytest.raises(StationError, match="reading 1 is not a finite number"):
        live.add(float("nan"))
    with pytest.raises(StationError, match="no readings yet"):
        LiveAnalysis(AnalysisConfig()).snapshot()


def test_the_readings_a_snapshot_takes_are_views_no_later_reading_changes():
    """The engine copies the live readings under its lock for every redraw: a view of arrays
    that only grow costs nothing, and what it shows stays as it was."""
    live = LiveChannel("x", AnalysisConfig())
    for value in (0.1, 0.2, 0.3):
        live.add(value, t=10.0 + value)
    before = live.readings()
    for value in np.linspace(0.4, 9.9, 200):  # enough to outgrow the first array
        live.add(float(value), t=20.0)
    after = live.readings()
    assert before.values.tolist() == [0.1, 0.2, 0.3] and before.cycles.tolist() == [1, 2, 3]
    assert before.times.tolist() == [10.1, 10.2, 10.3] and len(after.values) == 203
    assert np.shares_memory(after.values, live.readings().values)
    with pytest.raises(ValueError):
        after.values[0] = 5.0
    live.add(1.0)  # a reading without a time: the trend runs on cycle order
    assert live.readings().times is None


def test_a_snapshot_leaves_the_checks_it_does_not_show_until_asked(monkeypatch):
    """A redraw shows the figures, the histogram and the chart: the test of normality (it sorts
    every reading), the autocorrelation and the drift wait until something reads them."""
    from station.analysis import summary

    asked = []
    for name in ("normality", "autocorrelation", "drift"):
        original = getattr(summary, name)
        monkeypatch.setattr(
            summary, name, lambda *a, _f=original, _n=name, **k: asked.append(_n) or _f(*a, **k)
        )
    live = LiveChannel("x", AnalysisConfig(resolution=0.001))
    for value in np.round(np.random.default_rng(2).normal(0.0, 0.01, 60), 3):
        live.add(float(value))
    channel = live.snapshot()
    assert asked == [] and channel.descriptive.n == 60
    batch = analyze_channel("x", live.values, AnalysisConfig(resolution=0.001))
    assert channel.normality == batch.normality and channel.drift == batch.drift
    assert channel.autocorrelation == batch.autocorrelation
    assert sorted(set(asked)) == ["autocorrelation", "drift", "normality"]
