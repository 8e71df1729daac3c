"""The gauge linearity and bias study's figures (AIAG MSA 4th ed.), checked against AIAG's own
worked example, against an independent computation (scipy.stats.linregress and the formulas
written out here), on a hand-checked set with a known slope and bias, and against the
simulated gauge bench, whose injected linearity error it must recover."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from station.errors import StationError
from station.instruments.gauge_bench import GaugeBenchModel
from station.instruments.simulator import GaugeSpec
from station.methods.gauge_linearity.study import (
    ACCEPTABLE,
    INCONCLUSIVE,
    NOT_ACCEPTABLE,
    linearity_study,
)

# AIAG MSA 4th ed., the linearity example (Minitab's "Gage Linearity and Bias Study" example):
# five parts of reference 2, 4, 6, 8 and 10, each measured twelve times.
AIAG = {
    2.0: [2.7, 2.5, 2.4, 2.5, 2.7, 2.3, 2.5, 2.5, 2.4, 2.4, 2.6, 2.4],
    4.0: [5.1, 3.9, 4.2, 5.0, 3.8, 3.9, 3.9, 3.9, 3.9, 4.0, 4.1, 3.8],
    6.0: [5.8, 5.7, 5.9, 5.9, 6.0, 6.1, 6.0, 6.1, 6.4, 6.3, 6.0, 6.1],
    8.0: [7.6, 7.7, 7.8, 7.7, 7.8, 7.8, 7.8, 7.7, 7.8, 7.5, 7.6, 7.7],
    10.0: [9.1, 9.3, 9.5, 9.3, 9.4, 9.5, 9.5, 9.5, 9.6, 9.2, 9.3, 9.4],
}
AIAG_PV = 16.53
"""The example's process variation (6σ, σ = 2.7564)."""


def rows(table: dict[float, list[float]]) -> tuple[list[float], list[float]]:
    references = [size for size, values in table.items() for _ in values]
    values = [value for readings in table.values() for value in readings]
    return references, values


def test_aiag_example_gives_the_published_figures():
    references, values = rows(AIAG)
    study = linearity_study(references, values, process_variation=AIAG_PV, resolution=0.1)
    # Published: bias = 0.7367 − 0.1317·reference, R² 71.4 %, S 0.2395, t(slope) −12.04,
    # t(intercept) 10.16; linearity 2.18 (13.17 %); average bias −0.0533, t 1.729, p 0.089.
    assert study.slope == pytest.approx(-0.131667, abs=5e-6)
    assert study.intercept == pytest.approx(0.736667, abs=5e-6)
    assert study.r2 == pytest.approx(0.7143, abs=5e-4)
    assert study.s == pytest.approx(0.23954, abs=5e-5)
    assert study.slope_t == pytest.approx(-12.04, abs=0.01)
    assert study.intercept_t == pytest.approx(10.16, abs=0.01)
    assert study.linearity == pytest.approx(2.1765, abs=1e-3)
    assert study.pct_linearity == pytest.approx(13.17, abs=0.01)
    assert study.average_bias == pytest.approx(-0.053333, abs=1e-6)
    assert study.average_bias_t == pytest.approx(-1.729, abs=0.002)
    assert study.average_bias_p == pytest.approx(0.0894, abs=5e-4)
    published = {2.0: (0.491667, 13.73), 4.0: (0.125, 0.968), 6.0: (0.025, 0.442),
                 8.0: (-0.291667, -10.14), 10.0: (-0.616667, -14.56)}  # fmt: skip
    for master in study.masters:
        bias, t = published[master.reference]
        assert master.bias == pytest.approx(bias, abs=1e-6)
        assert master.t == pytest.approx(t, abs=0.01)
    # Bias changes with the size, and the line bias = 0 leaves the band: not acceptable.
    assert study.verdict == NOT_ACCEPTABLE and study.acceptable is False
    assert study.slope_p < 1e-6 and study.intercept_p < 1e-6
    # Against a tolerance the same readings say as much as they show: a proven bias of 0.47
    # is beyond 5 % of T = 4 (0.2); their band (up to ±0.69) is inside 5 % of T = 20 (1.0);
    # with T = 10 (0.5) neither is shown.
    verdicts = {
        tolerance: linearity_study(references, values, tolerance=tolerance).verdict
        for tolerance in (4.0, 10.0, 20.0)
    }
    assert verdicts == {4.0: NOT_ACCEPTABLE, 10.0: INCONCLUSIVE, 20.0: ACCEPTABLE}


def test_the_regression_agrees_with_an_independent_computation():
    """scipy.stats.linregress on the same biases, and the AIAG formulas written out."""
    references, values = rows(AIAG)
    study = linearity_study(references, values)
    x, y = np.asarray(references), np.asarray(values) - np.asarray(references)
    fit = stats.linregress(x, y)
    assert study.slope == pytest.approx(fit.slope, rel=1e-12)
    assert study.intercept == pytest.approx(fit.intercept, rel=1e-12)
    assert study.r2 == pytest.approx(fit.rvalue**2, rel=1e-12)
    assert study.slope_se == pytest.approx(fit.stderr, rel=1e-12)
    assert study.intercept_se == pytest.approx(fit.intercept_stderr, rel=1e-12)
    assert study.slope_p == pytest.approx(fit.pvalue, rel=1e-9)
    n, sxx = x.size, float(np.sum((x - x.mean()) ** 2))
    s = math.sqrt(float(np.sum((y - fit.intercept - fit.slope * x) ** 2)) / (n - 2))
    t_intercept = fit.intercept / (s * math.sqrt(1 / n + x.mean() ** 2 / sxx))
    assert study.intercept_t == pytest.approx(t_intercept, rel=1e-12)
    assert study.intercept_p == pytest.approx(2 * stats.t.sf(abs(t_intercept), n - 2), rel=1e-9)
    # Each master's bias test is scipy's one-sample t-test of its biases.
    for master in study.masters:
        test = stats.ttest_1samp(y[x == master.reference], 0.0)
        assert master.t == pytest.approx(test.statistic, rel=1e-9)
        assert master.p == pytest.approx(test.pvalue, rel=1e-9)


def known_gauge(slope: float, bias: float, spread: float) -> tuple[list[float], list[float]]:
    """Five masters 0.1 to 0.9 in, ten readings each: the master's size, its known bias
    ``bias + slope·size``, and ± ``spread`` about it (five each way: each master's mean bias
    is exactly the known one, its s is spread·√(10/9))."""
    references, values = [], []
    for size in (0.1, 0.3, 0.5, 0.7, 0.9):
        for sign in (1, -1) * 5:
            references.append(size)
            values.append(size + bias + slope * size + sign * spread)
    return references, values


def test_a_hand_checked_gauge_with_a_known_slope_and_bias():
    """By hand: every master's mean bias lies on the line bias = 0.0002 + 0.001·size, so the
    fit is that line exactly; the residuals are ±0.00005 (s² = 50·0.00005²/48), and the
    average bias is 0.0002 + 0.001·0.5 = 0.0007."""
    references, values = known_gauge(0.001, 0.0002, 0.00005)
    study = linearity_study(references, values, process_variation=0.01, tolerance=0.002)
    assert study.slope == pytest.approx(0.001, abs=1e-12)
    assert study.intercept == pytest.approx(0.0002, abs=1e-12)
    assert study.average_bias == pytest.approx(0.0007, abs=1e-12)
    assert study.s == pytest.approx(0.00005 * math.sqrt(50 / 48), rel=1e-9)
    sxx = 10 * sum((size - 0.5) ** 2 for size in (0.1, 0.3, 0.5, 0.7, 0.9))  # 0.4
    assert study.slope_se == pytest.approx(study.s / math.sqrt(sxx), rel=1e-9)
    assert study.linearity == pytest.approx(0.001 * 0.01, rel=1e-9)
    assert study.pct_linearity == pytest.approx(0.1, rel=1e-9)
    assert study.pct_bias == pytest.approx(100 * 0.0007 / 0.01)
    # Each master's readings are ±0.00005 about its bias: s = 0.00005·√(10/9), t = b/(s/√10).
    for master in study.masters:
        assert master.bias == pytest.approx(0.0002 + 0.001 * master.reference, abs=1e-12)
        assert master.sd == pytest.approx(0.00005 * math.sqrt(10 / 9), rel=1e-9)
        assert master.t == pytest.approx(master.bias / (master.sd / math.sqrt(10)), rel=1e-9)
    assert study.average_bias_t == pytest.approx(
        0.0007 / (0.00005 * math.sqrt(10 / 9) / math.sqrt(50)), rel=1e-9
    )
    # The largest bias, 0.0011 at 0.9 in, is proven (its band about it: proven + bound = twice
    # it), beyond the 5 % of T (0.0001) allowed.
    assert study.bias_proven_at == pytest.approx(0.9)
    assert study.bias_proven + study.bias_bound == pytest.approx(2 * 0.0011, rel=1e-9)
    assert study.bias_proven > 0.0001
    assert study.verdict == NOT_ACCEPTABLE and study.acceptable is False
    assert "proven at 0.9" in study.sentence


def test_a_gauge_without_bias_is_acceptable_and_says_what_it_cannot_exclude():
    references, values = known_gauge(0.0, 0.0, 0.00005)
    study = linearity_study(references, values, unit="in")
    assert study.slope == pytest.approx(0.0, abs=1e-12)
    assert study.verdict == ACCEPTABLE and study.acceptable is True
    assert "no bias or linearity detected" in study.sentence
    assert "cannot exclude a bias of up to" in study.sentence
    # With a tolerance its band fits inside the allowed bias: acceptable on the size too.
    judged = linearity_study(references, values, tolerance=0.01, unit="in")
    assert judged.verdict == ACCEPTABLE and judged.bias_bound <= 0.05 * 0.01


def test_a_small_bias_within_the_tolerance_is_acceptable_though_detected():
    references, values = known_gauge(0.0, 0.00002, 0.000002)
    study = linearity_study(references, values, tolerance=0.004)
    assert study.bias_proven > 0  # detected ...
    assert study.verdict == ACCEPTABLE  # ... and harmless: within 0.0002 (5 % of T)
    assert "a bias is detected but" in study.sentence


def test_an_unclear_case_is_inconclusive_and_says_what_would_settle_it():
    # A bias about the allowed 0.0001 (5 % of T = 0.002), measured too noisily to tell.
    references, values = known_gauge(0.0, 0.0001, 0.0003)
    study = linearity_study(references, values, tolerance=0.002)
    assert study.verdict == INCONCLUSIVE and study.acceptable is None
    assert "readings per master would settle it" in study.sentence


def test_readings_the_gauge_rounded_to_one_value_are_tested_against_its_rounding():
    references = [0.1] * 10 + [0.5] * 10 + [0.9] * 10
    values = [0.1001] * 10 + [0.5001] * 10 + [0.9001] * 10
    study = linearity_study(references, values, resolution=0.0001)
    assert all(m.rounded and m.sd == pytest.approx(0.0001 / math.sqrt(12)) for m in study.masters)
    assert study.s == pytest.approx(0.0001 / math.sqrt(12))
    assert all(math.isfinite(m.t) for m in study.masters)
    assert any("rounding" in note for note in study.notes())


@pytest.mark.parametrize(
    ("references", "values", "words"),
    [
        ([0.1] * 5, [0.1] * 5, "2 or more reference masters"),
        ([0.1, 0.1, 0.5], [0.1, 0.1, 0.5], "was read 1 time"),
        ([0.1, 0.5], [0.1, float("nan")], "not a finite number"),
    ],
)
def test_bad_studies_are_refused_with_a_sentence(references, values, words):
    with pytest.raises(StationError, match=words):
        linearity_study(references, values)


def test_the_simulated_bench_gives_back_the_injected_slope_and_bias():
    """The gauge bench's indicator reads a block of size r as r + bias + slope·r (plus its
    repeatability, at its resolution): the study recovers the slope and the bias within their
    95 % intervals, and calls the gauge not acceptable for it."""
    sizes, slope, bias = (0.1, 0.3, 0.5, 0.7, 0.9), 0.001, 0.0002
    gauge = GaugeSpec(0.0001, -0.5, 1.0, "in")
    bench = GaugeBenchModel(sizes, bias=bias, slope=slope, noise=0.00005, readings=12, gauge=gauge)
    rests = range(1, 5 * 12 + 1)
    references = [bench.block_of(rest) for rest in rests]
    values = [bench.value("x", rest, seed=7) for rest in rests]
    assert [bench.rest_of(3, 1), bench.block_of(bench.rest_of(3, 12))] == [25, 0.5]
    study = linearity_study(references, values, resolution=0.0001, tolerance=0.004)
    t = stats.t.ppf(0.975, study.n - 2)
    assert abs(study.slope - slope) <= t * study.slope_se
    assert abs(study.intercept - bias) <= t * study.intercept_se
    assert study.slope_p < 0.001 and study.verdict == NOT_ACCEPTABLE
