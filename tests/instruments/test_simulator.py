"""The simulated fixture: deterministic model, protocol frames on a real pty/socket, faults."""

from __future__ import annotations

import os
import select
import socket
import statistics
import time

import pytest
from waiting import wait_until

from station.errors import StationError
from station.instruments.base import Rejected, Value
from station.instruments.framing import FrameSplitter
from station.instruments.protocols import get_protocol, protocol_names
from station.instruments.simulator import (
    AxisModel,
    Faults,
    FixtureModel,
    GaugeSpec,
    RampModel,
    Simulator,
    demo_model,
    fixture_model,
)


def read_frames(fd_or_sock, protocol, count: int, timeout: float = 10.0) -> list[bytes]:
    """Read ``count`` frames from a raw pty slave fd or a socket, with the protocol's splitter.

    Returns as soon as ``count`` frames are in: the timeout only bounds a wait for frames that
    never come (generous, for a loaded machine)."""
    splitter = FrameSplitter(protocol.terminator)
    frames: list[bytes] = []
    deadline = time.monotonic() + timeout
    while len(frames) < count and time.monotonic() < deadline:
        ready, _, _ = select.select([fd_or_sock], [], [], 0.05)
        if not ready:
            continue
        data = (
            fd_or_sock.recv(4096)
            if isinstance(fd_or_sock, socket.socket)
            else os.read(fd_or_sock, 4096)
        )
        frames.extend(f for f in splitter.feed(data) if isinstance(f, bytes))
    return frames


def test_the_kth_reading_depends_only_on_seed_and_k() -> None:
    model = fixture_model(["x", "y"], axis=AxisModel(noise=0.01))
    forward = [model.value("x", k, 5) for k in range(50)]
    backward = [model.value("x", k, 5) for k in reversed(range(50))][::-1]
    assert forward == backward
    assert forward != [model.value("x", k, 6) for k in range(50)]
    assert forward != [model.value("y", k, 5) for k in range(50)]


def test_values_are_quantised_and_clipped_to_the_gauge() -> None:
    gauge = GaugeSpec(resolution=0.005, low=-0.02, high=0.02)
    model = fixture_model(["x"], axis=AxisModel(noise=0.05), gauge=gauge)
    values = [model.value("x", k, 1) for k in range(300)]
    assert min(values) == -0.02 and max(values) == 0.02
    assert all(abs(v / 0.005 - round(v / 0.005)) < 1e-9 for v in values)


def test_noise_bias_skew_drift_backlash_and_outliers() -> None:
    n = 3000
    fine = GaugeSpec(resolution=1e-6)
    plain = FixtureModel({"x": AxisModel(bias=0.01, noise=0.002)}, fine)
    values = [plain.value("x", k, 3) for k in range(n)]
    assert statistics.fmean(values) == pytest.approx(0.01, abs=3 * 0.002 / n**0.5)
    assert statistics.stdev(values) == pytest.approx(0.002, rel=0.06)

    skewed = FixtureModel({"x": AxisModel(noise=0.002, skew=6.0)}, fine)
    values = [skewed.value("x", k, 3) for k in range(n)]
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    skewness = statistics.fmean(((v - mean) / sd) ** 3 for v in values)
    assert skewness > 0.5
    assert sd == pytest.approx(0.002, rel=0.08)

    warm = FixtureModel({"x": AxisModel(noise=0.0, drift=0.05, drift_tau=5.0)}, fine)
    trace = [warm.value("x", k, 0) for k in range(40)]
    assert trace[0] == 0.0 and trace == sorted(trace)
    assert trace[-1] == pytest.approx(0.05, abs=1e-4)

    loose = FixtureModel({"x": AxisModel(noise=0.0, backlash=0.004)}, fine)
    assert {loose.value("x", k, 0) for k in range(100)} == {-0.002, 0.002}

    jumpy = FixtureModel({"x": AxisModel(noise=0.001, outlier_rate=0.05, outlier_size=10)}, fine)
    far = sum(abs(jumpy.value("x", k, 0)) > 0.006 for k in range(n))
    assert 0.03 * n < far < 0.07 * n


def test_a_one_gauge_protocol_refuses_several_channels() -> None:
    with pytest.raises(StationError, match="carries one gauge per port"):
        Simulator(get_protocol("sylvac"), fixture_model(["x", "y"]))


@pytest.mark.parametrize("name", protocol_names())
def test_it_speaks_each_protocol_on_a_pty(name: str) -> None:
    protocol = get_protocol(name)
    model = fixture_model(["x"], axis=AxisModel(bias=0.2, noise=0.01))
    sim = Simulator(protocol, model, seed=11)
    path = sim.start_pty()
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        if protocol.polled:
            for _ in range(3):
                os.write(fd, protocol.request("1"))
                frames = read_frames(fd, protocol, 1)
                assert len(frames) == 1
        else:
            sim.push(3)
            frames = read_frames(fd, protocol, 3)
    finally:
        os.close(fd)
        sim.stop()
    sent = sim.sent_values("x")
    assert sent == [sim.expected("x", k) for k in range(3)]
    assert [frame.frame.strip() for frame in sim.sent["x"]][-1] == frames[-1]
    parsed = protocol.parse(frames[-1])
    assert isinstance(parsed, Value) and parsed.value == pytest.approx(sent[-1])


def test_tcp_answers_polls_and_zero_commands_and_comes_back_on_the_same_port() -> None:
    protocol = get_protocol("cdi")
    sim = Simulator(protocol, fixture_model(["x"]), seed=2)
    url = sim.start_tcp(0)
    port = int(url.rsplit(":", 1)[1])
    try:
        with socket.create_connection(("127.0.0.1", port)) as client:
            client.sendall(b"R\r")
            assert len(read_frames(client, protocol, 1)) == 1
            client.sendall(b"C\r")
            assert wait_until(lambda: sim.zero_requests)
            assert sim.zero_requests == ["x"]
            sim.disconnect(down_time=0.5)
            assert client.recv(100) == b""  # the server went away
        # Down: the simulator's own word, not a refused connection (while the port is free,
        # another test running beside this one may be given it for a server of its own).
        assert not sim.wait_up(0.0)
        assert sim.wait_up(10.0)
        assert sim.url == url
        with socket.create_connection(("127.0.0.1", port)) as client:
            client.sendall(b"R\r")
            assert len(read_frames(client, protocol, 1)) == 1
    finally:
        sim.stop()
    first = sim.model.value("x", 0, sim.seed)
    # The zero command made the shown value at that time the new zero.
    assert sim.zero_offsets == {"x": first}
    assert sim.sent_values("x") == [first, sim.expected("x", 1)]
    # The robot stayed at its rest: the zeroed gauge reads 0 there.
    assert sim.expected("x", 1) == 0.0
    assert sim.disconnects == 1


def test_a_pty_disconnect_keeps_the_url_through_a_symlink() -> None:
    sim = Simulator(get_protocol("mitutoyo"), RampModel(["x"]), seed=0)
    url = sim.start_pty(link=True)
    first = os.path.realpath(url)
    fd = os.open(url, os.O_RDWR | os.O_NOCTTY)
    try:
        sim.disconnect(down_time=0.1)
        # The other side is gone, as after an unplug: readable at once, then EIO or end of file.
        assert select.select([fd], [], [], 1.0)[0] == [fd]
        try:
            data = os.read(fd, 10)
        except OSError:
            data = b""
        assert data == b""
        assert sim.wait_up(2.0)
        assert sim.url == url and os.path.realpath(url).startswith("/dev/pts/")
        second = os.open(url, os.O_RDWR | os.O_NOCTTY)
        os.write(second, b"1\r")
        assert read_frames(second, get_protocol("mitutoyo"), 1) == [b"01A-0012.500"]
        os.close(second)
    finally:
        os.close(fd)
        sim.stop()
    assert not os.path.lexists(url)
    assert first.startswith("/dev/pts/")


@pytest.mark.parametrize("name", protocol_names())
def test_faults_never_turn_into_readings(name: str) -> None:
    """Garbage, torn, error/status, silence and stale frames: every Value is a sent value."""
    protocol = get_protocol(name)
    faults = Faults(
        garbage_rate=0.3,
        torn_rate=0.3,
        error_rate=0.2,
        silence_rate=0.1,
        stale_rate=0.1,
        torn_pause=0.001,
    )
    sim = Simulator(protocol, RampModel(["x"]), faults, seed=4)
    path = sim.start_pty()
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        for _ in range(40):
            if protocol.polled:
                os.write(fd, protocol.request("1"))
            else:
                sim.push()
        time.sleep(0.1)
        frames = read_frames(fd, protocol, 10_000, timeout=0.3)
    finally:
        os.close(fd)
        sim.stop()
    sent = sim.sent_values("x")
    parsed = [protocol.parse(frame) for frame in frames]
    # Rounded: a parser may build the float by another route than the model (1e-12 apart).
    values = [round(p.value, 9) for p in parsed if isinstance(p, Value)]
    sent = [round(v, 9) for v in sent]
    rejected = [p for p in parsed if isinstance(p, Rejected)]
    assert set(values) <= set(sent)
    assert rejected  # the garbage lines at least
    fresh = []
    for value in values:  # stale copies repeat earlier values; fresh ones come in order
        if not fresh or value > fresh[-1]:
            fresh.append(value)
    assert fresh == sent
    assert 20 < len(sent) < 40


def test_the_demo_model_looks_like_the_reports_table_2_1() -> None:
    model = demo_model(("x", "y", "z"))
    values = [model.value("x", k, 0) for k in range(3000)]
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    assert mean == pytest.approx(0.00008, abs=0.00002)
    assert sd == pytest.approx(0.00026, rel=0.1)
    assert statistics.fmean(((v - mean) / sd) ** 3 for v in values) < 0
    assert all(abs(v / 0.0001 - round(v / 0.0001)) < 1e-6 for v in values)
    assert demo_model(("x",), unit="mm").gauge("x").resolution == 0.001
