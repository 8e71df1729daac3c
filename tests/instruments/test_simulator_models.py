"""The two-fixture (relative accuracy) and parallel-bar (linearity) models, alone and served by
the unchanged :class:`Simulator` on a real pseudo-terminal."""

from __future__ import annotations

import math
import os
import select
import time
import tty

import numpy as np
import pytest

from station.analysis.linearity import straightness
from station.analysis.strokes import A_TO_B, B_TO_A, profiles_from_stream
from station.errors import StationError
from station.instruments.base import Value
from station.instruments.framing import FrameSplitter
from station.instruments.protocols import get_protocol
from station.instruments.simulator import BarModel, GaugeSpec, Simulator, TwoFixtureModel
from tests.clock import ManualClock


def read_values(fd: int, protocol, count: int, timeout: float = 10.0) -> list[Value]:
    """Parse ``count`` frames from a raw pty slave."""
    splitter = FrameSplitter(protocol.terminator)
    values: list[Value] = []
    deadline = time.monotonic() + timeout
    while len(values) < count and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.05)
        if ready:
            for frame in splitter.feed(os.read(fd, 65536)):
                if isinstance(frame, bytes):
                    parsed = protocol.parse(frame)
                    assert isinstance(parsed, Value), frame
                    values.append(parsed)
    return values


# -- the bar --------------------------------------------------------------------------------


def test_the_bar_shuttles_a_to_b_and_back_with_dwell():
    model = BarModel(length=10.0, points=50, dwell=5)
    positions = [model.stroke_of(k) for k in range(3 * model.readings_per_stroke)]
    assert positions[0] == (1, 0.0)
    assert positions[4] == (1, 0.0)  # dwell at A
    assert positions[54] == (1, pytest.approx(10.0))  # end of stroke 1 at B
    assert positions[55] == (2, pytest.approx(10.0))  # dwell at B
    assert positions[109] == (2, pytest.approx(0.0))
    assert positions[110][0] == 3


def test_the_bar_profile_has_the_configured_bow_sag_and_wobble():
    model = BarModel(length=20.0, bow=0.002, sag=0.001, wobble=0.0, wobble_v=0.0, tilt_h=0.0)
    s = np.linspace(0.0, 20.0, 2001)
    h = np.array([model.profile("h", x) for x in s])
    v = np.array([model.profile("v", x) for x in s])
    assert h.max() == pytest.approx(0.002) and h[0] == h[-1] == 0.0
    assert straightness(s, v).mz == pytest.approx(0.001, rel=1e-6)
    wobbly = BarModel(length=20.0, bow=0.0, sag=0.0, wobble=0.0003, period=4.0, tilt_h=0.0)
    h = np.array([wobbly.profile("h", x) for x in s])
    assert straightness(s, h).mz == pytest.approx(0.0006, rel=1e-4)
    with pytest.raises(StationError):
        model.profile("s", 1.0)


def test_the_bar_stream_is_deterministic_and_quantised():
    model = BarModel(points=40, dwell=4)
    first, again = model.stream(3, seed=2), model.stream(3, seed=2)
    assert first == again
    assert first != model.stream(3, seed=3)
    assert all(len(v) == 3 * 44 + 4 for v in first.values())
    assert all(abs(v / 0.0001 - round(v / 0.0001)) < 1e-6 for v in first["h"])


@pytest.mark.parametrize("kwargs", [{"points": 1}, {"dwell": -1}, {"length": 0.0}, {"period": 0.0}])
def test_bad_bar_settings_are_refused(kwargs):
    with pytest.raises(StationError):
        BarModel(**kwargs)


def test_the_simulator_serves_the_bar_and_the_strokes_come_back():
    protocol = get_protocol("mitutoyo")
    model = BarModel(length=12.0, points=60, dwell=6, indicator=GaugeSpec(0.0001, -0.5, 0.5, "in"))
    sim = Simulator(protocol, model, seed=7)
    path = sim.start_pty()
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    sim.move_to_rest(1)  # the strokes: the robot shuttles, one point per set sent
    sets = 4 * model.readings_per_stroke + model.dwell
    try:
        for _ in range(0, sets, 22):
            sim.push(min(22, sets - len(sim.sent["s"])))
            time.sleep(0.005)  # a device's rate: the reader drains between bursts
        values = read_values(fd, protocol, 3 * sets)
    finally:
        os.close(fd)
        sim.stop()
    stream = {"h": [], "v": [], "s": []}
    for value in values:
        stream[sim.channel_map[value.device_channel]].append(value.value)
    assert stream == {c: [sim.expected(c, k) for k in range(sets)] for c in stream}
    profiles = profiles_from_stream(stream["s"], {"h": stream["h"], "v": stream["v"]})
    assert [p.direction for p in profiles] == [A_TO_B, B_TO_A, A_TO_B, B_TO_A]
    assert all(np.ptp(p.s) == pytest.approx(12.0, abs=0.03) for p in profiles)


# -- the two fixtures -------------------------------------------------------------------------


def test_placements_are_seeded_far_apart_and_shown_as_the_pendant_reads():
    model = TwoFixtureModel(reach_min=10.0, reach_max=40.0, seed=5)
    placements = [model.placement_of(p) for p in range(1, 9)]
    assert placements == [TwoFixtureModel(seed=5).placement_of(p) for p in range(1, 9)]
    assert placements != [TwoFixtureModel(seed=6).placement_of(p) for p in range(1, 9)]
    for placement in placements:
        assert all(10.0 <= abs(c) <= 40.0 for c in placement.pendant)
        assert all(c == round(c, 3) for c in placement.pendant)
        assert placement.distance == pytest.approx(math.dist((0, 0, 0), placement.pendant))
    text = placements[0].pendant_text()
    x, y, z = placements[0].pendant
    assert text == f"X={x:+.3f} Y={y:+.3f} Z={z:+.3f} in"
    with pytest.raises(StationError):
        model.placement_of(0)


def test_the_error_grows_with_the_move_scale_and_rotation():
    model = TwoFixtureModel(scale=(1e-5, 2e-5, -1e-5), rotation=(0.0, 0.0, 1e-5), seed=1)
    px, py, pz = model.placement_of(3).pendant
    ex, ey, ez = model.systematic_error(3)
    assert ex == pytest.approx(1e-5 * px - 1e-5 * py)
    assert ey == pytest.approx(2e-5 * py + 1e-5 * px)
    assert ez == pytest.approx(-1e-5 * pz)


def test_readings_follow_the_robots_rest_home_then_each_return():
    model = TwoFixtureModel(noise=0.0, captures=2, seed=2)
    assert [model.current_placement(r) for r in range(7)] == [1, 1, 1, 2, 2, 2, 3]
    assert [model.at_home(r) for r in range(4)] == [True, False, False, True]
    assert model.rest_of(2) == 3 and model.rest_of(2, 1) == 4
    error = model.gauge("x").show(model.systematic_error(2)[0])
    assert model.value("x", model.rest_of(2, 1), 0) == error
    assert model.value("x", model.rest_of(2), 0) == 0.0  # at home: no error, no preload
    with pytest.raises(StationError):
        model.rest_of(2, 3)
    with pytest.raises(StationError):
        TwoFixtureModel(captures=0)


def serve_two_fixtures(seed: int = 4, clock=time.monotonic):
    protocol = get_protocol("mitutoyo")
    model = TwoFixtureModel(captures=1, preload=0.05, noise=0.0002, seed=9)
    sim = Simulator(protocol, model, seed=seed, clock=clock)
    path = sim.start_pty()
    return protocol, model, sim, os.open(path, os.O_RDWR | os.O_NOCTTY)


def by_channel(sim: Simulator, values: list[Value]) -> dict[str, list[float]]:
    found: dict[str, list[float]] = {"x": [], "y": [], "z": []}
    for value in values:
        found[sim.channel_map[value.device_channel]].append(value.value)
    return found


def test_the_simulator_serves_the_two_fixtures_at_home_then_after_the_return():
    protocol, model, sim, fd = serve_two_fixtures()
    try:
        sim.push(2)
        home = by_channel(sim, read_values(fd, protocol, 6))
        sim.robot_returns()
        sim.push(1)
        back = by_channel(sim, read_values(fd, protocol, 3))
    finally:
        os.close(fd)
        sim.stop()
    for channel in ("x", "y", "z"):
        assert home[channel] == [model.value(channel, 0, 4)] * 2
        assert back[channel] == [model.value(channel, 1, 4)]
        index = "xyz".index(channel)
        error = model.systematic_error(1)[index]
        preload = model.preload_of(1)[index]
        assert abs(home[channel][0] - preload) < 0.001  # the preload and noise only
        assert back[channel][0] - home[channel][0] == pytest.approx(error, abs=0.0015)


def test_extra_reads_at_home_never_shift_which_fixture_is_read():
    """The frames check and a zero of several readings read home as often as they like: the
    capture after the return still reads the return, and the next placement's home its home."""
    protocol, model, sim, fd = serve_two_fixtures()
    try:
        sim.push(3)  # the frames check
        sim.push(5)  # a zero of five readings
        home = by_channel(sim, read_values(fd, protocol, 24))
        sim.move_to_rest(model.rest_of(1, 1))
        sim.push(1)
        back = by_channel(sim, read_values(fd, protocol, 3))
        sim.move_to_rest(model.rest_of(2))
        sim.push(7)  # more reads at the next home
        next_home = by_channel(sim, read_values(fd, protocol, 21))
    finally:
        os.close(fd)
        sim.stop()
    for channel in ("x", "y", "z"):
        assert set(home[channel]) == {model.value(channel, model.rest_of(1), 4)}
        assert back[channel] == [model.value(channel, model.rest_of(1, 1), 4)]
        assert set(next_home[channel]) == {model.value(channel, model.rest_of(2), 4)}


def request_set(fd: int, protocol, sim: Simulator) -> dict[str, list[float]]:
    """Poll every channel once, as the station does, and parse the answers."""
    for request in dict.fromkeys(protocol.request(device) for device in sim.channel_map):
        os.write(fd, request)
    return by_channel(sim, read_values(fd, protocol, 3))


def test_a_pause_in_the_polls_is_the_operator_moving_the_robot():
    """``station simulate``'s still robot: polls close together (the frames check, a zero's
    readings) read one rest; after a pause of ``return_gap`` the robot is at its next rest (the
    placement's return, then the next placement's home). The clock is the test's: the polls of
    one rest are close together however busy the machine is."""
    clock = ManualClock()
    protocol, model, sim, fd = serve_two_fixtures(clock=clock)
    sim.return_gap = 0.3
    try:
        tty.setraw(fd)
        home = []
        for _ in range(6):  # frames check + a zero
            home.append(request_set(fd, protocol, sim))
            clock.advance(0.01)
        clock.advance(0.4)
        back = request_set(fd, protocol, sim)
        clock.advance(0.4)
        next_home = request_set(fd, protocol, sim)
    finally:
        os.close(fd)
        sim.stop()
    for channel in ("x", "y", "z"):
        assert {s[channel][0] for s in home} == {model.value(channel, model.rest_of(1), 4)}
        assert back[channel] == [model.value(channel, model.rest_of(1, 1), 4)]
        assert next_home[channel] == [model.value(channel, model.rest_of(2), 4)]
