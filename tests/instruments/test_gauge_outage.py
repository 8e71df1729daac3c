"""A short line dropout costs a capture or a zero a delay, not a refused set: the gauge set waits
for a down port to come back until its timeout, then triggers. Real simulator on a real pty,
dropped and brought back by the simulator itself.

The simulator serves behind a link that survives its dropouts: a plain ``/dev/pts/N`` is free
while the line is down, and the kernel hands that number to the next pseudo-terminal any process
opens (another test run's simulator), which the reconnecting reader would then open and read.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest

from station.errors import StationError
from station.instruments.gauge import GaugeSet, PortSpec
from station.instruments.protocols import get_protocol
from station.instruments.reader import PortStatus
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model

CHANNELS = ("x", "y", "z")
DEVICE_MAP = {"1": "x", "2": "y", "3": "z"}


@pytest.fixture
def simulator() -> Iterator[Simulator]:
    model = fixture_model(
        CHANNELS,
        axis=AxisModel(bias=0.0, noise=0.0003),
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    sim = Simulator(get_protocol("mitutoyo"), model, seed=5)
    sim.start_pty(link=True)
    yield sim
    sim.stop()


@pytest.fixture
def gauges(simulator: Simulator) -> Iterator[GaugeSet]:
    spec = PortSpec(simulator.url, get_protocol("mitutoyo"), DEVICE_MAP)
    gauge_set = GaugeSet([spec], unit="in", resolution=0.0001, backoff=(0.05, 0.2))
    gauge_set.start()
    assert gauge_set.wait_connected(5.0), "the simulator's pty did not open"
    yield gauge_set
    gauge_set.stop()


def drop_line(simulator: Simulator, gauges: GaugeSet, down_time: float) -> None:
    """Drop the line for ``down_time`` seconds and return once the reader has said it is gone."""
    gone = threading.Event()

    def note(status: PortStatus) -> None:
        if status.state == "disconnected":
            gone.set()

    subscription = gauges.subscribe(on_status=note)
    try:
        simulator.disconnect(down_time)
        assert gone.wait(10.0), "the reader never noticed the dropped line"
    finally:
        subscription.cancel()


def test_capture_waits_out_a_short_dropout(simulator, gauges):
    drop_line(simulator, gauges, down_time=1.0)
    result = gauges.capture(timeout=15.0)
    assert result.complete, result.message
    assert not result.port_down
    assert set(result.readings) == set(CHANNELS)


def test_software_zero_waits_out_a_short_dropout(simulator, gauges):
    drop_line(simulator, gauges, down_time=1.0)
    results = gauges.zero(timeout=15.0)
    assert [z.channel for z in results] == list(CHANNELS)
    assert all(z.method == "software" for z in results)


def test_a_port_down_past_the_timeout_says_so_briefly(simulator, gauges):
    drop_line(simulator, gauges, down_time=60.0)
    result = gauges.capture(timeout=0.3)
    assert not result.complete
    assert result.port_down
    assert result.disconnected == CHANNELS
    assert result.stale == ()  # not "only readings from before the trigger"
    message = result.message
    assert "before the trigger" not in message
    assert "disconnected (reconnecting...)" in message
    assert ".." not in message.replace("...", "")  # one full stop, not "(...).."
    # Brief: measured with the port named as a plain /dev/pts/N (the link's folder is as long
    # as the temporary folder's path, which is not the sentence's doing).
    assert len(message.replace(simulator.url, "/dev/pts/N")) < 120, message


def test_zero_refuses_another_unit(simulator):
    spec = PortSpec(simulator.url, get_protocol("mitutoyo"), DEVICE_MAP)
    # Mitutoyo frames carry no unit: the reader labels them with the set's unit ("in" here),
    # so a session in mm must refuse to zero them as mm.
    with GaugeSet([spec], unit="in", resolution=0.0001, backoff=(0.05, 0.2)) as gauge_set:
        assert gauge_set.wait_connected(5.0)
        assert gauge_set.read_units(5.0) == dict.fromkeys(CHANNELS, "in")
        with pytest.raises(StationError, match="read in in but the session is in mm"):
            gauge_set.zero(timeout=5.0, unit="mm")
        assert gauge_set.zero_offsets() == dict.fromkeys(CHANNELS, 0.0)
