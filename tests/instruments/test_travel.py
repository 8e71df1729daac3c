"""The plungers' stop told from the robot at the fixture (issue 27, finding 0).

A robot away from the fixture leaves its indicators at their free-travel stop, perfectly still:
a zero "when the readings are still" zeroed them there, and every later cycle then read
+0.0000. :class:`TravelWatch` learns the stop from the robot's round trip and says when the
robot rests at the fixture. These tests feed it the simulated robot's own motion (a pure
function of time) from ten phases of its cycle: no wall clock.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig, ArrivalDetector
from station.instruments.motion import CycleMotion
from station.instruments.travel import SlidingWindow, TravelWatch

RES = 0.0001
BAND = 100 * RES
PERIOD = 2.0
POLL = 0.1
SETTLE = 0.4
FREE = -0.375
REST = {"x": 0.0003, "y": -0.0002, "z": 0.0001}
MOTION = CycleMotion(PERIOD, FREE, 20 * RES)


def watch(**options) -> TravelWatch:
    channels = options.pop("channels", "xyz")
    return TravelWatch(
        dict.fromkeys(channels, RES),
        dict.fromkeys(channels, BAND),
        still=2,
        settle=SETTLE,
        **options,
    )


def shown(channel: str, t: float) -> float:
    """What the simulated indicator shows at ``t``, rounded to the gauge's step (the rest is
    the same every cycle here: the watch needs no robot error to tell rest from stop)."""
    rest = REST[channel]
    return round(MOTION.position(channel, t, rest, rest) / RES) * RES


@pytest.mark.parametrize("phase", [k / 10 for k in range(10)])
def test_from_every_phase_the_robot_counts_as_at_the_fixture_only_while_it_rests_there(
    phase: float,
) -> None:
    travel = watch()
    start = phase * PERIOD
    first = None
    visits = 0
    was_at_fixture = False
    t = start
    while t < start + 3 * PERIOD:
        for channel in "xyz":
            travel.feed(channel, shown(channel, t), t)
        at_fixture = travel.at_fixture()
        if at_fixture:
            first = t if first is None else first
            # Whenever it says so, every indicator shows the rest position, never the stop.
            stage = MOTION.stage(t)[1]
            assert all(abs(shown(c, t) - REST[c]) <= 2 * RES for c in "xyz"), (t, stage)
        visits += at_fixture and not was_at_fixture
        was_at_fixture = at_fixture
        t = round(t + POLL, 6)
    assert first is not None, "never at the fixture in three round trips"
    # Once the stop is known, every later rest at the fixture is seen as one.
    assert visits >= 2, visits
    # Within one round trip and a settle time of the start, whatever the phase.
    assert first - start <= PERIOD + 2 * SETTLE, first - start
    assert travel.stops() == pytest.approx(dict.fromkeys("xyz", FREE))


def test_still_readings_without_a_round_trip_never_count_as_at_the_fixture() -> None:
    """Still at the stop or still at the fixture look alike: neither is trusted alone."""
    for level in (FREE, 0.0):
        travel = watch()
        for k in range(50):
            for channel in "xyz":
                travel.feed(channel, level, k * POLL)
        assert not travel.at_fixture()
        assert "not known yet" in travel.waiting_sentence()


def test_a_stated_stop_lets_a_robot_stopped_at_the_fixture_be_zeroed_at_once() -> None:
    travel = watch(free_travel=dict.fromkeys("xyz", FREE))
    for k in range(6):
        for channel in "xyz":
            travel.feed(channel, REST[channel], k * POLL)
    assert travel.at_fixture()
    stopped = watch(free_travel=dict.fromkeys("xyz", FREE))
    for k in range(6):
        for channel in "xyz":
            stopped.feed(channel, FREE, k * POLL)
    assert not stopped.at_fixture()
    assert "rest at the free-travel stop" in stopped.waiting_sentence()


def test_an_indicator_that_counts_the_other_way_has_its_stop_high() -> None:
    travel = watch(side="high", channels="x")
    levels = [0.0] * 8 + [0.375] * 8 + [0.0001] * 8
    for k, level in enumerate(levels):
        travel.feed("x", level, k * POLL)
    assert travel.stop("x") == pytest.approx(0.375)
    assert travel.at_fixture()
    with pytest.raises(StationError, match="'low' or 'high'"):
        watch(side="sideways")


def test_a_set_at_the_stop_is_named_and_a_device_zero_moves_the_stop_with_it() -> None:
    travel = watch(free_travel={"x": FREE, "y": FREE, "z": FREE})
    assert travel.at_stop({"x": FREE + RES, "y": 0.0, "z": FREE}) == ("x", "z")
    travel.shift("x", 0.01)  # the device zeroed itself at +0.01: it now sends 0.01 less
    assert travel.stop("x") == pytest.approx(FREE - 0.01)


def test_two_agreeing_readings_far_apart_are_no_stillness() -> None:
    """Under load (or at a slow push rate) two readings half a second apart may both catch a
    turning point of the settling swing: the arrival trigger must not take that as a rest
    (finding 10: a set taken 19 counts off the rest)."""
    config = ArrivalConfig(band=BAND, still=2, settle=SETTLE, timeout=3.0)
    detector: ArrivalDetector[str] = ArrivalDetector(["x"], RES, config)
    events = []
    trace = [(0.0, 0.0), (0.1, 0.0), (0.2, -0.3), (0.3, -0.3)]  # at rest, then away
    trace += [(1.0, 0.0019), (1.21, 0.0019), (1.42, 0.0019)]  # back: sparse, agreeing
    for t, value in trace:
        events += detector.feed("x", value, t, f"{value}@{t}")
    assert "settled" not in [e.kind for e in events]
    # Dense readings of a true rest do settle.
    for k in range(1, 7):
        t = 1.42 + k * POLL
        events += detector.feed("x", 0.0, t, f"0@{t}")
    assert [e.kind for e in events].count("settled") == 1


def test_a_return_seen_too_rarely_is_reported_with_the_reading_rate() -> None:
    config = ArrivalConfig(band=BAND, still=2, settle=SETTLE, timeout=2.0)
    detector: ArrivalDetector[str] = ArrivalDetector(["x"], RES, config)
    events = []
    for t, value in [(0.0, 0.0), (0.1, -0.3), (0.2, -0.3)]:
        events += detector.feed("x", value, t, "")
    t = 1.0
    while t < 4.0:
        events += detector.feed("x", 0.0, t, "")
        t += 0.5
    unsettled = [e for e in events if e.kind == "unsettled"]
    assert unsettled, [e.kind for e in events]
    assert "too rarely" in unsettled[0].message
    assert math.isclose(config.settle / 2, 0.2)


@given(st.lists(st.tuples(st.floats(0.0, 0.3), st.integers(-5, 5)), min_size=1, max_size=60))
def test_the_sliding_window_agrees_with_a_plain_recount(steps) -> None:
    """Spread, mean and gaps kept in O(1) per reading equal a recount of the window."""
    window = SlidingWindow(span=0.4, max_gap=0.2)
    kept: list[tuple[float, float]] = []
    t = 0.0
    for step, count in steps:
        t += step
        value = count * RES
        window.append(t, value)
        kept.append((t, value))
        while len(kept) >= 2 and kept[1][0] <= t - 0.4 + 1e-9:
            kept.pop(0)
        values = [v for _, v in kept]
        assert window.values() == kept
        assert window.spread() == pytest.approx(max(values) - min(values), abs=1e-12)
        assert window.mean() == pytest.approx(sum(values) / len(values), abs=1e-12)
        gaps = [b[0] - a[0] for a, b in zip(kept, kept[1:], strict=False)]
        assert window.gapless() == all(gap <= 0.2 + 1e-9 for gap in gaps)


def test_a_fixture_placed_again_with_another_preload_teaches_no_stop() -> None:
    """Two fixtures placed five times: each placement's cube presses the plungers a few
    hundredths deeper or shallower (more than the band) with no trip to the stop between. The
    CI's demo learned a "stop" from such a shift and refused the fifth placement's zero; less
    than half the cube's deflection is no round trip."""
    travel = watch(depth=0.375 / 2)
    t = 0.0
    for preload in (0.03, -0.04, 0.02, 0.045, -0.038):
        for _ in range(10):
            travel.feed("y", preload, t)
            t = round(t + POLL, 6)
    assert travel.stops() == {}
    assert travel.at_stop({"y": -0.038}) == ()
    # A real round trip, to the stop and back, is still learned.
    for value in (FREE,) * 10 + (-0.038,) * 10:
        travel.feed("y", value, t)
        t = round(t + POLL, 6)
    assert travel.stops() == pytest.approx({"y": FREE})
