"""The simulated robot's round trip as a pure function of time."""

from __future__ import annotations

import math

import pytest

from station.errors import StationError
from station.instruments.motion import CycleMotion, Settling, default_free_travel

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


RINGING = Settling({"x": 0.03, "y": 0.04}, period=0.1, decay=0.05)
SECOND_ORDER = CycleMotion(1.0, -9.525, 0.0, settling=RINGING)
APPROACH_END = 0.85
"""The default fractions: the approach ends 0.85 of a period in, the settling follows."""


def test_a_second_order_arrival_rings_past_the_rest_by_its_overshoot_and_dies_down() -> None:
    rest, following = 0.0012, -0.0007
    # The first period starts at rest: nothing rings there.
    assert SECOND_ORDER.position("x", 0.2, rest, following) == rest
    # The approach ends on the next rest; its first swing peaks past it (away from the free
    # travel) by the overshoot, the axis without one stays on it.
    assert SECOND_ORDER.position("x", APPROACH_END, rest, following) == pytest.approx(following)
    peak = APPROACH_END + RINGING.first_peak
    assert SECOND_ORDER.position("x", peak, rest, following) == pytest.approx(following + 0.03)
    assert SECOND_ORDER.position("y", peak, rest, following) == pytest.approx(following + 0.04)
    assert SECOND_ORDER.position("z", peak, rest, following) == pytest.approx(following)
    # Half a period later it swings back, the envelope down by exp(-0.05 / 0.05).
    back = SECOND_ORDER.position("x", peak + 0.05, rest, following) - following
    assert back == pytest.approx(-0.03 * math.exp(-1.0))
    # It rings on into the next rest without a jump, and is still there a rest later.
    before = SECOND_ORDER.position("x", 1.0 - 1e-9, rest, following)
    after = SECOND_ORDER.position("x", 1.0 + 1e-9, following, rest)
    assert after == pytest.approx(before, abs=1e-6)
    assert SECOND_ORDER.position("x", 1.3, following, rest) == pytest.approx(following, abs=1e-9)


def test_the_settlings_last_exit_and_the_approachs_entry_are_where_the_band_is_crossed() -> None:
    radius = 0.005
    distance = RINGING.overshoot_distance("xyz")
    assert distance == pytest.approx(0.05)
    last = RINGING.last_outside(radius, "xyz")
    # Brute force at 1 µs: the ringing distance is outside the band just before and never after.
    taus = [k * 1e-6 for k in range(400_000)]
    outside = [tau for tau in taus if distance * abs(RINGING.shape(tau)) > radius]
    assert last == pytest.approx(outside[-1], abs=2e-6)
    # The approach of 9.525 comes within the band this long before it ends.
    travel = 9.525
    lead = SECOND_ORDER.entry_lead(radius, travel)
    at = APPROACH_END - lead
    assert travel - abs(SECOND_ORDER.position("x", at, 0.0, 0.0) - -9.525) == pytest.approx(
        radius, rel=1e-6
    )
    assert SECOND_ORDER.stabilisation_time(radius, travel, "xyz") == pytest.approx(lead + last)


@pytest.mark.parametrize("kwargs", [{"period": 0.0}, {"decay": -1.0}, {"overshoot": {"x": -1}}])
def test_an_impossible_settling_is_refused(kwargs) -> None:
    values = {"overshoot": {"x": 0.01}, **kwargs}
    with pytest.raises(StationError):
        Settling(**values)
