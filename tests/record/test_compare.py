"""``station compare``: a known shift of y is reported, x and z are not (at the stated error
rate, over many seeds); different procedures or units are refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.cli import main
from station.record.compare import compare_axis, compare_channels, holm, hotelling_t2

from .conftest import write_accuracy, write_repeatability

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
    before = write_repeatability(sessions, seed=11, reject=None, alarm=False)
    after = write_repeatability(sessions, seed=12, bias={"y": 0.0004}, reject=None, alarm=False)
    assert main(["compare", str(before), str(after)]) == 0
    out = capsys.readouterr().out
    assert "y moved +0.000" in out and "the change between the sessions moved y" in out
    assert "x did not move detectably" in out and "z did not move detectably" in out
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
