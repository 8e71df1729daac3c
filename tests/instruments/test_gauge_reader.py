"""The gauge reader against the simulator over real pseudo-terminals and loopback sockets."""

from __future__ import annotations

import queue
import threading
import time

import pytest
from waiting import wait_until

from station.errors import StationError
from station.instruments.gauge import GaugeSet, PortSpec
from station.instruments.motion import CycleMotion
from station.instruments.protocols import get_protocol, protocol_names
from station.instruments.reader import GaugeReader
from station.instruments.simulator import (
    AxisModel,
    Faults,
    GaugeSpec,
    Simulator,
    fixture_model,
)

FAST = (0.05, 0.2)
"""A short reconnect back-off so the suite stays quick."""

MULTI_CHANNEL = {"mitutoyo", "uwave", "idh", "ascii"}
"""Protocols whose frames carry the device channel: one port serves x, y and z."""


def make_sim(
    name: str, channels: str = "xyz", faults: Faults | None = None, seed: int = 7, **kwargs
) -> Simulator:
    """A simulator of ``name`` with a noisy fixture on ``channels``."""
    model = fixture_model(
        list(channels),
        axis=AxisModel(bias=0.01, noise=0.004, skew=2.0, drift=0.003, backlash=0.002),
        gauge=GaugeSpec(resolution=0.001),
    )
    return Simulator(get_protocol(name), model, faults, seed, **kwargs)


def start(sim: Simulator, transport: str) -> str:
    return sim.start_pty() if transport == "pty" else sim.start_tcp(0)


def station_map(sim: Simulator) -> dict[str, str]:
    return dict(sim.channel_map)


@pytest.mark.parametrize("transport", ["pty", "tcp"])
@pytest.mark.parametrize("name", protocol_names())
def test_captures_give_the_models_values_in_order(name: str, transport: str) -> None:
    channels = "xyz" if name in MULTI_CHANNEL else "x"
    sim = make_sim(name, channels)
    url = start(sim, transport)
    protocol = get_protocol(name)
    trigger = "poll" if protocol.polled else "push"
    gauges = GaugeSet([PortSpec(url, protocol, station_map(sim))], trigger=trigger, backoff=FAST)
    captures = 8
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        assert sim.wait_client(3.0)
        results = []
        for _ in range(captures):
            if trigger == "push":
                # Arm first, then press DATA: the set must be the press after the trigger.
                results.append(_push_capture(gauges, sim))
            else:
                results.append(gauges.capture(2.0))
    finally:
        gauges.stop()
        sim.stop()
    for k, result in enumerate(results):
        assert result.complete, result.message
        assert not result.duplicated
        for channel in channels:
            reading = result.readings[channel]
            assert reading.value == pytest.approx(sim.expected(channel, k), abs=1e-9)
            assert reading.raw.encode() in sim.sent[channel][k].frame
            assert reading.port == url
    assert [r.readings[channels[0]].t_mono for r in results] == sorted(
        r.readings[channels[0]].t_mono for r in results
    )


def _push_capture(gauges: GaugeSet, sim: Simulator):
    assert gauges.arm() == []
    sim.push()
    return gauges.wait_set(2.0)


@pytest.mark.parametrize("name", ["mitutoyo", "uwave"])
def test_stable_trigger_waits_for_a_settled_set(name: str) -> None:
    # The robot leaves the fixture and comes back with an overshoot and a settling swing; the
    # stable trigger asked while it moves takes the next set that has settled at rest.
    model = fixture_model(["x", "y"], axis=AxisModel(noise=0.01), gauge=GaugeSpec(0.001))
    motion = CycleMotion(1.0, -5.0, 0.05, dwell=0.35, depart=0.1, away=0.05, approach=0.2)
    sim = Simulator(
        get_protocol(name), model, seed=1, push_rate=0 if name == "mitutoyo" else 50, motion=motion
    )
    url = sim.start_pty()
    gauges = GaugeSet(
        [PortSpec(url, get_protocol(name), dict(sim.channel_map))],
        trigger="stable",
        resolution=0.001,
        stable_k=2,
        stable_ms=150,
        poll_interval=0.02,
        backoff=FAST,
    )
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        # Ask once the robot has left (the set at rest before it does not count).
        while motion.stage(time.monotonic() - sim.motion_t0)[1] == "at rest":
            time.sleep(0.005)
        result = gauges.capture(5.0)
    finally:
        gauges.stop()
        sim.stop()
    assert result.complete, result.message
    for channel in ("x", "y"):
        taken = result.readings[channel].value
        # Settled: within 2 resolutions of where the robot came to rest, not mid-travel.
        assert any(abs(taken - sim.rest_value(channel, c)) <= 0.002 + 1e-9 for c in (1, 2))
        assert taken in sim.sent_values(channel)


def test_stale_frames_from_before_the_trigger_are_never_taken() -> None:
    sim = make_sim("mitutoyo")
    url = sim.start_pty()
    gauges = GaugeSet([PortSpec(url, get_protocol("mitutoyo"), station_map(sim))], backoff=FAST)
    try:
        # Frames pushed before anyone listens sit in the pty buffer: old readings.
        sim.push(3)
        gauges.start()
        assert gauges.wait_connected(3.0)
        first = gauges.capture(2.0)
        reader = gauges.readers[0]
        read_before = reader.reading_count
        sim.stale_burst(3)  # old frames delivered late, between two captures
        # They must be in before the second trigger (else they would be new frames to it).
        assert wait_until(lambda: reader.reading_count >= read_before + 3)
        second = gauges.capture(2.0)
    finally:
        gauges.stop()
        sim.stop()
    assert first.complete and second.complete
    for channel in "xyz":
        assert first.readings[channel].value == pytest.approx(sim.expected(channel, 3))
        assert second.readings[channel].value == pytest.approx(sim.expected(channel, 4))


def test_push_set_reports_a_channel_that_sent_twice() -> None:
    sim = make_sim("uwave")
    url = sim.start_pty()
    sets = []
    gauges = GaugeSet(
        [PortSpec(url, get_protocol("uwave"), station_map(sim))],
        trigger="push",
        on_set=sets.append,
        backoff=FAST,
    )
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        time.sleep(0.05)
        sim._send_reading("1", can_be_silent=False)  # x, a second press before y and z came
        sim.push()
        result = gauges.wait_set(2.0)
    finally:
        gauges.stop()
        sim.stop()
    assert result is not None and result.complete
    assert result.duplicated == ("x",)
    assert result.readings["x"].value == pytest.approx(sim.expected("x", 0))
    assert "more than one reading from x" in result.message
    assert sets == [result]


def test_a_poll_without_answer_names_the_missing_channel() -> None:
    sim = make_sim("sylvac", "x", faults=Faults(silence_rate=1.0))
    url = sim.start_pty()
    gauges = GaugeSet([PortSpec(url, get_protocol("sylvac"), {"1": "x"})], backoff=FAST)
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        result = gauges.capture(0.3)
    finally:
        gauges.stop()
        sim.stop()
    assert not result.complete
    assert result.missing == ("x",)
    assert "no reading from x" in result.message


def test_three_cables_and_a_mix_of_ports() -> None:
    sims = {c: make_sim("sylvac", c, seed=i) for i, c in enumerate("xy")}
    mux = make_sim("idh", "zw", seed=9)
    specs = [PortSpec(sim.start_pty(), get_protocol("sylvac"), {"1": c}) for c, sim in sims.items()]
    specs.append(PortSpec(mux.start_tcp(0), get_protocol("idh"), {"1": "z", "2": "w"}))
    gauges = GaugeSet(specs, backoff=FAST)
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        results = [gauges.capture(2.0) for _ in range(3)]
    finally:
        gauges.stop()
        for sim in [*sims.values(), mux]:
            sim.stop()
    assert gauges.channels == ("x", "y", "z", "w")
    for k, result in enumerate(results):
        assert result.complete, result.message
        for channel, sim in [*sims.items(), ("z", mux), ("w", mux)]:
            assert result.readings[channel].value == pytest.approx(sim.expected(channel, k))


def test_a_channel_on_two_ports_is_refused() -> None:
    spec = PortSpec("/dev/null", get_protocol("sylvac"), {"1": "x"})
    with pytest.raises(StationError, match="served by two ports"):
        GaugeSet([spec, spec])


def test_zero_uses_the_device_command_or_a_software_offset() -> None:
    cdi = make_sim("cdi", "x")
    mitutoyo = make_sim("mitutoyo", "yz")
    gauges = GaugeSet(
        [
            PortSpec(cdi.start_pty(), get_protocol("cdi"), {"1": "x"}),
            PortSpec(mitutoyo.start_pty(), get_protocol("mitutoyo"), {"1": "y", "2": "z"}),
        ],
        backoff=FAST,
    )
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        zeros = gauges.zero()
        after = gauges.capture(2.0)
    finally:
        gauges.stop()
        cdi.stop()
        mitutoyo.stop()
    assert [(z.channel, z.method) for z in zeros] == [
        ("x", "device"),
        ("y", "software"),
        ("z", "software"),
    ]
    assert cdi.zero_requests == ["x"]
    # The device zeroed itself: its next reading is relative to what it showed at zero time.
    model_x = cdi.model.value("x", 1, cdi.seed) - cdi.model.value("x", 0, cdi.seed)
    assert after.readings["x"].value == pytest.approx(model_x, abs=1e-9)
    assert after.readings["x"].zero_offset == 0.0
    for zero in zeros[1:]:
        reading = after.readings[zero.channel]
        assert zero.offset == pytest.approx(mitutoyo.expected(zero.channel, 0))
        assert reading.device_value == pytest.approx(mitutoyo.expected(zero.channel, 1))
        assert reading.value == pytest.approx(reading.device_value - zero.offset)
        assert reading.zero_offset == zero.offset


def test_rejections_are_counted_kept_and_queued_and_readings_survive_them() -> None:
    faults = Faults(garbage_rate=0.4, torn_rate=0.4, stale_rate=0.0)
    sim = make_sim("mitutoyo", faults=faults)
    url = sim.start_pty()
    events: queue.Queue = queue.Queue()
    device_error = threading.Event()

    def note(rejection) -> None:
        if rejection.reason == "error":
            device_error.set()

    gauges = GaugeSet(
        [PortSpec(url, get_protocol("mitutoyo"), station_map(sim))],
        events=events,
        on_rejection=note,
        backoff=FAST,
    )
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        results = [gauges.capture(2.0) for _ in range(10)]
        sim.inject("error", "2")
        assert device_error.wait(5.0), "the device's error frame never came through"
    finally:
        gauges.stop()
        sim.stop()
    reader = gauges.readers[0]
    for k, result in enumerate(results):
        assert result.complete, result.message
        for channel in "xyz":
            assert result.readings[channel].value == pytest.approx(sim.expected(channel, k))
    assert reader.rejected_count >= 2
    assert reader.rejected_count == len(reader.rejections)
    assert reader.rejections[-1].reason == "error" and reader.rejections[-1].raw == "921"
    assert {r.reason for r in reader.rejections} <= {"malformed", "error"}
    items = []
    while not events.empty():
        items.append(events.get_nowait())
    assert sum(not hasattr(item, "channel") for item in items) == reader.rejected_count
    assert sum(hasattr(item, "channel") for item in items) == reader.reading_count == 30


def test_a_failing_callback_is_reported_and_the_reader_keeps_going() -> None:
    sim = make_sim("uwave", "x", push_rate=0)
    url = sim.start_pty()
    statuses = []
    readings = []

    def explode(reading) -> None:
        readings.append(reading)
        raise RuntimeError("UI went away")

    reader = GaugeReader(
        url,
        get_protocol("uwave"),
        {"1": "x"},
        on_reading=explode,
        on_status=statuses.append,
        backoff=FAST,
    )
    try:
        reader.start()
        assert reader.wait_connected(3.0)
        sim.push(3)
        deadline = time.monotonic() + 2
        while len(readings) < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert reader.alive
    finally:
        reader.stop()
        sim.stop()
    assert [r.value for r in readings] == pytest.approx([sim.expected("x", k) for k in range(3)])
    assert sum("callback failed" in s.message for s in statuses) == 3


def test_stop_returns_promptly_even_while_reading() -> None:
    sim = make_sim("uwave", "x", push_rate=200)
    url = sim.start_tcp(0)
    reader = GaugeReader(url, get_protocol("uwave"), {"1": "x"}, backoff=FAST)
    reader.start()
    assert reader.wait_connected(3.0)
    assert wait_until(lambda: reader.reading_count >= 10)  # in the middle of a stream
    began = time.monotonic()
    reader.stop()
    took = time.monotonic() - began
    sim.stop()
    assert not reader.alive
    assert reader.state == "stopped"
    assert took < 1.0


def test_a_software_zero_leaves_the_decimal_the_display_shows() -> None:
    """0.0001 - 0.0003 is -0.00019999999999999998 in binary; the session must get -0.0002."""
    import os
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    events: queue.Queue = queue.Queue()
    reader = GaugeReader(
        os.ttyname(slave), get_protocol("mitutoyo"), {"1": "x"}, events=events, backoff=FAST
    )
    try:
        reader.start()
        assert reader.wait_connected(3.0)
        reader.set_zero_offset("x", 0.0003)
        os.write(master, b"01A+000.0001\r")
        deadline = time.monotonic() + 3
        reading = None
        while reading is None and time.monotonic() < deadline:
            item = events.get(timeout=3)
            reading = item if getattr(item, "channel", None) == "x" else None
    finally:
        reader.stop()
        os.close(master)
        os.close(slave)
    assert reading is not None
    assert reading.device_value == 0.0001
    assert reading.value == -0.0002
