"""Coarse readings handled as a metrologist would (issue 20, item 4): the gauge's discrimination
is judged and said, control limits never narrower than the gauge can tell apart, no percentile
index or normality verdict from rounded readings, the rule set's false-alarm chance stated, and
a run rule that stays violated is one alarm.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.analysis.capability import SpecLimits
from station.analysis.charts import control_chart
from station.analysis.discrimination import LIMIT_FLOOR_STEPS, discrimination
from station.analysis.false_alarms import false_alarm_chance
from station.analysis.monitor import LiveMonitor
from station.analysis.report import format_report
from station.analysis.rules import RULE_SETS, check_rules
from station.analysis.summary import AnalysisConfig, analyze

STEP = 0.0001
SESSIONS = 200
N = 30


def _rounded(rng: np.random.Generator, spread_steps: float, n: int = N) -> np.ndarray:
    """Stable readings with a sigma of ``spread_steps`` gauge steps, rounded to the step; the
    true centre lies anywhere within a step, as a zero does."""
    true = rng.normal(rng.uniform(-0.5, 0.5) * STEP, spread_steps * STEP, n)
    return np.round(true / STEP) * STEP


def _config(rule_set: str = "report", **extra: object) -> AnalysisConfig:
    return AnalysisConfig(
        resolution=STEP,
        unit="in",
        rule_set=rule_set,
        default_limits=SpecLimits(lsl=-0.001, usl=0.001),
        **extra,  # type: ignore[arg-type]
    )


# --- discrimination -----------------------------------------------------------------------


def test_a_one_step_spread_is_called_inadequate_with_its_figures() -> None:
    values = [0.0, 0.0, STEP, 0.0, -STEP, 0.0, 0.0, STEP, 0.0, 0.0] * 3
    analysis = analyze({"x": np.array(values)}, _config())
    found = analysis.channels["x"].discrimination
    assert found is not None and not found.adequate
    assert found.distinct == 3
    sentences = [h for h in analysis.hints if "too coarse for this spread" in h]
    assert len(sentences) == 1
    assert sentences[0].startswith("x: the gauge step 0.00010 in is too coarse")
    assert "(3 distinct readings, sigma within 0.55 steps, 3 possible moving ranges" in sentences[0]
    # The same sentence is in the text report's hints.
    assert "too coarse for this spread" in format_report(analysis).replace("\n", " ")


def test_fine_readings_carry_no_discrimination_sentence() -> None:
    rng = np.random.default_rng(3)
    values = np.round(rng.normal(0, 4 * STEP, N) / STEP) * STEP  # sigma four steps
    analysis = analyze({"x": values}, _config())
    found = analysis.channels["x"].discrimination
    assert found is not None and found.adequate and found.resolves_shape
    assert analysis.channels["x"].normality.rejected is not None  # type: ignore[union-attr]
    assert not [h for h in analysis.hints if "too coarse" in h]


def test_aiag_counts_the_possible_ranges_inside_the_range_chart_limit() -> None:
    # sigma of 2 steps but a moving-range UCL of 3.5 steps: 0, 1, 2, 3 steps fit, fewer than 5.
    found = discrimination(np.arange(10) * STEP, STEP, sigma=2 * STEP, range_ucl=3.5 * STEP)
    assert found is not None
    assert found.possible_ranges == 4 and not found.adequate
    assert discrimination([0.0, 1.0], None) is None


# --- control limits never narrower than the gauge can tell apart ----------------------------


def test_limits_are_held_at_one_and_a_half_steps() -> None:
    values = np.array([0.0] * 12 + [STEP] + [0.0] * 12)
    chart = control_chart(values, 1, resolution=STEP)
    assert chart.ucl is not None and chart.center is not None
    assert chart.ucl - chart.center == pytest.approx(LIMIT_FLOOR_STEPS * STEP)
    assert chart.floored
    # Without the gauge step the chart is the textbook one (and the step reading is beyond it).
    bare = control_chart(values, 1)
    assert bare.ucl is not None and bare.ucl - bare.center < STEP  # type: ignore[operator]


@pytest.mark.parametrize("rule_set", RULE_SETS)
def test_a_one_step_difference_raises_no_alarm(rule_set: str) -> None:
    """A healthy gauge check: readings at one value with now and then one step either way."""
    values = np.array(([0.0] * 7 + [STEP] + [0.0] * 6 + [-STEP]) * 4)
    analysis = analyze({"x": values}, _config(rule_set))
    assert analysis.channels["x"].alarms == ()


@pytest.mark.parametrize("rule_set", RULE_SETS)
@pytest.mark.parametrize("spread_steps", [0.35, 0.5])
def test_stable_coarse_readings_alarm_no_more_often_than_stated(
    rule_set: str, spread_steps: float
) -> None:
    """200 stable sessions of 30 readings rounded at 0.35 or 0.5 step of spread raise some
    alarm no more often than the false-alarm chance the report states for 30 points. The
    tolerance is three standard errors of the difference of the two simulated proportions
    (200 sessions here, the stated figure's own sessions there)."""
    rng = np.random.default_rng(2024)
    config = _config(rule_set, freeze_after=None)
    raised = sum(
        bool(analyze({"x": _rounded(rng, spread_steps)}, config).channels["x"].alarms)
        for _ in range(SESSIONS)
    )
    stated = false_alarm_chance(rule_set, N)
    assert stated is not None
    observed = raised / SESSIONS
    error = math.hypot(
        math.sqrt(stated.chance * (1 - stated.chance) / SESSIONS), stated.standard_error
    )
    assert observed <= stated.chance + 3 * error, (observed, stated.chance)


# --- no percentile index or normality verdict from rounded readings --------------------------


@pytest.mark.parametrize("spread_steps", [0.35, 0.5, 1.0])
def test_thirty_rounded_readings_never_give_a_percentile_index(spread_steps: float) -> None:
    """150 samples at each spread; before, 14 of 150 at one step gave Ppk (percentile) > 20."""
    rng = np.random.default_rng(7)
    config = _config()
    for _ in range(150):
        channel = analyze({"x": _rounded(rng, spread_steps)}, config).channels["x"]
        assert channel.shape_hidden
        assert channel.percentile is None
        assert channel.capability_method == "normal"
        assert channel.normality is not None and channel.normality.rejected is None
        assert "ties from the rounding, not the process" in (channel.normality.message or "")


def test_a_step_and_a_half_of_spread_gives_no_runaway_percentile_index() -> None:
    """At 1.5 steps some samples spread enough (sd 2 steps or more) to be judged: their index
    stays within twice the true Ppk (2.2 for +-10 steps at sd 1.5); before, one was 33010."""
    rng = np.random.default_rng(7)
    config = _config()
    judged = 0
    for _ in range(150):
        channel = analyze({"x": _rounded(rng, 1.5)}, config).channels["x"]
        if channel.shape_hidden:
            assert channel.percentile is None
            continue
        judged += 1
        ppk = None if channel.percentile is None else channel.percentile.ppk
        assert ppk is None or ppk < 2 * 10 / (3 * 1.5)
    assert judged  # the gate is not simply "never"


def test_the_report_says_why_there_is_no_normality_test() -> None:
    values = np.array([0.0, 0.0, STEP, 0.0, -STEP, 0.0] * 5)
    report = format_report(analyze({"x": values}, _config())).replace("\n", " ")
    assert "NORMALITY (Shapiro-Wilk): not tested (the gauge rounded the readings to 3" in report
    assert "ties from the rounding, not the process" in report
    assert "Ppk (percentile)" not in report


# --- the false-alarm chance ------------------------------------------------------------------


def test_the_false_alarm_chance_is_stated_in_the_report_and_json() -> None:
    from station.analysis.document import channel_to_json

    rng = np.random.default_rng(11)
    analysis = analyze({"x": rng.normal(0, 4 * STEP, N)}, _config())
    chance = false_alarm_chance("report", N)
    assert chance is not None and 0.02 < chance.chance < 0.5
    assert chance.text() in format_report(analysis, width=1000)
    document = channel_to_json(analysis.channels["x"])
    assert document["chart"]["false_alarm_chance"]["chance"] == chance.chance
    assert document["discrimination"]["adequate"] is True


def test_more_rules_cry_wolf_more_often() -> None:
    report, nelson = false_alarm_chance("report", N), false_alarm_chance("nelson", N)
    assert report is not None and nelson is not None
    assert nelson.chance > report.chance
    longer = false_alarm_chance("report", 5000)
    assert longer is not None and longer.at_least and "nearly every chart" in longer.text()


# --- one alarm for a run that stays violated ---------------------------------------------------


@pytest.mark.parametrize(
    ("rule_set", "rule", "pattern"),
    [
        # Fifteen points alternating up and down (report rule 3), going on for 40 cycles.
        ("report", "report-3", [0.5, -0.5]),
        # Fifteen points within 1 sigma (Nelson 7) after a wide start that set the limits.
        ("nelson", "nelson-7", None),
    ],
)
def test_a_run_that_stays_violated_is_one_live_alarm(
    rule_set: str, rule: str, pattern: list[float] | None
) -> None:
    config = AnalysisConfig(rule_set=rule_set)
    monitor = LiveMonitor(config, ["x"], freeze_after=20)
    if pattern is not None:
        values = [pattern[i % 2] * (1 + 0.01 * (i % 3)) for i in range(60)]
    else:
        rng = np.random.default_rng(5)
        values = list(rng.normal(0, 1, 20)) + [0.01 * (i % 5) for i in range(40)]
    raised = []
    for cycle, value in enumerate(values, start=1):
        raised += [a for a in monitor.add_set({"x": value}, cycle)[1] if a.alarm.rule == rule]
    assert len(raised) == 1, [a.cycle for a in raised]


def test_check_rules_counts_the_rounding_at_zone_lines() -> None:
    """Five points 1.2 sigma above the centre are beyond 1 sigma, but by less than half a
    gauge step: rounded readings that could all be within 1 sigma are not a signal."""
    sigma = 0.5 * STEP
    points = [1.2 * sigma] * 5
    assert {a.rule for a in check_rules(points, 0.0, sigma, "western-electric")} == {"we-3"}
    assert check_rules(points, 0.0, sigma, "western-electric", resolution=STEP) == []
