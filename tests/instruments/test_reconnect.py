"""Unplug and device-server restart: the reader reconnects and loses, invents, duplicates nothing.

The simulator serves a :class:`RampModel` (every reading a distinct value), so a lost, invented
or repeated reading is visible by value.
"""

from __future__ import annotations

import threading
import time

import pytest
from waiting import wait_until

from station.instruments.gauge import GaugeSet, PortSpec
from station.instruments.protocols import get_protocol
from station.instruments.reader import DEFAULT_BACKOFF, GaugeReader
from station.instruments.simulator import GaugeSpec, RampModel, Simulator

FAST = (0.05, 0.2)


class Recorder:
    """Collects readings and status changes from a reader thread."""

    def __init__(self) -> None:
        self.readings = []
        self.states = []
        self.connected_at: list[float] = []
        self.lock = threading.Lock()

    def reading(self, reading) -> None:
        with self.lock:
            self.readings.append(reading)

    def status(self, status) -> None:
        with self.lock:
            self.states.append(status.state)
            if status.state == "connected":
                self.connected_at.append(time.monotonic())

    def wait_for(self, predicate, timeout: float = 5.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                if predicate(self):
                    return True
            time.sleep(0.01)
        return False


def _check_stream(sim: Simulator, received: list, returned_at: float) -> None:
    """Received ⊆ sent, in order, once each; all sent after ``returned_at`` received."""
    sent = sim.sent["x"]
    by_value = {frame.value: frame.k for frame in sent}
    ks = [by_value.get(r.value) for r in received]
    assert None not in ks, "a reading the simulator never sent was delivered"
    assert len(ks) == len(set(ks)), "a reading was delivered twice"
    assert ks == sorted(ks), "readings arrived out of order"
    after_return = [frame.k for frame in sent if frame.t_mono > returned_at]
    assert after_return, "the simulator sent nothing after coming back"
    assert set(after_return) <= set(ks), "a reading sent after the return was lost"


@pytest.mark.parametrize("transport", ["pty", "tcp"])
def test_unplug_mid_stream_then_return(transport: str) -> None:
    model = RampModel(["x"], GaugeSpec(resolution=0.001))
    sim = Simulator(get_protocol("uwave"), model, seed=0, push_rate=200)
    url = sim.start_pty(link=True) if transport == "pty" else sim.start_tcp(0)
    record = Recorder()
    reader = GaugeReader(
        url,
        get_protocol("uwave"),
        {"1": "x"},
        on_reading=record.reading,
        on_status=record.status,
        backoff=FAST,
    )
    try:
        reader.start()
        assert record.wait_for(lambda r: len(r.readings) >= 40)
        sim.disconnect(down_time=0.3)
        assert record.wait_for(lambda r: "disconnected" in r.states)
        assert sim.wait_up(3.0)
        count_at_return = len(record.readings)
        assert record.wait_for(lambda r: len(r.connected_at) == 2)
        # Frames sent while the port was closed are gone, as with a real device (pyserial
        # flushes on open); from the moment the reader is back, nothing may be lost. Back is
        # the connection that delivers: under load a retry may first open the link while it
        # still names the old /dev/pts/N, which the kernel may have given to another test's
        # pseudo-terminal (nothing comes from it, and the reader moves on).
        assert record.wait_for(lambda r: len(r.readings) >= count_at_return + 60)
        returned_at = record.connected_at[-1]
        time.sleep(0.05)
        sim.push_rate = 0  # stop the stream (the simulator's loop sees it within 0.05 s)
        time.sleep(0.2)
        # Then let the last frames land, however slowly a loaded machine delivers them.
        assert record.wait_for(lambda r: r.readings[-1].value == sim.sent["x"][-1].value)
    finally:
        reader.stop()
        sim.stop()
    assert record.states[:2] == ["connecting", "connected"]
    assert "disconnected" in record.states
    assert record.states[-1] == "stopped"
    assert reader.reconnects >= 1
    _check_stream(sim, record.readings, returned_at)


def test_restarts_on_a_schedule_keep_the_capture_clean() -> None:
    """A poll station through repeated device-server restarts: captures succeed once back."""
    model = RampModel(["x", "y"], GaugeSpec(resolution=0.001))
    protocol = get_protocol("mitutoyo")
    sim = Simulator(protocol, model, seed=0)
    url = sim.start_tcp(0)
    statuses = []
    gauges = GaugeSet(
        [PortSpec(url, protocol, dict(sim.channel_map))], backoff=FAST, on_status=statuses.append
    )
    taken = []
    try:
        gauges.start()
        assert gauges.wait_connected(3.0)
        for round_ in range(3):
            result = gauges.capture(2.0)
            assert result.complete, result.message
            taken.append(result)
            sim.disconnect(down_time=0.15)
            # While down, a capture says which port is gone instead of inventing a reading.
            down = gauges.capture(0.1)
            assert down.readings == {}
            assert down.message
            assert sim.wait_up(3.0)
            reader = gauges.readers[0]
            deadline = time.monotonic() + 3.0
            while reader.reconnects <= round_ and time.monotonic() < deadline:
                time.sleep(0.01)
            assert gauges.wait_connected(3.0)
        final = gauges.capture(2.0)
    finally:
        gauges.stop()
        sim.stop()
    assert final.complete
    values = [r.readings["x"].value for r in [*taken, final]]
    assert values == [sim.sent["x"][k].value for k in range(len(values))]
    assert [s.state for s in statuses].count("disconnected") >= 3


def test_back_off_doubles_to_its_cap_and_stop_cuts_it_short() -> None:
    assert DEFAULT_BACKOFF == (0.5, 5.0)
    attempts: list[float] = []

    def note(status) -> None:
        if status.state == "disconnected":
            attempts.append(time.monotonic())

    missing = "/dev/ttyUSB_station_gone"
    reader = GaugeReader(missing, get_protocol("mitutoyo"), backoff=(0.05, 0.2), on_status=note)
    began = time.monotonic()
    reader.start()
    # Five failed attempts: four waits (0.05, 0.1, then twice the 0.2 cap).
    assert wait_until(lambda: len(attempts) >= 5, timeout=10.0)
    reader.stop()
    took = time.monotonic() - began
    gaps = [later - earlier for earlier, later in zip(attempts, attempts[1:], strict=False)]
    assert len(gaps) >= 4
    # Each wait is at least the back-off of its turn: 0.05, 0.1, 0.2, then capped at 0.2.
    for gap, least in zip(gaps, [0.05, 0.1, 0.2, 0.2, 0.2], strict=False):
        assert gap >= least * 0.95
    assert len(attempts) <= 1 + took / 0.05  # never faster than the first back-off
    assert "There is no serial port" in reader.last_message or reader.state == "stopped"

    # With the real back-off the thread sleeps up to 5 s between attempts; stop() still returns.
    failed = threading.Event()
    slow = GaugeReader(
        missing,
        get_protocol("mitutoyo"),
        on_status=lambda status: status.state == "disconnected" and failed.set(),
    )
    slow.start()
    assert failed.wait(10.0)  # the first attempt failed: the thread waits out its back-off
    began = time.monotonic()
    slow.stop()
    assert time.monotonic() - began < 1.0
    assert not slow.alive
