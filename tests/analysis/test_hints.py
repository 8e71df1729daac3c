"""Verdict hints: each fires on its condition and names the channel and the figure."""

from __future__ import annotations

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.summary import AnalysisConfig, analyze
from station.analysis.zeros import ZeroDraw

LIMITS = SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0)


def hints(values, **config) -> tuple[str, ...]:
    settings = dict(default_limits=LIMITS, resolution=0.0001, unit="in")
    settings.update(config)
    return analyze({"x": np.asarray(values, dtype=float)}, AnalysisConfig(**settings)).hints


def noise(n=30, sd=1e-4, seed=4):
    return np.round(np.random.default_rng(seed).normal(0, sd, n), 4)


def test_table_2_1_raises_no_hint(table_2_1):
    assert hints(table_2_1) == ()


def test_strong_skew_points_at_the_control_system():
    values = np.concatenate([np.zeros(20), [0.0001] * 5, [0.0002, 0.0003, 0.0005, 0.0008]])
    (hint,) = [h for h in hints(values) if "skewness" in h]
    assert hint.startswith("x: skewness a1 = +")
    assert "control system" in hint and "right" in hint


def test_mild_skew_raises_no_skew_hint(table_2_1):
    assert not [h for h in hints(table_2_1) if "skewness" in h]


def test_a_clear_offset_points_at_inverse_kinematics_or_temperature():
    values = noise() + 0.0002
    (hint,) = [h for h in hints(values) if "off nominal" in h]
    assert hint.startswith(f"x: the average is {values.mean():+.3g} in off nominal")
    assert "inverse kinematics" in hint and "temperature" in hint


def test_an_offset_within_chance_raises_no_hint():
    values = noise(seed=9)
    values = values - values.mean() + 0.00001
    assert not [h for h in hints(values) if "off nominal" in h]


def test_cp_met_but_cpk_not_is_a_shift():
    values = noise(sd=1e-4, seed=1) + 0.0008  # Cp about 3, Cpk below 1
    (hint,) = [h for h in hints(values) if "shifted" in h]
    assert "Cp = " in hint and "Cpk = " in hint and hint.startswith("x:")


def test_a_rule_alarm_asks_to_look_at_the_pattern():
    values = noise()
    values[20] = 0.0009
    (hint,) = [h for h in hints(values) if "pattern" in h]
    assert "report rule 1 (a point beyond the control limits) at cycle 21" in hint


def test_a_tolerance_under_ten_gauge_steps_means_the_gauge_is_too_coarse():
    narrow = SpecLimits(lsl=-0.0004, usl=0.0004)
    (hint,) = [h for h in hints(noise(), default_limits=narrow) if "too coarse" in h]
    assert "8 gauge steps" in hint and hint.startswith("x:")
    assert not [h for h in hints(noise()) if "too coarse" in h]


def test_an_offset_the_zero_explains_is_said_to_be_the_zeros():
    # Every reading carries the zero taken: +0.0002 off nominal with a zero known to ±0.0003
    # (2u) is no evidence against the robot (the one-reading zero of -0.0010).
    values = noise() + 0.0002
    (hint,) = [h for h in hints(values, zero_uncertainty={"x": 0.00015}) if "off nominal" in h]
    assert "within what the zero's uncertainty (±0.00030 in, rest to rest) explains" in hint
    assert "a zero is one rest of the robot" in hint
    assert "inverse kinematics" not in hint


def test_an_offset_beyond_the_zeros_uncertainty_still_points_at_the_robot():
    values = noise() + 0.0004
    (hint,) = [h for h in hints(values, zero_uncertainty={"x": 0.00003}) if "off nominal" in h]
    # At the figures' decimals like the average beside it, never in scientific notation.
    assert "beyond the zero's uncertainty (±0.00006 in, rest to rest)" in hint
    assert "inverse kinematics" in hint


def test_the_offset_hint_weighs_the_zeros_rest_to_rest_draw_not_its_within_rest_noise():
    """Issue 20: a zero of 5 readings at one rest of a still gauge has a tiny within-rest
    uncertainty, yet it is one draw of the robot's repeatability: Var(z) = s² − (1 − 1/m)·s_w²
    (here s_w = 0, so Var(z) = s²). An offset of 1.5 s is within that draw, not the robot's."""
    values = noise() + 0.00015
    sd = float(np.std(values, ddof=1))
    within_only = {"zero_uncertainty": {"x": 0.00003}}
    (blamed,) = [h for h in hints(values, **within_only) if "off nominal" in h]
    assert "inverse kinematics" in blamed  # the old comparison
    drawn = within_only | {"zero_draws": {"x": (ZeroDraw(readings=5, within_sd=0.0, weight=30),)}}
    (hint,) = [h for h in hints(values, **drawn) if "off nominal" in h]
    assert "inverse kinematics" not in hint
    assert f"(±{2 * sd:.5f} in, rest to rest)" in hint
    # A real offset well beyond the draw is still the robot's.
    (far,) = [h for h in hints(noise() + 0.0006, **drawn) if "off nominal" in h]
    assert "inverse kinematics" in far and "beyond the zero's uncertainty" in far
