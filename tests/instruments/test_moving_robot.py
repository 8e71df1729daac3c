"""A moving simulated robot (``station simulate --cycle-period``) read by a real GaugeSet.

The simulator runs as a real subprocess on a real pseudo-terminal (or in-process where a test
needs its clock); the gauge set reads it continuously with the ``arrival`` trigger, zeroes it
from several readings and infers what its frames say.
"""

from __future__ import annotations

import re
import subprocess
import threading
import time

import pytest
from helpers import start_simulator, stop_simulator

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig
from station.instruments.gauge import GaugeSet, PortSpec
from station.instruments.motion import CycleMotion
from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator

PERIOD = 0.5
PATIENCE = 40 * PERIOD
"""How long a set may take to come: waits end on the set, so a generous bound costs nothing
when the machine is idle and lets a loaded one (a second job, coverage) catch up."""
SEED = 5
NOISE = 0.01
"""10 resolutions: every cycle's rest position is told apart from its neighbours'."""
MAP = {"1": "x", "2": "y", "3": "z"}
FAST_ARRIVAL = ArrivalConfig(band=0.1, still=2, settle=0.08, timeout=1.0)


def simulate(*extra: str) -> tuple[subprocess.Popen, str]:
    """``station simulate`` (Mitutoyo, x y z in mm at 0.001) as a subprocess; its URL."""
    return start_simulator(
        "--protocol", "mitutoyo", "--seed", str(SEED), "--noise", str(NOISE), *extra
    )


def rest_values(cycles: int) -> list[dict[str, float]]:
    """Where the subprocess's robot comes to rest in cycles 0..cycles-1 (the same model)."""
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=NOISE)), GaugeSpec(0.001))
    return [{c: model.value(c, k, SEED) for c in "xyz"} for k in range(cycles)]


def cycle_of(values: dict[str, float], within: float = 0.0011) -> int:
    """The cycle whose rest position ``values`` are (each channel within a resolution: the
    tail of the settling swing may still round one count off); fails when there is none."""
    for cycle, rest in enumerate(rest_values(30)):
        if all(abs(values[c] - rest[c]) <= within for c in rest):
            return cycle
    raise AssertionError(f"{values} is no rest position of the robot")


def arrival_set(url: str, **kwargs) -> GaugeSet:
    return GaugeSet(
        [PortSpec(url, get_protocol("mitutoyo"), MAP)],
        trigger="arrival",
        resolution=0.001,
        poll_interval=0.02,
        arrival=kwargs.pop("arrival", FAST_ARRIVAL),
        backoff=(0.05, 0.2),
        **kwargs,
    )


def test_arrival_takes_one_set_per_round_trip_at_rest_spaced_by_the_period() -> None:
    process, url = simulate("--cycle-period", str(PERIOD))
    events = []
    gauges = arrival_set(url, on_arrival=events.append)
    wanted = 4
    try:
        gauges.start()
        assert gauges.wait_connected(5.0)
        sets = []
        for _ in range(wanted):
            result = gauges.wait_set(PATIENCE)
            assert result is not None, f"no arrival set; state {gauges.arrival_state}"
            sets.append((result, list(events)))
        time.sleep(0.1)
        extra = gauges.wait_set(0.0)
    finally:
        gauges.stop()
        stop_simulator(process)
    assert extra is None  # the robot still at rest after its set: no second set
    values = [{c: r.value for c, r in result.readings.items()} for result, _ in sets]
    # Every set is a rest position, of consecutive cycles: none was taken while the robot was
    # away (-9.525), approaching or overshooting (20 resolutions past rest), or settling.
    cycles = [cycle_of(value) for value in values]
    assert cycles == list(range(cycles[0], cycles[0] + wanted)), values
    assert all(result.trigger == "arrival" and result.complete for result, _ in sets)
    times = [result.readings["x"].t_mono for result, _ in sets]
    gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
    # One period apart, give or take a settle window or two: under load a late poll restarts
    # the stillness a set waits for (readings more than half a settle time apart prove none).
    assert all(abs(gap - PERIOD) < 0.15 for gap in gaps), gaps
    # One departure before each set, and each set a settle time after its arrival.
    assert "unsettled" not in [event.kind for event in events]
    departures = [sum(e.kind == "departed" for e in seen) for _, seen in sets]
    assert [b - a for a, b in zip(departures, departures[1:], strict=False)] == [1] * (wanted - 1)
    for result, _ in sets:
        last_reading = max(r.t_mono for r in result.readings.values())
        assert last_reading - result.t_trigger >= FAST_ARRIVAL.settle


def test_a_return_that_hunts_is_reported_and_not_recorded() -> None:
    process, url = simulate("--cycle-period", str(PERIOD), "--hunt", "y=0.01", "--hunt-every", "2")
    events = []
    gauges = arrival_set(url, on_arrival=events.append)
    try:
        gauges.start()
        assert gauges.wait_connected(5.0)
        sets = [gauges.wait_set(PATIENCE) for _ in range(2)]
        deadline = time.monotonic() + PATIENCE
        while not any(e.kind == "unsettled" for e in events) and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        gauges.stop()
        stop_simulator(process)
    assert all(s is not None for s in sets)
    cycles = [cycle_of({c: r.value for c, r in s.readings.items()}) for s in sets]
    # Only the odd cycles settle: every second return hunts on y and is not a set.
    assert all(cycle % 2 == 1 for cycle in cycles), cycles
    assert cycles[1] - cycles[0] == 2
    unsettled = [e for e in events if e.kind == "unsettled"]
    assert unsettled, [e.kind for e in events]
    assert "y" in unsettled[0].channels
    assert re.match(r"The robot came back to the fixture but (\w, )*y\b", unsettled[0].message)
    assert "no set was taken" in unsettled[0].message


def test_a_zero_while_a_gauge_moves_is_refused_naming_it_then_taken_at_rest() -> None:
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=NOISE)), GaugeSpec(0.001))
    motion = CycleMotion(PERIOD, -9.525, 0.02, hunt={"z": 0.01}, hunt_every=1)
    simulator = Simulator(get_protocol("mitutoyo"), model, seed=SEED, motion=motion)
    url = simulator.start_pty()
    gauges = GaugeSet(
        [PortSpec(url, get_protocol("mitutoyo"), MAP)],
        trigger="poll",
        resolution=0.001,
        backoff=(0.05, 0.2),
    )
    try:
        gauges.start()
        assert gauges.wait_connected(5.0)
        # While cycle 1 is at rest z hunts; x and y are still.
        _wait_until(simulator, PERIOD + 0.01)
        with pytest.raises(StationError) as caught:
            gauges.zero(readings=6, settle=0.1, timeout=1.0, unit="mm")
        assert "z moves" in caught.value.message
        assert "x moves" not in caught.value.message and "y moves" not in caught.value.message
        assert gauges.zero_offsets() == dict.fromkeys("xyz", 0.0)  # nothing was zeroed
        # x and y alone, at rest: n readings each, their mean, their spread.
        _wait_until(simulator, 2 * PERIOD + 0.01)
        zeros = gauges.zero(["x", "y"], readings=6, settle=0.1, timeout=1.0, unit="mm")
    finally:
        gauges.stop()
        simulator.stop()
    rest = {c: simulator.rest_value(c, 2) for c in "xy"}
    for zero in zeros:
        assert zero.n >= 6 and zero.method == "software"
        assert zero.mean == pytest.approx(rest[zero.channel]) and zero.spread == 0.0
        assert zero.record()["n"] == zero.n


def test_a_moving_robot_cannot_be_zeroed_while_it_travels() -> None:
    process, url = simulate("--cycle-period", "0.3")
    gauges = GaugeSet(
        [PortSpec(url, get_protocol("mitutoyo"), MAP)], resolution=0.001, backoff=(0.05, 0.2)
    )
    try:
        gauges.start()
        assert gauges.wait_connected(5.0)
        # A 0.4 s window always holds some of the robot's travel (0.105 s of every 0.3 s
        # is at rest): every channel moves.
        with pytest.raises(StationError, match=r"Could not zero: x moves .*; y moves .*; z moves"):
            gauges.zero(readings=10, settle=0.4, timeout=1.0)
    finally:
        gauges.stop()
        stop_simulator(process)


def test_frames_of_a_mm_simulator_refuse_an_inch_session_naming_both() -> None:
    process, url = simulate()
    gauges = GaugeSet(
        [PortSpec(url, get_protocol("mitutoyo"), MAP)],
        unit="in",
        resolution=0.0001,
        backoff=(0.05, 0.2),
    )
    try:
        gauges.start()
        assert gauges.wait_connected(5.0)
        sentence = gauges.check_frames("in", 0.0001, readings=5, timeout=2.0)
        agrees = gauges.check_frames("mm", 0.001, readings=1, timeout=2.0)
    finally:
        gauges.stop()
        stop_simulator(process)
    assert sentence == (
        "the gauges send steps of 0.001, which is mm on this protocol; "
        "the session is in inches at 0.0001"
    )
    assert agrees == ""


def _wait_until(simulator: Simulator, t: float) -> None:
    """Sleep until ``t`` seconds of the simulator's motion have passed."""
    remaining = simulator.motion_t0 + t - time.monotonic()
    if remaining > 0:
        threading.Event().wait(remaining)


def test_a_pushing_gauge_paces_the_arrival_trigger_and_states_its_unit() -> None:
    """U-WAVE pushes by itself (no polls) and its frames say inches: the arrival trigger works
    on the stream alone, and the frames refuse a session in mm."""
    model = FixtureModel(
        dict.fromkeys("xy", AxisModel(noise=0.001)), GaugeSpec(0.0001, -0.5, 0.5, "in")
    )
    motion = CycleMotion(PERIOD, -0.375, 0.002)
    simulator = Simulator(get_protocol("uwave"), model, seed=SEED, push_rate=50, motion=motion)
    url = simulator.start_tcp(0)
    gauges = GaugeSet(
        [PortSpec(url, get_protocol("uwave"), {"1": "x", "2": "y"})],
        trigger="arrival",
        unit="in",
        resolution=0.0001,
        arrival=ArrivalConfig(settle=0.06, timeout=1.0),
        backoff=(0.05, 0.2),
    )
    try:
        gauges.start()
        assert gauges.wait_connected(5.0) and simulator.wait_client(5.0)
        sets = [gauges.wait_set(PATIENCE) for _ in range(2)]
        refused = gauges.check_frames("mm", 0.0001, readings=3)
    finally:
        gauges.stop()
        simulator.stop()
    assert all(s is not None and s.complete for s in sets)
    for result in sets:
        for channel, reading in result.readings.items():
            assert reading.frame_unit == "in"
            cycle = simulator.motion.stage(reading.t_mono - simulator.motion_t0)[0]
            # Taken at rest (or in the last, still, part of the settling swing before it,
            # which may round one count off).
            rests = (simulator.rest_value(channel, cycle), simulator.rest_value(channel, cycle + 1))
            assert min(abs(reading.value - rest) for rest in rests) <= 0.00011, reading
    assert refused == "the gauges send steps of 0.0001 in; the session is in mm at 0.0001"


def test_a_zero_on_a_port_that_is_down_says_so(tmp_path) -> None:
    gauges = GaugeSet(
        [PortSpec(str(tmp_path / "no-such-port"), get_protocol("mitutoyo"), MAP)],
        backoff=(0.05, 0.2),
    )
    try:
        gauges.start()
        with pytest.raises(StationError, match=r"Could not zero x, y, z: the port .* (is|not)"):
            gauges.zero(readings=3, settle=0.05, timeout=0.2)
    finally:
        gauges.stop()
