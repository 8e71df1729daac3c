"""Checks of what the capability assumes, on generated data with known properties: provisional
verdicts, out-of-spec counts, autocorrelation, normality and the percentile indices, drift."""

from __future__ import annotations

import re

import numpy as np
import pytest

from station.analysis.capability import SpecLimits, capability
from station.analysis.diagnostics import (
    ALPHA,
    autocorrelation,
    drift,
    ewma_chart,
    normality,
    out_of_spec,
    percentile_capability,
    trend,
)
from station.analysis.document import to_json
from station.analysis.report import format_report
from station.analysis.rules import rule_name
from station.analysis.summary import AnalysisConfig, analyze
from station.analysis.verdict import cpk_text, judge_verdict, verdict_line

LIMITS = SpecLimits(-0.001, 0.001)


def ar1(phi: float, n: int, seed: int, sigma: float = 0.0001) -> np.ndarray:
    rng = np.random.default_rng(seed)
    noise = rng.normal(0.0, sigma, n)
    values = np.empty(n)
    values[0] = noise[0] / np.sqrt(1 - phi**2)
    for i in range(1, n):
        values[i] = phi * values[i - 1] + noise[i]
    return values


# Provisional verdicts ------------------------------------------------------------------------


def test_nine_readings_are_provisional_in_the_verdict_json_and_report():
    values = np.random.default_rng(3).normal(0.0, 0.0002, 9)
    analysis = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS))
    channel = analysis.channels["x"]
    assert channel.verdict.provisional and channel.verdict.label == "PROVISIONAL: 9 of 25"
    document = to_json(analysis)["channels"]["x"]
    assert document["capability"]["provisional"] is True
    assert document["capability"]["verdict"] == "PROVISIONAL: 9 of 25"
    assert "VERDICT: PROVISIONAL: 9 of 25 readings" in format_report(analysis)


def test_enough_readings_give_a_final_verdict():
    values = np.random.default_rng(3).normal(0.0, 0.0002, 25)
    channel = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS)).channels["x"]
    assert not channel.verdict.provisional
    assert channel.verdict.word in ("CAPABLE", "NOT CAPABLE", "INCONCLUSIVE")


@pytest.mark.parametrize(
    ("cpk", "shown"),
    [(1.17, "1.17"), (0.9996, "0.9996"), (0.99999994, "0.9999999"), (1.0004, "1.00")],
)
def test_the_shown_cpk_never_contradicts_the_word(cpk, shown):
    assert cpk_text(cpk, 1.0) == shown
    assert (float(cpk_text(cpk, 1.0)) >= 1.0) == (cpk >= 1.0)


def test_a_cpk_just_below_one_is_not_shown_as_1_00_not_capable():
    # Readings with Cpk = 0.9996: the old report said "Cpk 1.00 ... NOT CAPABLE".
    values = np.array([-1.0, 1.0] * 15)
    sd = float(np.std(values, ddof=1))
    usl = 3 * sd * 0.9996
    cap = capability(values, SpecLimits(-usl, usl))
    line = verdict_line(cap, min_n=25)
    # 30 readings cannot tell 0.9996 from 1: the verdict is inconclusive, and the report's rule
    # beside it shows the Cpk on its side of the threshold.
    assert "INCONCLUSIVE" in line and "1.00 " not in line
    assert "by the report's rule: not capable, Cpk 0.9996 < 1" in line


# Out of specification -------------------------------------------------------------------------


def test_out_of_spec_counts_each_side_with_its_cycles():
    values = [0.0, 0.0011, -0.0002, -0.0015, 0.0012]
    found = out_of_spec(values, SpecLimits(-0.001, 0.001), cycles=[1, 2, 4, 5, 6])
    assert (found.below, found.above) == (1, 2)
    assert found.cycles_above == (2, 6) and found.cycles_below == (5,) and found.cycles == (2, 5, 6)
    analysis = analyze({"y": np.array(values)}, AnalysisConfig(default_limits=LIMITS))
    assert to_json(analysis)["channels"]["y"]["out_of_spec"] == {
        "below": 1,
        "above": 2,
        "cycles": [2, 4, 5],
        "cycles_below": [4],
        "cycles_above": [2, 5],
    }
    assert "OUT OF SPEC: 3 readings" in format_report(analysis)


# Autocorrelation ------------------------------------------------------------------------------


def test_ar1_with_phi_0_8_is_flagged_with_the_explanation():
    flagged = [autocorrelation(ar1(0.8, 30, seed)).significant for seed in range(50)]
    assert sum(flagged) >= 45
    result = autocorrelation(ar1(0.8, 30, 7), sigma_within=0.0001)
    assert result.significant and result.r1 > 0.4
    assert "I-MR limits are too tight" in result.message


def test_independent_normal_data_hold_the_stated_false_alarm_rate():
    """Over 1000 seeds of n = 30, i.i.d. data are flagged at about ALPHA (5 %), not more: an
    upper bound of ALPHA + 3 binomial standard errors."""
    seeds = 1000
    flags = sum(
        bool(autocorrelation(np.random.default_rng(seed).normal(0, 1, 30)).significant)
        for seed in range(seeds)
    )
    assert flags / seeds <= ALPHA + 3 * np.sqrt(ALPHA * (1 - ALPHA) / seeds)


def test_the_report_shows_within_and_overall_indices_side_by_side_when_correlated():
    values = ar1(0.8, 30, 11) * 2
    analysis = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS))
    text = " ".join(format_report(analysis).split())
    assert "AUTOCORRELATION lag 1: r = +" in text and "(significant at 0.05)" in text
    assert "Side by side: Cpk (overall sigma" in text and "Cpk within (sigma" in text
    document = to_json(analysis)["channels"]["x"]["autocorrelation"]
    assert document["significant"] is True and document["sigma_ratio"] > 1


# Normality and the percentile indices ---------------------------------------------------------


def test_a_log_normal_sample_rejects_normality_and_reports_the_percentile_index():
    rng = np.random.default_rng(5)
    values = rng.lognormal(0.0, 0.8, 60) * 0.0001 - 0.0002
    result = normality(values)
    assert result.test == "Shapiro-Wilk" and result.rejected
    analysis = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS))
    channel = analysis.channels["x"]
    assert channel.percentile is not None and channel.capability_method == "percentile"
    # A long upper tail: the percentile index of the upper side is below the normal one.
    assert channel.percentile.ppu < channel.capability.cpu
    document = to_json(analysis)["channels"]["x"]
    assert document["normality"]["rejected"] is True
    assert document["capability"]["method"] == "percentile"
    assert document["capability"]["percentile"]["method"].startswith("percentile (ISO 22514-2)")
    text = format_report(analysis)
    assert "Ppk (percentile)" in text and "normality rejected" in text


def test_normal_data_keep_the_normal_method_and_the_percentile_index_is_close_to_cpk():
    values = np.random.default_rng(9).normal(0.0, 0.0002, 3000)
    assert not normality(values).rejected
    channel = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS)).channels["x"]
    assert channel.capability_method == "normal" and channel.percentile is None
    # Empirical quantiles at this size: the percentile Ppk agrees with Cpk to about 10 %.
    percentile = percentile_capability(values, LIMITS)
    assert percentile.method.endswith("empirical quantiles")
    assert percentile.ppk == pytest.approx(channel.capability.cpk, rel=0.1)


def test_a_handful_of_non_normal_readings_get_no_percentile_index():
    """Five placements (relative accuracy's few readings): a Johnson fit to them invents its
    tails (a Ppk of 114,618 once). No percentile index below the report's 25 readings; the
    report says why, and the verdict keeps the normal indices."""
    values = np.array([0.0, 0.00001, 0.0, -0.00001, 0.0009])
    assert normality(values).rejected
    assert percentile_capability(values, LIMITS) is None
    channel = analyze({"x": values}, AnalysisConfig(default_limits=LIMITS)).channels["x"]
    assert channel.percentile is None and channel.capability_method == "normal"
    text = " ".join(
        format_report(analyze({"x": values}, AnalysisConfig(default_limits=LIMITS))).split()
    )
    assert "5 readings are too few for percentile indices (at least 25)" in text
    assert "Ppk (percentile)" not in text


def test_large_samples_use_anderson_darling():
    values = np.random.default_rng(2).normal(0, 1, 6000)
    result = normality(values)
    assert result.test == "Anderson-Darling" and not result.rejected
    skewed = np.random.default_rng(2).exponential(1, 6000)
    assert normality(skewed).rejected
    # Far from normal (A² in the thousands): p is 0, not an overflow.
    two_steps = np.repeat([0.0, 0.0001], 50_000)
    result = normality(two_steps)
    assert result.rejected and result.p_value == 0.0


def test_a_coarse_gauge_step_is_noted():
    values = np.round(np.random.default_rng(1).normal(0, 0.0001, 30), 4)
    assert "tied readings" in normality(values, resolution=0.0001).ties


# Drift ----------------------------------------------------------------------------------------


def test_a_ramp_is_caught_by_the_trend_and_the_ewma():
    rng = np.random.default_rng(4)
    n = 30
    values = np.linspace(0.0, 0.0004, n) + rng.normal(0, 0.00005, n)
    times = 1_700_000_000 + 20.0 * np.arange(n)  # a cycle every 20 s
    result = drift(values, 0.00005, times=times, name="x", unit="in")
    assert result.trend.basis == "time" and result.trend.significant
    assert result.trend.per_span == pytest.approx(0.0004 / 29 * 10, rel=0.3)
    assert result.ewma.signals
    assert re.match(r"x drifts \+0\.0001\d in per 10 cycles, p (=|<) 0\.0", result.message)
    assert result.message.endswith("let the robot warm up and repeat")


def test_stable_data_rarely_show_drift():
    """Over 400 seeds of 30 i.i.d. readings the trend test flags about ALPHA, and the EWMA
    (λ 0.2, L 3, about 1 false signal in 500 points) well under 10 % of the runs."""
    seeds = 400
    samples = [np.random.default_rng(seed).normal(0, 1, 30) for seed in range(seeds)]
    trends = sum(bool(trend(values).significant) for values in samples)
    ewmas = sum(bool(ewma_chart(values, 0.0, 1.0).signals) for values in samples)
    assert trends / seeds <= ALPHA + 3 * np.sqrt(ALPHA * (1 - ALPHA) / seeds)
    assert ewmas / seeds < 0.10


def test_the_drift_is_in_the_json_and_the_report():
    values = np.linspace(0.0, 0.0006, 30) + np.random.default_rng(1).normal(0, 0.00004, 30)
    analysis = analyze({"z": values}, AnalysisConfig(default_limits=LIMITS, unit="in"))
    document = to_json(analysis)["channels"]["z"]["drift"]
    assert document["trend"]["significant"] is True and document["trend"]["basis"] == "cycle"
    assert document["ewma"]["signal_cycles"]
    assert any("let the robot warm up and repeat" in hint for hint in analysis.hints)
    assert "DRIFT: trend on cycle order +" in format_report(analysis)


# Rules in words -------------------------------------------------------------------------------


def test_rules_are_named_in_words():
    assert rule_name("report-1") == "report rule 1 (a point beyond the control limits)"
    assert rule_name("report-4").startswith("report rule 4 (two of three points beyond 2 sigma")
    assert rule_name("we-4").startswith("Western Electric rule 4")
    assert rule_name("ewma") == "drift rule (the EWMA beyond its limits (a drift of the mean))"
    assert judge_verdict(capability([0.0, 0.0001, -0.0001], LIMITS), 25).word == "PROVISIONAL"


def test_the_ewma_limits_of_a_long_chart_are_the_formula_at_every_point():
    """The batch computes the start-up term (1 - lambda)^2i only while it can change a limit;
    every limit is still exactly the formula's, and the live one's to rounding."""
    from station.analysis.diagnostics import ewma_limit_half_width, ewma_limit_half_widths

    for lam in (0.05, 0.2, 0.5, 1.0):
        i = np.arange(1, 3001)
        formula = 3.0 * 0.0003 * np.sqrt(lam / (2 - lam) * (1 - (1 - lam) ** (2 * i)))
        batch = ewma_limit_half_widths(0.0003, 3000, lam, 3.0)
        assert np.array_equal(batch, formula)
        live = [ewma_limit_half_width(0.0003, k, lam, 3.0) for k in (1, 10, 3000)]
        assert batch[[0, 9, 2999]] == pytest.approx(live, rel=1e-14)
