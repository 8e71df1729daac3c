"""A simulated set-up the session follows (``track``) is played by the procedure's steps alone.

The order-dependent failure of ``test_gauge_check_through_the_tui`` (NOT CAPABLE, its mean near
0 instead of the block's 0.1 in): ``station simulate``'s still robot also moves to its next rest
after a pause in the polls (``return_gap``, 1 s). On a busy machine the screens between the
frames check and the zero took longer than that, so the bench left the surface plate before the
zero, the zero was taken on the gauge block, and every seating then read about 0. The clock here
is the test's: the pause is certain, not a matter of load.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator

import pytest
import serial

from station.commands import simulate
from station.instruments.protocols import get_protocol
from station.tui.instruments import DemoFixture, running_fixture, start_demo_fixture, track
from tests.clock import ManualClock

PROTOCOL = get_protocol("mitutoyo")
REFERENCE = 0.1
"""The gauge block's size: the bench reads it at every rest after the plate (rest 0)."""
RETURN_GAP = 1.0
"""``station simulate``'s default ``--return-gap``."""


@pytest.fixture
def bench(request) -> Iterator[tuple[object, ManualClock]]:
    """``station simulate --model gauge-bench`` (return gap 1 s, as the TUI test's), on a real
    pty, on the test's clock."""
    parser = argparse.ArgumentParser()
    simulate.add_parser(parser.add_subparsers())
    args = parser.parse_args(
        ["simulate", "--protocol", "mitutoyo", "--model", "gauge-bench", "--reference", "0.1"]
    )
    simulator = simulate.build_simulator(args)
    clock = ManualClock()
    simulator.clock = clock
    simulator.start_pty()
    try:
        yield simulator, clock
    finally:
        simulator.stop()


def poll(port: serial.Serial) -> float:
    """Ask the indicator for one reading, as the station's poll does; its value."""
    port.write(PROTOCOL.request("1"))
    frame = port.read_until(PROTOCOL.terminator)
    assert frame.endswith(PROTOCOL.terminator), f"no answer: {frame!r}"
    return PROTOCOL.parse(frame.rstrip(b"\r\n")).value


def polls_around_a_pause(simulator, clock: ManualClock) -> tuple[float, float]:
    """A reading, a pause of ten return gaps in the polls, and another reading."""
    with serial.serial_for_url(simulator.url, timeout=10) as port:
        before = poll(port)
        clock.advance(10 * RETURN_GAP)
        after = poll(port)
    return before, after


def test_unfollowed_the_bench_moves_after_a_pause_in_the_polls(bench) -> None:
    """The control: nobody plays this robot, so the pause is the operator re-seating the block."""
    simulator, clock = bench
    assert simulator.return_gap == RETURN_GAP
    before, after = polls_around_a_pause(simulator, clock)
    assert before == pytest.approx(0.0, abs=0.001)  # the surface plate
    assert after == pytest.approx(REFERENCE, abs=0.001)  # the block


def test_followed_the_bench_stays_on_the_plate_however_long_the_polls_pause(bench) -> None:
    simulator, clock = bench
    fixture = track(DemoFixture(simulator.url, "mitutoyo", dict(simulator.channel_map), simulator))
    try:
        before, after = polls_around_a_pause(simulator, clock)
    finally:
        fixture.stop()
    assert before == pytest.approx(0.0, abs=0.001)
    assert after == pytest.approx(0.0, abs=0.001), "the pause moved a robot the steps play"
    assert simulator.rest == 0


def test_a_stale_fixture_stopped_again_leaves_the_new_one_on_its_path_followed() -> None:
    """The kernel hands a closed ``/dev/pts/N`` to the next pseudo-terminal opened: a second
    stop of the fixture that had it (a test's own stop, then its lab's) must not untrack the
    set-up that serves that path now."""
    stale = start_demo_fixture(1990)
    stale.stop()
    serving = start_demo_fixture(7)
    # The new set-up as it is found at the reused path.
    fresh = track(DemoFixture(stale.url, "mitutoyo", {"1": "x"}, serving.simulator))
    try:
        stale.stop()
        assert running_fixture(stale.url) is fresh
    finally:
        fresh.stop()
        serving.stop()
    assert running_fixture(stale.url) is None
