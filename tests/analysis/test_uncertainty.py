"""The GUM budget evaluator and the ISO 14253-1 decision rule, on hand-checked numbers."""

from __future__ import annotations

import math

import pytest

from station.analysis.uncertainty import (
    Budget,
    Contribution,
    GaugeRecord,
    Outcome,
    Rule,
    acceptance_zone,
    channel_budget,
    check_limits,
    cosine_error,
    decide,
    evaluate,
    from_expanded,
    from_half_width,
    judge_readings,
    repeatability,
    resolution,
    temperature,
    type_a,
    welch_satterthwaite,
)
from station.errors import StationError


def hand_budget() -> Budget:
    """Six lines whose squared contributions are 0.5, 0.03, 0.04, 0.04, 0.06, 0.02 (sum 0.69)."""
    return Budget(
        (
            type_a("repeatability", [1, 2, 3, 4, 5]),  # s² = 2.5, u² = 2.5/5 = 0.5, ν = 4
            from_half_width("resolution", 0.3, "rectangular"),  # 0.09/3 = 0.03
            from_expanded("certificate", 0.4, 2, dof=10),  # 0.2² = 0.04, ν = 10
            Contribution("temperature", 0.05, sensitivity=-4),  # (4 · 0.05)² = 0.04
            from_half_width("triangle", 0.6, "triangular"),  # 0.36/6 = 0.06
            from_half_width("cycling", 0.2, "arcsine"),  # 0.04/2 = 0.02
        ),
        unit="mm",
    )


def test_combined_uncertainty_dof_and_k_from_a_confidence():
    result = evaluate(hand_budget(), confidence=0.95)
    assert result.u_c == pytest.approx(math.sqrt(0.69))
    # ν_eff = 0.69² / (0.5²/4 + 0.04²/10) = 0.4761 / 0.06266
    assert result.nu_eff == pytest.approx(0.4761 / 0.06266)
    assert 7 < result.nu_eff < 8
    # k = t(0.975, 7) = 2.3646 (GUM Table G.2: 2.36), not t at 7.6 nor 1.96.
    assert result.k == pytest.approx(2.3646, abs=1e-4)
    expanded = result.U
    assert expanded == pytest.approx(2.3646 * math.sqrt(0.69), rel=1e-4)
    assert result.confidence == 0.95
    shares = [line.share for line in result.lines]
    assert shares == pytest.approx(
        [0.5 / 0.69, 0.03 / 0.69, 0.04 / 0.69, 0.04 / 0.69, 0.06 / 0.69, 0.02 / 0.69]
    )
    temperature_line = result.lines[3]
    assert (temperature_line.u, temperature_line.sensitivity, temperature_line.ui) == pytest.approx(
        (0.05, -4, 0.2)
    )
    assert result.lines[0].dof == 4 and math.isinf(result.lines[1].dof)


def test_k_given_or_defaulted():
    expanded = evaluate(hand_budget(), k=3).U
    assert expanded == pytest.approx(3 * math.sqrt(0.69))
    assert evaluate(hand_budget()).k == 2.0
    assert evaluate(hand_budget()).confidence is None


def test_gum_h1_coverage_at_99_percent_on_16_degrees_of_freedom():
    # GUM H.1: u_c = 32 nm, ν_eff = 16, U99 = 2.92 · 32 = 93 nm.
    result = evaluate([Contribution("end gauge", 32.0, dof=16)], confidence=0.99)
    assert result.nu_eff == pytest.approx(16)
    assert result.k == pytest.approx(2.921, abs=1e-3)
    assert round(result.U) == 93


def test_every_line_infinite_gives_the_normal_quantile():
    result = evaluate([Contribution("a", 3.0), Contribution("b", 4.0)], confidence=0.95)
    assert result.u_c == pytest.approx(5.0)
    assert math.isinf(result.nu_eff)
    assert result.k == pytest.approx(1.959964, abs=1e-6)


def test_nu_eff_truncates_not_rounds():
    # Two equal lines, each ν = 4.9: ν_eff = (2u²)² / (2u⁴/4.9) = 9.8 → t at 9, not 10.
    lines = [Contribution("a", 1.0, dof=4.9), Contribution("b", 1.0, dof=4.9)]
    assert welch_satterthwaite(lines) == pytest.approx(9.8)
    assert evaluate(lines, confidence=0.95).k == pytest.approx(2.2622, abs=1e-4)  # t(0.975, 9)


def test_tiny_and_large_budgets_keep_their_dof():
    # Fourth powers of 1e-200 underflow to 0 and would make ν_eff infinite; the sums are taken
    # relative to the largest line. Two equal lines, one on ν = 4: ν_eff = (2u²)²/(u⁴/4) = 16.
    for scale in (1e-200, 1.0, 1e140):
        result = evaluate([Contribution("a", scale, dof=4), Contribution("b", scale)])
        assert result.nu_eff == pytest.approx(16)
        assert result.u_c == pytest.approx(scale * math.sqrt(2))
        assert [line.share for line in result.lines] == pytest.approx([0.5, 0.5])


def test_the_lines_of_a_dial_indicator_channel():
    assert resolution(0.0001).u == pytest.approx(0.0001 / math.sqrt(12))  # 2.9e-5 in
    # 10 in of steel, ±1 °C: 1.15e-4 in rectangular, u = 6.6e-5 in (the reference's figure).
    assert temperature(10.0, 1.0).u == pytest.approx(6.64e-5, abs=1e-7)
    assert temperature(10.0, 1.0, distribution="arcsine").u == pytest.approx(1.15e-4 / math.sqrt(2))
    # 1 in of travel 0.01 rad off: 1 − cos 0.01 = 4.99996e-5 in short, rectangular over [0, it].
    assert cosine_error(1.0, 0.01).u == pytest.approx((1 - math.cos(0.01)) / math.sqrt(12))
    line = repeatability(0.0002, 30)
    assert (line.u, line.dof) == (0.0002, 29.0)
    assert from_half_width("normal", 0.3, "normal").u == pytest.approx(0.15)
    assert from_half_width("normal 3", 0.3, "normal", k=3).u == pytest.approx(0.1)


def test_zero_uncertainty_is_allowed_and_has_no_share():
    result = evaluate([Contribution("zero", 0.0)])
    assert (result.u_c, result.U, result.lines[0].share) == (0.0, 0.0, 0.0)
    assert math.isinf(result.nu_eff)


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: Contribution("cal", -1.0), "input 'cal': u must be a finite number 0 or more"),
        (lambda: Contribution("cal", math.nan), "input 'cal': u is NaN"),
        (lambda: Contribution("cal", math.inf), "input 'cal': u must be a finite number"),
        (
            lambda: Contribution("cal", 1.0, sensitivity="two"),
            "input 'cal': sensitivity must be a number",
        ),
        (
            lambda: Contribution("cal", 1.0, sensitivity=True),
            "input 'cal': sensitivity must be a number",
        ),
        (lambda: Contribution("cal", 1.0, sensitivity=math.inf), "sensitivity must be a finite"),
        (lambda: Contribution("cal", 1.0, dof=0.5), "input 'cal': dof must be 1 or more"),
        (lambda: Contribution("cal", 1e300, sensitivity=1e10), "input 'cal': |sensitivity| × u"),
        (lambda: from_expanded("cal", 1.0, 0), "input 'cal': k must be a finite number above 0"),
        (
            lambda: from_expanded("cal", 1.0, math.inf),
            "input 'cal': k must be a finite number above 0",
        ),
        (lambda: from_half_width("t", 1.0, "uniform"), "distribution 'uniform' is not one of"),
        (lambda: from_half_width("t", 1.0, "rectangular", k=2), "k goes with a normal half-width"),
        (lambda: type_a("rep", [1.0]), "input 'rep': readings need at least 2 values"),
        (lambda: Budget(()), "the budget has no inputs"),
        (lambda: Budget((Contribution("a", 1), Contribution("a", 2))), "input 'a' is given twice"),
        (lambda: evaluate([Contribution("a", 1)], k=2, confidence=0.95), "not both"),
        (
            lambda: evaluate([Contribution("a", 1)], confidence=1.0),
            "confidence must be a probability",
        ),
        (lambda: evaluate([Contribution("a", 1)], k=-1), "k must be a finite number above 0"),
    ],
)
def test_bad_budget_input_is_refused_naming_it(make, words):
    with pytest.raises(StationError, match=None) as caught:
        make()
    assert words in caught.value.message
    assert "\n" not in caught.value.message


# Limits ±1 and u_c = 0.125 at k = 2: U = 0.25, all exact in binary, so the edges are exact.
LIMITS = (-1.0, 1.0)
U_QUARTER = evaluate([from_expanded("gauge", 0.25, 2)])
NUDGE = 1e-9


@pytest.mark.parametrize(
    ("value", "verdict"),
    [
        (0.0, Outcome.PASS),
        (0.75, Outcome.PASS),  # on the guard band: still inside [LSL + U, USL − U]
        (-0.75, Outcome.PASS),
        (0.75 + NUDGE, Outcome.INDETERMINATE),
        (-0.75 - NUDGE, Outcome.INDETERMINATE),
        (1.0, Outcome.INDETERMINATE),  # on the limit itself
        (1.25, Outcome.INDETERMINATE),  # on the widened limit: not proven outside
        (1.25 + NUDGE, Outcome.FAIL),
        (-1.25 - NUDGE, Outcome.FAIL),
        (7.0, Outcome.FAIL),
    ],
)
def test_guarded_acceptance_at_and_near_the_guard_band(value, verdict):
    decision = decide(value, *LIMITS, U_QUARTER)
    assert decision.verdict is verdict
    assert decision.rule is Rule.GUARDED


def test_probability_of_conformance():
    # Φ((USL − y)/u_c) − Φ((LSL − y)/u_c) with u_c = 0.125.
    assert decide(0.75, *LIMITS, U_QUARTER).p_conformance == pytest.approx(0.9772499, abs=1e-7)
    assert decide(1.0, *LIMITS, U_QUARTER).p_conformance == pytest.approx(0.5, abs=1e-12)
    assert decide(1.25, *LIMITS, U_QUARTER).p_conformance == pytest.approx(0.0227501, abs=1e-7)
    assert decide(0.0, *LIMITS, U_QUARTER).p_conformance == pytest.approx(1.0, abs=1e-12)


def test_simple_acceptance_is_a_choice_without_indeterminate():
    assert decide(1.0, *LIMITS, U_QUARTER, "simple").verdict is Outcome.PASS
    assert decide(1.0 + NUDGE, *LIMITS, U_QUARTER, Rule.SIMPLE).verdict is Outcome.FAIL
    assert acceptance_zone(*LIMITS, 0.25, Rule.SIMPLE) == LIMITS
    assert acceptance_zone(*LIMITS, 0.25) == (-0.75, 0.75)


def test_one_sided_limit_and_overlapping_guard_bands():
    below = decide(-100.0, None, 1.0, U_QUARTER)
    assert below.verdict is Outcome.PASS and below.p_conformance == pytest.approx(1.0)
    assert decide(1.1, None, 1.0, U_QUARTER).verdict is Outcome.INDETERMINATE
    assert acceptance_zone(None, 1.0, 0.25) == (None, 0.75)
    # 2U = 0.5 > USL − LSL = 0.4: nothing can be proven inside.
    assert acceptance_zone(0.0, 0.4, 0.25) is None
    assert decide(0.2, 0.0, 0.4, U_QUARTER).verdict is Outcome.INDETERMINATE


def test_exact_budget_decides_by_the_limits():
    exact = evaluate([Contribution("none", 0.0)])
    assert decide(1.0, *LIMITS, exact).p_conformance == 1.0
    assert decide(1.5, *LIMITS, exact).p_conformance == 0.0


@pytest.mark.parametrize(
    ("lsl", "usl", "words"),
    [
        (1.0, 0.0, "the LSL 1 is not below the USL 0"),
        (1.0, 1.0, "the LSL 1 is not below the USL 1"),
        (None, None, "no limits to decide against"),
        (math.nan, 1.0, "the LSL must be a finite number"),
    ],
)
def test_impossible_limits_are_refused(lsl, usl, words):
    with pytest.raises(StationError) as caught:
        check_limits(lsl, usl)
    assert words in caught.value.message
    with pytest.raises(StationError):
        decide(0.0, lsl, usl, U_QUARTER)


# -- a session channel's budget and the decisions on its readings ------------------------------


def test_a_channel_budget_from_what_a_session_records():
    gauge = GaugeRecord(
        "G-1", certificate_U=0.0001, certificate_k=2.0, repeatability_sd=0.00005, repeatability_n=25
    )
    budget = channel_budget(0.0001, gauge, 0.00003, "in")
    assert budget is not None and budget.unit == "in"
    result = evaluate(budget)
    # By hand: r/√12, U/k, s (24 dof), the zero's u.
    parts = [0.0001 / math.sqrt(12), 0.00005, 0.00005, 0.00003]
    u_c = math.sqrt(sum(p * p for p in parts))
    assert [line.u for line in result.lines] == pytest.approx(parts, rel=1e-12)
    assert result.u_c == pytest.approx(u_c, rel=1e-12)
    assert result.nu_eff == pytest.approx(u_c**4 / (0.00005**4 / 24), rel=1e-12)
    assert (result.k, result.U) == (2.0, pytest.approx(2 * u_c, rel=1e-12))
    assert [line.name for line in result.lines] == [
        "gauge step (r/2 rectangular)",
        "certificate (U at k = 2)",
        "repeatability (Type-1, n = 25)",
        "zero",
    ]
    json_lines = result.as_json()["contributions"]
    assert json_lines[0]["dof"] is None and json_lines[2]["dof"] == 24.0
    # What is not recorded is not a line; nothing recorded is no budget at all.
    assert [c.name for c in channel_budget(0.0001).contributions] == [  # type: ignore[union-attr]
        "gauge step (r/2 rectangular)"
    ]
    assert channel_budget(None, GaugeRecord("G-2"), None) is None


def test_every_reading_is_decided_as_decide_would_with_the_same_budget():
    values = [0.0, 0.75, 0.75 + NUDGE, 1.0, 1.25, 1.25 + NUDGE, -0.75 - NUDGE, -7.0]
    cycles = list(range(3, 3 + len(values)))
    for rule in Rule:
        found = judge_readings(values, cycles, *LIMITS, U_QUARTER, rule)
        one_by_one = [decide(v, *LIMITS, U_QUARTER, rule).verdict for v in values]
        assert found.passed == one_by_one.count(Outcome.PASS)
        assert found.failed == one_by_one.count(Outcome.FAIL)
        assert found.indeterminate == one_by_one.count(Outcome.INDETERMINATE)
        assert found.cycles_failed == tuple(
            c for c, v in zip(cycles, one_by_one, strict=True) if v is Outcome.FAIL
        )
        assert found.cycles_indeterminate == tuple(
            c for c, v in zip(cycles, one_by_one, strict=True) if v is Outcome.INDETERMINATE
        )
        assert found.U == U_QUARTER.U
    guarded = judge_readings(values, cycles, *LIMITS, U_QUARTER)
    assert (guarded.passed, guarded.failed, guarded.indeterminate) == (2, 2, 4)
    assert guarded.zone == (-0.75, 0.75)
