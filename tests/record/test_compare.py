"""``station compare``: a known shift of y is reported, x and z are not (at the stated error
rate, over many seeds), also between separately zeroed sessions of the simulator; Holm's call is
said; different procedures or units are refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.analysis.zeros import ZeroDraw, zero_variance, zeros_variance
from station.cli import main
from station.instruments.simulator import AxisModel, GaugeSpec, fixture_model
from station.record.compare import (
    HolmCall,
    compare_axis,
    compare_channels,
    holm,
    holm_calls,
    hotelling_t2,
)
from station.session.header import zero_draws

from .conftest import simulated_session, write_accuracy, write_repeatability, write_simulated

SIGMA = 0.0002
SHIFT = 0.0003  # 1.5 sigma on 30 readings a side: Welch's power is close to 1
RESOLUTION = 0.0001
SEEDS = 200


def simulated(rng, shift_y=0.0):
    def axis(bias):
        return np.round((bias + rng.normal(0, SIGMA, 30)) / RESOLUTION) * RESOLUTION

    return {"x": axis(0.0), "y": axis(shift_y), "z": axis(0.0)}


def test_a_known_y_shift_is_found_and_x_z_are_not_at_the_stated_rate():
    found_y = false_alarms = spread_alarms = 0
    for seed in range(SEEDS):
        rng = np.random.default_rng(seed)
        before, after = simulated(rng), simulated(rng, SHIFT)
        result = {r.channel: r for r in compare_channels(before, after, confidence=0.95)}
        found_y += result["y"].shifted
        false_alarms += result["x"].shifted or result["z"].shifted
        spread_alarms += any(r.spread_changed for r in result.values())
        low, high = result["y"].shift_low, result["y"].shift_high
        assert result["y"].shift == pytest.approx(after["y"].mean() - before["y"].mean())
        assert low < result["y"].shift < high
    # Holm holds the family-wise rate at 5 %: allow three standard errors over 200 seeds.
    bound = 0.05 + 3 * np.sqrt(0.05 * 0.95 / SEEDS)
    assert found_y / SEEDS >= 0.97
    assert false_alarms / SEEDS <= bound
    assert spread_alarms / SEEDS <= bound


def test_the_shift_interval_covers_the_true_shift_at_its_confidence():
    covered = 0
    for seed in range(SEEDS):
        rng = np.random.default_rng(1000 + seed)
        a, b = rng.normal(0, 1, 25), rng.normal(0.5, 2, 40)
        result = compare_axis("x", a, b, confidence=0.9)
        covered += result.shift_low <= 0.5 <= result.shift_high
    assert abs(covered / SEEDS - 0.9) <= 3 * np.sqrt(0.9 * 0.1 / SEEDS)


def test_holm_steps_down():
    assert holm([0.01, 0.04, 0.03], 0.05) == [True, False, False]
    assert holm([0.01, 0.02, 0.04], 0.05) == [True, True, True]
    assert holm([0.2, 0.001], 0.05) == [False, True]


def test_hotelling_sees_a_3d_shift_and_not_noise():
    rng = np.random.default_rng(5)
    a = rng.normal(0, 1, (30, 3))
    assert hotelling_t2(a, rng.normal(0, 1, (30, 3))).p > 0.01
    shifted = hotelling_t2(a, rng.normal(0, 1, (30, 3)) + [0, 1, 0])
    assert shifted.p < 0.001 and shifted.shift[1] == pytest.approx(1, abs=0.5)


def test_compare_command_on_two_sessions(sessions, capsys):
    # Each session records its own zero: a shift of y must stand out beyond what two zeros of
    # a σ 0.0002 robot differ by (about σ·√2), so y moves 6 σ here.
    before = write_repeatability(sessions, seed=11, reject=None, alarm=False)
    after = write_repeatability(sessions, seed=12, bias={"y": 0.0012}, reject=None, alarm=False)
    assert main(["compare", str(before), str(after)]) == 0
    out = capsys.readouterr().out
    assert "y moved +0.001" in out and "the change between the sessions moved y" in out
    assert "x did not move detectably" in out and "z did not move detectably" in out
    x = next(line for line in out.splitlines() if line.startswith("x did not move"))
    assert "the shift measures the zeros more than the robot" in x
    assert "spread unchanged" in out
    assert "The 3-D mean moved" in out and "RP went from" in out

    assert main(["compare", str(before), str(after), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert [document["channels"][a]["shifted"] for a in "xyz"] == [False, True, False]
    assert document["hotelling"]["p"] < 0.001
    assert document["channels"]["y"]["shift_ci"][0] > 0


def test_compare_refuses_different_procedures_and_units(sessions, capsys):
    inch = write_repeatability(sessions, seed=1)
    assert main(["compare", str(inch), str(write_accuracy(sessions))]) == 2
    assert "only sessions of one procedure can be compared" in capsys.readouterr().err
    metric = write_repeatability(sessions, seed=2, robot="R-mm", unit="mm", resolution=0.001)
    assert main(["compare", str(inch), str(metric)]) == 2
    assert "only sessions in one unit can be compared" in capsys.readouterr().err


def test_holm_calls_give_each_threshold_and_where_the_procedure_stopped():
    calls = holm_calls([0.03, 0.031, 0.001], 0.05)
    assert [c.rejected for c in calls] == [False, False, True]
    assert calls[2].threshold == pytest.approx(0.05 / 3)
    assert calls[0].threshold == pytest.approx(0.025) and not calls[0].stopped
    assert calls[1].threshold == pytest.approx(0.05) and calls[1].stopped


def test_the_sentence_says_when_holms_correction_made_the_call():
    rng = np.random.default_rng(10)
    a = {c: rng.normal(0, 1, 30) for c in "xyz"}
    b = {c: rng.normal(0, 1, 30) for c in "xyz"}
    result = {r.channel: r for r in compare_channels(a, b)}
    x = result["x"]
    assert 0.05 / 3 < x.shift_p < 0.05  # significant alone, not over three channels
    assert not x.shifted
    assert "x did not move detectably" in x.sentence
    assert f"p = {x.shift_p:.3f}, above Holm's threshold 0.017 for 3 channels)" in x.sentence
    assert "Holm" not in result["y"].sentence  # p above 0.05: Holm decided nothing
    alone = compare_axis("x", a["x"], b["x"])
    assert alone.shifted and "Holm" not in alone.sentence
    stopped = compare_axis("x", a["x"], b["x"], shifted=HolmCall(False, 0.05, 2, stopped=True))
    assert "Holm's procedure for 2 channels stopped at a smaller p" in stopped.sentence


def test_the_zero_of_one_rest_adds_the_robots_own_scatter_to_the_mean():
    # A still gauge (no scatter at rest): the zero is one rest, Var(z) = σ².
    assert zero_variance(2.0, readings=5, within_sd=0.0) == pytest.approx(4.0)
    assert zero_variance(2.0, readings=5) == pytest.approx(4.0)
    # All the scatter is the gauge's: five readings average it down to σ²/5.
    assert zero_variance(2.0, readings=5, within_sd=2.0) == pytest.approx(0.8)
    assert zero_variance(2.0, readings=5, within_sd=9.0) == pytest.approx(0.8)
    assert zero_variance(2.0, readings=1, within_sd=2.0) == pytest.approx(4.0)
    assert zero_variance(0.0, readings=5) == 0.0
    # Two zeros under 10 and 30 readings: (1/4)² and (3/4)² of their variances.
    zeros = [ZeroDraw(5, 0.0, weight=10), ZeroDraw(5, 0.0, weight=30)]
    assert zeros_variance(2.0, zeros) == pytest.approx(4.0 * (1 / 16 + 9 / 16))
    assert zeros_variance(2.0, []) == 0.0


def test_zero_draws_read_the_zero_events_and_the_readings_under_them():
    events = [
        {"type": "zero", "channels": {"x": {"method": "software", "n": 3, "values": [1, 2, 3]}}},
        {"type": "zero", "channels": {"x": {"method": "software", "n": 3, "values": [1, 1, 1]}}},
        {"type": "reading", "channels": {"x": {"value": 0.1}, "y": {"value": 0.2}}},
        {"type": "reading", "channels": {"x": {"value": 0.1}, "y": {"value": 0.2}}},
        {"type": "zero", "channels": {"x": {"method": "device", "n": 5, "values": [0] * 5}}},
        {"type": "reading", "channels": {"x": {"value": 0.1}}},
    ]
    draws = zero_draws(events)
    # The first zero had no reading under it; y was never zeroed (the gauge's own values).
    assert draws == {
        "x": (ZeroDraw(3, 0.0, weight=2), ZeroDraw(1, None, weight=1)),
    }


def _zeroed_pair(model_a, model_b, seed):
    """Two sessions of the simulator, each zeroed at its own first rest as the runner does:
    their readings and the zeros they were taken under."""
    sessions = []
    for model, run in ((model_a, 2 * seed), (model_b, 2 * seed + 1)):
        zeros, readings = simulated_session(model, run)
        values = {c: [r["channels"][c]["value"] for r in readings] for c in model.channels}
        events = [{"type": "zero", **z} for z in zeros]
        events += [{"type": "reading", **r} for r in readings]
        sessions.append((values, zero_draws(events)))
    return sessions


GOOD_ROBOT = AxisModel(noise=0.00008)
"""A good robot at a 0.0001 in indicator that scatters 0.3 step at rest."""
INDICATOR = GaugeSpec(0.0001, -0.5, 0.5, "in", noise=0.00003)
ZEROED_SEEDS = 100


def test_separately_zeroed_sessions_of_an_unchanged_robot_call_no_shift():
    """Issue 20, item 5: each session's mean is minus its zero, one rest of the robot; Welch's
    test on the readings alone calls nearly every such pair moved. Counting the zeros, a shift
    is called in at most 5 % of seeds (Holm over x, y, z), and the 3-D test agrees."""
    model = fixture_model("xyz", axis=GOOD_ROBOT, gauge=INDICATOR)
    called = welch_called = hotelling_called = 0
    for seed in range(ZEROED_SEEDS):
        (a, zeros_a), (b, zeros_b) = _zeroed_pair(model, model, seed)
        result = compare_channels(a, b, zeros_a=zeros_a, zeros_b=zeros_b)
        called += any(r.shifted for r in result)
        assert all(r.separately_zeroed and r.zero_share > 0.5 for r in result)
        welch_called += any(r.shifted for r in compare_channels(a, b))
        columns = [np.column_stack([s[c] for c in "xyz"]) for s in (a, b)]
        h = hotelling_t2(*columns, [zeros_a[c] for c in "xyz"], [zeros_b[c] for c in "xyz"])
        hotelling_called += h.p <= 0.05
    assert called / ZEROED_SEEDS <= 0.05
    assert hotelling_called / ZEROED_SEEDS <= 0.05
    assert welch_called / ZEROED_SEEDS > 0.5  # what the readings alone said


def test_separately_zeroed_sessions_still_find_a_real_shift_of_y():
    """After the zero, session B's returns sit 0.0004 in higher in y than where its zero was
    taken (the simulator's offset reached by the first return; a constant offset of the robot
    would be zeroed away in each session and no comparison could see it)."""
    before = fixture_model("xyz", axis=GOOD_ROBOT, gauge=INDICATOR)
    moved_y = AxisModel(noise=0.00008, drift=0.0004, drift_tau=1e-6)
    after = fixture_model(
        "xyz", axis={"x": GOOD_ROBOT, "y": moved_y, "z": GOOD_ROBOT}, gauge=INDICATOR
    )
    found = others = 0
    for seed in range(ZEROED_SEEDS):
        (a, zeros_a), (b, zeros_b) = _zeroed_pair(before, after, seed)
        result = {r.channel: r for r in compare_channels(a, b, zeros_a=zeros_a, zeros_b=zeros_b)}
        found += result["y"].shifted
        others += result["x"].shifted or result["z"].shifted
    assert found / ZEROED_SEEDS >= 0.7  # most seeds (85 of these 100)
    assert others / ZEROED_SEEDS <= 0.05


def test_sessions_on_one_reference_keep_welchs_test():
    """Neither session zeroed the channel (both read the gauge's own reference): no zero term,
    and the shift's p is Welch's."""
    from scipy import stats

    rng = np.random.default_rng(3)
    a, b = rng.normal(0, 1, 30), rng.normal(0.4, 1.5, 25)
    result = compare_axis("x", a, b)
    assert not result.separately_zeroed and result.zero_share == 0.0
    assert result.shift_p == pytest.approx(stats.ttest_ind(b, a, equal_var=False).pvalue)
    assert "zero" not in result.sentence


def test_compare_command_on_separately_zeroed_simulated_sessions(sessions, capsys):
    model = fixture_model("xyz", axis=GOOD_ROBOT, gauge=INDICATOR)
    before, after = write_simulated(sessions, model, 1), write_simulated(sessions, model, 2)
    assert main(["compare", str(before), str(after), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    for axis in "xyz":
        channel = document["channels"][axis]
        assert channel["zeroed"] == "separately" and not channel["shifted"]
        assert channel["zero_share"] > 0.5 and all(u > 0 for u in channel["zero_u"])
        assert "the shift measures the zeros more than the robot" in channel["sentence"]
    assert document["hotelling"]["zeroed"] and document["hotelling"]["p"] > 0.05
