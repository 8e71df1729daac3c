"""The simulated robot's round trip as a pure function of time."""

from __future__ import annotations

import pytest

from station.errors import StationError
from station.instruments.motion import CycleMotion, default_free_travel

MOTION = CycleMotion(1.0, -9.525, 0.02)


def test_a_period_is_rest_departure_away_approach_settling_in_that_order() -> None:
    stages = [MOTION.stage(t / 100)[1] for t in range(100)]
    order = [s for i, s in enumerate(stages) if i == 0 or stages[i - 1] != s]
    assert order == ["at rest", "departing", "away", "approaching", "settling"]
    assert MOTION.stage(1.0)[:2] == (1, "at rest")
    assert MOTION.rest_window(3) == (3.0, 3.35)


def test_positions_rest_free_travel_overshoot_and_the_next_rest() -> None:
    rest, following = 0.0012, -0.0007
    assert MOTION.position("x", 0.2, rest, following) == rest
    assert MOTION.position("x", 0.6, rest, following) == -9.525
    # The approach ends past the next rest, in the direction of travel, by the overshoot.
    end_of_approach = MOTION.position("x", 0.85 - 1e-9, rest, following)
    assert end_of_approach == pytest.approx(following + 0.02, abs=1e-6)
    # The settling swing ends exactly on the next rest position.
    assert MOTION.position("x", 1.0 - 1e-9, rest, following) == pytest.approx(following, abs=1e-9)
    swing = [MOTION.position("x", 0.85 + k / 1000, rest, following) for k in range(150)]
    assert min(swing) < following < max(swing)  # it swings through, not creeps in


def test_a_hunting_axis_never_rests_on_its_hunting_returns_only() -> None:
    motion = CycleMotion(1.0, -9.525, 0.02, hunt={"y": 0.01}, hunt_every=2)
    at_rest_2 = [motion.position("y", 2.0 + k / 100, 0.0, 0.0) for k in range(30)]
    at_rest_3 = [motion.position("y", 3.0 + k / 100, 0.0, 0.0) for k in range(30)]
    assert max(at_rest_2) - min(at_rest_2) > 0.015
    assert at_rest_3 == [0.0] * 30
    assert [motion.position("x", 2.0 + k / 100, 0.0, 0.0) for k in range(30)] == [0.0] * 30


def test_free_travel_defaults_to_three_eighths_of_an_inch() -> None:
    assert default_free_travel("in") == -0.375
    assert default_free_travel("mm") == pytest.approx(-9.525)


@pytest.mark.parametrize(
    "kwargs", [{"period": 0}, {"dwell": 0.5, "away": 0.4}, {"hunt_every": 0}, {"depart": 0}]
)
def test_impossible_motions_are_refused(kwargs) -> None:
    values = {"period": 1.0, "free_travel": -1.0, "overshoot": 0.02, **kwargs}
    with pytest.raises(StationError):
        CycleMotion(**values)
