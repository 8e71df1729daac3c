"""The arrival state machine, fed by hand: departure, arrival, stillness, one set per trip."""

from __future__ import annotations

import pytest

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig, ArrivalDetector

RES = 0.001
CONFIG = ArrivalConfig(band=0.1, still=2, settle=0.2, timeout=1.0)


def feed_all(detector, samples, dt=0.02, t0=0.0):
    """Feed ``samples`` (a list of {channel: value}) one poll every ``dt``; all events."""
    events = []
    t = t0
    for sample in samples:
        for channel, value in sample.items():
            events.extend(detector.feed(channel, value, t, (channel, value, round(t, 6))))
        t += dt
    return events, t


def at(value, n):
    return [{"x": value, "y": value}] * n


def test_a_trip_away_and_back_gives_one_set_after_stillness() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    samples = at(0.0, 10) + at(-9.5, 10) + [{"x": 0.02, "y": 0.015}] * 3 + at(0.001, 30)
    events, _ = feed_all(detector, samples)
    kinds = [e.kind for e in events]
    assert kinds == ["departed", "returned", "settled"]
    settled = events[-1]
    # Both channels' readings in the set are at rest, and the set came a settle time after
    # the robot stopped moving (the overshoot readings at t 0.40-0.44).
    assert {c: r[1] for c, r in settled.readings.items()} == {"x": 0.001, "y": 0.001}
    assert settled.t == pytest.approx(0.46 + 0.2, abs=0.021)
    assert settled.t_arrived == pytest.approx(0.40)


def test_nothing_while_at_the_fixture_and_nothing_while_away() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    events, _ = feed_all(detector, at(0.0, 100))
    assert events == []  # no departure: a still robot at the fixture is not a cycle
    events, _ = feed_all(detector, at(-9.5, 100), t0=2.0)
    assert [e.kind for e in events] == ["departed"]  # still at free travel is no arrival


def test_one_departure_gives_at_most_one_set() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    events, _ = feed_all(detector, at(0.0, 5) + at(-9.5, 5) + at(0.0, 200))
    assert [e.kind for e in events].count("settled") == 1


def test_a_return_that_does_not_settle_is_reported_not_taken() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    hunting = [{"x": 0.0, "y": 0.005 * (-1) ** i} for i in range(80)]
    events, t = feed_all(detector, at(0.0, 5) + at(-9.5, 5) + hunting)
    kinds = [e.kind for e in events]
    assert "settled" not in kinds
    unsettled = [e for e in events if e.kind == "unsettled"]
    assert len(unsettled) == 1
    assert unsettled[0].channels == ("y",)
    assert "y was not still" in unsettled[0].message
    assert "no set was taken" in unsettled[0].message
    # Once the return is given up, the robot must leave again before a set is taken.
    events, _ = feed_all(detector, at(0.0, 40), t0=t)
    assert [e.kind for e in events] == []
    events, _ = feed_all(detector, at(-9.5, 5) + at(0.0, 40), t0=t + 1)
    assert [e.kind for e in events] == ["departed", "returned", "settled"]


def test_the_timeout_is_reported_by_the_clock_alone_when_readings_stop() -> None:
    detector = ArrivalDetector(("x",), RES, CONFIG)
    feed_all(detector, [{"x": 0.0}] * 3 + [{"x": -9.5}] * 3 + [{"x": 0.03}, {"x": 0.0}])
    assert detector.state == "returned"
    assert detector.tick(0.5) == []
    events = detector.tick(2.0)
    assert [e.kind for e in events] == ["unsettled"]
    assert events[0].channels == ("x",)


def test_a_gap_in_the_readings_is_no_proof_of_stillness() -> None:
    detector = ArrivalDetector(("x",), RES, CONFIG)
    feed_all(detector, [{"x": 0.0}] * 3 + [{"x": -9.5}] * 3 + [{"x": 0.0}])
    # One reading, then the next 0.3 s later: the settle time passed, but nothing was seen.
    assert detector.feed("x", 0.0, 0.5, None) == []
    assert detector.state == "returned"


def test_bouncing_in_and_out_of_the_band_is_reported_once_by_the_timeout() -> None:
    detector = ArrivalDetector(("x",), RES, CONFIG)
    bouncing = [{"x": 0.0}, {"x": 0.5}] * 40  # in and out of the band, never still
    events, _ = feed_all(detector, [{"x": 0.0}] * 3 + [{"x": -9.5}] * 3 + bouncing)
    kinds = [e.kind for e in events]
    assert "settled" not in kinds and kinds.count("unsettled") == 1
    (unsettled,) = [e for e in events if e.kind == "unsettled"]
    assert unsettled.t - unsettled.t_arrived > CONFIG.timeout  # reported once, by the timeout


def test_a_robot_back_but_moving_that_leaves_again_is_reported_and_departs() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    hunting = [{"x": 0.0, "y": 0.005 * (-1) ** i} for i in range(15)]  # 0.3 s, in the band
    events, _ = feed_all(detector, at(0.0, 3) + at(-9.5, 3) + hunting + at(-9.5, 3) + at(0.0, 20))
    kinds = [e.kind for e in events]
    assert kinds == ["departed", "returned", "unsettled", "departed", "returned", "settled"]
    unsettled = events[2]
    assert unsettled.channels == ("y",)
    assert "before it left again" in unsettled.message


def test_a_channel_without_readings_holds_the_arrival() -> None:
    detector = ArrivalDetector(("x", "y"), RES, CONFIG)
    events, _ = feed_all(detector, [{"x": 0.0}] * 3 + [{"x": -9.5}] * 3 + [{"x": 0.0}] * 30)
    assert [e.kind for e in events] == ["departed"]


def test_the_band_defaults_to_100_resolutions_about_the_centre() -> None:
    config = ArrivalConfig(settle=0.2, centre={"x": 0.375})
    detector = ArrivalDetector(("x",), 0.0001, config)
    assert detector.feed("x", 0.375 + 0.0099, 0.0, None) == []
    assert [e.kind for e in detector.feed("x", 0.375 + 0.0101, 0.02, None)] == ["departed"]


def test_reset_forgets_a_departure() -> None:
    detector = ArrivalDetector(("x",), RES, CONFIG)
    feed_all(detector, [{"x": -9.5}] * 3)
    assert detector.state == "away"
    detector.reset()
    events, _ = feed_all(detector, [{"x": 0.0}] * 30, t0=1.0)
    assert events == []


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"band": 0}, "band"),
        ({"still": 0}, "stillness"),
        ({"settle": 0}, "settle time"),
        ({"settle": 2, "timeout": 1}, "longer than the settle time"),
    ],
)
def test_impossible_parameters_are_refused_with_a_sentence(kwargs, words) -> None:
    with pytest.raises(StationError, match=words):
        ArrivalConfig(**kwargs)


def test_a_settled_return_hands_over_its_trace_from_the_approach_to_the_set() -> None:
    detector = ArrivalDetector(("x", "y"), RES, ArrivalConfig(band=0.1, settle=0.2, trace=100))
    approach = [{"x": v, "y": v} for v in (-9.5, -5.0, -1.0, -0.3)]
    samples = at(0.0, 10) + at(-9.5, 10) + approach + [{"x": 0.02, "y": 0.015}] * 3 + at(0.0, 30)
    events, _ = feed_all(detector, samples)
    settled = events[-1]
    assert settled.kind == "settled"
    trace = settled.trace
    assert trace is not None and trace.channels == ("x", "y") and trace.every == 1
    # The approach's last rows (the free travel, then the ramp) open it, 8 with the arrival's.
    assert trace.rows[:7] == ((-9.5, -9.5),) * 4 + tuple((v, v) for v in (-5.0, -1.0, -0.3))
    assert trace.rows[7] == (0.02, 0.015) and trace.arrived == pytest.approx(0.48)
    # A row per poll (both channels read), until the set was taken (its poll's x decided it,
    # before y made the row whole).
    assert trace.t[-1] == pytest.approx(settled.t - 0.02)
    assert all(b - a == pytest.approx(0.02) for a, b in zip(trace.t, trace.t[1:], strict=False))
    assert trace.rows[-1] == (0.0, 0.0)


def test_a_long_trace_is_decimated_to_its_bound_and_says_so() -> None:
    config = ArrivalConfig(band=0.1, settle=0.2, timeout=20.0, trace=20)
    detector = ArrivalDetector(("x",), RES, config)
    ringing = [{"x": 0.01 * (-1) ** i} for i in range(100)]  # 2 s of swinging in the band
    events, _ = feed_all(
        detector, [{"x": 0.0}] * 5 + [{"x": -9.5}] * 5 + ringing + [{"x": 0.0}] * 30
    )
    trace = events[-1].trace
    assert trace is not None and len(trace.rows) <= 20
    # 8 + 100 + about 11 rows came: every 8th kept, so 0.16 s apart, the return whole.
    assert trace.every == 8
    assert all(b - a == pytest.approx(0.16) for a, b in zip(trace.t, trace.t[1:], strict=False))
    # From 7 rows before the arrival at 0.2 s to within a kept interval of the set.
    assert trace.t[0] == pytest.approx(0.06) and trace.t[-1] >= events[-1].t - 0.16


def test_a_return_that_does_not_settle_leaves_no_trace_for_the_next() -> None:
    config = ArrivalConfig(band=0.1, settle=0.2, timeout=1.0, trace=100)
    detector = ArrivalDetector(("x",), RES, config)
    hunting = [{"x": 0.005 * (-1) ** i} for i in range(80)]
    trip = [{"x": 0.0}] * 5 + [{"x": -9.5}] * 5
    events, t = feed_all(detector, trip + hunting)
    assert [e.kind for e in events] == ["departed", "returned", "unsettled"]
    events, _ = feed_all(detector, [{"x": -9.5}] * 5 + [{"x": 0.0}] * 20, t0=t)
    trace = events[-1].trace
    assert events[-1].kind == "settled" and trace is not None
    assert max(abs(row[0]) for row in trace.rows[8:]) == 0.0  # none of the hunting return's


def test_a_trace_bound_too_small_to_hold_the_approach_is_refused() -> None:
    with pytest.raises(StationError, match="trace"):
        ArrivalConfig(trace=5)
